// Which moves cut at a point: the attribution of a gouge (check) or of a difference between two
// programs (diff) to the lines of the program.
#pragma once

#include <functional>
#include <optional>
#include <vector>

#include "pipeline/pipeline.hpp"
#include "tridex/geometry.hpp"

namespace tridex::cli {

// Calls `visit` once for each move of `r`'s direction groups (group by group, each in program
// order) whose swept cutter reaches one of `points` (work frame): the point lies above the
// move's swept lower surface in the group's frame, within `slack`. A move that reaches a point
// only at its start, where the move before it left the cutter, cut nothing there (a retract from
// the bottom of a plunge) and is not visited for it. Then each simultaneous move (r.simultaneous)
// whose cutter, over its poses, comes within `slack` of a point (simultaneous_reach).
void for_each_reaching_move(const SimulationResult& r, const std::vector<Vec3>& points,
                            double slack, const std::function<void(const gcode::Move&)>& visit);

// A cutting move near a point and how far its swept cutter passes from it (mm, 0: it reaches it).
struct NearMove {
  std::optional<gcode::Move> move;  // a copy: the groups keep their moves compactly (MoveList)
  double gap = 0;
  bool over = false;  // its footprint covers a point: it passes over it, at `gap` or higher
};

// The moves nearest material left where it should not be (check's excess, regress's regions the
// new program leaves): material no move reached, so the moves that should have removed it are
// the cutting moves (not rapids) that pass closest. The gap from a point p to a move, in its
// group's frame: above the cutter's footprint (the tip segment widened by the radius), how far
// the swept lower surface lies above p (detail::MoveGeometry); beside it, the horizontal distance
// past the radius and the tip's height above p, combined (a bound from below on the true distance
// for a flat end, close to it for the others). Returns, nearest first, the nearest move of each
// line among those within `within` of one of `points` or passing over one (at any height: a
// plunge that stopped short, a pass that ran high), at most `count` lines; when no move is within
// `within`, the nearest and those within `slack` of its gap, with those passing over.
std::vector<NearMove> nearest_moves(const SimulationResult& r, const std::vector<Vec3>& points,
                                    double within, double slack, std::size_t count);

}  // namespace tridex::cli
