// tridex — the swept surfaces of the milling kernel's moves, kLanes points at a time: BallLanes,
// FlatLanes, BullLanes and ProfileLanes, each MoveGeometry's minimum (move_geometry.hpp, after
// Inui, Chen and Umezu, CAD&A 19(4) 2022, §3.1) rewritten for its cutter so that the hot path
// of milling needs few square roots and no branches per point.
//
// Ball end moves are bounded kLanes tiles at a time and evaluated kLanes points at a time, with
// one square root per point (BallLanes); flat end and bull nose moves are bounded and evaluated
// kLanes at a time too (FlatLanes: a closed form; BullLanes: the still cutter where the minimum is
// at an end of the move, else Halley steps with no square root), and so are the other cutters'
// (ProfileLanes: a closed form per profile piece).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>

#include "tridex/cutter.hpp"
#include "tridex/detail/move_geometry.hpp"
#include "tridex/detail/simd_lanes.hpp"

namespace tridex::detail {

// The ball end's swept surface S for one non-vertical move, kLanes points at a time: the hot
// path of milling. It is MoveGeometry::ball_lowest rewritten with one square root per point:
// with the move stored rising (w ≥ 0; a falling move is the same swept solid run backwards), the
// minimiser t* = t⊥ − c·k (c = w / (|v|·√(|v|² + w²)), k = √(R² − e²)) lies
//   * before the start exactly when t⊥ < 0 or t⊥² < c²k², and S is the start sphere's
//     az + R − √(R² − |u|²);
//   * past the end exactly when t⊥ > 1 and (t⊥ − 1)² > c²k², and S is the end sphere's;
//   * otherwise on the swept cylinder, whose lowest point above q is
//     az + R + t⊥·w − √(k²·(1 + w²/|v|²))  (a vertical line meeting a tilted cylinder),
// and in each case q is covered exactly when the square root's argument is not negative.
// The cylinder's gradient is w·v/|v|² + (1 + w²/|v|²)·(u − t⊥·v)/√(…) and a sphere's (u −
// t·v)/√(…), the supporting plane of MoveGeometry::supporting_plane in other terms.
//
// Across the move S also rises at least quadratically from that plane: with n the move's unit
// horizontal normal,  S(q) ≥ S(c) + ∇S(c)·(q − c) + ((q − c)·n)² / 2R  ("across"). Proof: the
// ball's lower surface h(|p|) has curvature ≥ 1/R in every direction, so h(|p|) − (p·n + κ)²/2R
// is convex in p; p = q − C(t) is affine in (q, t), and p·n differs from (q − c)·n by a constant
// along a straight move; so S(q) − ((q − c)·n)²/2R, a minimum over t of a function jointly convex
// in (q, t), is convex, and lies above its tangent plane at c.
struct BallLanes {
  double ax = 0, ay = 0,
         top = 0;  // start of the (rising) move; top = its tip + R, the ball's centre
  double vx = 0, vy = 0, w = 0, vv = 0, inv_vv = 0, stretch = 1, c2 = 0, radius = 0, r2 = 0,
         inv_diameter = 0, rim = 0;
  double slope_x = 0, slope_y = 0;  // w·v/|v|²
  double nx = 0, ny = 0;            // unit horizontal normal of the move

  BallLanes() = default;

  explicit BallLanes(const MoveGeometry& m) {
    const bool falling = m.w < 0;
    ax = falling ? m.ax + m.vx : m.ax, ay = falling ? m.ay + m.vy : m.ay;
    vx = falling ? -m.vx : m.vx, vy = falling ? -m.vy : m.vy, w = std::abs(m.w);
    top = m.lowest_tip() + m.radius;
    vv = m.vv, inv_vv = m.inv_vv, radius = m.radius, r2 = m.radius2, inv_diameter = 0.5 / m.radius;
    stretch = 1 + w * w * inv_vv;
    c2 = w * w * inv_vv / (vv + w * w);
    rim = r2 * 1e-7;  // as MoveGeometry::lowest_with_plane: no plane this close to the rim
    slope_x = w * vx * inv_vv, slope_y = w * vy * inv_vv;
    nx = -vy * m.inv_len, ny = vx * m.inv_len;
  }

