#include "checks/reaching_moves.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <set>

#include "tridex/detail/move_geometry.hpp"

namespace tridex::cli {

void for_each_reaching_move(const SimulationResult& r, const std::vector<Vec3>& points,
                            double slack, const std::function<void(const gcode::Move&)>& visit) {
  for (const gcode::MoveGroup& group : r.groups) {
    std::vector<Vec3> local;
    for (const Vec3& p : points) local.push_back(group.frame.to_local(p));
    std::optional<Vec3> previous_end;
    for (const gcode::Move& m : group.moves) {
      const bool continues = previous_end && glm::length(*previous_end - m.start) < 1e-9;
      previous_end = m.end;
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
  // The moves whose tool turns, swept pose by pose (in no group).
  for (const gcode::Move& m : r.simultaneous) {
    const SimultaneousReach reach = simultaneous_reach(r, m, points, slack / 4);
    if (reach.valid && reach.gap <= slack) visit(m);
  }
}

std::vector<NearMove> nearest_moves(const SimulationResult& r, const std::vector<Vec3>& points,
                                    double within, double slack, std::size_t count) {
  // A candidate names its move: the groups read their moves back by value (MoveList).
  struct Candidate {
    std::size_t group, index;  // group == r.groups.size(): r.simultaneous[index]
    double gap;
    bool over;
  };
  std::vector<Candidate> all;
  for (std::size_t g = 0; g < r.groups.size(); ++g) {
    const gcode::MoveGroup& group = r.groups[g];
    std::vector<Vec3> local;
    for (const Vec3& p : points) local.push_back(group.frame.to_local(p));
    for (std::size_t k = 0; k < group.moves.size(); ++k) {
      const gcode::Move m = group.moves[k];
      if (m.kind == gcode::MoveKind::rapid) continue;
      const Cutter& cutter = r.cutters[r.cutter_of_tool.at(m.tool)];
      const Segment tip{group.frame.to_local(m.start), group.frame.to_local(m.end)};
      const double radius = cutter.radius();
      const glm::dvec2 a(tip.a.x, tip.a.y), ab = glm::dvec2(tip.b.x, tip.b.y) - a;
      const double length2 = glm::dot(ab, ab);
      double best = std::numeric_limits<double>::infinity();
      bool over = false;  // the move passes over a point (at any height)
      for (const Vec3& p : local) {
        const glm::dvec2 q(p.x, p.y);
        const double t = length2 > 0 ? std::clamp(glm::dot(q - a, ab) / length2, 0.0, 1.0) : 0.0;
        const double beside = glm::length(q - (a + t * ab)) - radius;
        double gap = 0;
        if (beside <= 0) {
          over = true;
          gap = std::max(0.0, detail::MoveGeometry(cutter, tip).lowest(p.x, p.y).z - p.z);
        } else {
          const double above = std::max(0.0, tip.a.z + t * (tip.b.z - tip.a.z) - p.z);
          gap = std::hypot(beside, above);
        }
        best = std::min(best, gap);
      }
      if (best < std::numeric_limits<double>::infinity()) all.push_back({g, k, best, over});
    }
  }
  for (std::size_t k = 0; k < r.simultaneous.size(); ++k) {
    const gcode::Move& m = r.simultaneous[k];
    if (m.kind == gcode::MoveKind::rapid) continue;
    const SimultaneousReach reach = simultaneous_reach(r, m, points, slack / 4);
    // A turning cutter has no footprint to pass over: it reaches a point or passes beside it.
    if (reach.valid) all.push_back({r.groups.size(), k, std::max(0.0, reach.gap), reach.gap <= 0});
  }
  std::stable_sort(all.begin(), all.end(),
                   [](const Candidate& p, const Candidate& q) { return p.gap < q.gap; });
  std::vector<NearMove> kept;  // the nearest move of each line
  if (all.empty()) return kept;
  const double limit = all.front().gap <= within ? within : all.front().gap + slack;
  std::set<std::pair<int, int>> lines;
  for (const Candidate& near : all) {
    if (kept.size() >= count) break;
    const gcode::Move m = near.group < r.groups.size() ? r.groups[near.group].moves[near.index]
                                                       : r.simultaneous[near.index];
    if ((near.gap <= limit || near.over) && lines.insert({m.file, m.line}).second)
      kept.push_back({m, near.gap, near.over});
  }
  return kept;
}

}  // namespace tridex::cli
