// tridex — Z-map milling (Step 1 of Inui, Chen and Umezu, CAD&A 19(4) 2022, §3.1): the contract.
//
// Each linear move of the tool tip lowers every grid point q of a Z-map to the lowest point of the
// swept cutter above it,
//     S(q) = min_t f(t),   f(t) = C_z(t) + h(|q − C_xy(t)|),   C(t) = a + t·(b − a), t ∈ [0, 1],
// h the cutter's lower surface (cutter.hpp). mill() does so exactly for a whole program at once;
// cut_depth() measures one move against what a map holds. The milled map does not depend on the
// thread count or on the order of the moves (for one build: the vector width and FMA contraction
// change the last bits).
//
// The machinery lives in detail/, included after the contract:
//   simd_lanes.hpp     kLanes doubles as one value (AVX-512, AVX or SSE2: the build's target);
//   move_geometry.hpp  MoveGeometry: one move's exact minimum of f, per cutter shape;
//   cutter_lanes.hpp   the same kLanes points at a time, per cutter (BallLanes, FlatLanes, ...);
//   miller.hpp         Miller, the tiled milling loop: work blocks on threads, pass 1 per tile row;
//   tile_cuts.hpp      Miller's pass 2: the moves left for a tile, cut row by row.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "tridex/cutter.hpp"
#include "tridex/error.hpp"
#include "tridex/geometry.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

// A straight move of the tool tip in the Z-map's frame, cut with cutters[cutter].
struct CutMove {
  Segment tip;
  std::uint32_t cutter = 0;
};

struct MillOptions {
  unsigned threads = 0;  // 0: every hardware thread
};

// Mills `moves` (tool-tip segments in the Z-map's frame) into `map`: every grid point ends at the
// lowest of its height and the moves' S. Throws tridex::Error, before changing anything, if a
// move is not finite or names a missing cutter.
inline void mill(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves,
                 MillOptions options = {});

// How deep one move would cut into what `map` holds now: the largest height − S(q) over the grid
// points under its footprint (S the move's swept lower surface, zero or less when it cuts
// nothing), and the grid point where that happens. For checks such as "does this rapid meet
// stock?": call it before milling the move. Evaluates every point of the footprint (no skipping):
// meant for the few moves that need checking, not for milling.
struct CutDepth {
  double depth = -std::numeric_limits<double>::infinity();  // mm along the frame's z
  int i = -1, j = -1;                                       // where (−1 when off the grid)
};

// The grid points within `radius` of the move's box across the spindle, clipped to the grid
// (empty when none): the points a cutter of that radius on `tip` can reach.
struct PointRange {
  int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
  bool empty() const { return i0 > i1 || j0 > j1; }
};

inline PointRange footprint_points(const ZMapGrid& g, double radius, const Segment& tip);

inline CutDepth cut_depth(const ZMap& map, const Cutter& cutter, const Segment& tip);

}  // namespace tridex

#include "tridex/detail/cutter_lanes.hpp"
#include "tridex/detail/miller.hpp"
#include "tridex/detail/move_geometry.hpp"
#include "tridex/detail/simd_lanes.hpp"
#include "tridex/detail/tile_cuts.hpp"

namespace tridex {

inline void mill(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves,
                 MillOptions options) {
  if (moves.size() > std::numeric_limits<std::uint32_t>::max())
    detail::fail("mill: too many moves in one call (", moves.size(), ")");
  for (std::size_t k = 0; k < moves.size(); ++k) {
    if (!is_finite(moves[k].tip.a) || !is_finite(moves[k].tip.b))
      detail::fail("mill: move ", k, " has a coordinate that is not finite");
    if (moves[k].cutter >= cutters.size())
      detail::fail("mill: move ", k, " uses cutter ", moves[k].cutter, " but only ", cutters.size(),
                   " are given");
  }
  if (map.heights.size() != map.grid.size())
    detail::fail("mill: Z-map heights do not match its grid");
  detail::Miller(map, cutters, moves).run(options.threads);
}

inline PointRange footprint_points(const ZMapGrid& g, double radius, const Segment& tip) {
  // In double until clipped: a move far off the grid must not overflow an int.
  double i0 = std::ceil((std::min(tip.a.x, tip.b.x) - radius - g.x0) / g.cell);
  double i1 = std::floor((std::max(tip.a.x, tip.b.x) + radius - g.x0) / g.cell);
  double j0 = std::ceil((std::min(tip.a.y, tip.b.y) - radius - g.y0) / g.cell);
  double j1 = std::floor((std::max(tip.a.y, tip.b.y) + radius - g.y0) / g.cell);
  i0 = std::max(i0, 0.0), j0 = std::max(j0, 0.0);
  i1 = std::min(i1, g.nx - 1.0), j1 = std::min(j1, g.ny - 1.0);
  if (i0 > i1 || j0 > j1) return {};
  return {static_cast<int>(i0), static_cast<int>(i1), static_cast<int>(j0), static_cast<int>(j1)};
}

inline CutDepth cut_depth(const ZMap& map, const Cutter& cutter, const Segment& tip) {
  if (!is_finite(tip.a) || !is_finite(tip.b)) detail::fail("cut_depth: move is not finite");
  const ZMapGrid& g = map.grid;
  const PointRange points = footprint_points(g, cutter.radius(), tip);
  CutDepth deepest;
  if (points.empty()) return deepest;
  detail::MoveGeometry m(cutter, tip);
  for (int j = points.j0; j <= points.j1; ++j)
    for (int i = points.i0; i <= points.i1; ++i) {
      if (map.is_empty(i, j)) continue;
      double depth = map.height(i, j) - m.lowest_above(g.x(i), g.y(j));
      if (depth > deepest.depth) deepest = {depth, i, j};
    }
  return deepest;
}

}  // namespace tridex
