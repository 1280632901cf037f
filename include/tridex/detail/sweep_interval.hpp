// tridex — machinery of sweep.hpp: the interval a dexel ray meets in a convex cutter translated
// with a fixed axis, in closed form.
//
// A ray point x(u) = p + u·e lies in the sweep of a cutter piece K (tip moving from `from` by s·T,
// s ∈ [0, 1]) iff some s puts y = x(u) − from − s·T in K. The pieces here are a frustum (distance
// from the axis ≤ ρ0 + m·(h − lo) for heights h ∈ [lo, hi]: flat, cone, chamfer and shank
// cylinders) and a ball centred on the axis (ball and tapered-ball tips). Each is a quadratic
// inequality F(u, s) ≤ 0 with linear side conditions (0 ≤ s ≤ 1, lo ≤ h ≤ hi), a compact convex set
// in the (u, s) plane; the ray's interval is that set's extent in u. The extremes of a linear
// function over such a set lie at a vertex of the side conditions, where a side line meets the
// conic, or where the conic's tangent is parallel to the s axis (∂F/∂s = 0): a handful of
// quadratics, no search. The bull nose's torus is no quadric; sweep.hpp searches it instead.
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/geometry.hpp"

namespace tridex::detail {

// One convex piece of a cutter over heights [lo, hi] above the tip: a frustum (radius
// rho0 + slope·(h − lo)) or a ball of `radius` centred `centre` above the tip on the axis.
struct SweepPiece {
  double lo = 0, hi = 0;
  bool ball = false;
  double rho0 = 0, slope = 0;
  double centre = 0, radius = 0;
};

// F(u, s) = A u² + 2B us + C s² + 2D u + 2E s + G.
struct SweepConic {
  double a = 0, b = 0, c = 0, d = 0, e = 0, g = 0;
  double at(double u, double s) const {
    return a * u * u + 2 * b * u * s + c * s * s + 2 * d * u + 2 * e * s + g;
  }
  // Adds sign·(g0 + u·g1 + s·g2)².
  void add_square(double g0, double g1, double g2, double sign) {
    a += sign * g1 * g1, b += sign * g1 * g2, c += sign * g2 * g2;
    d += sign * g0 * g1, e += sign * g0 * g2, g += sign * g0 * g0;
  }
};

// A side condition lu·u + ls·s + l0 ≥ 0.
struct SweepSide {
  double lu = 0, ls = 0, l0 = 0;
  double at(double u, double s) const { return lu * u + ls * s + l0; }
};

// The real roots of q2 x² + q1 x + q0 (none when all vanish: the caller's vertices cover a line
// lying in the set). A discriminant a rounding below zero counts as a double root (tangency).
template <class Out>
void sweep_roots(double q2, double q1, double q0, Out&& out) {
  const double scale = std::abs(q2) + std::abs(q1) + std::abs(q0);
  if (!(scale > 0)) return;
  if (std::abs(q2) <= 1e-13 * scale) {
    if (std::abs(q1) > 1e-13 * scale) out(-q0 / q1);
    return;
  }
  double disc = q1 * q1 - 4 * q2 * q0;
  if (disc < 0) {
    if (disc < -1e-12 * (q1 * q1 + std::abs(4 * q2 * q0))) return;
    disc = 0;
  }
  const double q = -0.5 * (q1 + std::copysign(std::sqrt(disc), q1));
  out(q / q2);
  if (q != 0) out(q0 / q);
}

// F restricted to the line s = s0 + s1·u, as a quadratic in u.
inline void sweep_along_s(const SweepConic& f, double s0, double s1, double& q2, double& q1,
                          double& q0) {
  q2 = f.a + 2 * f.b * s1 + f.c * s1 * s1;
  q1 = 2 * (f.b * s0 + f.c * s0 * s1 + f.d + f.e * s1);
  q0 = f.c * s0 * s0 + 2 * f.e * s0 + f.g;
}

// The extent in u of {F ≤ 0} ∩ sides, or nullopt if empty. `tol`: slack in mm for the tests of
// candidate points (F is about 2·radius·distance near the surface).
inline std::optional<std::pair<double, double>> sweep_conic_range(const SweepConic& f,
                                                                  std::span<const SweepSide> sides,
                                                                  double f_tol, double tol) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  auto consider = [&](double u, double s) {
    if (u >= lo && u <= hi) return;  // cannot widen the extent: no need to test it
    if (!std::isfinite(u) || !std::isfinite(s)) return;
    for (const SweepSide& side : sides)
      if (side.at(u, s) < -tol) return;
    if (f.at(u, s) > f_tol) return;
    lo = std::min(lo, u), hi = std::max(hi, u);
  };
  double q2, q1, q0;
  if (std::abs(f.c) > 1e-14 * (std::abs(f.a) + std::abs(f.b) + std::abs(f.c))) {
    const double s1 = -f.b / f.c, s0 = -f.e / f.c;  // ∂F/∂s = 0
    sweep_along_s(f, s0, s1, q2, q1, q0);
    sweep_roots(q2, q1, q0, [&](double u) { consider(u, s0 + s1 * u); });
  }
  for (const SweepSide& side : sides) {
    if (std::abs(side.ls) >= std::abs(side.lu)) {
      if (side.ls == 0) continue;
      const double s1 = -side.lu / side.ls, s0 = -side.l0 / side.ls;
      sweep_along_s(f, s0, s1, q2, q1, q0);
      sweep_roots(q2, q1, q0, [&](double u) { consider(u, s0 + s1 * u); });
    } else {
      const double u1 = -side.ls / side.lu, u0 = -side.l0 / side.lu;  // u = u0 + u1·s
      q2 = f.a * u1 * u1 + 2 * f.b * u1 + f.c;
      q1 = 2 * (f.a * u0 * u1 + f.b * u0 + f.d * u1 + f.e);
      q0 = f.a * u0 * u0 + 2 * f.d * u0 + f.g;
      sweep_roots(q2, q1, q0, [&](double s) { consider(u0 + u1 * s, s); });
    }
  }
  for (std::size_t i = 0; i < sides.size(); ++i)
    for (std::size_t j = i + 1; j < sides.size(); ++j) {
      const SweepSide &p = sides[i], &q = sides[j];
      const double det = p.lu * q.ls - q.lu * p.ls;
      if (std::abs(det) <= 1e-14 * (std::abs(p.lu * q.ls) + std::abs(q.lu * p.ls))) continue;
      consider((-p.l0 * q.ls + q.l0 * p.ls) / det, (-p.lu * q.l0 + q.lu * p.l0) / det);
    }
  if (!(lo <= hi)) return std::nullopt;
  return std::pair{lo, hi};
}

