// tridex — the exact lowest point of one move's swept cutter above a grid point (Step 1 of Inui,
// Chen and Umezu, CAD&A 19(4) 2022, §3.1): MoveGeometry, the scalar form that the vector
// lanes (cutter_lanes.hpp) rewrite and that fine cells and cut_depth call directly.
//
// Each linear move of the tool tip lowers every grid point to the lowest point of the swept
// cutter above it. For a move C(t) = a + t·(b − a), t ∈ [0, 1], and a grid point q, that is
//     S(q) = min_t f(t),   f(t) = C_z(t) + h(|q − C_xy(t)|)
// with h the cutter's lower surface (cutter.hpp). f is convex in t (a convex function of an
// affine map plus a linear term), so its minimum is exact:
//   * flat end: f is linear where the disc covers q, so the minimum is at an end of that interval;
//   * ball end: setting f'(t) = 0 gives the closed form t* = t⊥ − w·k / (|v|·√(|v|² + w²)), with
//     v the move's horizontal vector, w its rise, t⊥ the foot of q on the move and k² = R² − e²
//     (e the distance from q to the move's line), clamped to the covering interval (the lowest
//     hit of a vertical line with a capsule);
//   * bull nose: f' has one sign under the flat bottom, so the minimum lies on one side of it,
//     where Newton's method (kept in a bracket) finds the root of f' on the corner torus;
//   * other cutters: f' = 0 where φ(d) = h'(d)·√(d² − e²)/d equals the move's slope, explicit
//     per profile piece (a line, or an arc centred on the axis) or at a joint of two pieces
//     (MoveGeometry::convex_minimum).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>

#include "tridex/cutter.hpp"
#include "tridex/detail/simd_lanes.hpp"
#include "tridex/geometry.hpp"

namespace tridex::detail {

// The geometry of one move, in coordinates relative to its start point.
struct MoveGeometry {
  const Cutter* cutter;
  double ax, ay, az;  // start of the tip path
  double vx, vy, w;   // horizontal displacement and rise
  double vv;          // vx² + vy²
  double inv_vv, inv_len, ball_factor;
  double radius, radius2;
  bool vertical;  // no horizontal displacement: a plunge, a retract or a point

  MoveGeometry(const Cutter& c, const Segment& s) : cutter(&c) {
    ax = s.a.x, ay = s.a.y, az = s.a.z;
    vx = s.b.x - s.a.x, vy = s.b.y - s.a.y, w = s.b.z - s.a.z;
    // A level move that went through a tilted frame rises by rounding noise; taken as level (an
    // error far below float heights) it gets the level moves' closed form.
    if (std::abs(w) <= 1e-9) w = 0;
    vv = vx * vx + vy * vy;
    radius = c.radius(), radius2 = radius * radius;
    // Below this the move is treated as vertical: the horizontal drift is far below float
    // resolution of any height.
    vertical = vv <= 1e-24 * std::max(1.0, radius2);
    inv_vv = vertical ? 0 : 1 / vv;
    inv_len = vertical ? 0 : 1 / std::sqrt(vv);
    ball_factor = vertical ? 0 : inv_len / std::sqrt(vv + w * w);
  }

  double lowest_tip() const { return std::min(az, az + w); }

  // The lowest point of the swept cutter above (x, y): its height z (+infinity if the cutter
  // does not pass over the point) and the move parameter t where it is reached.
  struct Lowest {
    double z, t;
  };

  Lowest lowest(double x, double y) const {
    double ux = x - ax, uy = y - ay;
    double uu = ux * ux + uy * uy;
    if (vertical) {
      if (uu > radius2) return {kInf, 0};
      return {lowest_tip() + cutter->lower_height(std::sqrt(uu)), w < 0 ? 1.0 : 0.0};
    }
    double t_foot = (ux * vx + uy * vy) * inv_vv;          // foot of q on the move's line
    double e2 = std::max(0.0, uu - t_foot * t_foot * vv);  // squared distance to the line
    if (e2 > radius2) return {kInf, 0};
    double k = std::sqrt(radius2 - e2);
    double lo = std::max(0.0, t_foot - k * inv_len), hi = std::min(1.0, t_foot + k * inv_len);
    if (lo > hi) return {kInf, 0};
    if (w == 0 && cutter->shape() != CutterShape::ball) {
      // A level move (the roughing passes of most programs): the cutter is lowest above q where
      // it comes closest to q, for any cutter.
      double t = std::clamp(t_foot, lo, hi), s = t - t_foot;
      return {az + cutter->lower_height(std::sqrt(e2 + s * s * vv)), t};
    }
    switch (cutter->shape()) {
      case CutterShape::flat: {
        double t = w > 0 ? lo : hi;
        return {az + t * w, t};
      }
      case CutterShape::ball:
        return ball_lowest(ux, uy);
      case CutterShape::bull_nose:
        return bull_nose_lowest(e2, t_foot, lo, hi);
      default:
        return convex_minimum(e2, t_foot, lo, hi);
    }
  }

