// tridex — machinery of sweep.hpp: the signed distance to a cutter of finite height, and the
// minimisation of convex functions of one variable that turns it into exact ray intervals.
//
// A cutter (cutter.hpp) is a convex solid of revolution; cut at a height H above its tip it stays
// convex, and the Euclidean signed distance to a convex solid is a convex function of the point
// (Boyd and Vandenberghe, "Convex Optimization", §3.2.5: the distance to a convex set is convex,
// and inside it −distance to the complement's boundary is convex too). Along an affine family of
// points, as a ray or a translation, it is therefore convex in the parameters, and its minimum
// over one of them is convex in the other (partial minimisation, ibid. §3.2.5): golden-section
// search finds minima and bisection the zeros to any precision, with no sampling that could
// miss a thin contact.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "tridex/cutter.hpp"
#include "tridex/geometry.hpp"

namespace tridex::detail {

// √(x² + y²) without std::hypot's care for overflow, which costs several times more and which
// lengths of millimetres never need.
inline double length_2d(double x, double y) { return std::sqrt(x * x + y * y); }

// Distance from (px, py) to the segment (ax, ay)–(bx, by).
inline double segment_distance_2d(double px, double py, double ax, double ay, double bx,
                                  double by) {
  const double dx = bx - ax, dy = by - ay, len2 = dx * dx + dy * dy;
  double t = len2 > 0 ? ((px - ax) * dx + (py - ay) * dy) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return length_2d(px - ax - t * dx, py - ay - t * dy);
}

// Distance from the meridian point (d, h) to one piece of a cutter's lower surface.
inline double piece_distance(const ProfilePiece& p, double d, double h) {
  const double h0 = p.height(p.d0), h1 = p.height(p.d1);
  if (!p.is_arc) return segment_distance_2d(d, h, p.d0, h0, p.d1, h1);
  // A lower arc: the circle's nearest point is on the arc when it lies below the centre and
  // within [d0, d1]; otherwise an end point is nearest.
  const double vx = d - p.centre_d, vy = h - p.centre_h, len = length_2d(vx, vy);
  if (len > 0 && vy <= 0) {
    const double x = p.centre_d + p.radius * vx / len;
    if (x >= p.d0 && x <= p.d1) return std::abs(len - p.radius);
  }
  return std::min(length_2d(d - p.d0, h - h0), length_2d(d - p.d1, h - h1));
}

// Signed distance (negative inside) from the meridian point (d ≥ 0 from the axis, h above the
// tip) to the cutter cut at `height` (> profile_height()): the profile, the side d = R and the top.
// The section is symmetric about the axis, so a point with d ≥ 0 is nearest to its own side.
inline double meridian_distance(const Cutter& c, double height, double d, double h) {
  const double r = c.radius(), top_of_profile = c.profile_height();
  double best = std::min(segment_distance_2d(d, h, r, top_of_profile, r, height),
                         segment_distance_2d(d, h, 0, height, r, height));
  for (const ProfilePiece& p : c.pieces()) best = std::min(best, piece_distance(p, d, h));
  const bool inside = d <= r && h <= height && h >= c.lower_height(d);
  return inside ? -best : best;
}

// Signed distance from `x` to the cutter with its tip at `tip` and unit axis `axis`.
inline double cutter_distance(const Cutter& c, double height, const Vec3& tip, const Vec3& axis,
                              const Vec3& x) {
  const Vec3 v = x - tip;
  const double h = glm::dot(v, axis);
  const double d = glm::length(v - h * axis);
  return meridian_distance(c, height, d, h);
}

inline constexpr double kGolden = 0.6180339887498949;

// The minimum of convex f on [lo, hi] to within `precision` of its argument, as golden-section
// search finds it, stopping early at the first value ≤ 0 (the callers ask only whether f reaches
// 0) and, given f's Lipschitz constant `lipschitz`, as soon as the values seen prove f > 0 on the
// bracket (which holds the minimum). Returns (argument, value): the value is f's there.
template <class F>
std::pair<double, double> convex_minimum(F&& f, double lo, double hi, double precision,
                                         double lipschitz = -1) {
  std::pair<double, double> best{lo, f(lo)};
  if (best.second <= 0) return best;
  if (double v = f(hi); v <= 0 || v < best.second) best = {hi, v};
  if (best.second <= 0) return best;
  double a = lo, b = hi;
  double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
  double f1 = f(x1), f2 = f(x2);
  for (;;) {
    if (f1 < best.second) best = {x1, f1};
    if (f2 < best.second) best = {x2, f2};
    if (best.second <= 0 || b - a <= precision) return best;
    if (lipschitz >= 0 && std::min(f1, f2) > lipschitz * (b - a)) return best;
    if (f1 <= f2) {
      b = x2, x2 = x1, f2 = f1;
      x1 = b - kGolden * (b - a), f1 = f(x1);
    } else {
      a = x1, x1 = x2, f1 = f2;
      x2 = a + kGolden * (b - a), f2 = f(x2);
    }
  }
}

// The minimum of convex f on [lo, hi] to within `precision` of its argument by golden-section
// search, without convex_minimum's stop at 0 (for the depth, which is the minimum itself). Given
// a finite `bar` and f 1-Lipschitz, it returns a value ≥ `bar` as soon as the values seen prove
// the minimum is (the bracket holds it, and f drops by at most its width from any value in it).
// Returns (argument, value).
template <class F>
std::pair<double, double> golden_minimum(const F& f, double lo, double hi, double precision,
                                         double bar = std::numeric_limits<double>::infinity()) {
  const bool stop_at_bar = bar < std::numeric_limits<double>::infinity();
  double a = lo, b = hi;
  double x1 = b - kGolden * (b - a), x2 = a + kGolden * (b - a);
  double f1 = f(x1), f2 = f(x2);
  std::pair<double, double> best{lo, f(lo)};
  if (const double v = f(hi); v < best.second) best = {hi, v};
  while (b - a > precision) {
    if (stop_at_bar && std::min(f1, f2) - (b - a) >= bar) return {x1, std::max(f1, bar)};
    if (f1 <= f2)
      b = x2, x2 = x1, f2 = f1, x1 = b - kGolden * (b - a), f1 = f(x1);
    else
      a = x1, x1 = x2, f1 = f2, x2 = a + kGolden * (b - a), f2 = f(x2);
  }
  if (f1 < best.second) best = {x1, f1};
  if (f2 < best.second) best = {x2, f2};
  return best;
}

// The zero of f between `inside` (f ≤ 0) and `outside` (f > 0), to within `precision`, on the
// outside's side (so an interval from these ends covers the set f ≤ 0). `is_inside(x)`: f(x) ≤ 0.
template <class Inside>
double convex_crossing(Inside&& is_inside, double inside, double outside, double precision) {
  while (std::abs(outside - inside) > precision) {
    const double mid = 0.5 * (inside + outside);
    (is_inside(mid) ? inside : outside) = mid;
  }
  return outside;
}

}  // namespace tridex::detail
