#include "checks/rapid_check.hpp"

#include <algorithm>
#include <limits>

namespace tridex::cli {

std::vector<RapidCut> rapid_cuts(const ZMap& feed_map, std::span<const Cutter> cutters,
                                 std::span<const CutMove> rapids, double tolerance) {
  std::vector<RapidCut> found;
  float top = -std::numeric_limits<float>::infinity();
  for (float h : feed_map.heights) top = std::max(top, h);
  for (std::size_t r = 0; r < rapids.size(); ++r) {
    const CutMove& move = rapids[r];
    // Most rapids pass above everything; cut_depth looks at every point under the footprint.
    if (std::min(move.tip.a.z, move.tip.b.z) >= double(top) - tolerance) continue;
    CutDepth deepest = cut_depth(feed_map, cutters[move.cutter], move.tip);
    if (deepest.depth > tolerance) found.push_back(RapidCut{r, deepest.depth});
  }
  return found;
}

}  // namespace tridex::cli