// sweep_conic_range for a frustum's sides s ≥ 0, s ≤ 1 and lo ≤ h ≤ hi, where the height
// above the tip is h = hw + hu·u + hs·s (l_lo = hw − lo, l_hi = hi − hw): the same candidates,
// computed as it computes them, each tested only against the sides it does not lie on. A point
// on a side's line satisfies that side and the one parallel to it (hi − lo apart) to within
// rounding far below `tol`, so the extent is the same, at a fraction of the cost (a bull nose's
// chords cost about one such solve a ray·sub-step near the cutter).
inline std::optional<std::pair<double, double>> sweep_frustum_range(const SweepConic& f, double hu,
                                                                    double hs, double l_lo,
                                                                    double l_hi, double f_tol,
                                                                    double tol) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  auto accept = [&](double u, double s) {
    if (f.at(u, s) > f_tol) return;
    lo = std::min(lo, u), hi = std::max(hi, u);
  };
  auto in_s = [&](double s) { return s >= -tol && -s + 1 >= -tol; };
  auto in_h = [&](double u, double s) {
    return hu * u + hs * s + l_lo >= -tol && -hu * u + -hs * s + l_hi >= -tol;
  };
  double q2, q1, q0;
  if (std::abs(f.c) > 1e-14 * (std::abs(f.a) + std::abs(f.b) + std::abs(f.c))) {
    const double s1 = -f.b / f.c, s0 = -f.e / f.c;  // ∂F/∂s = 0
    sweep_along_s(f, s0, s1, q2, q1, q0);
    sweep_roots(q2, q1, q0, [&](double u) {
      if (u >= lo && u <= hi) return;
      const double s = s0 + s1 * u;
      if (std::isfinite(u) && std::isfinite(s) && in_s(s) && in_h(u, s)) accept(u, s);
    });
  }
  for (const double s : {0.0, 1.0}) {  // the sweep's ends: F along s = 0 and s = 1
    q2 = f.a, q1 = s == 0 ? 2 * f.d : 2 * (f.b + f.d), q0 = s == 0 ? f.g : f.c + 2 * f.e + f.g;
    sweep_roots(q2, q1, q0, [&](double u) {
      if (u >= lo && u <= hi) return;
      if (std::isfinite(u) && in_h(u, s)) accept(u, s);
    });
  }
  const SweepSide slab[2] = {{hu, hs, l_lo}, {-hu, -hs, l_hi}};
  for (const SweepSide& side : slab) {  // the lines h = lo and h = hi
    if (std::abs(side.ls) >= std::abs(side.lu)) {
      if (side.ls == 0) continue;
      const double s1 = -side.lu / side.ls, s0 = -side.l0 / side.ls;
      sweep_along_s(f, s0, s1, q2, q1, q0);
      sweep_roots(q2, q1, q0, [&](double u) {
        if (u >= lo && u <= hi) return;
        const double s = s0 + s1 * u;
        if (std::isfinite(u) && std::isfinite(s) && in_s(s)) accept(u, s);
      });
    } else {
      const double u1 = -side.ls / side.lu, u0 = -side.l0 / side.lu;  // u = u0 + u1·s
      q2 = f.a * u1 * u1 + 2 * f.b * u1 + f.c;
      q1 = 2 * (f.a * u0 * u1 + f.b * u0 + f.d * u1 + f.e);
      q0 = f.a * u0 * u0 + 2 * f.d * u0 + f.g;
      sweep_roots(q2, q1, q0, [&](double s) {
        const double u = u0 + u1 * s;
        if (u >= lo && u <= hi) return;
        if (std::isfinite(u) && std::isfinite(s) && in_s(s)) accept(u, s);
      });
    }
  }
  if (hu != 0) {  // the four corners (s = 0 or 1, h = lo or hi)
    const double corners[4][2] = {
        {l_lo / -hu, 0}, {l_hi / hu, 0}, {(-hs - l_lo) / hu, 1}, {(hs - l_hi) / -hu, 1}};
    for (const auto& c : corners)
      if (!(c[0] >= lo && c[0] <= hi) && std::isfinite(c[0])) accept(c[0], c[1]);
  }
  if (!(lo <= hi)) return std::nullopt;
  return std::pair{lo, hi};
}

