// tridex::gcode — grouping moves by spindle direction.
//
// The method (Inui, Chen and Umezu, CAD&A 19(4) 2022, §3) mills one Z-map per spindle direction
// and intersects the results, and material removal does not depend on the order of moves, so all
// moves of one direction can be gathered across the whole program. Each group carries the
// canonical frame of its direction (Frame::from_axis); the kernel's mill() takes tool-tip
// segments in that frame: frame.to_local(move.start), frame.to_local(move.end).
#pragma once

#include <set>
#include <span>
#include <vector>

#include "tridex/gcode/move_list.hpp"
#include "tridex/geometry.hpp"

namespace tridex::gcode {

struct MoveGroup {
  Vec3 axis{0.0, 0.0, 1.0};  // the direction of the group's first move
  Frame frame;               // Frame::from_axis(axis)
  MoveList moves;            // in program order
  std::set<int> tools;
};

// Incremental form, for streaming: add() each move as the interpreter emits it.
class DirectionGrouper {
 public:
  explicit DirectionGrouper(double angle_tolerance_deg = 1e-3);
  // Adds a move to the group of its direction (a new group if none is within the tolerance of
  // the group's axis) and returns that group's index.
  std::size_t add(const Move& move);
  const std::vector<MoveGroup>& groups() const { return groups_; }
  std::vector<MoveGroup> take() { return std::move(groups_); }

 private:
  double cos_tolerance_;
  std::size_t last_ = 0;
  std::vector<MoveGroup> groups_;
};

// Groups in order of first appearance; a move joins the first group whose axis is within
// `angle_tolerance_deg` of its own.
std::vector<MoveGroup> group_by_direction(std::span<const Move> moves,
                                          double angle_tolerance_deg = 1e-3);

}  // namespace tridex::gcode