  // The ball end's closed form for a non-vertical move, at offset (ux, uy) from the move's start:
  // the hot path of milling, kept short.
  Lowest ball_lowest(double ux, double uy) const {
    double dot = ux * vx + uy * vy;
    double t_foot = dot * inv_vv;
    double e2 = ux * ux + uy * uy - t_foot * dot;
    if (e2 > radius2) return {kInf, 0};
    double k = std::sqrt(std::max(0.0, radius2 - e2));
    double lo = std::max(0.0, t_foot - k * inv_len), hi = std::min(1.0, t_foot + k * inv_len);
    if (lo > hi) return {kInf, 0};
    double t = std::min(std::max(t_foot - w * k * ball_factor, lo), hi);
    double dx = ux - t * vx, dy = uy - t * vy;
    return {az + t * w + radius - std::sqrt(std::max(0.0, radius2 - (dx * dx + dy * dy))), t};
  }

  // The bull nose: its lower surface is flat out to R0 = R − r, where f' = w has one sign, so the
  // minimum lies on the side of that stretch where the move is lower; there f is smooth (the
  // corner torus) and the root of f' is found by regula falsi on the reduced bracket.
  Lowest bull_nose_lowest(double e2, double t_foot, double lo, double hi) const {
    const double corner = cutter->corner_radius(), flat = radius - corner;
    if (e2 < flat * flat) {
      double half = std::sqrt(flat * flat - e2) * inv_len;
      double flat_lo = t_foot - half, flat_hi = t_foot + half;
      if (flat_lo <= hi && flat_hi >= lo) {  // the flat bottom passes over q
        if (w == 0) return {az, std::clamp(t_foot, lo, hi)};
        if (w > 0)
          hi = std::max(lo, flat_lo);
        else
          lo = std::min(hi, flat_hi);
      }
    }
    auto height = [&](double t) {
      double s = t - t_foot;
      double reach = std::max(0.0, std::sqrt(e2 + s * s * vv) - flat);
      return az + t * w + corner - std::sqrt(std::max(0.0, corner * corner - reach * reach));
    };
    // f' and f'' on the corner: with ρ = d − R0, h' = ρ/√(r² − ρ²), h'' = r²/(r² − ρ²)^(3/2),
    // d' = s·|v|²/d and d'' = |v|²·e²/d³.
    auto slopes = [&](double t, double& curvature) {
      double s = t - t_foot;
      double d = std::sqrt(e2 + s * s * vv), reach = d - flat;
      curvature = 0;
      if (reach <= 0 || d == 0) return w;
      double root2 = corner * corner - reach * reach;
      if (root2 <= 0) return s > 0 ? kInf : -kInf;
      double root = std::sqrt(root2), dd = s * vv / d;
      curvature = corner * corner / (root2 * root) * dd * dd + reach / root * vv * e2 / (d * d * d);
      return w + reach / root * dd;
    };
    auto slope = [&](double t) {
      double curvature;
      return slopes(t, curvature);
    };
    double slope_lo = slope(lo);
    if (slope_lo >= 0) return {height(lo), lo};
    double slope_hi = slope(hi);
    if (slope_hi <= 0) return {height(hi), hi};
    // Newton's method on f', kept inside the bracket (bisection where a step would leave it).
    double t = 0.5 * (lo + hi);
    for (int iteration = 0; iteration < 60 && hi - lo > 1e-13; ++iteration) {
      double curvature, g = slopes(t, curvature);
      if (g == 0) break;
      (g > 0 ? hi : lo) = t;
      double next = curvature > 0 ? t - g / curvature : kInf;
      if (!(next > lo && next < hi)) next = 0.5 * (lo + hi);
      if (std::abs(next - t) < 1e-14) {
        t = next;
        break;
      }
      t = next;
    }
    return {height(t), t};
  }

  double lowest_above(double x, double y) const { return lowest(x, y).z; }

