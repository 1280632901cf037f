// tridex::gcode — the pose of a simultaneous 5-axis move (Move::pose ≠ fixed) at any point of it,
// as the control interpolates it (docs/gcode.md, "Simultaneous 5-axis"), and the bounds on how
// fast its tip moves and its axis turns that certify a sweep's sub-steps (tridex/sweep.hpp).
//
// joints (raw rotary words): the linear axes' machine coordinates X(s) and the rotary positions
// R(s) run linearly in s ∈ [0, 1]; the tip on the part is tip_in_part(X(s), R(s)).
// tcp (G43.4, G43.5): the tip runs straight on the part, R(s) linearly.
// Either way the tool axis is tool_direction(R(s)).
#pragma once

#include "tridex/gcode/kinematics.hpp"
#include "tridex/gcode/move.hpp"
#include "tridex/sweep.hpp"

namespace tridex::gcode {

class MovePath {
 public:
  // `move` must be simultaneous and come from a run with `kin`.
  MovePath(const Kinematics& kin, const Move& move);
  ToolPose at(double s) const;
  // Certified bounds per unit s: the tip's speed (under the joints law, |ΔX| plus each rotary's
  // turn times a bound on the distance from its axis: the machine coordinates' norm plus five times
  // the pivots', each turn about a pivot moving a point's norm by at most twice the pivot's), and
  // the axis's turn rate (at most the sum of the rotaries' turns, in radians).
  PoseBounds bounds() const;
  const Vec3& machine_start() const { return machine_start_; }

 private:
  const Kinematics* kin_;
  Move move_;
  Vec3 offset_{0.0};  // part frame − the move's frame (the interpreter's world origin)
  Vec3 machine_start_{0.0};
};

}  // namespace tridex::gcode
