// tridex — dexelization, the "ray algorithm" (Step 2 of Inui, Chen and Umezu, CAD&A 19(4) 2022,
// §4.2): cast the three families of axis-parallel rays of a triple-dexel lattice through a solid
// and keep the spans inside it.
//
// (a) A Z-map's polyhedron: each lattice ray is taken into the map's frame and intersected with
//     the polyhedron through the grid tree (grid_tree.hpp), without building the mesh. Rays whose
//     (u, v) position misses the polyhedron's world box are skipped.
// (b) Any closed, outward-oriented mesh: each triangle is scan-converted onto the rays of each
//     family. Ray (u, v) positions and the projected vertices are put on one fixed-point grid
//     (2^F subdivisions of the spacing, F chosen so that every edge function fits in 64 bits),
//     where point-in-triangle tests are exact. A ray through a projected vertex or edge is
//     decided by symbolic perturbation (Edelsbrunner & Mücke 1990): the ray is moved to
//     (u + ε, v + ε²), which lies on no edge, so a ray crosses a closed surface an even number of
//     times and never loses or doubles a hit. Rounding the vertices onto the grid moves them by
//     at most 2^−(F+1) spacings, consistently for every triangle that shares them. Spans come
//     from the winding number of the sorted crossings (enter +1, exit −1; inside where > 0), so
//     overlapping closed shells unite.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "tridex/dexel_ops.hpp"
#include "tridex/error.hpp"
#include "tridex/grid_tree.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/mesh.hpp"
#include "tridex/parallel.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

struct DexelizeOptions {
  unsigned threads = 0;  // 0: every hardware thread
};