  double lowest_tip() const { return top - radius; }

  struct Cases {
    MaskN before, after;    // t* < 0, t* > 1
    DoubleN t_foot, root2;  // t⊥ and the square root's argument (< 0: q not covered)
  };

  // At offsets (ux, uy) from the start.
  Cases cases(DoubleN ux, DoubleN uy) const {
    DoubleN dot = ux * vx + uy * vy, t = dot * inv_vv, uu = ux * ux + uy * uy;
    DoubleN k2 = r2 - (uu - t * dot), ck2 = c2 * k2, t1 = t - 1;
    MaskN before = (t < 0) | (t * t < ck2);
    MaskN after = (t1 > 0) & (t1 * t1 > ck2);
    DoubleN root2 = before ? r2 - uu : after ? r2 - (uu - 2 * dot + vv) : k2 * stretch;
    return {before, after, t, root2};
  }

  DoubleN base(const Cases& c) const {
    return c.before ? splat(top) : c.after ? splat(top + w) : top + c.t_foot * w;
  }

  // S at the points; +infinity where the cutter does not pass.
  DoubleN at(DoubleN ux, DoubleN uy) const {
    Cases c = cases(ux, uy);
    DoubleN z = base(c) - sqrt_n(max_n(c.root2, splat(0)));
    return c.root2 >= 0 ? z : splat(kInf);
  }

  // S and its supporting plane's slope (where `has_plane`).
  struct Plane {
    DoubleN z, gx, gy;
    MaskN has_plane;
  };
  Plane plane_at(DoubleN ux, DoubleN uy) const {
    Cases c = cases(ux, uy);
    MaskN sphere = c.before | c.after;
    DoubleN root = sqrt_n(max_n(c.root2, splat(0)));
    Plane p;
    p.z = base(c) - root;
    p.has_plane = c.root2 > (sphere ? splat(rim) : rim * stretch * stretch);
    root = p.has_plane ? root : splat(1);
    DoubleN t = c.before ? splat(0) : c.after ? splat(1) : c.t_foot;
    DoubleN scale = (sphere ? splat(1) : splat(stretch)) / root;
    p.gx = (sphere ? splat(0) : splat(slope_x)) + scale * (ux - t * vx);
    p.gy = (sphere ? splat(0) : splat(slope_y)) + scale * (uy - t * vy);
    return p;
  }
};

// A non-vertical move stored rising (w ≥ 0; a falling move is the same swept solid run
// backwards), for the flat end's, the bull nose's and the profiles' vector forms: which points
// its cutter of radius R passes over, and the parameter interval [lo, hi] over which it covers
// each, as in MoveGeometry::lowest.
struct RisingMove {
  double ax = 0, ay = 0, low = 0;  // start of the rising move and its tip height
  double vx = 0, vy = 0, w = 0, vv = 0, inv_vv = 0, inv_len = 0, r2 = 0;

  RisingMove() = default;

  explicit RisingMove(const MoveGeometry& m) {
    const bool falling = m.w < 0;
    ax = falling ? m.ax + m.vx : m.ax, ay = falling ? m.ay + m.vy : m.ay;
    vx = falling ? -m.vx : m.vx, vy = falling ? -m.vy : m.vy, w = std::abs(m.w);
    low = m.lowest_tip();
    vv = m.vv, inv_vv = m.inv_vv, inv_len = m.inv_len, r2 = m.radius2;
  }

  struct Cover {
    DoubleN t_foot, e2, lo, hi;  // foot on the move's line, squared distance to it, the interval
    DoubleN half;                // half the interval's length before clipping to [0, 1]: k/|v|
    MaskN covered;
  };

  // At offsets (ux, uy) from the start.
  Cover cover(DoubleN ux, DoubleN uy) const {
    DoubleN dot = ux * vx + uy * vy, t = dot * inv_vv;
    DoubleN e2 = max_n(ux * ux + uy * uy - t * dot, splat(0));
    DoubleN k = sqrt_n(max_n(r2 - e2, splat(0))) * inv_len;
    DoubleN lo = t - k, hi = t + k;
    return {t, e2, max_n(lo, splat(0)), min_n(hi, splat(1)), k, (e2 <= r2) & (lo <= 1) & (hi >= 0)};
  }
};

// The flat end's swept surface S, kLanes points at a time (MoveGeometry::lowest's closed form):
// a rising move is lowest above q where its end disc first covers q, S = low + w·lo.
struct FlatLanes : RisingMove {
  double side = 0;  // k/|v| for k = 1e-6·R: closer to the footprint's side, no plane

