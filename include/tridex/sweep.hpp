// tridex — simultaneous 5-axis moves on the triple dexel: the material a cutter removes while
// its axis turns, cut from the dexel rays directly (docs/design.md, "Simultaneous moves").
//
// A Z-map (zmap.hpp) needs one spindle direction; a move whose tool axis turns has none. Its
// removal is computed ray by ray on the triple dexel instead, after the 3+2 maps are intersected
// (removal commutes with intersection: the order does not change the result).
//
// The exact primitive is a cutter with a FIXED axis translated along a segment: the swept solid
// is convex (a Minkowski sum of convex sets), so each dexel ray meets it in one interval. With the
// signed distance D to the cutter (convex, detail/sweep_distance.hpp), a ray point x(u) lies in
// the sweep iff F(u) = min over s in [0, 1] of D(x(u) − s·(to − from)) ≤ 0, and F is convex in u:
// golden-section search finds a point where it is ≤ 0 (or its minimum) and bisection its zeros, to
// `precision`, with no sampling that could miss a contact. Ball, flat, bull nose, cone, chamfer and
// every convex profile go through this one path (the distance to lines and arcs of the profile is
// closed form).
//
// A turning tool is split into sub-steps, each swept with the tool axis held at its middle pose
// and the tip moved straight between the sub-step's end poses. plan_sweep() bounds how far any
// point of the true moving cutter strays from that approximation (the band e): the true swept
// volume lies between the approximation shrunk by e and grown by e. For a sub-step of length Δ
// (in the move's parameter s) sampled at K + 1 points, with the tip speed V and the axis's turn
// rate Ω (per unit s) bounded by the caller,
//   e ≤ max_j |tip(s_j) − chord(s_j)| + V·Δ/K   (0 when the tip runs straight, as under TCP)
//     + reach · (max_j ∠(axis(s_j), axis_mid) + Ω·Δ/(2K)),
// the sampled deviations being Lipschitz with constants 2V and Ω, and a point at distance ≤ reach
// from the tip moving by at most reach·angle when the axis turns by that angle. Sub-steps double
// until e ≤ the tolerance (or a cap, and the band achieved is reported).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/detail/sweep_distance.hpp"
#include "tridex/dexel.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/geometry.hpp"