namespace detail {

// The spans of one ray as float intervals: rounding can make a span empty or make two touch;
// those are dropped or merged so that the ray's list stays sorted, disjoint and non-empty.
inline void push_span(std::vector<DexelInterval>& out, std::size_t ray_start, double enter,
                      double exit) {
  float e0 = static_cast<float>(enter), e1 = static_cast<float>(exit);
  if (!(e0 < e1)) return;
  if (out.size() > ray_start && e0 <= out.back().exit) {
    out.back().exit = std::max(out.back().exit, e1);
    return;
  }
  out.push_back({e0, e1});
}

struct MeshHit {
  std::uint32_t ray;
  float t;
  std::int32_t direction;  // +1 entering, −1 leaving (along +axis)
};

inline int perturbed_sign(std::int64_t value, std::int64_t du, std::int64_t dv) {
  // Sign of E(P + (ε, ε²)) = E(P) − dv·ε + du·ε² for an edge with direction (du, dv).
  if (value != 0) return value > 0 ? 1 : -1;
  if (dv != 0) return dv < 0 ? 1 : -1;
  return du > 0 ? 1 : (du < 0 ? -1 : 0);
}

// Files each list's crossings by chunk of build_grid_chunks (ray / kGridChunk), each list on a
// thread of its own: starts[w][c] is where list w's chunk c begins (its end: starts[w][c + 1]).
inline std::vector<std::vector<std::size_t>> hits_by_chunk(std::vector<std::vector<MeshHit>>& found,
                                                           std::size_t rays, unsigned threads) {
  const std::size_t chunks = (rays + kGridChunk - 1) / kGridChunk;
  std::vector<std::vector<std::size_t>> starts(found.size());
  for_each_chunk(found.size(), threads, [&](std::size_t w) {
    std::vector<MeshHit>& list = found[w];
    std::vector<std::size_t>& start = starts[w];
    start.assign(chunks + 1, 0);
    for (const MeshHit& h : list) ++start[h.ray / kGridChunk + 1];
    for (std::size_t c = 0; c < chunks; ++c) start[c + 1] += start[c];
    std::vector<MeshHit> sorted(list.size());
    std::vector<std::size_t> fill(start.begin(), start.end() - 1);
    for (const MeshHit& h : list) sorted[fill[h.ray / kGridChunk]++] = h;
    list.swap(sorted);
  });
  return starts;
}

// One ray family from its crossings (found in any order, by any number of threads): per ray, a
// sort by position and spans by winding number, so that overlapping shells unite; then
// emit(r, spans, out) appends ray r's intervals to `out` from its spans (a copy, or the spans
// intersected with another grid's ray). The crossings are filed by chunk of rays on the threads
// (hits_by_chunk), then each chunk sorts its own by ray (a counting sort over its rays): a
// counting sort over every ray of the family at once ran on one thread. A ray's spans depend
// only on its crossings, not on their order. `unbalanced(ray, t)` is called (and must throw)
// where a ray's crossings do not balance: an open or inside-out solid.
template <class Unbalanced, class Emit>
DexelGrid grid_from_hits(const DexelLattice& lattice, int axis, unsigned threads,
                         std::vector<std::vector<MeshHit>>& found, Unbalanced&& unbalanced,
                         Emit&& emit) {
  const std::size_t rays = static_cast<std::size_t>(lattice.n[TripleDexel::u_axis(axis)]) *
                           static_cast<std::size_t>(lattice.n[TripleDexel::v_axis(axis)]);
  const std::vector<std::vector<std::size_t>> starts = hits_by_chunk(found, rays, threads);
  DexelGrid grid = build_grid_chunks(
      lattice, axis, threads,
      [&](std::size_t begin, std::size_t end, std::vector<DexelInterval>& out,
          std::uint32_t* counts) {
        const std::size_t c = begin / kGridChunk;
        thread_local std::vector<std::uint32_t> start;
        thread_local std::vector<MeshHit> sorted;
        thread_local std::vector<DexelInterval> spans;
        start.assign(end - begin + 1, 0);
        for (std::size_t w = 0; w < found.size(); ++w)
          for (std::size_t k = starts[w][c]; k < starts[w][c + 1]; ++k)
            ++start[found[w][k].ray - begin + 1];
        for (std::size_t r = 0; r < end - begin; ++r) start[r + 1] += start[r];
        sorted.resize(start[end - begin]);
        for (std::size_t w = 0; w < found.size(); ++w)
          for (std::size_t k = starts[w][c]; k < starts[w][c + 1]; ++k) {
            const MeshHit& h = found[w][k];
            sorted[start[h.ray - begin]++] = h;
          }
        // `start` now holds each ray's end.
        for (std::size_t r = begin; r < end; ++r) {
          auto first = sorted.begin() + (r == begin ? 0 : start[r - begin - 1]);
          auto last = sorted.begin() + start[r - begin];
          if (last - first == 2) {  // the usual case: one span
            if (first[1].t < first[0].t) std::swap(first[0], first[1]);
          } else {
            std::sort(first, last, [](const MeshHit& p, const MeshHit& q) { return p.t < q.t; });
          }
          spans.clear();
          int winding = 0;
          double enter = 0;
          for (auto it = first; it != last;) {
            float t = it->t;
            int before = winding;
            for (; it != last && it->t == t; ++it) winding += it->direction;
            if (winding < 0 || (it == last && winding != 0)) unbalanced(r, t);
            if (before == 0 && winding > 0) enter = t;
            if (before > 0 && winding == 0) push_span(spans, 0, enter, t);
          }
          const std::size_t before = out.size();
          emit(r, std::span<const DexelInterval>(spans), out);
          counts[r - begin] = static_cast<std::uint32_t>(out.size() - before);
        }
      });
  for (std::vector<MeshHit>& list : found) std::vector<MeshHit>().swap(list);
  return grid;
}

// The same, the spans copied.
template <class Unbalanced>
DexelGrid grid_from_hits(const DexelLattice& lattice, int axis, unsigned threads,
                         std::vector<std::vector<MeshHit>>& found, Unbalanced&& unbalanced) {
  return grid_from_hits(
      lattice, axis, threads, found, unbalanced,
      [](std::size_t, std::span<const DexelInterval> spans, std::vector<DexelInterval>& out) {
        out.insert(out.end(), spans.begin(), spans.end());
      });
}

}  // namespace detail