// The interval of the ray x(u) = point + u·e_axis (point's axis coordinate ignored) in the
// capsule of radius r around the segment c0–c1: the hull of the ray's crossings with the two end
// balls and with the side cylinder where it lies between them (the capsule is convex and its
// boundary is made of these; the ray–cylinder quadratic as in Quílez's capsule intersection).
inline std::optional<std::pair<double, double>> capsule_interval(const Vec3& c0, const Vec3& c1,
                                                                 double r, const Vec3& point,
                                                                 int axis) {
  double lo = std::numeric_limits<double>::infinity(), hi = -lo;
  Vec3 m = point - c0;
  m[axis] = -c0[axis];
  const Vec3 d = c1 - c0;
  const double me = m[axis], mm = glm::dot(m, m), r2 = r * r;
  auto ball = [&](double b, double c) {  // u² + 2bu + c = 0
    const double disc = b * b - c;
    if (disc < 0) return;
    const double root = std::sqrt(disc);
    lo = std::min(lo, -b - root), hi = std::max(hi, -b + root);
  };
  ball(me, mm - r2);
  const double dd = glm::dot(d, d);
  if (dd > 0) {
    const Vec3 m1 = m - d;
    ball(m1[axis], glm::dot(m1, m1) - r2);
    const double md = glm::dot(m, d), nd = d[axis];
    const double a = dd - nd * nd, b = dd * me - nd * md, c = dd * (mm - r2) - md * md;
    const double disc = b * b - a * c;
    if (a > 1e-12 * dd && disc >= 0) {
      const double root = std::sqrt(disc);
      for (const double u : {(-b - root) / a, (-b + root) / a}) {
        const double t = md + u * nd;  // dd × the parameter of the nearest segment point
        if (t >= 0 && t <= dd) lo = std::min(lo, u), hi = std::max(hi, u);
      }
    }
  }
  if (!(lo <= hi)) return std::nullopt;
  return std::pair{lo, hi};
}