  // A supporting plane of the swept lower surface S at (x, y), where S(x, y) = p.z is finite:
  // S(q) ≥ p.z + gradient·(q − (x, y)) for every q. S is convex (the lower surface of a convex
  // swept solid), and where the cutter's lower surface is differentiable at the minimiser, the
  // gradient is h'(d)·(q − C(t*))/d (joint convexity in (q, t) plus optimality of t*; where t*
  // is clamped to an end of the move, the sign of f' there keeps the bound). False where that
  // does not hold: at the rim (d = R) and near kinks of the profile (within far more than the
  // minimiser's error: regula falsi ends on a bracket of 1e-13 in t).
  bool supporting_plane(double x, double y, const Lowest& p, Vec2& gradient) const {
    CutterShape shape = cutter->shape();
    if (shape == CutterShape::flat) return flat_supporting_plane(x, y, gradient);
    double dx = x - (ax + p.t * vx), dy = y - (ay + p.t * vy);
    double d2 = dx * dx + dy * dy;
    if (d2 >= radius2 * (1 - 1e-7)) return false;
    if (shape == CutterShape::ball) {  // h'(d)/d = 1/√(R² − d²)
      gradient = Vec2(dx, dy) / std::sqrt(radius2 - d2);
      return true;
    }
    double d = std::sqrt(d2);
    if (shape == CutterShape::general && near_kink(d)) return false;
    gradient = d > 0 ? (cutter->lower_slope(d) / d) * Vec2(dx, dy) : Vec2(0);
    return true;
  }

  // Whether h(|p|) may not be differentiable within 1e-8·R of distance d: at the joints of the
  // profile's pieces, and on the axis where the profile starts sloped (a cone's point).
  bool near_kink(double d) const {
    const double tolerance = 1e-8 * radius;
    const std::vector<ProfilePiece>& pieces = cutter->pieces();
    if (d <= tolerance && pieces.front().derivative(0) != 0) return true;
    for (std::size_t k = 1; k < pieces.size(); ++k)
      if (std::abs(d - pieces[k].d0) <= tolerance) return true;
    return false;
  }

  // The flat end's S is az + w·t_edge, t_edge the parameter where the end disc first (w > 0) or
  // last (w < 0) covers q: t⊥ ∓ k/|v|, clamped to [0, 1]. Its gradient, w·∇t_edge with
  // ∇t⊥ = v/|v|², ∇k = −(u − t⊥·v)/k, is a limit of gradients of the convex S, hence a supporting
  // slope. Zero where t_edge is clamped or the move is vertical or level.
  bool flat_supporting_plane(double x, double y, Vec2& gradient) const {
    gradient = Vec2(0);
    if (vertical || w == 0) return true;
    double ux = x - ax, uy = y - ay;
    double t_foot = (ux * vx + uy * vy) * inv_vv;
    double e2 = std::max(0.0, ux * ux + uy * uy - t_foot * t_foot * vv);
    double k = std::sqrt(std::max(0.0, radius2 - e2));
    if (k <= radius * 1e-6) return false;  // at the side of the footprint: S is vertical there
    double sign = w > 0 ? -1.0 : 1.0;      // entering edge when rising, leaving edge when falling
    double t_edge = t_foot + sign * k * inv_len;
    if (t_edge <= 0 || t_edge >= 1) return true;
    Vec2 across(ux - t_foot * vx, uy - t_foot * vy);
    gradient = w * (Vec2(vx, vy) * inv_vv - sign * across * (inv_len / k));
    return true;
  }

  // lowest() and supporting_plane() at once; for the ball end, sharing the square root.
  bool lowest_with_plane(double x, double y, Lowest& p, Vec2& gradient) const {
    if (cutter->shape() != CutterShape::ball || vertical) {
      p = lowest(x, y);
      return p.z < kInf && supporting_plane(x, y, p, gradient);
    }
    p = ball_lowest(x - ax, y - ay);
    if (!(p.z < kInf)) return false;
    double root = az + p.t * w + radius - p.z;  // √(R² − d²) at the minimiser
    if (root * root <= radius2 * 1e-7) return false;
    gradient = Vec2(x - ax - p.t * vx, y - ay - p.t * vy) / root;
    return true;
  }