  FlatLanes() = default;
  explicit FlatLanes(const MoveGeometry& m) : RisingMove(m), side(1e-6 * m.radius * m.inv_len) {}

  // The cutter's height at distance d ≤ R from the axis.
  static DoubleN height(DoubleN) { return splat(0); }

  DoubleN at(DoubleN ux, DoubleN uy) const {
    Cover c = cover(ux, uy);
    return c.covered ? low + w * c.lo : splat(kInf);
  }

  // S and its supporting plane's slope (MoveGeometry::flat_supporting_plane): w·∇t_edge, with
  // t_edge = t⊥ − k/|v| the entry parameter, ∇t⊥ = v/|v|², ∇k = −(u − t⊥·v)/k; zero where t_edge
  // is clipped. No plane where q is not covered or is within 1e-6·R of the footprint's side.
  struct Plane {
    DoubleN z, gx, gy;
    MaskN has_plane;
  };
  Plane plane_at(DoubleN ux, DoubleN uy) const {
    Cover c = cover(ux, uy);
    Plane p;
    p.z = low + w * c.lo;
    p.has_plane = c.covered & (c.half > side);
    const DoubleN entry = c.t_foot - c.half;
    const MaskN sloped = (entry > 0) & (entry < 1) & p.has_plane;
    const DoubleN scale =
        sloped ? w * inv_vv / max_n(c.half, splat(side)) : splat(0);  // w·∇t_edge across
    p.gx = (sloped ? splat(w * vx * inv_vv) : splat(0)) + scale * (ux - c.t_foot * vx);
    p.gy = (sloped ? splat(w * vy * inv_vv) : splat(0)) + scale * (uy - c.t_foot * vy);
    return p;
  }
};

// The bull nose's swept surface S, kLanes points at a time. A level move is lowest where it comes
// closest to q (closed form). A rising move (slope m = w/|v| > 0) has f(t) = low + t·w + h(d(t)),
// d(t)² = e² + s²|v|², s = t − t⊥, convex, with f' = w + h'(d)·s|v|²/d: w > 0 under the flat
// bottom (d ≤ R0 = R − r) and behind the axis (s > 0), so its one root lies ahead (s < 0) on
// the corner, reach ρ = d − R0 ∈ (0, r], where h'(d) = ρ/√(r² − ρ²). There f' = 0 reads
// ρ·√(d² − e²) = m·d·√(r² − ρ²), and dividing its square by ρ²d²,
//     Q(ρ) = 1 + m² − m²r²/ρ² − e²/(R0 + ρ)² = 0,
// with Q increasing and concave on ρ > 0, Q ≤ 0 at max(mr/√(1 + m²), e − R0) and Q(r) ≥ 0. Halley's
// method from that left end, kept in [that end, r], converges cubically, with no square root and
// one division per step (Q and its derivatives times powers of ρd): on a 40 × 40 mm cut of
// bench_mill's bull nose raster, 2.9 steps a call where Newton's method took 5.0 (a call steps
// until its slowest lane stops). Then t* = t⊥ − √(d*² − e²)/|v|, and S = f(t*) evaluated at a
// point of the move, so a step short of the root can only leave S a little high, never cut below
// the swept solid. Most points a move is tested on have their minimum clamped to an end of the
// move (the neighbouring move of the same pass is lower there), and that needs no root: t* ≤ 0
// exactly when t⊥ ≤ 0 or d* ≥ |u| (d(0) = |u|), i.e. Q(|u| − R0) ≤ 0 since Q increases; t* ≥ 1
// exactly when t⊥ ≥ 1 and Q(|u − v| − R0) ≥ 0. There S is the still cutter at that end.
struct BullLanes : RisingMove {
  double radius = 0, flat = 0, corner = 0, corner2 = 0, m2 = 0, start = 0;
  double reach_scale = 0;  // 1/(R + R0)