// The interval of the ray x(u) = point + u·e_ray_axis (point's ray-axis coordinate ignored) in
// the sweep of `piece` with unit axis `axis`, tip from `from` moved by `travel`.
inline std::optional<std::pair<double, double>> sweep_piece_interval(
    const SweepPiece& piece, const Vec3& from, const Vec3& travel, const Vec3& axis,
    const Vec3& point, int ray_axis) {
  if (piece.ball) {
    const Vec3 c0 = from + piece.centre * axis;
    return capsule_interval(c0, c0 + travel, piece.radius, point, ray_axis);
  }
  Vec3 w = point - from;
  w[ray_axis] = -from[ray_axis];
  const double hw = glm::dot(w, axis), hu = axis[ray_axis], hs = -glm::dot(travel, axis);
  // |y|² − h² − (ρ0 + m(h − lo))²: the squared distance from the axis less the squared radius.
  SweepConic f;
  for (int i = 0; i < 3; ++i) f.add_square(w[i], i == ray_axis ? 1.0 : 0.0, -travel[i], 1);
  f.add_square(hw, hu, hs, -1);
  const double m = piece.slope;
  f.add_square(piece.rho0 + m * (hw - piece.lo), m * hu, m * hs, -1);
  const double size = piece.hi + glm::length(travel) + piece.rho0 + m * (piece.hi - piece.lo);
  const double tol = 1e-9 * (1 + size);
  return sweep_frustum_range(f, hu, hs, hw - piece.lo, piece.hi - hw, 2 * tol * (1 + size), tol);
}

// `p` grown by e ≥ 0: a ball's radius by e; a frustum's heights by e each way and its side moved
// e outward (its radius by e·√(1 + m²) at each height). It holds every point within e of `p`: the
// offset of an intersection of half-spaces lies within the intersection of their offsets.
inline SweepPiece sweep_grown_piece(const SweepPiece& p, double e) {
  if (p.ball) return {p.lo - e, p.hi + e, true, 0, 0, p.centre, p.radius + e};
  const double rho0 = p.rho0 - p.slope * e + e * std::sqrt(1 + p.slope * p.slope);
  return {p.lo - e, p.hi + e, false, rho0, p.slope, 0, 0};
}

// A frustum of slope |m| at least this is grown with its widening end capped
// (sweep_grown_interval). A cap costs a second solve; a bull nose's chords of slope 1–4 capped as
// well let as many of its groups through (2·10^4 segments: 670 k against 674 k, 733 k with no cap)
// for 4 % more solves.
inline constexpr double kSweepCapSlope = 4;

