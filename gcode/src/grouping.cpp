// tridex::gcode — grouping moves by spindle direction (see grouping.hpp).
#include "tridex/gcode/grouping.hpp"

#include <algorithm>
#include <cmath>
#include <utility>

#include "tridex/error.hpp"

namespace tridex::gcode {

DirectionGrouper::DirectionGrouper(double angle_tolerance_deg) {
  if (!std::isfinite(angle_tolerance_deg) || angle_tolerance_deg < 0 || angle_tolerance_deg >= 90)
    detail::fail("group_by_direction: angle_tolerance_deg must be in [0, 90), got ",
                 angle_tolerance_deg);
  // A zero tolerance still has to group equal unit vectors whose dot product rounds below 1.
  cos_tolerance_ = std::min(std::cos(glm::radians(angle_tolerance_deg)), 1.0 - 1e-15);
}

std::size_t DirectionGrouper::add(const Move& move) {
  double length = glm::length(move.axis);
  if (!std::isfinite(length) || !(length > 1e-12))
    detail::fail("group_by_direction: move from line ", move.line, " has no spindle direction");
  Vec3 axis = move.axis / length;
  // Consecutive moves nearly always share a direction: try the last group first.
  auto matches = [&](std::size_t g) { return glm::dot(groups_[g].axis, axis) >= cos_tolerance_; };
  std::size_t found = groups_.size();
  if (last_ < groups_.size() && matches(last_)) {
    found = last_;
  } else {
    for (std::size_t g = 0; g < groups_.size(); ++g)
      if (matches(g)) {
        found = g;
        break;
      }
  }
  if (found == groups_.size()) {
    MoveGroup group;
    group.axis = axis;
    group.frame = Frame::from_axis(axis);
    groups_.push_back(std::move(group));
  }
  MoveGroup& group = groups_[found];
  // Tools change rarely: the set is searched only when this move's differs from the last one's.
  if (group.moves.empty() || group.moves.back().tool != move.tool) group.tools.insert(move.tool);
  group.moves.push_back(move);
  last_ = found;
  return found;
}

std::vector<MoveGroup> group_by_direction(std::span<const Move> moves, double angle_tolerance_deg) {
  DirectionGrouper grouper(angle_tolerance_deg);
  for (const Move& move : moves) grouper.add(move);
  return grouper.take();
}

}  // namespace tridex::gcode