  BullLanes() = default;
  explicit BullLanes(const MoveGeometry& m) : RisingMove(m) {
    radius = m.radius;
    corner = m.cutter->corner_radius(), corner2 = corner * corner;
    flat = m.radius - corner;
    m2 = w * w * inv_vv;
    start = corner * std::sqrt(m2 / (1 + m2));  // the root for e = 0
    reach_scale = 1 / (radius + flat);
  }

  // The corner's height h at distance d from the axis (0 under the flat bottom).
  DoubleN height(DoubleN d) const {
    DoubleN reach = max_n(d - flat, splat(0));
    return corner - sqrt_n(max_n(corner2 - reach * reach, splat(0)));
  }

  // S at the points where `wanted` (+infinity elsewhere and where the cutter does not pass).
  DoubleN at(DoubleN ux, DoubleN uy, MaskN wanted) const {
    DoubleN z[1];
    at<1>({ux}, uy, {wanted}, z);
    return z[0];
  }

  // The same for G groups of kLanes points of one row at once: their Halley steps are
  // independent, so interleaved they overlap each other's division latency (a step is one
  // dependent chain through a division).
  template <int G>
  void at(const DoubleN (&ux)[G], DoubleN uy, const MaskN (&wanted)[G], DoubleN (&z)[G]) const {
    DoubleN t[G], d[G];
    if (!lowest<G>(ux, uy, wanted, t, d)) {
      for (int g = 0; g < G; ++g) z[g] = splat(kInf);
      return;
    }
    for (int g = 0; g < G; ++g) z[g] = d[g] < kInf ? low + t[g] * w + height(d[g]) : splat(kInf);
  }

  // S and its supporting plane's slope at the points (MoveGeometry::supporting_plane): h'(d)/d
  // times q − C(t*), h'(d) = ρ/√(r² − ρ²) on the corner and 0 under the flat bottom. No plane
  // where the cutter does not pass or q is within 1e-7·R² (in d²) of the rim.
  using Plane = FlatLanes::Plane;
  Plane plane_at(DoubleN ux, DoubleN uy) const {
    DoubleN t[1], d[1];
    MaskN all{};
    all = all == 0;
    Plane p{splat(kInf), splat(0), splat(0), MaskN{}};
    if (!lowest<1>({ux}, uy, {all}, t, d)) return p;
    // d* = |q − C(t*)| (up to rounding: t* is clamped to the move only by rounding), so h and
    // h' share one square root, and dividing by d* needs no other.
    const DoubleN px = ux - t[0] * vx, py = uy - t[0] * vy, dist = min_n(d[0], splat(radius));
    p.has_plane = (d[0] < kInf) & (px * px + py * py < r2 * (1 - 1e-7));
    const DoubleN reach = max_n(dist - flat, splat(0)),
                  root2 = max_n(corner2 - reach * reach, splat(0));
    const DoubleN root = sqrt_n(root2);
    const DoubleN factor =
        (p.has_plane & (reach > 0)) ? reach / (max_n(root, splat(corner * 1e-7)) * dist) : splat(0);
    p.z = d[0] < kInf ? low + t[0] * w + (corner - root) : splat(kInf);
    p.gx = factor * px, p.gy = factor * py;
    return p;
  }

