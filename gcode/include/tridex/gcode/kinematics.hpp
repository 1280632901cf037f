// tridex::gcode — a five-axis machine's rotary kinematics: where the tool points on the part for
// given rotary positions, the rigid map between machine coordinates and the part, and the rotary
// positions that put the tool along a wanted direction (3+2 machining: the rotaries index, then
// stay put while XYZ cut).
//
// The model. Each rotary axis is a line in machine coordinates (a pivot point on it and a unit
// direction, both as they are when every rotary axis is at 0) about which its carriage turns
// right-handed by the axis position times `sense`. Axes on the TABLE carry the part; axes on the
// HEAD carry the spindle. Each side is a chain listed from the machine frame outward (table: bed
// → part; head: ram → spindle), so an outer axis rides on the inner one:
//   table:  part point p (its machine coordinates with every rotary at 0) is at T1(T2(p));
//   head:   the tool tip is at X + H1(H2(0)), pointing along H1·H2·(0,0,1),
// where Ti, Hi turn about axis i's line and X is the machine position of the linear axes. With
// every rotary at 0 the tip is at X: machine coordinates are tool-tip coordinates (tool length
// applied), and head pivots are given relative to that tip (e.g. (0, 0, 150): the head's pivot
// 150 mm above the tip). The part frame is the machine frame as the part sits with every rotary
// at 0; a work offset measured there (G54) is the caller's to subtract.
//
// Inverse: the two rotary angles that turn the tool to a direction solve Rot(a, α)·x = Rot(b, β)·y
// (Paden–Kahan subproblem 2; Murray, Li and Sastry, "A Mathematical Introduction to Robotic
// Manipulation", CRC 1994, §3.2.2): the common vector lies on two cones, at most two solutions.
//
// The machine file's "kinematics" key and the bundled profiles are the machine module's
// (machine.hpp).
#pragma once

#include <array>
#include <optional>
#include <string>
#include <vector>

#include "tridex/geometry.hpp"

namespace tridex::gcode {

enum class MachineType { table_table, head_table, head_head };

struct RotaryAxis {
  char letter = 'A';        // 'A', 'B' or 'C'
  bool on_head = false;     // false: on the table
  Vec3 direction{1, 0, 0};  // unit; a positive position turns right-handed about it (sense applied)
  Vec3 pivot{0.0};          // a point on the axis line, mm, every rotary at 0
  std::optional<std::array<double, 2>> limits;  // degrees [min, max]; none: turns without end
};

// Rotary positions in degrees, indexed A = 0, B = 1, C = 2; an axis the machine lacks stays 0.
using RotaryPositions = std::array<double, 3>;

// 0, 1, 2 for 'A', 'B', 'C' (either case); -1 otherwise.
int rotary_index(char letter);

struct Kinematics {
  MachineType type = MachineType::table_table;
  std::vector<RotaryAxis> axes;  // chain order (see above)
  // The travel of the linear axes X, Y, Z: [min, max] in machine coordinates (mm, the tool tip
  // with every rotary at 0, as `Move::machine`); none: that axis is not limited.
  std::array<std::optional<std::array<double, 2>>, 3> travel;

  // The axis with this letter, or nullptr when the machine has none.
  const RotaryAxis* find(char letter) const;

  // Checks the model (1 or 2 axes, letters distinct, sides matching the type, unit directions,
  // finite pivots, min < max); throws tridex::Error naming what is wrong.
  void validate() const;
};

// ---- forward ----------------------------------------------------------------------------------

// Where the part is: the rigid map from part coordinates to machine coordinates of the table
// chain (identity without table axes).
Frame part_to_machine(const Kinematics& kin, const RotaryPositions& rotary);

// Where the tool is relative to the linear axes: rotation = the head chain's turn, origin = the
// tip's offset from the machine position X (zero without head axes).
Frame head_offset(const Kinematics& kin, const RotaryPositions& rotary);

// The tool direction (tip towards spindle, unit) in the part frame.
Vec3 tool_direction(const Kinematics& kin, const RotaryPositions& rotary);

// The tool tip in the part frame for machine position X: raw rotary-word programs without TCP,
// whose X Y Z are machine coordinates.
Vec3 tip_in_part(const Kinematics& kin, const Vec3& machine_xyz, const RotaryPositions& rotary);

// The inverse: the machine position X that puts the tip at a part point (TCP, G43.4/G43.5;
// Haas DWO, G254).
Vec3 machine_from_part(const Kinematics& kin, const Vec3& part_tip, const RotaryPositions& rotary);

// The rigid map machine → part for fixed rotaries: to_world(X) = tip_in_part(X).
Frame machine_to_part(const Kinematics& kin, const RotaryPositions& rotary);

// ---- inverse ----------------------------------------------------------------------------------

// Rotary positions, within the limits, that turn the tool along `part_direction` (need not be
// unit); of those, the one nearest `current` (least total turn, each axis taken on the turn
// nearest its current position). Where an axis's angle is free (the direction lies along it,
// e.g. C with the tool vertical on a trunnion) it keeps its current position. Axes the machine
// lacks keep `current`. Throws tridex::Error: "not reachable" with the direction when no
// rotary positions give it, or naming the limits that exclude every solution.
RotaryPositions orient_tool(const Kinematics& kin, const Vec3& part_direction,
                            const RotaryPositions& current);

// Throws tridex::Error naming the axis, its position and its limits when a position is outside.
void check_limits(const Kinematics& kin, const RotaryPositions& rotary);

// One axis past its travel (X, Y, Z: machine coordinates, mm) or its limits (A, B, C: degrees).
struct TravelViolation {
  char axis = 'X';
  double value = 0;
  double limit = 0;  // the end of the travel it passed
};

// The axes of a machine position (linear machine coordinates and rotary positions) that lie
// outside the kinematics' travel and rotary limits, in the order X Y Z A B C. (The interpreter
// refuses a rotary word past its limits already; the rotary check is for positions from
// elsewhere.)
std::vector<TravelViolation> travel_violations(const Kinematics& kin, const Vec3& machine_xyz,
                                               const RotaryPositions& rotary);

}  // namespace tridex::gcode
