// Shared fixtures of the backend tests: random milled Z-maps in random frames, and a per-ray
// comparison of triple dexels.
#pragma once

#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "tridex/dexel.hpp"
#include "tridex/mill.hpp"
#include "tridex/zmap.hpp"
#include "tridex/fine_cells.hpp"

namespace backend_tests {

using namespace tridex;

inline Frame random_frame(std::mt19937& rng, bool tilted) {
  std::uniform_real_distribution<double> angle(-70, 70), spin(-180, 180);
  if (!tilted) return Frame{};
  return Frame::from_rotation(
      rotation_z(spin(rng)) * rotation_x(angle(rng)) * rotation_z(spin(rng)), Vec3(0.3, -0.2, 0.1));
}

// A box stock's Z-map in `frame`, milled by random ball, flat and bull-nose moves, some of them
// through the stock (so that some points become empty).
// With `fine`, the steep cells are then refined from the same moves (fine_cells.hpp).
inline ZMap random_milled_map(std::mt19937& rng, const Aabb& stock, const Frame& frame, double cell,
                              int moves_count = 12, bool fine = false) {
  ZMap map = ZMap::from_box(frame, stock, cell);
  std::uniform_real_distribution<double> unit(0, 1);
  Aabb local = local_bounds(frame, stock);
  std::vector<Cutter> cutters{Cutter::ball(0.7), Cutter::flat(0.5), Cutter::bull_nose(0.6, 0.2)};
  std::vector<CutMove> moves;
  for (int k = 0; k < moves_count; ++k) {
    double depth = k % 5 == 4 ? 1.3 : 0.8;  // every fifth move may cut through
    auto point = [&] {
      return Vec3(local.min.x + unit(rng) * (local.max.x - local.min.x),
                  local.min.y + unit(rng) * (local.max.y - local.min.y),
                  local.max.z - 0.1 - depth * (local.max.z - local.min.z) * unit(rng));
    };
    moves.push_back({Segment{point(), point()}, static_cast<std::uint32_t>(k % 3)});
  }
  mill(map, cutters, moves, {.threads = 1});
  if (fine) refine_steep_cells(map, cutters, moves, {.threads = 1});
  return map;
}

struct RayComparison {
  std::size_t rays = 0, mismatches = 0, intervals = 0;
  double worst = 0;  // largest end-point difference among rays with equal counts
};

// Per ray: the same interval count and end points within `epsilon`.
inline RayComparison compare_rays(const TripleDexel& a, const TripleDexel& b, double epsilon) {
  RayComparison c;
  REQUIRE(a.lattice() == b.lattice());
  for (int axis = 0; axis < 3; ++axis)
    for (std::size_t r = 0; r < a.grids[axis].ray_count(); ++r) {
      auto x = a.grids[axis].ray(r), y = b.grids[axis].ray(r);
      ++c.rays;
      c.intervals += x.size();
      bool same = x.size() == y.size();
      for (std::size_t k = 0; same && k < x.size(); ++k) {
        double d = std::max(std::abs(double(x[k].enter) - y[k].enter),
                            std::abs(double(x[k].exit) - y[k].exit));
        c.worst = std::max(c.worst, d);
        same = d <= epsilon;
      }
      c.mismatches += same ? 0 : 1;
      if (!same && std::getenv("TRIDEX_DEBUG_RAYS")) {
        std::fprintf(stderr, "axis %d ray %zu:", axis, r);
        for (auto s : x) std::fprintf(stderr, " [%.7g %.7g]", s.enter, s.exit);
        std::fprintf(stderr, " vs");
        for (auto s : y) std::fprintf(stderr, " [%.7g %.7g]", s.enter, s.exit);
        std::fprintf(stderr, "\n");
      }
    }
  return c;
}

}  // namespace backend_tests