  // Where S is reached, t* and d(t*), at the points where `wanted` (d = +infinity elsewhere and
  // where the cutter does not pass); false if no point is wanted.
  template <int G>
  bool lowest(const DoubleN (&ux)[G], DoubleN uy, const MaskN (&wanted)[G], DoubleN (&t)[G],
              DoubleN (&d)[G]) const {
    MaskN any_wanted{};
    for (int g = 0; g < G; ++g) any_wanted |= wanted[g];
    if (!any_n(any_wanted)) return false;
    if (w == 0) {  // level: lowest where the axis comes closest to q
      for (int g = 0; g < G; ++g) {
        const Cover c = cover(ux[g], uy);
        t[g] = min_n(max_n(c.t_foot, c.lo), c.hi);
        const DoubleN s = t[g] - c.t_foot;
        d[g] = c.covered & wanted[g] ? sqrt_n(c.e2 + s * s * vv) : splat(kInf);
      }
      return true;
    }
    const DoubleN mr2 = splat(m2 * corner2), q0 = splat(1 + m2);
    // P(ρ) = ρ²d²·Q(ρ) with d = R0 + ρ: the sign of Q without a division.
    auto p = [&](DoubleN e2, DoubleN reach, DoubleN dist) {
      const DoubleN rr = reach * reach, dd = dist * dist;
      return q0 * rr * dd - mr2 * dd - e2 * rr;
    };
    DoubleN t_foot[G], e2[G], reach[G];
    MaskN inside[G], any_inside{};
    for (int g = 0; g < G; ++g) {
      const DoubleN dot = ux[g] * vx + uy * vy, uu = ux[g] * ux[g] + uy * uy, ex = ux[g] - vx,
                    ey = uy - vy;
      t_foot[g] = dot * inv_vv;
      e2[g] = max_n(uu - t_foot[g] * dot, splat(0));
      // Where the root lies before the start or past the end, S is the cutter at that end (see
      // above): Q(ρ_a) ≤ 0 at the start's reach ρ_a = |u| − R0, Q(ρ_b) ≥ 0 at the end's. There q
      // is covered if that end covers it; inside, if e ≤ R (then ρ* ≤ r, as Q(r) = 1 − e²/R² ≥ 0).
      const DoubleN da = sqrt_n(uu), db = sqrt_n(ex * ex + ey * ey), reach_a = da - flat,
                    reach_b = db - flat;
      const MaskN before = (t_foot[g] <= 0) | (reach_a <= 0) | (p(e2[g], reach_a, da) <= 0);
      const MaskN after = ~before & (t_foot[g] >= 1) & (reach_b > 0) & (p(e2[g], reach_b, db) >= 0);
      const MaskN covered = wanted[g] & (before  ? da <= radius
                                         : after ? db <= radius
                                                 : e2[g] <= r2);
      inside[g] = covered & ~before & ~after;
      any_inside |= inside[g];
      t[g] = before ? splat(0) : splat(1);
      d[g] = before ? da : after ? db : splat(kInf);
      d[g] = covered ? d[g] : splat(kInf);
      // Lower bounds of the root: the root for e = 0 and, past the end, ρ_b.
      reach[g] = max_n(splat(start), t_foot[g] >= 1 ? reach_b : splat(0));
    }
    if (any_n(any_inside)) {
      DoubleN
          least[G];  // the lower bounds: the root for e = 0, ρ_b past the end, and e − R0 (e ≤ d)
      MaskN moving[G];
      for (int g = 0; g < G; ++g) {
        least[g] = reach[g] = max_n(reach[g], (e2[g] - flat * flat) * reach_scale);
        moving[g] = inside[g];
      }
      for (int step = 0; step < 30; ++step) {
        MaskN any_moving{};
        for (int g = 0; g < G; ++g) {
          // Halley's step −2QQ'/(2Q'² − QQ''), with Q' = 2m²r²/ρ³ + 2e²/d³ = 2A/(ρ³d³) and
          // Q'' = −6m²r²/ρ⁴ − 6e²/d⁴ = −6B/(ρ⁴d⁴): in terms of P = ρ²d²·Q, 2ρd·P·A/(4A² + 3PB),
          // one division. The denominator is kept ≥ A² (a step at most four Newton steps; it only
          // binds far left of the root, where P < 0), and the step inside [least, r].
          const DoubleN r = reach[g], dr = flat + r, rr = r * r, dd = dr * dr;
          const DoubleN pr = p(e2[g], r, dr), a = mr2 * dd * dr + e2[g] * rr * r,
                        b = mr2 * dd * dd + e2[g] * rr * rr;
          const DoubleN delta = 2 * r * dr * pr * a / max_n(4 * a * a + 3 * pr * b, a * a);
          reach[g] = moving[g] ? min_n(max_n(r - delta, least[g]), splat(corner)) : r;
          // Lanes stop one by one, so that each point's root is its own whatever its neighbours
          // need. Halley's method converges cubically: after a step of 1e-8·r the error is far
          // below rounding (checked offline against bisection, 3e-14·r over slopes 1e-5 to 10,
          // corner radii 0.01R to 0.9R and e from 0 to R; test_mill checks slopes 1e-6 to 1e3
          // against MoveGeometry::lowest).
          moving[g] &= abs_n(delta) > 1e-8 * corner;
          any_moving |= moving[g];
        }
        if (!any_n(any_moving)) break;
      }
      for (int g = 0; g < G; ++g) {
        // t* = t⊥ − √(d*² − e²)/|v| has d(t*) = d*; clamped only by rounding.
        const DoubleN root_d = flat + reach[g];
        const DoubleN root_t =
            t_foot[g] - sqrt_n(max_n(root_d * root_d - e2[g], splat(0))) * inv_len;
        t[g] = inside[g] ? min_n(max_n(root_t, splat(0)), splat(1)) : t[g];
        d[g] = inside[g] ? root_d : d[g];
      }
    }
    return true;
  }
};

// The swept surface S of a cutter made of lines and arcs centred on the axis (cone, chamfer,
// tapered ball, from_profile), kLanes points at a time: MoveGeometry::convex_minimum's closed
// form per profile piece, with its tests squared so that they need no square root. For a rising
// move (slope m = w/|v| > 0) the minimiser lies behind the foot at the distance d* where
// φ(d) = h'(d)·√(d² − e²)/d reaches m, found on the first piece (from the axis out) where it
// does: φ(from) ≥ m puts d* on the piece's inner end (a kink, or e itself); else φ(to) ≥ m puts it
// inside, where a line of slope k has φ ≥ m ⟺ k²(d² − e²) ≥ m²d², d*² = e²k²/(k² − m²), and an
// arc of radius a centred on the axis (h' = d/√(a² − d²)) has φ ≥ m ⟺ d² − e² ≥ m²(a² − d²),
// d*² = (e² + m²a²)/(1 + m²). Then t* = t⊥ − √(d*² − e²)/|v| clamped to the covering interval,
// and S = low + t*·w + h(d(t*)). Three square roots a point (one more per arc), where the scalar
// form spent four to five and a call through the piece list per piece.
struct ProfileLanes : RisingMove {
  const Cutter* cutter = nullptr;
  double m2 = 0, radius = 0;

