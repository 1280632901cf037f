// tridex command — the shank and the holder against the stock, in program order (issue 14).
//
// Each move's non-cutting parts (tridex/tool_body.hpp: the shank above the flutes, the holder's
// sections) are tested, before the move is milled, against its direction's Z-map as it stands
// then: a part collides where some grid point's height lies more than a tolerance above the part's
// swept lower surface (the depth, along the spindle), and comes near where the part grown by the
// clearance reaches the material (the closest distance found by bisection on the growth).
//
// The map is milled in batches (mill() does not depend on the order within a batch), so it may
// still hold material that moves since the last batch removed; heights only fall, so a part clear
// of the stale map is clear of the true one, and only a part that comes near material that a
// pending move may remove (in a tile under a pending move's footprint) is tested again after the
// pending moves are milled (`flush`): elsewhere the stale heights are the true ones, so the batch
// goes on growing while a tool works near walls it has already cut. Tiles of 16×16 grid points
// keep their highest height, refreshed after every batch, so that parts above all material cost
// little.
//
// Across directions the check is conservative, as the rapid check is (pipeline.hpp): material that
// another direction's moves removed earlier still counts in this direction's map, so a holder may
// be reported in a pocket that a machine reaches safely after another setup cleared it.
#pragma once

#include <functional>
#include <limits>
#include <map>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/gcode/move.hpp"
#include "tridex/mill.hpp"
#include "tridex/tool_body.hpp"
#include "tridex/zmap.hpp"

namespace tridex::cli {

// A part deeper than this in the material is a collision (mm): as for rapids, above the rounding
// of float heights.
constexpr double kCollisionTolerance = 0.005;

struct BodyFinding {
  int file = 0;  // Move::file: an index into the program's files (SimulationResult::files)
  int line = 0;
  int tool = 0;
  std::string part;     // "shank", "holder section k" (k = 1 at the holder's face)
  double depth_mm = 0;  // collision: how deep along the spindle; near miss: the closest distance
  Vec3 where{0};        // the grid point of the material (work frame)
  Vec3 axis{0, 0, 1};
  std::size_t group = 0;
};

struct BodyFindings {
  std::vector<BodyFinding> collisions;   // one per source line and part (the deepest)
  std::vector<BodyFinding> near_misses;  // one per source line and part (the closest)
  // (tool, group) -> the deepest holder collision, for the stick-out a program needs.
  std::map<std::pair<int, std::size_t>, double> holder_depth;
  double seconds = 0;  // spent in the check itself (not in the milling it asks for)
};

// Keeps one finding per source line and part: the deepest collision (keep_larger), the closest
// near miss (not).
void record_body_finding(std::vector<BodyFinding>& list, BodyFinding f, bool keep_larger);

class BodyCheck {
 public:
  // `bodies[c]` describes cutters[c]'s parts (empty: nothing to check). `clearance` ≥ 0 (mm).
  BodyCheck(const ZMap& map, std::span<const ToolBody> bodies, double clearance);

  // Tests the move `cut` (its tip in the map's frame) of `move` against `map`. `up_to_date` says
  // whether the map holds every earlier move; if not, `flush` mills those (and must call milled).
  void check(const ZMap& map, const gcode::Move& move, const CutMove& cut, const Vec3& axis,
             const Frame& frame, std::size_t group, bool up_to_date,
             const std::function<void()>& flush, BodyFindings& found);

  // To be told of each move put in the batch (not yet milled): marks the tiles it may lower.
  void will_mill(const ZMap& map, const Cutter& cutter, const CutMove& move);

  // To be told after each batch is milled into the map: refreshes the tiles it touched and clears
  // their pending marks.
  void milled(const ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> batch);

  // The largest height − S(q) of the swept surface over the footprint, where it exceeds 0 (grid
  // points in tiles wholly below the tip are skipped, so a result ≤ 0 only says "no contact").
  // `stale`, where given, is set when a point of contact lies in a tile that a pending move (one
  // not yet milled) may lower.
  CutDepth contact_depth(const ZMap& map, const Cutter& surface, const Segment& tip,
                         bool* stale = nullptr) const;

 private:
  void refresh_tiles(const ZMap& map, int i0, int i1, int j0, int j1);

  std::span<const ToolBody> bodies_;
  double clearance_;
  std::vector<std::vector<Cutter>> plain_, grown_;  // per cutter, per part
  int tiles_x_ = 0, tiles_y_ = 0;
  std::vector<float> tile_top_;
  double map_top_ = -std::numeric_limits<double>::infinity();  // the stock's highest point
  std::vector<unsigned char> tile_pending_;  // 1: a move of the batch not yet milled reaches it
};

}  // namespace tridex::cli