// (b): any closed, outward-oriented mesh. Throws tridex::Error for an invalid lattice, a vertex
// that is not finite, a triangle naming a missing vertex, a mesh reaching too far beyond the
// lattice for exact arithmetic (over ~4 million spacings), or a ray whose crossings do not balance
// (the mesh is open or inside out; the message names the ray).
inline TripleDexel dexelize(const Mesh& mesh, const DexelLattice& lattice,
                            DexelizeOptions options = {}) {
  detail::require_lattice(lattice, "dexelize");
  detail::require_valid_indices(mesh, "dexelize");
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    if (!is_finite(Vec3(mesh.positions[v])))
      detail::fail("dexelize: mesh vertex ", v, " is not finite");
  TripleDexel result = TripleDexel::empty(lattice);
  if (mesh.triangles.empty()) return result;
  const unsigned threads = detail::resolve_threads(options.threads);
  const double s = lattice.spacing;

  for (int axis = 0; axis < 3; ++axis) {
    const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
    const int nu = lattice.n[u], nv = lattice.n[v];
    // Fixed point: lattice units times 2^F, |coordinate| < 2^29 so that differences stay below
    // 2^30 and edge functions below 2^61.
    double reach = std::max(nu, nv) + 2.0;
    for (const glm::vec3& p : mesh.positions)
      reach = std::max({reach, std::abs((p[u] - lattice.origin[u]) / s),
                        std::abs((p[v] - lattice.origin[v]) / s)});
    int bits = 28 - static_cast<int>(std::ceil(std::log2(reach + 1)));
    if (bits < 6)
      detail::fail("dexelize: mesh reaches ", reach,
                   " spacings from the lattice origin, too far for exact ray tests");
    bits = std::min(bits, 24);
    const double scale = std::ldexp(1.0, bits);
    std::vector<std::int64_t> qu(mesh.positions.size()), qv(mesh.positions.size());
    for (std::size_t k = 0; k < mesh.positions.size(); ++k) {
      qu[k] = std::llround((mesh.positions[k][u] - lattice.origin[u]) / s * scale);
      qv[k] = std::llround((mesh.positions[k][v] - lattice.origin[v]) / s * scale);
    }

    // Crossings, gathered per thread over chunks of triangles.
    const std::size_t triangle_count = mesh.triangles.size();
    std::vector<std::vector<detail::MeshHit>> found(threads);
    const std::size_t chunk = 1024;
    auto work = [&](std::size_t chunk_index, unsigned id) {
      std::vector<detail::MeshHit>& hits = found[id];
      {
        const std::size_t c = chunk_index * chunk;
        std::size_t end = std::min(triangle_count, c + chunk);
        for (std::size_t k = c; k < end; ++k) {
          const glm::uvec3& t = mesh.triangles[k];
          std::int64_t au = qu[t.x], av = qv[t.x], bu = qu[t.y], bv = qv[t.y], cu = qu[t.z],
                       cv = qv[t.z];
          std::int64_t area = (bu - au) * (cv - av) - (bv - av) * (cu - au);
          if (area == 0) continue;  // seen edge-on: the perturbed ray misses it
          const int orientation = area > 0 ? 1 : -1;
          std::int64_t lo_u = std::min({au, bu, cu}), hi_u = std::max({au, bu, cu});
          std::int64_t lo_v = std::min({av, bv, cv}), hi_v = std::max({av, bv, cv});
          // Rays with index in [ceil(lo), floor(hi)]; the perturbation only moves rays up/right,
          // so a ray on the box's low side may still hit and one on the high side cannot matter.
          std::int64_t one = std::int64_t{1} << bits;
          auto floor_div = [&](std::int64_t x) {
            return x >= 0 ? x / one : -((-x + one - 1) / one);
          };
          std::int64_t iu0 = std::max<std::int64_t>(0, floor_div(lo_u)),
                       iu1 = std::min<std::int64_t>(nu - 1, floor_div(hi_u));
          std::int64_t iv0 = std::max<std::int64_t>(0, floor_div(lo_v)),
                       iv1 = std::min<std::int64_t>(nv - 1, floor_div(hi_v));
          const double za = mesh.positions[t.x][axis], zb = mesh.positions[t.y][axis],
                       zc = mesh.positions[t.z][axis];
          for (std::int64_t iv = iv0; iv <= iv1; ++iv)
            for (std::int64_t iu = iu0; iu <= iu1; ++iu) {
              std::int64_t pu = iu * one, pv = iv * one;
              std::int64_t wc = (bu - au) * (pv - av) - (bv - av) * (pu - au);  // edge a→b
              if (detail::perturbed_sign(wc, bu - au, bv - av) != orientation) continue;
              std::int64_t wa = (cu - bu) * (pv - bv) - (cv - bv) * (pu - bu);  // edge b→c
              if (detail::perturbed_sign(wa, cu - bu, cv - bv) != orientation) continue;
              std::int64_t wb = (au - cu) * (pv - cv) - (av - cv) * (pu - cu);  // edge c→a
              if (detail::perturbed_sign(wb, au - cu, av - cv) != orientation) continue;
              double z = (double(wa) * za + double(wb) * zb + double(wc) * zc) / double(area);
              // Clamp against rounding: the crossing lies within the triangle's extent.
              z = std::clamp(z, std::min({za, zb, zc}), std::max({za, zb, zc}));
              auto ray = static_cast<std::uint32_t>(iu + static_cast<std::int64_t>(nu) * iv);
              // Normal along +axis (counter-clockwise in (u, v)) means the ray leaves there.
              hits.push_back({ray, static_cast<float>(z), -orientation});
            }
        }
      }
    };
    detail::for_each_chunk_indexed((triangle_count + chunk - 1) / chunk, threads, work);
    result.grids[axis] =
        detail::grid_from_hits(lattice, axis, threads, found, [&](std::size_t r, float t) {
          detail::fail("dexelize: mesh is not closed or not outward-oriented: ray ",
                       r % static_cast<std::size_t>(nu), ", ", r / static_cast<std::size_t>(nu),
                       " along axis ", "xyz"[axis], " has unbalanced crossings at ", t);
        });
  }
  return result;
}