  ProfileLanes() = default;
  explicit ProfileLanes(const MoveGeometry& m)
      : RisingMove(m), cutter(m.cutter), m2(w * w * inv_vv), radius(m.radius) {}

  // Whether the cutter's pieces all have this closed form (an arc off the axis has not).
  static bool closed_form(const Cutter& c) {
    for (const ProfilePiece& piece : c.pieces())
      if (piece.is_arc && piece.centre_d != 0) return false;
    return true;
  }

  // h at distance d (d ≤ R): the piece holding d, as Cutter::lower_height.
  DoubleN height(DoubleN d) const {
    DoubleN h = splat(0);
    for (const ProfilePiece& piece : cutter->pieces()) {
      const MaskN on = d >= piece.d0;
      if (!any_n(on)) break;
      const DoubleN z =
          piece.is_arc
              ? piece.centre_h - sqrt_n(max_n(piece.radius * piece.radius - d * d, splat(0)))
              : piece.h0 + piece.slope * (d - piece.d0);
      h = on ? z : h;
    }
    return h;
  }

  // φ(d) ≥ m for the piece, from d² (e² = the points' squared distance to the move's line).
  MaskN reaches(const ProfilePiece& piece, DoubleN d2, DoubleN e2) const {
    if (piece.is_arc) {
      const DoubleN a2 = splat(piece.radius * piece.radius);
      return (d2 >= a2) | (d2 - e2 >= m2 * (a2 - d2));
    }
    const double k2 = piece.slope * piece.slope;
    // On the axis φ = h'(0), the piece's slope.
    const MaskN on_axis = d2 <= 0, sloped = k2 * (d2 - e2) >= m2 * d2;
    return k2 >= m2 ? on_axis | sloped : ~on_axis & sloped;
  }