  // min over t ∈ [lo, hi] of f(t) = az + t·w + h(√(e² + (t − t⊥)²·|v|²)), for any cutter, on
  // a move that is not level. The minimiser lies on the side of the foot where the move is lower
  // (s = t − t⊥ of the sign of −w: on the other side both terms of f' = w + h'(d)·s|v|²/d have
  // w's sign), at the distance d* where
  //     φ(d) = h'(d)·√(d² − e²)/d = m,   m = |w|/|v|,
  // φ non-decreasing on [e, R] (h' is, and √(d² − e²)/d is). Per profile piece the root is
  // explicit: a line of slope k gives d*² = e²k²/(k² − m²); an arc centred on the axis (radius a)
  // d*² = (e² + m²a²)/(1 + m²); a jump of φ at a joint of the pieces (a kink) puts d* on the
  // joint. Then t* = t⊥ ∓ √(d*² − e²)/|v|, clamped to [lo, hi] (f is convex). An arc off the axis
  // (only the bull nose's corner, which has its own path) falls back to regula falsi.
  Lowest convex_minimum(double e2, double t_foot, double lo, double hi) const {
    const double e = std::sqrt(e2), m = std::abs(w) * inv_len;
    auto phi = [&](const ProfilePiece& piece, double d) {
      if (d <= 0) return piece.derivative(0);
      return piece.derivative(d) * std::sqrt(std::max(0.0, d * d - e2)) / d;
    };
    double root_d = radius;  // φ < m up to the rim: the minimiser leaves the footprint
    bool closed = true;
    for (const ProfilePiece& piece : cutter->pieces()) {
      if (piece.d1 < e) continue;
      const double from = std::max(piece.d0, e), to = std::min(piece.d1, radius);
      if (phi(piece, from) >= m) {  // a kink at the joint, or e itself
        root_d = from;
        break;
      }
      if (phi(piece, to) < m) continue;
      if (!piece.is_arc) {
        root_d = std::sqrt(e2 * piece.slope * piece.slope / (piece.slope * piece.slope - m * m));
      } else if (piece.centre_d == 0) {
        root_d = std::sqrt((e2 + m * m * piece.radius * piece.radius) / (1 + m * m));
      } else {
        closed = false;
      }
      root_d = std::clamp(root_d, from, to);
      break;
    }
    if (closed) {
      const double side = std::sqrt(std::max(0.0, root_d * root_d - e2)) * inv_len;
      const double t = std::clamp(w > 0 ? t_foot - side : t_foot + side, lo, hi), s = t - t_foot;
      // Where φ < m up to the rim (a steep move), d(t*) = R, which rounding may put past the rim
      // (where lower_height is +infinity, as if q were not covered).
      return {az + t * w + cutter->lower_height(std::min(radius, std::sqrt(e2 + s * s * vv))), t};
    }
    return convex_regula_falsi(e2, t_foot, lo, hi);
  }

  // The same by regula falsi on f', for any convex profile.
  Lowest convex_regula_falsi(double e2, double t_foot, double lo, double hi) const {
    auto f = [&](double t) {
      double s = t - t_foot;
      return az + t * w + cutter->lower_height(std::sqrt(e2 + s * s * vv));
    };
    auto slope = [&](double t) {
      double s = t - t_foot;
      double d = std::sqrt(e2 + s * s * vv);
      if (d == 0) return w;
      double ds = s * vv / d;  // dd/dt
      double dh = cutter->lower_slope(std::min(d, radius));
      return w + (ds == 0 ? 0 : dh * ds);
    };
    return convex_root(f, slope, lo, hi);
  }

  // The minimum of a convex f on [lo, hi] from its non-decreasing derivative: an end where f'
  // does not change sign, else the root of f' by the Illinois variant of regula falsi
  // (superlinear where f' is smooth), with bisection where the secant leaves the bracket.
  template <class F, class Slope>
  static Lowest convex_root(F&& f, Slope&& slope, double lo, double hi) {
    double slope_lo = slope(lo);
    if (slope_lo >= 0) return {f(lo), lo};
    double slope_hi = slope(hi);
    if (slope_hi <= 0) return {f(hi), hi};
    int kept = 0;  // which end survived the last step: −1 low, +1 high
    for (int iteration = 0; iteration < 100 && hi - lo > 1e-13; ++iteration) {
      double t = (lo * slope_hi - hi * slope_lo) / (slope_hi - slope_lo);
      if (!(t > lo && t < hi)) t = 0.5 * (lo + hi);
      double g = slope(t);
      if (g > 0) {
        hi = t, slope_hi = g;
        if (kept == -1) slope_lo *= 0.5;
        kept = -1;
      } else if (g < 0) {
        lo = t, slope_lo = g;
        if (kept == 1) slope_hi *= 0.5;
        kept = 1;
      } else {
        lo = hi = t;
      }
    }
    double f_lo = f(lo), f_hi = f(hi);
    return f_lo <= f_hi ? Lowest{f_lo, lo} : Lowest{f_hi, hi};
  }
};

}  // namespace tridex::detail