// (a): the polyhedron of a Z-map (polyhedron.hpp), through its grid tree. Throws tridex::Error
// for an invalid lattice or a Z-map with fewer than 2 × 2 points.
inline TripleDexel dexelize(const ZMap& map, const DexelLattice& lattice,
                            DexelizeOptions options = {}) {
  detail::require_lattice(lattice, "dexelize");
  const GridTree tree(map);
  const Frame& frame = map.grid.frame;
  // The polyhedron's world box, for skipping rays that miss it.
  Aabb local{
      Vec3(map.grid.x(0), map.grid.y(0), tree.bottom()),
      Vec3(map.grid.x(map.grid.nx - 1), map.grid.y(map.grid.ny - 1), double(tree.nodes()[0].hi))};
  Aabb world;
  for (const Vec3& c : local.corners()) world.extend(frame.to_world(c));
  TripleDexel result;
  result.origin = lattice.origin, result.spacing = lattice.spacing, result.n = lattice.n;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
    const int nu = lattice.n[u];
    Vec3 direction(0);
    direction[axis] = 1;
    const Vec3 d = frame.direction_to_local(direction);
    result.grids[axis] = detail::build_grid(
        lattice, axis, options.threads, [&](std::size_t r, std::vector<DexelInterval>& out) {
          Vec3 o(0);
          o[u] = lattice.origin[u] +
                 lattice.spacing * static_cast<double>(r % static_cast<std::size_t>(nu));
          o[v] = lattice.origin[v] +
                 lattice.spacing * static_cast<double>(r / static_cast<std::size_t>(nu));
          if (o[u] < world.min[u] || o[u] > world.max[u] || o[v] < world.min[v] ||
              o[v] > world.max[v])
            return;
          thread_local std::vector<RaySpan> spans;
          spans.clear();
          // With o on the plane axis = 0 and a unit direction, t is the world coordinate along
          // axis.
          tree.spans(frame.to_local(o), d, spans, world.min[axis] - 1, world.max[axis] + 1);
          std::size_t ray_start = out.size();
          for (const RaySpan& span : spans)
            detail::push_span(out, ray_start, span.enter, span.exit);
        });
  }
  return result;
}

}  // namespace tridex