namespace tridex {

// A cutter cut at `height` above its tip (a sweep needs a finite solid; cutter.hpp's cutters
// continue upward without end, which only a fixed direction allows).
struct SweepCutter {
  Cutter cutter;
  double height = 0;  // > cutter.profile_height()
  // The farthest cutter point from the tip.
  double reach() const { return std::hypot(cutter.radius(), height); }
  double distance(const Vec3& tip, const Vec3& axis, const Vec3& x) const {
    return detail::cutter_distance(cutter, height, tip, axis, x);
  }
};

struct ToolPose {
  Vec3 tip{0.0};
  Vec3 axis{0.0, 0.0, 1.0};  // unit
};

// One swept piece: cutter `cutter` (an index into the caller's cutters) with unit axis `axis`
// translated from tip `from` to tip `to`.
struct SweepStep {
  Vec3 from{0.0}, to{0.0};
  Vec3 axis{0.0, 0.0, 1.0};
  std::uint32_t cutter = 0;
};

// Bounds on a move's pose as a function of its parameter s ∈ [0, 1] (per unit s).
struct PoseBounds {
  double tip_speed = 0;       // |d tip / ds|
  double turn_rate = 0;       // |d axis / ds| (radians)
  bool tip_straight = false;  // the tip runs straight, linearly in s (TCP)
};

struct SweepPlan {
  std::vector<SweepStep> steps;
  double band = 0;  // the largest e of its sub-steps, mm
};

inline constexpr int kMaxSubSteps = 1 << 14;       // per move
inline constexpr long kMaxPoseSamples = 1L << 22;  // per move

// The sub-steps of one move whose pose `pose_at(s)` (a ToolPose) turns, with e ≤ `tolerance` or,
// at max_steps, the band achieved. The move is sampled at S + 1 equally spaced poses, S a power
// of two chosen so that the Lipschitz margins (V/S and reach·Ω/(2S)) take at most a quarter of
// the tolerance; then sub-steps double (K = S/N samples each) until the sampled deviations fit.
template <class PoseAt>
SweepPlan plan_sweep(PoseAt&& pose_at, const PoseBounds& bounds, double reach, double tolerance,
                     std::uint32_t cutter = 0, int max_steps = kMaxSubSteps) {
  detail::require_positive(tolerance, "sweep tolerance");
  const double margin_rate =
      (bounds.tip_straight ? 0.0 : bounds.tip_speed) + reach * bounds.turn_rate / 2;
  long samples = 64;
  while (samples < kMaxPoseSamples && margin_rate / static_cast<double>(samples) > tolerance / 4)
    samples *= 2;
  std::vector<ToolPose> poses;
  auto sample = [&] {
    poses.resize(static_cast<std::size_t>(samples) + 1);
    for (std::size_t j = 0; j < poses.size(); ++j)
      poses[j] = pose_at(static_cast<double>(j) / static_cast<double>(samples));
  };
  sample();
  for (long n = 1;; n *= 2) {
    if (2 * n > samples && samples < kMaxPoseSamples) {
      samples *= 2;
      sample();
    }
    const long k = samples / n;
    SweepPlan plan;
    const double margin = margin_rate / static_cast<double>(samples);
    for (long i = 0; i < n; ++i) {
      const ToolPose* p = poses.data() + i * k;  // p[0] … p[k]
      const Vec3 mid = p[k / 2].axis;
      double tip = 0, angle = 0;
      for (long j = 0; j <= k; ++j) {
        const double t = static_cast<double>(j) / static_cast<double>(k);
        if (!bounds.tip_straight)
          tip = std::max(tip, glm::length(p[j].tip - (p[0].tip + t * (p[k].tip - p[0].tip))));
        angle = std::max(angle, std::acos(std::clamp(glm::dot(p[j].axis, mid), -1.0, 1.0)));
      }
      plan.band = std::max(plan.band, tip + reach * angle + margin);
      plan.steps.push_back({p[0].tip, p[k].tip, mid, cutter});
    }
    if (plan.band <= tolerance || n >= max_steps || k < 2) return plan;
  }
}

// The box around cutter `c` in one sub-step (both end poses; the sweep is their convex hull).
inline Aabb sweep_step_bounds(const SweepCutter& c, const SweepStep& step) {
  Aabb box;
  Vec3 lateral;
  for (int i = 0; i < 3; ++i)
    lateral[i] = c.cutter.radius() * std::sqrt(std::max(0.0, 1.0 - step.axis[i] * step.axis[i]));
  for (const Vec3& tip : {step.from, step.to})
    for (const Vec3& end : {tip, tip + c.height * step.axis}) {
      box.extend(end - lateral);
      box.extend(end + lateral);
    }
  return box;
}

// The interval [enter, exit] of the ray x(u) = point + u·e_axis, u ∈ [lo, hi], inside the
// sweep of `step`, to within `precision` (mm, on the side of more removal); nullopt if none.
inline std::optional<std::pair<double, double>> ray_sweep_interval(const SweepCutter& c,
                                                                   const SweepStep& step,
                                                                   const Vec3& point, int axis,
                                                                   double lo, double hi,
                                                                   double precision) {
  const Vec3 travel = step.to - step.from;
  const double length = glm::length(travel);
  auto at = [&](double u) {
    Vec3 x = point;
    x[axis] = u;
    return x;
  };
  // F(u) = min over s of the distance, exact where positive (the outer search compares values);
  // the distance is 1-Lipschitz in u and `length`-Lipschitz in s.
  auto f = [&](double u) {
    const Vec3 x = at(u);
    if (length <= precision) return c.distance(step.from, step.axis, x);
    auto along = [&](double s) { return c.distance(step.from + s * travel, step.axis, x); };
    return detail::convex_minimum(along, 0.0, 1.0, precision / length).second;
  };
  auto inside = [&](double u) {
    const Vec3 x = at(u);
    if (length <= precision) return c.distance(step.from, step.axis, x) <= 0;
    auto along = [&](double s) { return c.distance(step.from + s * travel, step.axis, x); };
    return detail::convex_minimum(along, 0.0, 1.0, precision / length, length).second <= 0;
  };
  const auto [u_in, f_in] = detail::convex_minimum(f, lo, hi, precision, 1.0);
  if (f_in > 0) return std::nullopt;
  const double enter = inside(lo) ? lo : detail::convex_crossing(inside, u_in, lo, precision);
  const double exit = inside(hi) ? hi : detail::convex_crossing(inside, u_in, hi, precision);
  return std::pair{enter, exit};
}

namespace detail {

// Ray r of grid `axis` (lattice coordinates iu, iv) less the sweeps of `steps` listed for its row.
// Each sweep is subtracted as soon as it is found, and the next is searched only over the
// material left within its box: the sub-steps of a move overlap, so most rays find nothing left
// to cut after the first (subtraction in any order gives the same set).
inline void sweep_ray(std::span<const DexelInterval> ray, const TripleDexel& d, int axis, int iu,
                      int iv, std::span<const SweepCutter> cutters,
                      std::span<const SweepStep> steps, std::span<const Aabb> boxes,
                      std::span<const std::uint32_t> row, double precision,
                      std::vector<DexelInterval>& current, std::vector<DexelInterval>& out) {
  const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
  Vec3 point = d.origin;
  point[u] += d.spacing * iu;
  point[v] += d.spacing * iv;
  current.assign(ray.begin(), ray.end());
  std::vector<DexelInterval> next;
  for (std::uint32_t s : row) {
    const Aabb& box = boxes[s];
    if (current.empty()) break;
    if (point[u] < box.min[u] || point[u] > box.max[u] || point[v] < box.min[v] ||
        point[v] > box.max[v])
      continue;
    double lo = box.max[axis], hi = box.min[axis];  // the material left within the box
    for (const DexelInterval& span : current)
      if (span.exit >= box.min[axis] && span.enter <= box.max[axis]) {
        lo = std::min(lo, std::max<double>(span.enter, box.min[axis]));
        hi = std::max(hi, std::min<double>(span.exit, box.max[axis]));
      }
    if (!(lo <= hi)) continue;
    auto cut =
        ray_sweep_interval(cutters[steps[s].cutter], steps[s], point, axis, lo, hi, precision);
    if (!cut) continue;
    const DexelInterval removed{static_cast<float>(cut->first), static_cast<float>(cut->second)};
    next.clear();
    subtract_ray(current, {&removed, 1}, next);
    current.swap(next);
  }
  out.insert(out.end(), current.begin(), current.end());
}

}  // namespace detail

// Removes the sweeps of `steps` (each with its cutter) from every ray of `d`, to within
// `precision` mm. Rays are independent and the grids are rebuilt in ray order, so the result does
// not depend on `threads`.
inline void sweep_remove(TripleDexel& d, std::span<const SweepCutter> cutters,
                         std::span<const SweepStep> steps, unsigned threads,
                         double precision = 1e-4) {
  detail::require_positive(precision, "sweep precision");
  std::vector<Aabb> boxes;
  boxes.reserve(steps.size());
  for (const SweepStep& s : steps) {
    if (s.cutter >= cutters.size()) detail::fail("sweep_remove: step names cutter ", s.cutter);
    boxes.push_back(sweep_step_bounds(cutters[s.cutter], s));
  }
  for (int axis = 0; axis < 3; ++axis) {
    const int v = TripleDexel::v_axis(axis);
    const DexelGrid& old = d.grids[axis];
    // Each step listed for the rows (v index) its box spans.
    std::vector<std::vector<std::uint32_t>> rows(static_cast<std::size_t>(old.nv));
    for (std::size_t s = 0; s < steps.size(); ++s) {
      const double first = std::ceil((boxes[s].min[v] - d.origin[v]) / d.spacing);
      const double last = std::floor((boxes[s].max[v] - d.origin[v]) / d.spacing);
      for (double iv = std::max(first, 0.0); iv <= std::min(last, old.nv - 1.0); ++iv)
        rows[static_cast<std::size_t>(iv)].push_back(static_cast<std::uint32_t>(s));
    }
    DexelGrid next = detail::build_grid(
        d.lattice(), axis, threads, [&](std::size_t r, std::vector<DexelInterval>& out) {
          const int iu = static_cast<int>(r % static_cast<std::size_t>(old.nu));
          const int iv = static_cast<int>(r / static_cast<std::size_t>(old.nu));
          const auto& row = rows[static_cast<std::size_t>(iv)];
          if (row.empty()) {
            const auto ray = old.ray(r);
            out.insert(out.end(), ray.begin(), ray.end());
            return;
          }
          thread_local std::vector<DexelInterval> scratch;
          detail::sweep_ray(old.ray(r), d, axis, iu, iv, cutters, steps, boxes, row, precision,
                            scratch, out);
        });
    d.grids[axis] = std::move(next);
  }
}

}  // namespace tridex