// The interval of the ray x(u) = point + u·e_ray_axis in the sweep of `p` grown by e > 0: the
// offset cone of sweep_grown_piece, carried e past the piece's end heights, widens there by
// (|m| + √(1 + m²) − 1)·e beyond rho_max + e, the largest distance from the axis of any point
// within e of `p` (thirty times e for a bull nose's lowest, nearly flat chord: a group bound that
// loose reaches material its members do not). For |m| ≥ kSweepCapSlope that end is capped by the
// cylinder of radius rho_max + e: the cone where it is narrower, the cylinder beyond, two pieces
// whose union (convex: the radius bound is the least of a linear function and a constant) still
// holds every point within e of `p`; the interval is the hull of theirs.
inline std::optional<std::pair<double, double>> sweep_grown_interval(
    const SweepPiece& p, double e, const Vec3& from, const Vec3& travel, const Vec3& axis,
    const Vec3& point, int ray_axis) {
  const SweepPiece g = sweep_grown_piece(p, e);
  const double m = p.slope;
  if (p.ball || std::abs(m) < kSweepCapSlope)
    return sweep_piece_interval(g, from, travel, axis, point, ray_axis);
  const double cap = std::max(p.rho0, p.rho0 + m * (p.hi - p.lo)) + e;
  const double h = g.lo + (cap - g.rho0) / m;  // where the offset cone's radius is `cap`
  const SweepPiece cone = m > 0 ? SweepPiece{g.lo, h, false, g.rho0, m, 0, 0}
                                : SweepPiece{h, g.hi, false, cap, m, 0, 0};
  const SweepPiece cylinder =
      m > 0 ? SweepPiece{h, g.hi, false, cap, 0, 0, 0} : SweepPiece{g.lo, h, false, cap, 0, 0, 0};
  const auto a = sweep_piece_interval(cone, from, travel, axis, point, ray_axis);
  const auto b = sweep_piece_interval(cylinder, from, travel, axis, point, ray_axis);
  if (!a || !b) return a ? a : b;
  return std::pair{std::min(a->first, b->first), std::max(a->second, b->second)};
}

// What sweep_pieces_hull tests a piece by, computed once: its heights above the tip, its largest
// radius, the farthest of its points from the tip, and how much its largest radius grows per
// unit it is grown by (sweep_grown_interval).
struct SweepPieceSpan {
  double h0 = 0, h1 = 0, rho = 0, reach = 0, widen = 1;
};

inline SweepPieceSpan sweep_piece_span(const SweepPiece& p) {
  SweepPieceSpan b;
  b.h0 = p.ball ? p.centre - p.radius : p.lo, b.h1 = p.ball ? p.centre + p.radius : p.hi;
  b.rho = p.ball ? p.radius : std::max(p.rho0, p.rho0 + p.slope * (b.h1 - b.h0));
  b.reach = std::hypot(b.rho, std::max(std::abs(b.h0), std::abs(b.h1)));
  if (!p.ball && std::abs(p.slope) < kSweepCapSlope)
    b.widen = std::abs(p.slope) + std::sqrt(1 + p.slope * p.slope);
  return b;
}

// The hull of the intervals of the ray x(u) = point + u·e_ray_axis in the sweeps of `pieces`, each
// grown by grow(piece) ≥ 0 (sweep_grown_interval), with unit axis `axis`, tip from `from` moved by
// `travel`, where they may meet material lying within [lo, hi]; nullopt if none may. `spans`: the
// pieces' sweep_piece_span, grow(k) ≥ 0 how far piece k is grown. Only pieces k < 64 whose bit is
// set in `only` are taken (and all others); `met` gets the bits of those not skipped for missing
// the ray or the material (whatever the hull): a piece grown by e holds the piece moved by e.
//
// A piece between heights h0 and h1 above the tip meets the ray only where the ray's height
// above the moving tip, w + u·axis[ray_axis] − s·(travel·axis) for some s ∈ [0, 1], lies in
// [h0, h1] (w: that height at u = 0): a range of u found with no root. A piece is skipped when
// that range (grown by `margin`, far above the conic solve's slack) lies within the hull of the
// pieces already cut (it cannot widen it) or misses [lo, hi] (it meets no material: the hull of
// the others, less what lies outside the material, removes the same). Pieces are taken top first,
// then bottom, where a ray along the axis enters and leaves, so that the middle ones are skipped.
// Seen along the ray, a piece lies within the cylinder of its largest radius ρ between h0 and h1,
// whose shadow is an ellipse (semi-axes ρ, and ρ·|axis along the ray| along the axis's shadow)
// moved (h1 − h0)/2·|axis across the ray| each way along that shadow, and along the travel.
// Stretched by 1/|axis along the ray| along the shadow, that is a disc of radius ρ around a
// segment, moved along the stretched travel (within half its length of its middle): a piece
// farther than that from the ray is skipped too. Where the axis lies nearly across the ray the
// stretch is ill-conditioned: the circle of radius ρ around the path of its middle height is used.
struct SweepNeverEnough {
  bool operator()(const std::pair<double, double>&) const { return false; }
};

