// tridex — machinery of sweep_remove (tridex/sweep.hpp): which steps a dexel ray meets, grouped.
//
// A finishing program's segments are short (0.05–0.2 mm) against the cutter (6 mm), so a ray
// lies in the boxes of thousands of steps, most of which no longer reach the material left on it
// when their turn comes (the ray was cut lower by a nearer pass). Consecutive steps of one cutter
// part are therefore grouped (up to kSweepGroup or kSweepGroupPieces, while their boxes stay within
// a few spacings of one step's) under a bound: the union of their boxes, and for ball tips the
// capsule around the chord of their centres grown by the members' largest distance from it. A ray
// skips a whole group when the bound cannot meet its material; otherwise its members are cut as
// before. Removal commutes (the set difference does not depend on the order), so results are
// identical.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "tridex/detail/sweep_interval.hpp"
#include "tridex/dexel.hpp"
#include "tridex/geometry.hpp"

namespace tridex {

struct SweepPartShape;

namespace detail {

// A step as sweep_ray cuts it: its box, its part, and for a ball tip (one ball piece) the capsule
// of the ball's centre, computed once per step rather than once per ray.
struct SweepStepCut {
  Aabb box;
  const SweepPartShape* part = nullptr;
  bool capsule = false;
  Vec3 c0{0.0}, c1{0.0};
  double radius = 0;
};

// The first and last ray index along lattice axis `a` (n rays) within [box.min[a], box.max[a]].
inline std::pair<int, int> sweep_index_range(const TripleDexel& d, const Aabb& box, int a, int n) {
  const double first = std::ceil((box.min[a] - d.origin[a]) / d.spacing);
  const double last = std::floor((box.max[a] - d.origin[a]) / d.spacing);
  return {static_cast<int>(std::max(first, 0.0)), static_cast<int>(std::min(last, n - 1.0))};
}

// The groups (by index) of one grid listed by row (v index) and block of kBlock rays along it.
struct SweepRows {
  static constexpr int kBlock = 32;
  int blocks = 0;
  std::vector<std::uint32_t> offsets, steps;
  std::span<const std::uint32_t> at(int iu, int iv) const {
    const std::size_t k = static_cast<std::size_t>(iv) * static_cast<std::size_t>(blocks) +
                          static_cast<std::size_t>(iu / kBlock);
    return {steps.data() + offsets[k], steps.data() + offsets[k + 1]};
  }
};

// Lists items 0 … count − 1 by the rows and blocks of grid `axis` that box_of(item) covers.
template <class BoxOf>
SweepRows sweep_rows(const TripleDexel& d, int axis, std::size_t count, BoxOf&& box_of) {
  const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
  const DexelGrid& g = d.grids[static_cast<std::size_t>(axis)];
  SweepRows rows;
  rows.blocks = (g.nu + SweepRows::kBlock - 1) / SweepRows::kBlock;
  rows.offsets.assign(static_cast<std::size_t>(g.nv) * static_cast<std::size_t>(rows.blocks) + 1,
                      0);
  for (int pass = 0; pass < 2; ++pass) {
    std::vector<std::uint32_t> fill(rows.offsets.begin(), rows.offsets.end() - 1);
    for (std::size_t s = 0; s < count; ++s) {
      const Aabb& box = box_of(s);
      const auto [u0, u1] = sweep_index_range(d, box, u, g.nu);
      const auto [v0, v1] = sweep_index_range(d, box, v, g.nv);
      if (u0 > u1) continue;
      for (int iv = v0; iv <= v1; ++iv)
        for (int b = u0 / SweepRows::kBlock; b <= u1 / SweepRows::kBlock; ++b) {
          const std::size_t k =
              static_cast<std::size_t>(iv) * static_cast<std::size_t>(rows.blocks) +
              static_cast<std::size_t>(b);
          if (pass == 0)
            ++rows.offsets[k + 1];
          else
            rows.steps[fill[k]++] = static_cast<std::uint32_t>(s);
        }
    }
    if (pass == 0) {
      for (std::size_t k = 1; k < rows.offsets.size(); ++k) rows.offsets[k] += rows.offsets[k - 1];
      rows.steps.resize(rows.offsets.back());
    }
  }
  return rows;
}

// At most this many steps a group: kSweepGroup, or kSweepGroupPieces for a part of several pieces
// (a bull nose's chords), whose members cost more each, so that a smaller group skips more of
// them (bull nose at 2·10^4 segments: 8 % less time; a ball's capsules are cheaper at 16).
inline constexpr std::uint32_t kSweepGroup = 16, kSweepGroupPieces = 8;

// How a group bounds its members' sweeps: by the union of their boxes alone, by a capsule
// (ball tips: the chord of their centres, c0–c1, and `radius`), or by the pieces of their part,
// each grown by `tip` + its reach·`turn` (sweep.hpp, sweep_group_bound), with unit axis `axis`
// moved from tip c0 to tip c1.
enum class SweepBound : std::uint8_t { box, capsule, pieces };

// Steps cut together: members[first, first + count) of SweepGroups, in program order.
struct SweepGroup {
  Aabb box;  // the union of the members' boxes
  std::uint32_t first = 0, count = 0;
  SweepBound bound = SweepBound::box;
  Vec3 c0{0.0}, c1{0.0}, axis{0.0, 0.0, 1.0};
  double radius = 0;
  const SweepPartShape* part = nullptr;
  double tip = 0, turn = 0;
};

struct SweepGroups {
  std::vector<SweepGroup> groups;
  std::vector<std::uint32_t> members;
};

// The distance from x to the segment a–b.
inline double distance_to_segment(const Vec3& x, const Vec3& a, const Vec3& b) {
  const Vec3 d = b - a;
  const double dd = glm::dot(d, d);
  const double t = dd > 0 ? std::clamp(glm::dot(x - a, d) / dd, 0.0, 1.0) : 0.0;
  return glm::length(x - (a + t * d));
}

// Groups consecutive steps of one key (key_of(s): cutter and part), at most limit(key), while
// the union of their boxes is no wider on any side than `grow` past their widest member's. With
// `group` false each step is a group of its own, in order (a searched part's interval depends
// on the material left: its steps keep their order). bound(members, group) sets the bound of a
// group of more than one step.
template <class KeyOf, class Limit, class Bound>
SweepGroups sweep_groups(std::span<const SweepStepCut> cuts, std::size_t keys, KeyOf&& key_of,
                         Limit&& limit, double grow, bool group, Bound&& bound) {
  SweepGroups out;
  out.members.reserve(cuts.size());
  struct Open {
    std::vector<std::uint32_t> members;
    Aabb box;
    double widest = 0;
  };
  std::vector<Open> open(keys);
  auto close = [&](Open& o) {
    if (o.members.empty()) return;
    SweepGroup g;
    g.box = o.box;
    g.first = static_cast<std::uint32_t>(out.members.size());
    g.count = static_cast<std::uint32_t>(o.members.size());
    out.members.insert(out.members.end(), o.members.begin(), o.members.end());
    if (o.members.size() > 1) bound(std::span<const std::uint32_t>(o.members), g);
    out.groups.push_back(g);
    o.members.clear();
    o.box = Aabb{};
    o.widest = 0;
  };
  auto widest = [](const Aabb& b) {
    const Vec3 e = b.max - b.min;
    return std::max({e.x, e.y, e.z});
  };
  for (std::size_t s = 0; s < cuts.size(); ++s) {
    Open& o = open[key_of(s)];
    Aabb joined = o.box;
    joined.extend(cuts[s].box.min);
    joined.extend(cuts[s].box.max);
    const double w = std::max(o.widest, widest(cuts[s].box));
    if (!group || o.members.size() >= limit(key_of(s)) || widest(joined) > w + grow) {
      close(o);
      joined = cuts[s].box;
    }
    o.members.push_back(static_cast<std::uint32_t>(s));
    o.box = joined;
    o.widest = std::max(o.widest, widest(cuts[s].box));
  }
  for (Open& o : open) close(o);
  return out;
}

// Whether `bound` (an interval on a ray), grown for float rounding, meets the spans `current`.
inline bool sweep_bound_meets(const std::pair<double, double>& bound,
                              std::span<const DexelInterval> current) {
  const double margin = 1e-5 * (1 + std::abs(bound.first) + std::abs(bound.second));
  const double a = bound.first - margin, b = bound.second + margin;
  for (const DexelInterval& span : current)
    if (span.exit > a && span.enter < b) return true;
  return false;
}

// Whether group `g` may remove anything from the spans `current` of the ray through `point`
// along `axis`: false only if none of its members can (their boxes hold no material, or their
// sweeps' intervals, within the bound's grown for float rounding, meet none). pieces_hull(lo, hi):
// the interval of a SweepBound::pieces bound, or part of it that meets `current`, where it may
// meet material within [lo, hi].
template <class PiecesHull>
bool sweep_group_may_cut(const SweepGroup& g, std::span<const DexelInterval> current,
                         const Vec3& point, int axis, PiecesHull&& pieces_hull) {
  bool boxed = false;  // as sweep_ray's test of a step's box, cheaper than the bounds below
  for (const DexelInterval& span : current)
    boxed = boxed || (span.exit >= g.box.min[axis] && span.enter <= g.box.max[axis]);
  if (!boxed || g.bound == SweepBound::box) return boxed;
  if (g.bound == SweepBound::capsule) {
    const auto bound = capsule_interval(g.c0, g.c1, g.radius, point, axis);
    return bound && sweep_bound_meets(*bound, current);
  }
  double lo = g.box.max[axis], hi = g.box.min[axis];  // the material within the box
  for (const DexelInterval& span : current)
    if (span.exit >= g.box.min[axis] && span.enter <= g.box.max[axis]) {
      lo = std::min(lo, std::max<double>(span.enter, g.box.min[axis]));
      hi = std::max(hi, std::min<double>(span.exit, g.box.max[axis]));
    }
  const auto bound = pieces_hull(lo, hi);
  return bound && sweep_bound_meets(*bound, current);
}

// Removes [cut.enter, cut.exit] from the sorted disjoint spans of `spans` in place, as
// subtract_ray(spans, {cut}) would (a span touching the cut only at an end is kept whole).
inline void subtract_one(std::vector<DexelInterval>& spans, DexelInterval cut) {
  const std::size_t n = spans.size();
  std::size_t i = 0;
  while (i < n && spans[i].exit <= cut.enter) ++i;
  std::size_t j = i;
  while (j < n && spans[j].enter < cut.exit) ++j;
  if (j == i) return;  // the spans i… lie above the cut
  DexelInterval pieces[2];
  std::size_t k = 0;
  if (cut.enter > spans[i].enter) pieces[k++] = {spans[i].enter, cut.enter};
  const float lo = std::max(spans[j - 1].enter, cut.exit);
  if (lo < spans[j - 1].exit) pieces[k++] = {lo, spans[j - 1].exit};
  const std::size_t old = j - i;
  if (k > old) {
    spans.insert(spans.begin() + static_cast<std::ptrdiff_t>(j), pieces[k - 1]);
    spans[i] = pieces[0];
    return;
  }
  for (std::size_t q = 0; q < k; ++q) spans[i + q] = pieces[q];
  spans.erase(spans.begin() + static_cast<std::ptrdiff_t>(i + k),
              spans.begin() + static_cast<std::ptrdiff_t>(j));
}

}  // namespace detail
}  // namespace tridex