  // h' at distance d (d ≤ R): the piece holding d, as Cutter::lower_slope.
  DoubleN slope(DoubleN d) const {
    DoubleN k = splat(0);
    for (const ProfilePiece& piece : cutter->pieces()) {
      const MaskN on = d >= piece.d0;
      if (!any_n(on)) break;
      const DoubleN z = piece.is_arc
                            ? d / sqrt_n(max_n(piece.radius * piece.radius - d * d, splat(0)))
                            : splat(piece.slope);
      k = on ? z : k;
    }
    return k;
  }

  // S at the points where `wanted` (+infinity elsewhere and where the cutter does not pass).
  DoubleN at(DoubleN ux, DoubleN uy, MaskN wanted) const {
    DoubleN t, d;
    const MaskN covered = lowest(ux, uy, wanted, t, d);
    return covered ? low + t * w + height(d) : splat(kInf);
  }

  // S and its supporting plane's slope at the points (MoveGeometry::supporting_plane): h'(d)/d
  // times q − C(t*). No plane where the cutter does not pass, where q is within 1e-7·R² (in d²)
  // of the rim, or where d is within 1e-8·R of a kink of the profile (MoveGeometry::near_kink:
  // a joint of two pieces, or the axis of a profile that starts sloped).
  using Plane = FlatLanes::Plane;
  Plane plane_at(DoubleN ux, DoubleN uy) const {
    MaskN all{};
    all = all == 0;
    DoubleN t, d;
    const MaskN covered = lowest(ux, uy, all, t, d);
    const DoubleN px = ux - t * vx, py = uy - t * vy, d2 = px * px + py * py;
    const double tolerance = 1e-8 * radius;
    MaskN kink = d <= tolerance;
    if (cutter->pieces().front().derivative(0) == 0) kink = MaskN{};
    for (std::size_t k = 1; k < cutter->pieces().size(); ++k)
      kink |= abs_n(d - cutter->pieces()[k].d0) <= tolerance;
    Plane p;
    p.z = covered ? low + t * w + height(d) : splat(kInf);
    p.has_plane = covered & (d2 < r2 * (1 - 1e-7)) & ~kink;
    const DoubleN factor = (p.has_plane & (d > 0)) ? slope(d) / d : splat(0);
    p.gx = factor * px, p.gy = factor * py;
    return p;
  }

  // Where S is reached, t* and d(t*) (at most R), at the points where `wanted`; the mask of
  // those the cutter passes over.
  MaskN lowest(DoubleN ux, DoubleN uy, MaskN wanted, DoubleN& t, DoubleN& d) const {
    const Cover c = cover(ux, uy);
    const MaskN covered = c.covered & wanted;
    t = d = splat(0);
    if (!any_n(covered)) return covered;
    t = min_n(max_n(c.t_foot, c.lo), c.hi);  // a level move: where the axis comes closest
    if (w > 0) {
      DoubleN root2 = splat(r2);  // φ < m up to the rim: the minimiser leaves the footprint
      MaskN found = ~covered;
      for (const ProfilePiece& piece : cutter->pieces()) {
        const MaskN here = ~found & (c.e2 <= piece.d1 * piece.d1);
        if (!any_n(here)) continue;
        const DoubleN from2 = max_n(splat(piece.d0 * piece.d0), c.e2),
                      to2 = splat(std::min(piece.d1 * piece.d1, r2));
        const MaskN at_from = here & reaches(piece, from2, c.e2);
        const MaskN inside = here & ~at_from & reaches(piece, to2, c.e2);
        const DoubleN explicit2 =
            piece.is_arc ? (c.e2 + m2 * piece.radius * piece.radius) / (1 + m2)
                         : c.e2 * (piece.slope * piece.slope) / (piece.slope * piece.slope - m2);
        root2 = at_from ? from2 : inside ? min_n(max_n(explicit2, from2), to2) : root2;
        found |= at_from | inside;
        if (all_n(found)) break;
      }
      t = min_n(max_n(c.t_foot - sqrt_n(max_n(root2 - c.e2, splat(0))) * inv_len, c.lo), c.hi);
    }
    const DoubleN s = t - c.t_foot;
    d = min_n(sqrt_n(c.e2 + s * s * vv), splat(radius));
    return covered;
  }
};

}  // namespace tridex::detail