template <class Grow, class Enough = SweepNeverEnough>
std::optional<std::pair<double, double>> sweep_pieces_hull(
    std::span<const SweepPiece> pieces, std::span<const SweepPieceSpan> spans, double margin,
    const Vec3& from, const Vec3& travel, const Vec3& axis, const Vec3& point, int ray_axis,
    double lo, double hi, Grow&& grow, std::uint64_t only = ~std::uint64_t{0},
    std::uint64_t* met = nullptr, Enough&& enough = {}) {
  std::optional<std::pair<double, double>> hull;
  Vec3 w = point - from;
  w[ray_axis] = -from[ray_axis];
  const double w0 = glm::dot(w, axis), along = axis[ray_axis];
  const double shift = -glm::dot(travel, axis);
  const double s_lo = std::min(0.0, shift), s_hi = std::max(0.0, shift);
  const bool slabs = std::abs(along) > 1e-6;
  const std::size_t n = pieces.size();
  const int iu = (ray_axis + 1) % 3, iv = (ray_axis + 2) % 3;
  const double tu = travel[iu], tv = travel[iv], tt = tu * tu + tv * tv;
  const double au = axis[iu], av = axis[iv], across = std::sqrt(au * au + av * av);
  const double qu = point[iu] - from[iu], qv = point[iv] - from[iv];
  const double along_abs = std::abs(along);
  const bool ellipse = along_abs > 0.05 && across > 1e-9;
  // The ellipse test's stretched coordinates of the ray about a piece's middle height hm: x
  // across the axis's shadow (the same for every height) and y = |y0 − hm·k| along it.
  double x2 = 0, y0 = 0, k = 0, slack = 0;
  if (ellipse) {
    const double tx = (-tu * av + tv * au) / across,
                 ty = (tu * au + tv * av) / (across * along_abs);
    slack = 0.5 * std::sqrt(tx * tx + ty * ty) + margin / along_abs;
    const double pu = qu - 0.5 * tu, pv = qv - 0.5 * tv;
    const double x = (-pu * av + pv * au) / across;
    x2 = x * x;
    y0 = (pu * au + pv * av) / (across * along_abs);
    k = across / along_abs;
  }
  // The least squared distance, seen along the ray, from the ray to the path of axis height h.
  auto off_path2 = [&](double h) {
    const double du = qu - h * au, dv = qv - h * av;
    const double t = tt > 0 ? std::clamp((du * tu + dv * tv) / tt, 0.0, 1.0) : 0.0;
    return (du - t * tu) * (du - t * tu) + (dv - t * tv) * (dv - t * tv);
  };
  std::uint64_t done = 0;
  for (std::size_t j = 0; j < n; ++j) {
    const std::size_t i = j == 0 ? n - 1 : j - 1;
    const std::uint64_t bit = i < 64 ? std::uint64_t{1} << i : 0;
    if (i < 64 && !(only & bit)) continue;
    done |= bit;
    const double e = grow(i);
    const SweepPieceSpan& span = spans[i];
    const double h0 = span.h0 - e, h1 = span.h1 + e;
    double u0 = 0, u1 = 0;
    if (slabs) {  // the cheaper test first: both only skip a piece
      u0 = (h0 - margin - w0 - s_hi) / along, u1 = (h1 + margin - w0 - s_lo) / along;
      if (u0 > u1) std::swap(u0, u1);
      if (u1 < lo - margin || u0 > hi + margin) continue;
    }
    const double rho = span.rho + e * span.widen;
    if (ellipse) {
      const double y = std::max(0.0, std::abs(y0 - 0.5 * (h0 + h1) * k) - 0.5 * (h1 - h0) * k);
      const double reach = rho + slack;
      if (x2 + y * y > reach * reach) continue;
    } else {
      const double reach = rho + margin + 0.5 * (h1 - h0) * across;
      if (off_path2(0.5 * (h0 + h1)) > reach * reach) continue;
    }
    if (met) *met |= bit;
    if (slabs && hull && hull->first <= u0 && u1 <= hull->second) continue;
    const auto cut = e > 0 ? sweep_grown_interval(pieces[i], e, from, travel, axis, point, ray_axis)
                           : sweep_piece_interval(pieces[i], from, travel, axis, point, ray_axis);
    if (!cut || cut->second < lo - margin || cut->first > hi + margin) {
      if (met) *met &= ~bit;
      if (!cut) continue;
    }
    // The part is convex, so its pieces' intervals on one ray overlap: their hull is the union.
    hull = hull ? std::pair{std::min(hull->first, cut->first), std::max(hull->second, cut->second)}
                : *cut;
    if (enough(*hull)) {  // the pieces not yet taken may meet the ray
      if (met) *met |= only & ~done;
      break;
    }
  }
  return hull;
}

