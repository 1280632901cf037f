#include "rapid_check.hpp"

#include <algorithm>
#include <cmath>

namespace tridex::cli {

std::vector<RapidCut> rapid_cuts(const ZMap& feed_map, std::span<const Cutter> cutters,
                                 std::span<const CutMove> rapids, double tolerance) {
  std::vector<RapidCut> found;
  const ZMapGrid& g = feed_map.grid;
  float top = -std::numeric_limits<float>::infinity();
  for (float h : feed_map.heights) top = std::max(top, h);
  for (std::size_t r = 0; r < rapids.size(); ++r) {
    const CutMove& move = rapids[r];
    const Cutter& cutter = cutters[move.cutter];
    detail::MoveGeometry m(cutter, move.tip);
    // Most rapids pass above everything: nothing to look at.
    if (m.lowest_tip() >= double(top) - tolerance) continue;
    const double radius = cutter.radius();
    double x_lo = std::min(move.tip.a.x, move.tip.b.x) - radius, x_hi = std::max(move.tip.a.x, move.tip.b.x) + radius;
    double y_lo = std::min(move.tip.a.y, move.tip.b.y) - radius, y_hi = std::max(move.tip.a.y, move.tip.b.y) + radius;
    int i0 = std::max(0, static_cast<int>(std::ceil((x_lo - g.x0) / g.cell)));
    int i1 = std::min(g.nx - 1, static_cast<int>(std::floor((x_hi - g.x0) / g.cell)));
    int j0 = std::max(0, static_cast<int>(std::ceil((y_lo - g.y0) / g.cell)));
    int j1 = std::min(g.ny - 1, static_cast<int>(std::floor((y_hi - g.y0) / g.cell)));
    double depth = 0;
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        if (feed_map.is_empty(i, j)) continue;  // no material above this point
        double h = feed_map.height(i, j);
        if (m.lowest_tip() >= h - tolerance) continue;
        double z = m.lowest_above(g.x(i), g.y(j));
        depth = std::max(depth, h - z);
      }
    if (depth > tolerance) found.push_back(RapidCut{r, depth});
  }
  return found;
}

}  // namespace tridex::cli
