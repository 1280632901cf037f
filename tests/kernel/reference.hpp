// Brute-force references for the kernel tests, written from docs/design.md's formulas and
// independent of the kernel's fast paths: a cutter is only its radius function ρ(h), and the
// swept cutter is sampled densely along the move.
#pragma once

#include <algorithm>
#include <cmath>
#include <functional>
#include <limits>
#include <random>

#include "tridex/cutter.hpp"
#include "tridex/geometry.hpp"

namespace tridex::test {

// ρ(h): the cutter's radius at height h above the tip, straight from the design notes.
struct RadiusFunction {
  double radius;
  std::function<double(double)> rho;
};

inline RadiusFunction flat_rho(double r) {
  return {r, [r](double) { return r; }};
}
inline RadiusFunction ball_rho(double r) {
  return {r, [r](double h) { return h >= r ? r : std::sqrt(r * r - (r - h) * (r - h)); }};
}
inline RadiusFunction bull_rho(double r, double c) {
  return {r,
          [r, c](double h) { return h >= c ? r : (r - c) + std::sqrt(c * c - (c - h) * (c - h)); }};
}
inline RadiusFunction chamfer_rho(double r, double tip, double half_angle_deg) {
  double t = std::tan(half_angle_deg * M_PI / 180);
  return {r, [=](double h) { return std::min(r, tip + h * t); }};
}
inline RadiusFunction tapered_ball_rho(double r, double tip, double half_angle_deg) {
  double a = half_angle_deg * M_PI / 180;
  double h_tangent = tip - tip * std::sin(a);  // where the cone leaves the ball
  double d_tangent = tip * std::cos(a);
  double slope = std::tan(a);
  return {r, [=](double h) {
            if (h <= h_tangent) return std::sqrt(std::max(0.0, tip * tip - (tip - h) * (tip - h)));
            return std::min(r, d_tangent + (h - h_tangent) * slope);
          }};
}

// The lowest height above the tip at horizontal distance d: the smallest h with ρ(h) ≥ d, by
// bisection on the non-decreasing ρ. +infinity beyond the radius.
inline double lowest_height(const RadiusFunction& f, double d) {
  if (d > f.radius) return std::numeric_limits<double>::infinity();
  if (f.rho(0) >= d) return 0;
  double lo = 0, hi = 1;
  while (f.rho(hi) < d) hi *= 2;
  for (int k = 0; k < 200 && hi - lo > 1e-14; ++k) {
    double mid = 0.5 * (lo + hi);
    (f.rho(mid) >= d ? hi : lo) = mid;
  }
  return hi;
}

// The lowest point of the swept cutter above (x, y) by dense sampling of the tip along the move:
// an upper bound of the exact value that converges to it as `samples` grows. `best_t` returns
// the best sample's parameter.
inline double sampled_lowest(const RadiusFunction& f, const Segment& s, double x, double y,
                             int samples, double* best_t = nullptr) {
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k <= samples; ++k) {
    double t = double(k) / samples;
    Vec3 c = s.a + t * (s.b - s.a);
    double z = c.z + lowest_height(f, std::hypot(x - c.x, y - c.y));
    if (z < best) {
      best = z;
      if (best_t) *best_t = t;
    }
  }
  return best;
}

// The same value refined: ternary search (valid because the value is convex in t) on the
// covered sub-interval around the best sample.
inline double refined_lowest(const RadiusFunction& f, const Segment& s, double x, double y) {
  const int samples = 400;
  double t_best = 0;
  double best = sampled_lowest(f, s, x, y, samples, &t_best);
  if (!std::isfinite(best)) return best;
  auto value = [&](double t) {
    Vec3 c = s.a + t * (s.b - s.a);
    return c.z + lowest_height(f, std::hypot(x - c.x, y - c.y));
  };
  // Shrink the window to where the cutter covers the point, keeping t_best inside.
  auto covered_edge = [&](double inside, double outside) {
    if (std::isfinite(value(outside))) return outside;
    for (int k = 0; k < 100; ++k) {
      double mid = 0.5 * (inside + outside);
      (std::isfinite(value(mid)) ? inside : outside) = mid;
    }
    return inside;
  };
  double lo = covered_edge(t_best, std::max(0.0, t_best - 1.0 / samples));
  double hi = covered_edge(t_best, std::min(1.0, t_best + 1.0 / samples));
  for (int k = 0; k < 200 && hi - lo > 1e-13; ++k) {
    double m1 = lo + (hi - lo) / 3, m2 = hi - (hi - lo) / 3;
    if (value(m1) > value(m2))
      lo = m1;
    else
      hi = m2;
  }
  return std::min({best, value(lo), value(hi), value(0.5 * (lo + hi))});
}

}  // namespace tridex::test
