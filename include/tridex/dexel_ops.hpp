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

// Builds grid `axis` of a triple dexel on `lattice` by calling per_ray(r, out) for every ray r
// in order within a chunk; per_ray appends ray r's intervals to `out`. Chunks run on `threads`
// threads and are concatenated in ray order, so the result is independent of the thread count.
template <class PerRay>
DexelGrid build_grid(const DexelLattice& lattice, int axis, unsigned threads, PerRay&& per_ray) {
  DexelGrid g;
  g.axis = axis;
  g.nu = lattice.n[TripleDexel::u_axis(axis)];
  g.nv = lattice.n[TripleDexel::v_axis(axis)];
  const std::size_t rays = g.ray_count();
  g.offsets.assign(rays + 1, 0);
  const std::size_t chunk = 4096;
  const std::size_t chunks = (rays + chunk - 1) / chunk;
  std::vector<std::vector<DexelInterval>> parts(chunks);
  for_each_chunk(chunks, threads, [&](std::size_t c) {
    std::vector<DexelInterval>& out = parts[c];
    std::size_t end = std::min(rays, (c + 1) * chunk);
    for (std::size_t r = c * chunk; r < end; ++r) {
      std::size_t before = out.size();
      per_ray(r, out);
      g.offsets[r + 1] = static_cast<std::uint32_t>(out.size() - before);  // count, summed below
    }
  });
  std::size_t total = 0;
  for (const auto& p : parts) total += p.size();
  if (total > std::numeric_limits<std::uint32_t>::max())
    fail("triple dexel: grid ", axis, " would hold ", total,
         " intervals, over the 32-bit offset limit");
  for (std::size_t r = 0; r < rays; ++r) g.offsets[r + 1] += g.offsets[r];
  g.intervals.resize(total);
  std::size_t at = 0;
  for (auto& p : parts) {
    if (!p.empty())
      std::memcpy(g.intervals.data() + at, p.data(), p.size() * sizeof(DexelInterval));
    at += p.size();
    std::vector<DexelInterval>().swap(p);
  }
  return g;
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
