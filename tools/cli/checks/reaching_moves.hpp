// Which moves cut at a point: the attribution of a gouge (check) or of a difference between two
// programs (diff) to the lines of the program.
#pragma once

#include <functional>
#include <vector>

#include "pipeline/pipeline.hpp"
#include "tridex/geometry.hpp"

namespace tridex::cli {

// Calls `visit` once for each move of `r`'s direction groups (group by group, each in program
// order) whose swept cutter reaches one of `points` (work frame): the point lies above the
// move's swept lower surface in the group's frame, within `slack`. A move that reaches a point
// only at its start, where the move before it left the cutter, cut nothing there (a retract from
// the bottom of a plunge) and is not visited for it.
void for_each_reaching_move(const SimulationResult& r, const std::vector<Vec3>& points,
                            double slack, const std::function<void(const gcode::Move&)>& visit);

}  // namespace tridex::cli