// Appends the frustum between meridian points (d0, h0) and (d1, h1), h1 > h0, clipped to [lo, hi].
inline void sweep_frustum(double d0, double h0, double d1, double h1, double lo, double hi,
                          std::vector<SweepPiece>& out) {
  if (h1 <= lo || h0 >= hi || h1 <= h0) return;  // a flat bottom: the face of the piece above it
  const double slope = (d1 - d0) / (h1 - h0), a = std::max(lo, h0), b = std::min(hi, h1);
  out.push_back({a, b, false, d0 + slope * (a - h0), slope, 0, 0});
}

// The convex pieces of cutter `c` cut at `height` between heights lo and hi; false if an arc off
// the axis (the bull nose's torus, no quadric) is met and `chord` is 0. With `chord` > 0 such an
// arc is replaced by inscribed chords (frusta) whose sagitta is at most `chord`: the pieces then
// lie inside the cutter and the cutter within `error` (the largest sagitta) of them. An arc
// centred on the axis is the whole ball (it lies inside the cutter: the profile above it is
// tangent or wider), so a piece list with a ball may reach above `hi` by up to the ball's radius,
// never outside the cutter.
inline bool sweep_pieces(const Cutter& c, double height, double lo, double hi, double chord,
                         std::vector<SweepPiece>& out, double& error) {
  for (const ProfilePiece& p : c.pieces()) {
    const double h0 = p.height(p.d0), h1 = p.height(p.d1);
    if (h1 <= lo || h0 >= hi) continue;
    if (!p.is_arc) {
      sweep_frustum(p.d0, h0, p.d1, h1, lo, hi, out);
      continue;
    }
    if (p.centre_d == 0 && p.d0 == 0 && p.centre_h + p.radius <= height) {
      out.push_back({0, p.centre_h + p.radius, true, 0, 0, p.centre_h, p.radius});
      continue;
    }
    if (!(chord > 0)) return false;
    // The lower arc at angles from the downward vertical: d = centre_d + radius·sin(angle).
    const double a0 = std::asin(std::clamp((p.d0 - p.centre_d) / p.radius, -1.0, 1.0));
    const double a1 = std::asin(std::clamp((p.d1 - p.centre_d) / p.radius, -1.0, 1.0));
    const double step = 2 * std::acos(std::max(0.0, 1 - chord / p.radius));
    const int k = std::max(1, static_cast<int>(std::ceil((a1 - a0) / step)));
    error = std::max(error, p.radius * (1 - std::cos((a1 - a0) / (2 * k))));
    for (int i = 0; i < k; ++i) {
      const double b0 = a0 + (a1 - a0) * i / k, b1 = a0 + (a1 - a0) * (i + 1) / k;
      sweep_frustum(p.centre_d + p.radius * std::sin(b0), p.centre_h - p.radius * std::cos(b0),
                    p.centre_d + p.radius * std::sin(b1), p.centre_h - p.radius * std::cos(b1), lo,
                    hi, out);
    }
  }
  const double top = std::max(lo, c.profile_height()), end = std::min(hi, height);
  if (end > top) out.push_back({top, end, false, c.radius(), 0, 0, 0});
  return true;
}

}  // namespace tridex::detail
