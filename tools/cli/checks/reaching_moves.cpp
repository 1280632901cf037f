#include "checks/reaching_moves.hpp"

#include <algorithm>

#include "tridex/detail/move_geometry.hpp"

namespace tridex::cli {

void for_each_reaching_move(const SimulationResult& r, const std::vector<Vec3>& points,
                            double slack, const std::function<void(const gcode::Move&)>& visit) {
  for (const gcode::MoveGroup& group : r.groups) {
    std::vector<Vec3> local;
    for (const Vec3& p : points) local.push_back(group.frame.to_local(p));
    const gcode::Move* previous = nullptr;
    for (const gcode::Move& m : group.moves) {
      const bool continues = previous && glm::length(previous->end - m.start) < 1e-9;
      previous = &m;
      const Cutter& cutter = r.cutters[r.cutter_of_tool.at(m.tool)];
      Segment tip{group.frame.to_local(m.start), group.frame.to_local(m.end)};
      const double radius = cutter.radius();
      for (const Vec3& p : local) {
        if (p.x < std::min(tip.a.x, tip.b.x) - radius ||
            p.x > std::max(tip.a.x, tip.b.x) + radius ||
            p.y < std::min(tip.a.y, tip.b.y) - radius ||
            p.y > std::max(tip.a.y, tip.b.y) + radius || p.z + slack < std::min(tip.a.z, tip.b.z))
          continue;
        detail::MoveGeometry::Lowest lowest = detail::MoveGeometry(cutter, tip).lowest(p.x, p.y);
        if (p.z + slack >= lowest.z && !(continues && lowest.t <= 1e-9)) {
          visit(m);
          break;
        }
      }
    }
  }
}

}  // namespace tridex::cli
