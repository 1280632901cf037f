// tridex::gcode — the pose of a simultaneous 5-axis move (simultaneous.hpp).
#include "tridex/gcode/simultaneous.hpp"

#include <cmath>

namespace tridex::gcode {

MovePath::MovePath(const Kinematics& kin, const Move& move) : kin_(&kin), move_(move) {
  if (move.pose == PoseLaw::fixed) detail::fail("MovePath: move of line ", move.line, " is fixed");
  offset_ = tip_in_part(kin, move.machine, move.rotary) - move.end;
  machine_start_ = machine_from_part(kin, move.start + offset_, move.rotary_start);
}

namespace {
RotaryPositions simultaneous_rotary_between(const RotaryPositions& a, const RotaryPositions& b,
                                            double s) {
  RotaryPositions r;
  for (std::size_t i = 0; i < 3; ++i) r[i] = a[i] + s * (b[i] - a[i]);
  return r;
}
}  // namespace

ToolPose MovePath::at(double s) const {
  const RotaryPositions r = simultaneous_rotary_between(move_.rotary_start, move_.rotary, s);
  ToolPose pose;
  pose.axis = tool_direction(*kin_, r);
  if (move_.pose == PoseLaw::tcp)
    pose.tip = move_.start + s * (move_.end - move_.start);
  else
    pose.tip =
        tip_in_part(*kin_, machine_start_ + s * (move_.machine - machine_start_), r) - offset_;
  if (s == 0) pose.tip = move_.start;  // the ends exactly as the interpreter gave them
  if (s == 1) pose.tip = move_.end;
  return pose;
}

PoseBounds MovePath::bounds() const {
  double turn = 0, pivots = 0;
  for (const RotaryAxis& axis : kin_->axes) {
    const auto i = static_cast<std::size_t>(rotary_index(axis.letter));
    turn += std::abs(glm::radians(move_.rotary[i] - move_.rotary_start[i]));
    pivots += glm::length(axis.pivot);
  }
  PoseBounds b;
  b.turn_rate = turn;
  if (move_.pose == PoseLaw::tcp) {
    b.tip_straight = true;
    b.tip_speed = glm::length(move_.end - move_.start);
  } else {
    const double reach =
        std::max(glm::length(machine_start_), glm::length(move_.machine)) + 5 * pivots;
    b.tip_speed = glm::length(move_.machine - machine_start_) + turn * reach;
  }
  return b;
}

}  // namespace tridex::gcode
