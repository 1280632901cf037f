// tridex — Steps 2–3 as one kernel call, the intersection of the stock with the milled Z-maps
// (Inui, Chen and Umezu, CAD&A 19(4) 2022, §3.2): intersect_milled gives W = W0 ∩ M1 ∩ … ∩ MN,
// Mi the polyhedron of direction i's milled Z-map, taken back to world coordinates by its frame.
//
// Mi is never stored as a triple dexel. Each ray starts from the stock's intervals and is cut by
// each Z-map in turn, its grid-tree query clipped to the stock's extent on that ray (an empty ray
// stops early). The clip depends on the stock alone and intersection is exact on float end
// points, so the result does not depend on the order of the maps or the thread count.
#pragma once

#include <span>
#include <vector>

#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/grid_tree.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

// W0 ∩ M1 ∩ … ∩ MN on the stock's lattice. Throws tridex::Error for a malformed stock or a
// Z-map with fewer than 2 × 2 points.
inline TripleDexel intersect_milled(const TripleDexel& stock, std::span<const ZMap> milled,
                                    unsigned threads = 0) {
  validate(stock);
  std::vector<GridTree> trees;
  trees.reserve(milled.size());
  std::vector<Aabb> world_boxes;
  for (const ZMap& map : milled) {
    trees.emplace_back(map);
    const GridTree& tree = trees.back();
    Aabb local{
        Vec3(map.grid.x(0), map.grid.y(0), tree.bottom()),
        Vec3(map.grid.x(map.grid.nx - 1), map.grid.y(map.grid.ny - 1), double(tree.nodes()[0].hi))};
    Aabb world;
    for (const Vec3& c : local.corners()) world.extend(map.grid.frame.to_world(c));
    world_boxes.push_back(world);
  }
  const DexelLattice lattice = stock.lattice();
  TripleDexel result;
  result.origin = stock.origin, result.spacing = stock.spacing, result.n = stock.n;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
    const auto nu = static_cast<std::size_t>(lattice.n[u]);
    const DexelGrid& source = stock.grids[axis];
    result.grids[axis] = detail::build_grid(
        lattice, axis, threads, [&](std::size_t r, std::vector<DexelInterval>& out) {
          std::span<const DexelInterval> initial = source.ray(r);
          if (initial.empty()) return;
          thread_local std::vector<DexelInterval> current, next;
          thread_local std::vector<DexelInterval> cut;
          thread_local std::vector<RaySpan> spans;
          current.assign(initial.begin(), initial.end());
          Vec3 o(0), direction(0);
          o[u] = lattice.origin[u] + lattice.spacing * static_cast<double>(r % nu);
          o[v] = lattice.origin[v] + lattice.spacing * static_cast<double>(r / nu);
          direction[axis] = 1;
          for (std::size_t m = 0; m < trees.size() && !current.empty(); ++m) {
            const Aabb& box = world_boxes[m];
            if (o[u] < box.min[u] || o[u] > box.max[u] || o[v] < box.min[v] || o[v] > box.max[v]) {
              current.clear();  // the ray misses Mi altogether
              break;
            }
            const Frame& frame = milled[m].grid.frame;
            spans.clear();
            trees[m].spans(frame.to_local(o), frame.direction_to_local(direction), spans,
                           double(initial.front().enter) - 1e-3,
                           double(initial.back().exit) + 1e-3);
            cut.clear();
            for (const RaySpan& s : spans) detail::push_span(cut, 0, s.enter, s.exit);
            next.clear();
            detail::intersect_ray(current, cut, next);
            current.swap(next);
          }
          out.insert(out.end(), current.begin(), current.end());
        });
  }
  return result;
}

// The same from a box stock on `lattice`.
inline TripleDexel intersect_milled(const Aabb& stock, const DexelLattice& lattice,
                                    std::span<const ZMap> milled, unsigned threads = 0) {
  return intersect_milled(TripleDexel::box(lattice, stock), milled, threads);
}

// The same from a closed stock mesh (for example an STL) dexelized on `lattice`.
inline TripleDexel intersect_milled(const Mesh& stock, const DexelLattice& lattice,
                                    std::span<const ZMap> milled, unsigned threads = 0) {
  return intersect_milled(dexelize(stock, lattice, {.threads = threads}), milled, threads);
}

}  // namespace tridex
