// tridex — Booleans, volume and point membership on triple dexels (Step 3 of Inui, Chen and
// Umezu, CAD&A 19(4) 2022, §3.2: the machined solid is W0 ∩ M1 ∩ … ∩ MN, evaluated ray by ray).
//
// Every operation works on each ray's sorted interval list on its own (a linear merge), so the
// three grids are independent and rays are split into chunks over threads; the result does not
// depend on the thread count. Operations take values and return new ones; both operands must
// share one lattice.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <limits>
#include <vector>

#include "tridex/dexel.hpp"
#include "tridex/error.hpp"
#include "tridex/parallel.hpp"

namespace tridex {

namespace detail {

// The rays of one chunk of build_grid_chunks: every grid is built this many rays at a time.
inline constexpr std::size_t kGridChunk = 4096;

// Builds grid `axis` of a triple dexel on `lattice` chunk by chunk: per_chunk(begin, end, out,
// counts) appends the intervals of rays [begin, end) to `out` in ray order and sets counts[r −
// begin] to ray r's number of intervals. Chunks (kGridChunk rays) run on `threads` threads and
// are concatenated in ray order, on the threads too, so the result is independent of the thread
// count.
template <class PerChunk>
DexelGrid build_grid_chunks(const DexelLattice& lattice, int axis, unsigned threads,
                            PerChunk&& per_chunk) {
  DexelGrid g;
  g.axis = axis;
  g.nu = lattice.n[TripleDexel::u_axis(axis)];
  g.nv = lattice.n[TripleDexel::v_axis(axis)];
  const std::size_t rays = g.ray_count();
  g.offsets.resize(rays + 1);
  g.offsets[0] = 0;
  const std::size_t chunks = (rays + kGridChunk - 1) / kGridChunk;
  std::vector<std::vector<DexelInterval>> parts(chunks);
  for_each_chunk(chunks, threads, [&](std::size_t c) {
    const std::size_t begin = c * kGridChunk, end = std::min(rays, begin + kGridChunk);
    per_chunk(begin, end, parts[c], g.offsets.data() + begin + 1);  // counts, summed below
  });
  // Where each chunk's intervals go: a serial pass over the chunks only, then the rays' offsets
  // and the copies on the threads (they were a serial pass over every ray and interval).
  std::vector<std::size_t> base(chunks + 1, 0);
  for (std::size_t c = 0; c < chunks; ++c) base[c + 1] = base[c] + parts[c].size();
  const std::size_t total = base[chunks];
  if (total > std::numeric_limits<std::uint32_t>::max())
    fail("triple dexel: grid ", axis, " would hold ", total,
         " intervals, over the 32-bit offset limit");
  g.intervals.resize(total);
  for_each_chunk(chunks, threads, [&](std::size_t c) {
    const std::size_t begin = c * kGridChunk, end = std::min(rays, begin + kGridChunk);
    auto at = static_cast<std::uint32_t>(base[c]);
    for (std::size_t r = begin; r < end; ++r) g.offsets[r + 1] = at += g.offsets[r + 1];
    std::vector<DexelInterval>& p = parts[c];
    if (!p.empty())
      std::memcpy(g.intervals.data() + base[c], p.data(), p.size() * sizeof(DexelInterval));
    std::vector<DexelInterval>().swap(p);
  });
  return g;
}

// Builds grid `axis` of a triple dexel on `lattice` by calling per_ray(r, out) for every ray r
// in order within a chunk; per_ray appends ray r's intervals to `out` (build_grid_chunks).
template <class PerRay>
DexelGrid build_grid(const DexelLattice& lattice, int axis, unsigned threads, PerRay&& per_ray) {
  return build_grid_chunks(lattice, axis, threads,
                           [&](std::size_t begin, std::size_t end, std::vector<DexelInterval>& out,
                               std::uint32_t* counts) {
                             for (std::size_t r = begin; r < end; ++r) {
                               const std::size_t before = out.size();
                               per_ray(r, out);
                               counts[r - begin] = static_cast<std::uint32_t>(out.size() - before);
                             }
                           });
}

inline void require_same_lattice(const TripleDexel& a, const TripleDexel& b, const char* who) {
  if (a.lattice() == b.lattice()) return;
  fail(who, ": operands are on different lattices (origin (", a.origin.x, ", ", a.origin.y, ", ",
       a.origin.z, ") spacing ", a.spacing, " nodes ", a.n.x, "x", a.n.y, "x", a.n.z,
       " vs origin (", b.origin.x, ", ", b.origin.y, ", ", b.origin.z, ") spacing ", b.spacing,
       " nodes ", b.n.x, "x", b.n.y, "x", b.n.z, ")");
}

inline void intersect_ray(std::span<const DexelInterval> a, std::span<const DexelInterval> b,
                          std::vector<DexelInterval>& out) {
  std::size_t i = 0, j = 0;
  while (i < a.size() && j < b.size()) {
    float lo = std::max(a[i].enter, b[j].enter), hi = std::min(a[i].exit, b[j].exit);
    if (lo < hi) out.push_back({lo, hi});
    if (a[i].exit < b[j].exit)
      ++i;
    else
      ++j;
  }
}

inline void unite_ray(std::span<const DexelInterval> a, std::span<const DexelInterval> b,
                      std::vector<DexelInterval>& out) {
  std::size_t i = 0, j = 0;
  bool open = false;
  DexelInterval current{};
  while (i < a.size() || j < b.size()) {
    const DexelInterval& next =
        (j == b.size() || (i < a.size() && a[i].enter <= b[j].enter)) ? a[i++] : b[j++];
    if (open && next.enter <= current.exit) {
      current.exit = std::max(current.exit, next.exit);  // touching spans merge: no zero gaps
    } else {
      if (open) out.push_back(current);
      current = next, open = true;
    }
  }
  if (open) out.push_back(current);
}

inline void subtract_ray(std::span<const DexelInterval> a, std::span<const DexelInterval> b,
                         std::vector<DexelInterval>& out) {
  std::size_t j = 0;
  for (const DexelInterval& span : a) {
    float lo = span.enter;
    while (j < b.size() && b[j].exit <= lo) ++j;
    std::size_t k = j;  // b[k] may also cut the next span of a: do not consume it here
    for (; k < b.size() && b[k].enter < span.exit; ++k) {
      if (b[k].enter > lo) out.push_back({lo, b[k].enter});
      lo = std::max(lo, b[k].exit);
      if (lo >= span.exit) break;
    }
    if (lo < span.exit) out.push_back({lo, span.exit});
  }
}

template <class RayOp>
TripleDexel combine(const TripleDexel& a, const TripleDexel& b, unsigned threads, RayOp op) {
  TripleDexel out;
  out.origin = a.origin, out.spacing = a.spacing, out.n = a.n;
  for (int axis = 0; axis < 3; ++axis) {
    const DexelGrid &ga = a.grids[axis], &gb = b.grids[axis];
    out.grids[axis] = build_grid(
        a.lattice(), axis, threads,
        [&](std::size_t r, std::vector<DexelInterval>& o) { op(ga.ray(r), gb.ray(r), o); });
  }
  return out;
}

}  // namespace detail

// Throws tridex::Error unless `d` is well formed: a valid lattice, three grids of the right
// sizes, offsets starting at 0, non-decreasing and ending at the interval count, and every ray's
// intervals finite, non-empty, sorted and disjoint.
inline void validate(const TripleDexel& d) {
  detail::require_lattice(d.lattice(), "triple dexel");
  for (int a = 0; a < 3; ++a) {
    const DexelGrid& g = d.grids[a];
    if (g.axis != a || g.nu != d.n[TripleDexel::u_axis(a)] || g.nv != d.n[TripleDexel::v_axis(a)])
      detail::fail("triple dexel: grid ", a, " has axis ", g.axis, " and ", g.nu, " x ", g.nv,
                   " rays, which does not match the lattice");
    if (g.offsets.size() != g.ray_count() + 1 || g.offsets.front() != 0 ||
        g.offsets.back() != g.intervals.size())
      detail::fail("triple dexel: grid ", a, " offsets do not match its ", g.ray_count(),
                   " rays and ", g.intervals.size(), " intervals");
    for (std::size_t r = 0; r < g.ray_count(); ++r) {
      if (g.offsets[r] > g.offsets[r + 1])
        detail::fail("triple dexel: grid ", a, " offsets decrease at ray ", r);
      float previous = -std::numeric_limits<float>::infinity();
      for (const DexelInterval& s : g.ray(r)) {
        if (!std::isfinite(s.enter) || !std::isfinite(s.exit) || !(s.enter < s.exit) ||
            !(s.enter > previous))
          detail::fail("triple dexel: grid ", a, " ray ", r,
                       " has an empty, unsorted or overlapping interval [", s.enter, ", ", s.exit,
                       "]");
        previous = s.exit;
      }
    }
  }
}

// A ∩ B, ray by ray.
inline TripleDexel intersect(const TripleDexel& a, const TripleDexel& b, unsigned threads = 0) {
  detail::require_same_lattice(a, b, "intersect");
  return detail::combine(a, b, threads, detail::intersect_ray);
}

// A ∪ B, ray by ray; spans that touch are merged.
inline TripleDexel unite(const TripleDexel& a, const TripleDexel& b, unsigned threads = 0) {
  detail::require_same_lattice(a, b, "unite");
  return detail::combine(a, b, threads, detail::unite_ray);
}

// A − B, ray by ray.
inline TripleDexel subtract(const TripleDexel& a, const TripleDexel& b, unsigned threads = 0) {
  detail::require_same_lattice(a, b, "subtract");
  return detail::combine(a, b, threads, detail::subtract_ray);
}

// The dexel length integrated over each grid's rays times spacing² (each ray stands for a
// spacing × spacing column), averaged over the three grids. For a solid well inside the lattice
// each grid's estimate is a midpoint-rule integral whose error is bounded by the surface area
// times the spacing; the mean cancels part of the facet-orientation bias.
inline double volume(const TripleDexel& d) {
  double sum = 0;
  for (const DexelGrid& g : d.grids) {
    double length = 0;
    for (const DexelInterval& s : g.intervals) length += double(s.exit) - double(s.enter);
    sum += length;
  }
  return sum * d.spacing * d.spacing / 3.0;
}

// The total number of intervals over the three grids (a memory measure).
inline std::size_t interval_count(const TripleDexel& d) {
  return d.grids[0].intervals.size() + d.grids[1].intervals.size() + d.grids[2].intervals.size();
}

// Point membership: each grid votes with its ray nearest to p (inside when p's coordinate along
// the ray lies in one of its intervals, half-open [enter, exit)); p is inside when at least two
// grids say so. Exact for points on a ray of each family; elsewhere the answer may be wrong only
// within about one spacing of the surface. Points beyond the lattice's outer rays are outside.
inline bool contains(const TripleDexel& d, const Vec3& p) {
  if (!is_finite(p)) detail::fail("contains: point is not finite");
  int votes = 0;
  for (int a = 0; a < 3; ++a) {
    int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
    double fu = std::round((p[u] - d.origin[u]) / d.spacing),
           fv = std::round((p[v] - d.origin[v]) / d.spacing);
    if (fu < 0 || fv < 0 || fu >= d.n[u] || fv >= d.n[v]) continue;
    std::span<const DexelInterval> ray = d.grids[a].ray(static_cast<int>(fu), static_cast<int>(fv));
    auto it = std::upper_bound(ray.begin(), ray.end(), p[a],
                               [](double x, const DexelInterval& s) { return x < double(s.exit); });
    if (it != ray.end() && double(it->enter) <= p[a]) ++votes;
  }
  return votes >= 2;
}

}  // namespace tridex
