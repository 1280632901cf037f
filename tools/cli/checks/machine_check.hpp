// tridex check — the machine and the fixture (issue 33): the tool (flutes, shank, holder) and the
// machine's head-side parts against the fixtures and the table-side parts, and the machine's
// parts against each other, along every move; travel and rotary limits along each move.
//
// Frames. Everything is placed in the bed frame: the machine frame of kinematics.hpp with the
// linear axes split between the sides ("linear_axes"; default: all move the head). A head-side
// link at machine state (X, rotaries) is Trans(X_head) ∘ H1 ∘ … ∘ Hk, a table-side one
// Trans(−X_table) ∘ T1 ∘ … ∘ Tk (each Ti, Hi a turn about its axis line), so that the tool tip
// (tool coordinates: the tip at the origin, +Z up the tool) sits at X + H(0) relative to the part
// point T(p), as kinematics.hpp has it. A linear axis's carriage moves along its axis only. The
// work frame (fixtures) is the part frame shifted by the work offset, found from each move as
// tip_in_part(machine) − tip (work). The spindle's parts sit at the gauge point, the tool's length
// above the tip (the tool table's tool length; else the top of the holder; else of the flutes).
//
// Continuous check (conservative advancement; Mirtich, "Impulse-based dynamic simulation of rigid
// body systems", PhD thesis, Berkeley 1996, §2.3; Zhang et al., "Continuous collision detection for
// articulated models using Taylor models and temporal culling", SIGGRAPH 2007): along a move,
// t ∈ [0, 1], a bound V on how fast any point of either body moves (mm per unit t: the linear
// axes' travel plus, per rotary axis, its turn in radians times the farthest the body reaches
// from that axis through the chain) means the distance d at t cannot fall below the clearance
// before t + (d − clearance) / V. Stepping by that, a contact is never passed between two poses,
// whatever the speed or the thinness of the obstacle (tests/tools/test_machine_check.cpp plants
// plates and spikes between the poses a fixed-step sampler would test).
#pragma once

#include <array>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include "tridex/collide.hpp"
#include "tridex/gcode/kinematics.hpp"
#include "tridex/gcode/machine.hpp"

namespace tridex::cli {

// Where a body rides. bed; carriage (index: 0 X, 1 Y, 2 Z); table/head (index: how many of that
// side's rotary axes it rides on, from the machine outward); work (the part's frame: fixtures);
// spindle (index unused: the gauge point); tool (the tip, +Z up the tool).
enum class LinkKind { bed, carriage, table, head, work, spindle, tool };

struct Link {
  LinkKind kind = LinkKind::bed;
  int index = 0;
  bool operator==(const Link&) const = default;
};

struct MachineBody {
  std::string name;   // "vise.stl", "head", "tool 3 holder"
  std::string group;  // "fixture", "component", "tool"
  Link link;
  int tool = -1;  // tool parts: the tool they belong to
  std::shared_ptr<const TriangleTree> tree;
  std::shared_ptr<const Mesh> mesh;  // what the tree was built from (the HTML page draws it)
  Vec3 centre{0};                    // a bounding sphere of the tree (its own coordinates)
  double radius = 0;
  std::vector<Vec3> pieces;  // a vertex of each connected piece (TriangleTree::piece_vertices)
};

// The machine's state: the linear axes' machine coordinates and the rotary positions (degrees).
struct MachineState {
  Vec3 x{0};
  gcode::RotaryPositions rotary{};
};

// One move as the check sees it: from one state to another. Under TCP (`tip_linear`) the tip
// moves straight in the work frame while the rotaries turn (machine coordinates follow from
// machine_from_part); otherwise the machine's axes move straight.
struct MachineMove {
  int file = 0, line = 0, tool = 0;
  MachineState from, to;
  bool tip_linear = false;
  Vec3 tip_from{0}, tip_to{0};  // work frame (tip_linear only)
  Vec3 offset{0};               // part frame − work frame
  double gauge = 0;             // tool length: the tip to the spindle's gauge point
  bool gauge_known = true;      // else the spindle's parts are not tested on this move
};

struct MachineFinding {
  int file = 0, line = 0, tool = 0;
  std::string a, b;     // the pair's names
  double distance = 0;  // the closest the pair came (collision: ≤ the clearance)
  double t = 0;         // where along the move (0..1), collisions: the first contact
  MachineState state;   // the axes' positions there
  Vec3 where{0};        // a point near the contact, work frame
  // The pair as bodies() lists them, and each one's frame there (its coordinates to the work
  // frame): the HTML page draws the two at this pose.
  int body_a = -1, body_b = -1;
  Frame pose_a, pose_b;
};

struct TravelAlong {
  int file = 0, line = 0;
  char axis = 'X';
  double value = 0, limit = 0, t = 0;
};

struct MachineFindings {
  std::vector<MachineFinding> collisions, near_misses;
  std::vector<TravelAlong> travel;  // limits passed inside a move whose ends are within
  long long queries = 0;            // distance queries made
  long long moves = 0;
  double seconds = 0;
};

class MachineCheck {
 public:
  MachineCheck(std::optional<gcode::Kinematics> kinematics, std::array<bool, 3> linear_on_head,
               gcode::CollisionSettings settings);

  // Off: every query searches for the exact distance and no pair reuses the last move's bound
  // (the first version's behaviour; bench/tools/machine_bench.cpp compares the two).
  void set_bounded_search(bool on) { bounded_ = on; }

  // Adds a body (its tree in its link's coordinates, work-frame bodies in the work frame).
  void add(MachineBody body);
  const std::vector<MachineBody>& bodies() const { return bodies_; }

  // The body's frame (its coordinates to the bed frame) at `state`.
  Frame frame_of(const MachineBody& body, const MachineState& state, const MachineMove& move) const;
  MachineState state_at(const MachineMove& move, double t) const;

  // Checks one move: every pair that may meet, continuously, and the travel along it. Moves in
  // program order let a pair reuse the bound it ended the last move with (PairBound); any order
  // is sound.
  void check(const MachineMove& move, MachineFindings& found);

 private:
  bool pair_tested(const MachineBody& a, const MachineBody& b, int tool) const;
  double speed_bound(const MachineBody& body, const MachineMove& move, double linear) const;
  double linear_speed_bound(const MachineMove& move) const;
  double swept_distance(const MachineBody& a, const MachineBody& b, const MachineMove& move,
                        double cap) const;
  // What a pair knew at the end of the last move it was checked on: the distance there is at
  // least `lower` (the last distance found, less the farthest the bodies could close in since).
  // A move that starts within |ΔX| + |Δoffset| of that pose (rotaries, tool and gauge the same)
  // starts at least that much less, and is skipped when even its fastest point cannot close the
  // rest of the gap to the near-miss distance.
  struct PairBound {
    bool valid = false;
    MachineState at;
    Vec3 offset{0};
    double gauge = 0;
    int tool = 0;
    double lower = 0;
  };
  void check_pair(const MachineBody& a, const MachineBody& b, const MachineMove& move,
                  MachineFindings& found, PairBound& bound) const;
  void check_travel(const MachineMove& move, MachineFindings& found) const;

  std::optional<gcode::Kinematics> kin_;
  std::array<bool, 3> on_head_;
  gcode::CollisionSettings settings_;
  std::vector<MachineBody> bodies_;
  std::vector<const gcode::RotaryAxis*> table_axes_, head_axes_;  // chain order
  std::vector<PairBound> bounds_;                                 // bodies² (i < j used)
  bool bounded_ = true;
};

}  // namespace tridex::cli
