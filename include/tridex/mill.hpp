// tridex — Z-map milling (Step 1 of Inui, Chen and Umezu, CAD&A 19(4) 2022, §3.1).
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
//
// Speed comes from touching only what a move can still lower (Miller below). S is convex too (the
// lower surface of a convex swept solid), so its tangent plane at any point bounds it from below
// everywhere; for the ball end S also rises at least quadratically across the move (BallLanes).
// The grid is cut into 16×16-point tiles and the tiles into 8×8-tile work blocks, milled on all
// threads. A block is milled one row of tiles at a time, in two passes over its moves:
//   1. every move is bounded over every tile of the row it reaches, by S's tangent plane at the
//      tile's centre, and each tile is cut first by the move lowest at its centre among those
//      whose footprint covers the whole tile (if any does): that leaves it close to its final
//      shape, and that move's plane P then follows its surface;
//   2. the moves whose bound is still below the tile's highest point, and below max(height − P)
//      when measured from P (so that sloped surfaces skip as well as flat ones), cut the tile
//      row by row, each row read once and lowered by every move admitted there.
// Ball end moves are bounded kLanes tiles at a time and evaluated kLanes points at a time, with
// one square root per point (BallLanes); flat end and bull nose moves are bounded and evaluated
// kLanes at a time too (FlatLanes: a closed form; BullLanes: the still cutter where the minimum is
// at an end of the move, else Halley steps with no square root), and so are the other cutters'
// moves (ProfileLanes: a closed form per profile piece). The moves
// left for a tile in pass 2 are cut lowest bound first, a run of one cutter at a time, each run
// checked against what the tile holds by then: so a tile first cut by any cutter, or roughed
// deeper by another cutter, still rejects the moves that cut air. Runs of other cutters than the
// ball end are short, and each flat end move is checked against each row as it stands by then
// (its neighbouring passes cut nearly equal surfaces: Miller::cut_others). Every point ends at
// the minimum over moves of a value computed the same way whatever the order (a move is skipped
// only where it cannot lower a point), so the result is identical for any thread count and any
// move order (for one build: the vector width and FMA contraction change the last bits).
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#if defined(__SSE2__) || defined(__AVX__) || defined(__AVX512F__)
#include <immintrin.h>
#endif

#include "tridex/cutter.hpp"
#include "tridex/error.hpp"
#include "tridex/geometry.hpp"
#include "tridex/parallel.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

// A straight move of the tool tip in the Z-map's frame, cut with cutters[cutter].
struct CutMove {
  Segment tip;
  std::uint32_t cutter = 0;
};

struct MillOptions {
  unsigned threads = 0;  // 0: every hardware thread
};

namespace detail {

constexpr int kTile = 16;        // points along each side of a tile
constexpr int kBinTiles = 8;     // tiles along each side of a work block
constexpr double kInf = std::numeric_limits<double>::infinity();
// Moves of a flat end or a bull nose milled together before the tile is measured again (see
// Miller::cut_others): 1, 2, 4, 8 and 16 measured on the flat end's raster of bench_mill, 8 best.
constexpr std::ptrdiff_t kOtherRun = 8;

// Doubles processed as one value (GCC/Clang vector extension): eight with AVX-512, four with
// AVX, two with the SSE2 of every x86-64, two in plain scalar code elsewhere; the compiler's
// target decides (the project's build picks the building machine's, see TRIDEX_SIMD in
// CMakeLists.txt). Comparisons give a MaskN of all-ones/all-zeros lanes.
#if defined(__AVX512F__)
using DoubleN = double __attribute__((vector_size(64)));
using MaskN = long long __attribute__((vector_size(64)));
using FloatN = float __attribute__((vector_size(32)));
#elif defined(__AVX__)
using DoubleN = double __attribute__((vector_size(32)));
using MaskN = long long __attribute__((vector_size(32)));
using FloatN = float __attribute__((vector_size(16)));
#else
using DoubleN = double __attribute__((vector_size(16)));
using MaskN = long long __attribute__((vector_size(16)));
using FloatN = float __attribute__((vector_size(8)));
#endif
constexpr int kLanes = static_cast<int>(sizeof(DoubleN) / sizeof(double));
inline DoubleN splat(double v) { return DoubleN{} + v; }
inline DoubleN load_n(const double* p) {
  DoubleN v;
  __builtin_memcpy(&v, p, sizeof v);
  return v;
}
inline void store_n(double* p, DoubleN v) { __builtin_memcpy(p, &v, sizeof v); }
inline DoubleN min_n(DoubleN a, DoubleN b) { return a < b ? a : b; }
inline DoubleN max_n(DoubleN a, DoubleN b) { return a > b ? a : b; }
inline DoubleN abs_n(DoubleN a) { return a < 0 ? -a : a; }
inline DoubleN sqrt_n(DoubleN a) {
#if defined(__AVX512F__)
  // The masked form: GCC 12 warns of an uninitialised operand in _mm512_sqrt_pd.
  const __m512d v = reinterpret_cast<__m512d>(a);
  return reinterpret_cast<DoubleN>(_mm512_mask_sqrt_pd(v, static_cast<__mmask8>(0xff), v));
#elif defined(__AVX__)
  return reinterpret_cast<DoubleN>(_mm256_sqrt_pd(reinterpret_cast<__m256d>(a)));
#elif defined(__SSE2__)
  return reinterpret_cast<DoubleN>(_mm_sqrt_pd(reinterpret_cast<__m128d>(a)));
#else
  return DoubleN{std::sqrt(a[0]), std::sqrt(a[1])};
#endif
}
inline bool any_n(MaskN m) {
#if defined(__AVX512F__)
  return _mm512_test_epi64_mask(reinterpret_cast<__m512i>(m), reinterpret_cast<__m512i>(m)) != 0;
#elif defined(__AVX__)
  return _mm256_movemask_pd(reinterpret_cast<__m256d>(m)) != 0;
#elif defined(__SSE2__)
  return _mm_movemask_pd(reinterpret_cast<__m128d>(m)) != 0;
#else
  return (m[0] | m[1]) != 0;
#endif
}
inline bool all_n(MaskN m) {
#if defined(__AVX512F__)
  return _mm512_test_epi64_mask(reinterpret_cast<__m512i>(m), reinterpret_cast<__m512i>(m)) == 0xff;
#elif defined(__AVX__)
  return _mm256_movemask_pd(reinterpret_cast<__m256d>(m)) == (1 << kLanes) - 1;
#elif defined(__SSE2__)
  return _mm_movemask_pd(reinterpret_cast<__m128d>(m)) == (1 << kLanes) - 1;
#else
  return (m[0] & m[1]) != 0;
#endif
}
// Bit l set where lane l of m is set.
inline std::uint32_t lane_bits(MaskN m) {
#if defined(__AVX512F__)
  return _mm512_test_epi64_mask(reinterpret_cast<__m512i>(m), reinterpret_cast<__m512i>(m));
#elif defined(__AVX__)
  return static_cast<std::uint32_t>(_mm256_movemask_pd(reinterpret_cast<__m256d>(m)));
#elif defined(__SSE2__)
  return static_cast<std::uint32_t>(_mm_movemask_pd(reinterpret_cast<__m128d>(m)));
#else
  return (m[0] != 0 ? 1u : 0u) | (m[1] != 0 ? 2u : 0u);
#endif
}
inline double max_lane(DoubleN a) {
  double m = a[0];
  for (int l = 1; l < kLanes; ++l) m = std::max(m, a[l]);
  return m;
}
inline DoubleN lane_index() {
  DoubleN lane{};
  for (int l = 0; l < kLanes; ++l) lane[l] = l;
  return lane;
}

// The squared distance from points at offsets (ux, uy) from a move's start to its path (v, and
// 1/|v|² > 0).
inline DoubleN path_distance2(DoubleN ux, DoubleN uy, double vx, double vy, double inv_vv) {
  const DoubleN along = min_n(max_n((ux * vx + uy * vy) * inv_vv, splat(0)), splat(1));
  const DoubleN dx = ux - along * vx, dy = uy - along * vy;
  return dx * dx + dy * dy;
}

// The geometry of one move, in coordinates relative to its start point.
struct MoveGeometry {
  const Cutter* cutter;
  double ax, ay, az;   // start of the tip path
  double vx, vy, w;    // horizontal displacement and rise
  double vv;           // vx² + vy²
  double inv_vv, inv_len, ball_factor;
  double radius, radius2;
  bool vertical;       // no horizontal displacement: a plunge, a retract or a point

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
    double t_foot = (ux * vx + uy * vy) * inv_vv;           // foot of q on the move's line
    double e2 = std::max(0.0, uu - t_foot * t_foot * vv);   // squared distance to the line
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
        if (w > 0) hi = std::max(lo, flat_lo);
        else lo = std::min(hi, flat_hi);
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
// The cylinder's gradient is w·v/|v|² + (1 + w²/|v|²)·(u − t⊥·v)/√(…) and a sphere's (u − t·v)/√(…),
// the supporting plane of MoveGeometry::supporting_plane in other terms.
//
// Across the move S also rises at least quadratically from that plane: with n the move's unit
// horizontal normal,  S(q) ≥ S(c) + ∇S(c)·(q − c) + ((q − c)·n)² / 2R  ("across"). Proof: the
// ball's lower surface h(|p|) has curvature ≥ 1/R in every direction, so h(|p|) − (p·n + κ)²/2R
// is convex in p; p = q − C(t) is affine in (q, t), and p·n differs from (q − c)·n by a constant
// along a straight move; so S(q) − ((q − c)·n)²/2R, a minimum over t of a function jointly convex
// in (q, t), is convex, and lies above its tangent plane at c.
struct BallLanes {
  double ax = 0, ay = 0, top = 0;  // start of the (rising) move; top = its tip + R, the ball's centre
  double vx = 0, vy = 0, w = 0, vv = 0, inv_vv = 0, stretch = 1, c2 = 0, radius = 0, r2 = 0, inv_diameter = 0, rim = 0;
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
    MaskN before, after;   // t* < 0, t* > 1
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

  DoubleN base(const Cases& c) const { return c.before ? splat(top) : c.after ? splat(top + w) : top + c.t_foot * w; }

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
    const DoubleN scale = sloped ? w * inv_vv / max_n(c.half, splat(side)) : splat(0);  // w·∇t_edge across
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
    const DoubleN reach = max_n(dist - flat, splat(0)), root2 = max_n(corner2 - reach * reach, splat(0));
    const DoubleN root = sqrt_n(root2);
    const DoubleN factor = p.has_plane & (reach > 0) ? reach / (max_n(root, splat(corner * 1e-7)) * dist) : splat(0);
    p.z = d[0] < kInf ? low + t[0] * w + (corner - root) : splat(kInf);
    p.gx = factor * px, p.gy = factor * py;
    return p;
  }

  // Where S is reached, t* and d(t*), at the points where `wanted` (d = +infinity elsewhere and
  // where the cutter does not pass); false if no point is wanted.
  template <int G>
  bool lowest(const DoubleN (&ux)[G], DoubleN uy, const MaskN (&wanted)[G], DoubleN (&t)[G], DoubleN (&d)[G]) const {
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
      const DoubleN dot = ux[g] * vx + uy * vy, uu = ux[g] * ux[g] + uy * uy, ex = ux[g] - vx, ey = uy - vy;
      t_foot[g] = dot * inv_vv;
      e2[g] = max_n(uu - t_foot[g] * dot, splat(0));
      // Where the root lies before the start or past the end, S is the cutter at that end (see
      // above): Q(ρ_a) ≤ 0 at the start's reach ρ_a = |u| − R0, Q(ρ_b) ≥ 0 at the end's. There q
      // is covered if that end covers it; inside, if e ≤ R (then ρ* ≤ r, as Q(r) = 1 − e²/R² ≥ 0).
      const DoubleN da = sqrt_n(uu), db = sqrt_n(ex * ex + ey * ey), reach_a = da - flat, reach_b = db - flat;
      const MaskN before = (t_foot[g] <= 0) | (reach_a <= 0) | (p(e2[g], reach_a, da) <= 0);
      const MaskN after = ~before & (t_foot[g] >= 1) & (reach_b > 0) & (p(e2[g], reach_b, db) >= 0);
      const MaskN covered = wanted[g] & (before ? da <= radius : after ? db <= radius : e2[g] <= r2);
      inside[g] = covered & ~before & ~after;
      any_inside |= inside[g];
      t[g] = before ? splat(0) : splat(1);
      d[g] = before ? da : after ? db : splat(kInf);
      d[g] = covered ? d[g] : splat(kInf);
      // Lower bounds of the root: the root for e = 0 and, past the end, ρ_b.
      reach[g] = max_n(splat(start), t_foot[g] >= 1 ? reach_b : splat(0));
    }
    if (any_n(any_inside)) {
      DoubleN least[G];  // the lower bounds: the root for e = 0, ρ_b past the end, and e − R0 (e ≤ d)
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
          const DoubleN pr = p(e2[g], r, dr), a = mr2 * dd * dr + e2[g] * rr * r, b = mr2 * dd * dd + e2[g] * rr * rr;
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
        const DoubleN root_t = t_foot[g] - sqrt_n(max_n(root_d * root_d - e2[g], splat(0))) * inv_len;
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
      const DoubleN z = piece.is_arc ? piece.centre_h - sqrt_n(max_n(piece.radius * piece.radius - d * d, splat(0)))
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
      const DoubleN z = piece.is_arc ? d / sqrt_n(max_n(piece.radius * piece.radius - d * d, splat(0)))
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
    for (std::size_t k = 1; k < cutter->pieces().size(); ++k) kink |= abs_n(d - cutter->pieces()[k].d0) <= tolerance;
    Plane p;
    p.z = covered ? low + t * w + height(d) : splat(kInf);
    p.has_plane = covered & (d2 < r2 * (1 - 1e-7)) & ~kink;
    const DoubleN factor = p.has_plane & (d > 0) ? slope(d) / d : splat(0);
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
        const DoubleN from2 = max_n(splat(piece.d0 * piece.d0), c.e2), to2 = splat(std::min(piece.d1 * piece.d1, r2));
        const MaskN at_from = here & reaches(piece, from2, c.e2);
        const MaskN inside = here & ~at_from & reaches(piece, to2, c.e2);
        const DoubleN explicit2 = piece.is_arc ? (c.e2 + m2 * piece.radius * piece.radius) / (1 + m2)
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

// The milling of one Z-map: moves are binned to work blocks; each block is milled by one thread,
// one row of tiles at a time (see `mill_bin`).
class Miller {
 public:
  Miller(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves)
      : map_(map), g_(map.grid), cutters_(cutters), moves_(moves) {
    tiles_x_ = (g_.nx + kTile - 1) / kTile;
    tiles_y_ = (g_.ny + kTile - 1) / kTile;
    bins_x_ = (tiles_x_ + kBinTiles - 1) / kBinTiles;
    bins_y_ = (tiles_y_ + kBinTiles - 1) / kBinTiles;
  }

  void run(unsigned threads) {
    bin_moves();
    const std::size_t bin_count = static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(bins_y_);
    for_each_chunk_with(bin_count, threads, [](unsigned) { return BlockScratch{}; },
                        [&](std::size_t b, BlockScratch& scratch) { mill_bin(b, scratch); });
  }

 private:
  struct IndexBox {
    int i0, j0, i1, j1;
  };

  // A move that reaches a tile, with lower bounds of its swept surface over the tile.
  struct Candidate {
    std::uint32_t move = 0;  // index into the block's moves
    bool has_plane = false;
    double bound = kInf;     // lower bound of the swept surface over the tile
    double centre_z = kInf;  // the swept surface at the tile's centre (+inf if not covered)
    Vec2 gradient{0};        // its supporting plane's slope there, if `has_plane`
  };

  // What a tile holds, row by row: the highest point and the largest height above P.
  struct TileState {
    std::array<double, kTile> row_top, row_excess;
    double top = -kInf, excess = -kInf;
    void summarise(int rows) {
      top = *std::max_element(row_top.begin(), row_top.begin() + rows);
      excess = *std::max_element(row_excess.begin(), row_excess.begin() + rows);
    }
  };

  // A plane P through the tile's centre at height z with slope `gradient`, that approximates the
  // tile's surface once a smooth move has cut it.
  struct TilePlane {
    bool valid = false;
    double z = 0;
    Vec2 gradient{0};
  };

  struct Tile {
    IndexBox box;
    double xc, yc, hx, hy;   // centre and half extents
    double half_diagonal;    // √(hx² + hy²)
    TileState state;
    TilePlane plane;
    std::vector<Candidate> candidates;
  };

  // The tiles of one row of a work block. The arrays hold, tile by tile, what the ball end's
  // vector code reads kLanes tiles at a time.
  struct TileRow {
    int first_tx = 0, count = 0;
    std::array<Tile, kBinTiles> tiles;
    struct Lanes {
      alignas(32) double xc[kBinTiles], hx[kBinTiles], half_diagonal[kBinTiles], top[kBinTiles];
      // The move to cut first: its index (as a double), centre height, plane slope and bound.
      alignas(32) double first[kBinTiles], first_z[kBinTiles], first_gx[kBinTiles], first_gy[kBinTiles],
          first_bound[kBinTiles];
      // Whether that move's footprint covers the whole tile (ball ends count as covering: see
      // find_first_cuts).
      alignas(32) double first_covers[kBinTiles];
      // The tile's plane P and its largest height above P (P valid where plane_valid ≠ 0).
      alignas(32) double plane_valid[kBinTiles], plane_z[kBinTiles], plane_gx[kBinTiles], plane_gy[kBinTiles],
          excess[kBinTiles];
    } lanes;
  };
  static_assert(kBinTiles % kLanes == 0);

  // A ball end move's bounds over kLanes tiles of a row, from pass 1 for pass 2.
  struct BallBounds {
    DoubleN z, gx, gy, bound;  // the plane at each tile's centre (where `has_plane`), the bound
    MaskN has_plane, in_range;  // in_range: the move reaches that tile
    std::uint32_t move;
    int lane0;
  };

  // A ball end move left out of pass 1, and its distance from the row's tiles.
  struct FarMove {
    std::uint32_t move;
    int col0, col1;
    double distance;
  };

  // A move of another cutter left out of pass 1 over some tiles of the row (its near_bound is not
  // below the lowest centre height found there so far): bit `col` of `tiles` for each.
  struct DeferredMove {
    std::uint32_t move;
    std::uint32_t tiles;
  };
  static_assert(kBinTiles <= 32);

  // How a move's swept surface is evaluated on a tile's points: kLanes at a time by the ball
  // end's, the flat end's, the bull nose's or the other profiles' vector form, or one point at a
  // time (MoveGeometry::lowest: plunges, and profiles with an arc off the axis).
  enum class LaneKind : unsigned char { scalar, ball, flat, bull_nose, profile };

  static LaneKind lane_kind(const MoveGeometry& m) {
    if (m.vertical) return LaneKind::scalar;
    switch (m.cutter->shape()) {
      case CutterShape::ball: return LaneKind::ball;
      case CutterShape::flat: return LaneKind::flat;
      case CutterShape::bull_nose: return LaneKind::bull_nose;
      default: return ProfileLanes::closed_form(*m.cutter) ? LaneKind::profile : LaneKind::scalar;
    }
  }

  struct BlockScratch {
    std::vector<BallBounds> ball_bounds;  // of the current row
    std::vector<FarMove> far_moves;       // of the current row
    std::vector<DeferredMove> deferred;   // of the current row
    std::vector<std::uint32_t> by_tip;    // the other cutters' moves, lowest tip first
    std::vector<MoveGeometry> moves;
    // Parallel to `moves`: how each is evaluated, and its vector form where it has one.
    std::vector<LaneKind> kind;
    std::vector<BallLanes> balls;
    std::vector<FlatLanes> flats;
    std::vector<BullLanes> bulls;
    std::vector<ProfileLanes> profiles;
    std::vector<IndexBox> boxes;
    TileRow row;
  };

  // Grid-index box of a move's footprint, clipped to the grid; false if it misses the grid.
  bool footprint_box(const CutMove& move, IndexBox& box) const {
    double r = cutters_[move.cutter].radius();
    double x_lo = std::min(move.tip.a.x, move.tip.b.x) - r, x_hi = std::max(move.tip.a.x, move.tip.b.x) + r;
    double y_lo = std::min(move.tip.a.y, move.tip.b.y) - r, y_hi = std::max(move.tip.a.y, move.tip.b.y) + r;
    double fi0 = std::ceil((x_lo - g_.x0) / g_.cell), fi1 = std::floor((x_hi - g_.x0) / g_.cell);
    double fj0 = std::ceil((y_lo - g_.y0) / g_.cell), fj1 = std::floor((y_hi - g_.y0) / g_.cell);
    // One point of slack on each side against rounding; the exact test is per point.
    fi0 = std::max(fi0 - 1, 0.0), fj0 = std::max(fj0 - 1, 0.0);
    fi1 = std::min(fi1 + 1, g_.nx - 1.0), fj1 = std::min(fj1 + 1, g_.ny - 1.0);
    if (fi0 > fi1 || fj0 > fj1) return false;
    box = {static_cast<int>(fi0), static_cast<int>(fj0), static_cast<int>(fi1), static_cast<int>(fj1)};
    return true;
  }

  // Counting sort of move indices into blocks, keeping program order within each block.
  void bin_moves() {
    std::size_t bin_count = static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(bins_y_);
    bin_start_.assign(bin_count + 1, 0);
    const int span = kTile * kBinTiles;
    auto for_each_bin = [&](const CutMove& move, auto&& visit) {
      IndexBox b;
      if (!footprint_box(move, b)) return;
      for (int by = b.j0 / span; by <= b.j1 / span; ++by)
        for (int bx = b.i0 / span; bx <= b.i1 / span; ++bx)
          visit(static_cast<std::size_t>(bx) + static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(by));
    };
    for (const CutMove& move : moves_) for_each_bin(move, [&](std::size_t b) { ++bin_start_[b + 1]; });
    for (std::size_t b = 0; b < bin_count; ++b) bin_start_[b + 1] += bin_start_[b];
    bin_moves_.resize(bin_start_[bin_count]);
    std::vector<std::size_t> fill(bin_start_.begin(), bin_start_.end() - 1);
    for (std::size_t m = 0; m < moves_.size(); ++m)
      for_each_bin(moves_[m], [&](std::size_t b) { bin_moves_[fill[b]++] = static_cast<std::uint32_t>(m); });
  }

  // Mills one work block, one row of tiles at a time, in the two passes of the header comment:
  // find_first_cuts and cut_first (pass 1), find_other_cuts and cut_others (pass 2). A move is
  // skipped over a tile (or one of its rows) when its bound is not below the highest point there,
  // or when min(S − P) ≥ max(height − P), P the first cut's plane.
  void mill_bin(std::size_t bin, BlockScratch& scratch) {
    if (bin_start_[bin] == bin_start_[bin + 1]) return;
    scratch.moves.clear();
    scratch.kind.clear();
    scratch.balls.clear();
    scratch.flats.clear();
    scratch.bulls.clear();
    scratch.profiles.clear();
    scratch.boxes.clear();
    for (std::size_t k = bin_start_[bin]; k < bin_start_[bin + 1]; ++k) {
      const CutMove& move = moves_[bin_moves_[k]];
      const MoveGeometry& m = scratch.moves.emplace_back(cutters_[move.cutter], move.tip);
      const LaneKind kind = lane_kind(m);
      scratch.kind.push_back(kind);
      scratch.balls.push_back(kind == LaneKind::ball ? BallLanes(m) : BallLanes{});
      scratch.flats.push_back(kind == LaneKind::flat ? FlatLanes(m) : FlatLanes{});
      scratch.bulls.push_back(kind == LaneKind::bull_nose ? BullLanes(m) : BullLanes{});
      scratch.profiles.push_back(kind == LaneKind::profile ? ProfileLanes(m) : ProfileLanes{});
      scratch.boxes.emplace_back();
      footprint_box(move, scratch.boxes.back());
    }
    scratch.by_tip.clear();
    for (std::size_t k = 0; k < scratch.moves.size(); ++k)
      if (scratch.kind[k] != LaneKind::ball) scratch.by_tip.push_back(static_cast<std::uint32_t>(k));
    std::sort(scratch.by_tip.begin(), scratch.by_tip.end(), [&](std::uint32_t a, std::uint32_t b) {
      const double ta = scratch.moves[a].lowest_tip(), tb = scratch.moves[b].lowest_tip();
      return ta < tb || (ta == tb && a < b);
    });
    int bx = static_cast<int>(bin % static_cast<std::size_t>(bins_x_));
    int by = static_cast<int>(bin / static_cast<std::size_t>(bins_x_));
    int tx1 = std::min(tiles_x_, (bx + 1) * kBinTiles), ty1 = std::min(tiles_y_, (by + 1) * kBinTiles);
    TileRow& row = scratch.row;
    for (int ty = by * kBinTiles; ty < ty1; ++ty) {
      start_row(row, bx * kBinTiles, tx1 - bx * kBinTiles, ty);
      find_first_cuts(row, scratch);
      for (int col = 0; col < row.count; ++col) cut_first(row, col, scratch);
      find_other_cuts(row, scratch);
      for (int col = 0; col < row.count; ++col) cut_others(row.tiles[static_cast<std::size_t>(col)], scratch);
    }
  }

  // Sets up the tiles of one row of a block: their extents and what they hold now.
  void start_row(TileRow& row, int first_tx, int count, int ty) {
    row.first_tx = first_tx, row.count = count;
    const int j0 = ty * kTile, j1 = std::min(g_.ny, (ty + 1) * kTile) - 1;
    TileRow::Lanes& lanes = row.lanes;
    for (int col = 0; col < kBinTiles; ++col) {
      // Columns past the grid's edge repeat the last tile (their lanes are computed, not used).
      const int tx = first_tx + std::min(col, count - 1);
      const int i0 = tx * kTile, i1 = std::min(g_.nx, (tx + 1) * kTile) - 1;
      Tile& tile = row.tiles[static_cast<std::size_t>(col)];
      tile.box = {i0, j0, i1, j1};
      tile.xc = 0.5 * (g_.x(i0) + g_.x(i1)), tile.yc = 0.5 * (g_.y(j0) + g_.y(j1));
      tile.hx = 0.5 * (g_.x(i1) - g_.x(i0)), tile.hy = 0.5 * (g_.y(j1) - g_.y(j0));
      tile.half_diagonal = std::sqrt(tile.hx * tile.hx + tile.hy * tile.hy);
      tile.plane = {};
      tile.candidates.clear();
      for (int j = j0; j <= j1; ++j) {
        const float* heights = &map_.heights[g_.index(i0, j)];
        DoubleN top = load_heights(heights, i1 - i0 + 1);
        for (int i = kLanes; i < kTile; i += kLanes) top = max_n(top, load_heights(heights + i, i1 - i0 + 1 - i));
        tile.state.row_top[static_cast<std::size_t>(j - j0)] = max_lane(top);
        tile.state.row_excess[static_cast<std::size_t>(j - j0)] = -kInf;
      }
      tile.state.summarise(j1 - j0 + 1);
      lanes.xc[col] = tile.xc, lanes.hx[col] = tile.hx, lanes.top[col] = tile.state.top;
      lanes.half_diagonal[col] = tile.half_diagonal;
      lanes.first[col] = -1, lanes.first_z[col] = kInf, lanes.first_bound[col] = kInf;
      lanes.first_gx[col] = lanes.first_gy[col] = 0;
      lanes.first_covers[col] = 0;
    }
  }

  // Calls visit(k, col0, col1) for each move k of the block that reaches the row's tiles col0..col1.
  template <class Visit>
  void for_each_move(const TileRow& row, const BlockScratch& scratch, Visit&& visit) const {
    for (std::size_t k = 0; k < scratch.moves.size(); ++k) {
      int col0, col1;
      if (columns(row, scratch.boxes[k], col0, col1)) visit(k, col0, col1);
    }
  }

  // The row's tiles col0..col1 that a footprint box reaches; false if none.
  static bool columns(const TileRow& row, const IndexBox& b, int& col0, int& col1) {
    const IndexBox& any = row.tiles[0].box;
    if (b.j1 < any.j0 || b.j0 > any.j1) return false;
    col0 = std::max(0, b.i0 / kTile - row.first_tx);
    col1 = std::min(row.count - 1, b.i1 / kTile - row.first_tx);
    return col0 <= col1;
  }

  // A ball end move's bounds over the row's tiles lane0 .. lane0 + kLanes − 1 (those in
  // col0..col1 are in range).
  BallBounds ball_bounds(const BallLanes& ball, const TileRow& row, std::uint32_t move, int lane0, int col0,
                         int col1) const {
    const Tile& tile = row.tiles[0];
    const DoubleN hx = load_n(&row.lanes.hx[lane0]);
    const DoubleN ux = load_n(&row.lanes.xc[lane0]) - ball.ax, uy = splat(tile.yc - ball.ay);
    BallLanes::Plane p = ball.plane_at(ux, uy);
    // Without a plane: the lowest tip plus the ball's height at the tile's distance s from the
    // path, bounded below by s²/2R (h(s) = R − √(R² − s²) = s² / (R + √(R² − s²))).
    DoubleN bound = p.z - abs_n(p.gx) * hx - abs_n(p.gy) * tile.hy;
    if (!all_n(p.has_plane)) {
      DoubleN gap = max_n(sqrt_n(path_distance2(ux, uy, ball.vx, ball.vy, ball.inv_vv)) - load_n(&row.lanes.half_diagonal[lane0]), splat(0));
      DoubleN far = gap * gap > ball.r2 ? splat(kInf) : ball.lowest_tip() + gap * gap * ball.inv_diameter;
      bound = p.has_plane ? bound : far;
    }
    const DoubleN col = lane_index() + lane0;
    return {p.z, p.gx, p.gy, bound, p.has_plane, (col >= col0) & (col <= col1), move, lane0};
  }

  // Pass 1: for each tile, the move whose swept surface is lowest at its centre among those with
  // a supporting plane there (ties: the lower bound). Moves other than ball ends are kept.
  //
  // A ball end move whose path stays farther than R/2 from the row's tiles is left for pass 2,
  // where most such moves fall to a scalar test: the lowest point of the ball within a distance d
  // of its path is at least d²/2R above the tip, and a tile's surface comes within d of the move
  // only if the move passes within d of it. The first cut is only a choice (any move gives a
  // correct result); in a raster it is the nearby move a little downhill, well within R/2.
  void find_first_cuts(TileRow& row, BlockScratch& scratch) {
    TileRow::Lanes& lanes = row.lanes;
    scratch.ball_bounds.clear();
    scratch.far_moves.clear();
    const Tile& last = row.tiles[static_cast<std::size_t>(row.count - 1)];
    const double row_x0 = g_.x(row.tiles[0].box.i0), row_x1 = g_.x(last.box.i1);
    const double row_y0 = g_.y(last.box.j0), row_y1 = g_.y(last.box.j1);
    for_each_move(row, scratch, [&](std::size_t k, int col0, int col1) {
      const MoveGeometry& m = scratch.moves[k];
      if (scratch.kind[k] != LaneKind::ball) return;
      const BallLanes& ball = scratch.balls[k];
      // Distance between the path's bounding box and the row's rectangle.
      const double dx = std::max({0.0, std::min(m.ax, m.ax + m.vx) - row_x1, row_x0 - std::max(m.ax, m.ax + m.vx)});
      const double dy = std::max({0.0, std::min(m.ay, m.ay + m.vy) - row_y1, row_y0 - std::max(m.ay, m.ay + m.vy)});
      const double distance = std::sqrt(dx * dx + dy * dy);
      if (distance > 0.5 * m.radius) {
        scratch.far_moves.push_back({static_cast<std::uint32_t>(k), col0, col1, distance});
        return;
      }
      for (int lane0 = col0 / kLanes * kLanes; lane0 <= col1; lane0 += kLanes) {
        const BallBounds& b =
            scratch.ball_bounds.emplace_back(ball_bounds(ball, row, static_cast<std::uint32_t>(k), lane0, col0, col1));
        const DoubleN first_z = load_n(&lanes.first_z[lane0]), first_bound = load_n(&lanes.first_bound[lane0]);
        const MaskN better = b.in_range & b.has_plane & (b.bound < load_n(&lanes.top[lane0])) &
                             ((load_n(&lanes.first_covers[lane0]) == 0) | (b.z < first_z) |
                              ((b.z == first_z) & (b.bound < first_bound)));
        if (!any_n(better)) continue;
        store_n(&lanes.first_covers[lane0], better ? splat(1) : load_n(&lanes.first_covers[lane0]));
        store_n(&lanes.first[lane0], better ? splat(static_cast<double>(k)) : load_n(&lanes.first[lane0]));
        store_n(&lanes.first_z[lane0], better ? b.z : first_z);
        store_n(&lanes.first_gx[lane0], better ? b.gx : load_n(&lanes.first_gx[lane0]));
        store_n(&lanes.first_gy[lane0], better ? b.gy : load_n(&lanes.first_gy[lane0]));
        store_n(&lanes.first_bound[lane0], better ? b.bound : first_bound);
      }
    });
    // The other cutters' moves, lowest tip first; one whose tip is not below the lowest centre
    // height found for a tile cannot be its first cut, and waits for pass 2 (where, after the
    // first cut, most such moves fall to the same cheap test against the tile's top: the upper
    // levels of a Z-level roughing, for instance).
    //
    // A move whose footprint covers the whole tile is preferred to one lower at the centre that
    // does not: a flat end's surface is lowest at the side of its footprint wherever the program
    // slopes across its passes (the bench's raster), and a first cut that leaves part of the tile
    // untouched leaves its top where it was, so that no later move is rejected (on bench_mill's
    // flat raster, 84 moves a tile were left for pass 2, against 4 for the ball). Ball ends count
    // as covering: their first cut is chosen as before.
    scratch.deferred.clear();
    for (std::uint32_t k : scratch.by_tip) {
      int col0, col1;
      if (!columns(row, scratch.boxes[k], col0, col1)) continue;
      const MoveGeometry& m = scratch.moves[k];
      // Which tiles the move can reach below their top, and which of those it is deferred on (its
      // near_bound not below their first cut's centre height), kLanes tiles at a time: a move
      // spans most of a row, and on bench_mill's bull nose raster one test per tile made 16.5 M
      // tests and 13.4 M deferred records. Each tile's test reads only its own first cut, so
      // testing them together before any is updated changes nothing.
      std::uint32_t bounded = 0, deferred = 0;
      for (int lane0 = col0 / kLanes * kLanes; lane0 <= col1; lane0 += kLanes) {
        const DoubleN col = lane_index() + lane0, near = near_bound(scratch, row, k, lane0);
        const MaskN below = (col >= col0) & (col <= col1) & (near < load_n(&lanes.top[lane0]));
        const MaskN defer = below & (load_n(&lanes.first_covers[lane0]) != 0) & (near >= load_n(&lanes.first_z[lane0]));
        bounded |= lane_bits(below & ~defer) << lane0;
        deferred |= lane_bits(defer) << lane0;
      }
      if (deferred != 0) scratch.deferred.push_back({k, deferred});
      // Bounds kLanes tiles at a time where the move has a vector form (MoveBounds).
      MoveBounds bounds;
      for (; bounded != 0; bounded &= bounded - 1) {
        const int col = std::countr_zero(bounded);
        Tile& tile = row.tiles[static_cast<std::size_t>(col)];
        const bool first_covers = lanes.first_covers[col] != 0;
        Candidate c = bounds.at(scratch, row, k, col);
        if (c.bound >= tile.state.top) continue;
        tile.candidates.push_back(c);
        if (!c.has_plane) continue;
        const bool lower = c.centre_z < lanes.first_z[col] ||
                           (c.centre_z == lanes.first_z[col] && c.bound < lanes.first_bound[col]);
        if (!lower && first_covers) continue;
        const bool covers = covers_tile(m, tile);
        if (covers ? (lower || !first_covers) : (lower && !first_covers)) {
          lanes.first[col] = static_cast<double>(k), lanes.first_z[col] = c.centre_z;
          lanes.first_gx[col] = c.gradient.x, lanes.first_gy[col] = c.gradient.y;
          lanes.first_bound[col] = c.bound, lanes.first_covers[col] = covers;
        }
      }
    }
  }

  // Cuts a tile with its first move (if it has one), and records the plane and state that the
  // other moves are then measured against.
  void cut_first(TileRow& row, int col, const BlockScratch& scratch) {
    Tile& tile = row.tiles[static_cast<std::size_t>(col)];
    TileRow::Lanes& lanes = row.lanes;
    if (lanes.first[col] >= 0) {
      Candidate first{static_cast<std::uint32_t>(lanes.first[col]), true, lanes.first_bound[col], lanes.first_z[col],
                      Vec2(lanes.first_gx[col], lanes.first_gy[col])};
      tile.plane = {true, first.centre_z, first.gradient};
      mill_tile(std::span<const Candidate>(&first, 1), tile, scratch, true);
    }
    lanes.top[col] = tile.state.top, lanes.excess[col] = tile.state.excess;
    lanes.plane_valid[col] = tile.plane.valid, lanes.plane_z[col] = tile.plane.z;
    lanes.plane_gx[col] = tile.plane.gradient.x, lanes.plane_gy[col] = tile.plane.gradient.y;
  }

  // min(S − P) over a tile (or over one of its rows, with half_height = 0 and dy its offset).
  static double above_plane(const Candidate& c, const Tile& tile, double dy, double half_height) {
    const TilePlane& p = tile.plane;
    if (!c.has_plane)
      return c.bound - (p.z + p.gradient.y * dy + std::abs(p.gradient.x) * tile.hx +
                        std::abs(p.gradient.y) * half_height);
    return (c.centre_z - p.z) + (c.gradient.y - p.gradient.y) * dy - std::abs(c.gradient.x - p.gradient.x) * tile.hx -
           std::abs(c.gradient.y - p.gradient.y) * half_height;
  }

  static bool can_cut(const Candidate& c, const Tile& tile) {
    return c.bound < tile.state.top && (!tile.plane.valid || above_plane(c, tile, 0, tile.hy) < tile.state.excess);
  }

  // Pass 2: the moves that can still cut each tile after its first cut (the same test as
  // `can_cut`, kLanes tiles at a time for the ball end).
  void find_other_cuts(TileRow& row, const BlockScratch& scratch) {
    const TileRow::Lanes& lanes = row.lanes;
    for (int col = 0; col < row.count; ++col) {
      Tile& tile = row.tiles[static_cast<std::size_t>(col)];
      const auto first = static_cast<std::uint32_t>(std::max(0.0, lanes.first[col]));
      const bool has_first = lanes.first[col] >= 0;
      std::erase_if(tile.candidates,
                    [&](const Candidate& c) { return (has_first && c.move == first) || !can_cut(c, tile); });
    }
    // A deferred move is bounded only over the tiles whose first cut left their top above its
    // near_bound (most are not: the upper levels of a Z-level roughing, for instance), kLanes
    // tiles at a time.
    MoveBounds bounds;
    for (const DeferredMove& d : scratch.deferred) {
      const DoubleN move = splat(static_cast<double>(d.move));
      std::uint32_t tiles = 0;
      for (int lane0 = 0; lane0 < row.count; lane0 += kLanes) {
        if (((d.tiles >> lane0) & ((1u << kLanes) - 1)) == 0) continue;
        const DoubleN near = near_bound(scratch, row, d.move, lane0);
        tiles |= lane_bits((near < load_n(&lanes.top[lane0])) & (load_n(&lanes.first[lane0]) != move)) << lane0;
      }
      for (tiles &= d.tiles; tiles != 0; tiles &= tiles - 1) {
        const int col = std::countr_zero(tiles);
        Tile& tile = row.tiles[static_cast<std::size_t>(col)];
        const Candidate c = bounds.at(scratch, row, d.move, col);
        if (can_cut(c, tile)) tile.candidates.push_back(c);
      }
    }
    for (const BallBounds& b : scratch.ball_bounds) keep_other_cuts(row, b);
    double row_top = -kInf;
    for (int col = 0; col < row.count; ++col) row_top = std::max(row_top, lanes.top[col]);
    for (const FarMove& far : scratch.far_moves) {
      const BallLanes& ball = scratch.balls[far.move];
      if (ball.lowest_tip() + far.distance * far.distance * ball.inv_diameter >= row_top) continue;
      for (int lane0 = far.col0 / kLanes * kLanes; lane0 <= far.col1; lane0 += kLanes)
        keep_other_cuts(row, ball_bounds(ball, row, far.move, lane0, far.col0, far.col1));
    }
  }

  // The tiles of b's lanes where its move can still cut (see `can_cut`) get it as a candidate.
  void keep_other_cuts(TileRow& row, const BallBounds& b) const {
    const TileRow::Lanes& lanes = row.lanes;
    const double hy = row.tiles[0].hy;
    const int lane0 = b.lane0;
    const DoubleN hx = load_n(&lanes.hx[lane0]);
    const DoubleN pz = load_n(&lanes.plane_z[lane0]), pgx = load_n(&lanes.plane_gx[lane0]),
                  pgy = load_n(&lanes.plane_gy[lane0]);
    DoubleN with_plane = (b.z - pz) - abs_n(b.gx - pgx) * hx - abs_n(b.gy - pgy) * hy;
    DoubleN without_plane = b.bound - (pz + abs_n(pgx) * hx + abs_n(pgy) * hy);
    DoubleN above = b.has_plane ? with_plane : without_plane;
    MaskN cuts = b.in_range & (b.bound < load_n(&lanes.top[lane0])) &
                 ((load_n(&lanes.plane_valid[lane0]) == 0) | (above < load_n(&lanes.excess[lane0]))) &
                 (load_n(&lanes.first[lane0]) != static_cast<double>(b.move));
    if (!any_n(cuts)) return;
    for (int l = 0; l < kLanes; ++l) {
      if (!cuts[l]) continue;
      Candidate c{b.move, b.has_plane[l] != 0, b.bound[l], kInf, Vec2(0)};
      if (c.has_plane) c.centre_z = b.z[l], c.gradient = Vec2(b.gx[l], b.gy[l]);
      row.tiles[static_cast<std::size_t>(lane0 + l)].candidates.push_back(c);
    }
  }

  // Cuts a tile with the moves left, lowest bound first, so that deep cuts (a roughing pass
  // below the finish, say) come before the moves they leave nothing for. A run of consecutive
  // moves of one cutter with a vector form is milled together, row by row (a ball end's admitted
  // by what the tile held before the run: their rows are cheap, a fresher test costs more than it
  // saves); each run, and each move without a vector form (its points cost far more), is checked
  // again against what the tile holds by then. A run of another cutter is at most kOtherRun
  // moves, and a flat end's rows are measured again after each of its moves (mill_tile): its
  // neighbouring passes leave nearly equal surfaces, so that the first cut leaves a tile far from
  // its final shape (a flat end's raster on a slope is lowest under the side of a neighbouring
  // pass, which covers a few rows of a tile), and a test against the state after the first cut
  // admitted 20 times the rows that the ball end's did. The bull nose's rows are not measured
  // again: on bench_mill's bull nose raster that cost 8 % more than the rows it rejected.
  void cut_others(Tile& tile, const BlockScratch& scratch) {
    std::vector<Candidate>& candidates = tile.candidates;
    std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
      return a.bound < b.bound || (a.bound == b.bound && a.move < b.move);
    });
    for (auto c = candidates.begin(); c != candidates.end();) {
      if (c->bound >= tile.state.top) break;
      if (scratch.kind[c->move] == LaneKind::scalar) {
        if (can_cut(*c, tile)) mill_tile(std::span<const Candidate>(&*c, 1), tile, scratch, false);
        ++c;
        continue;
      }
      const Cutter* cutter = scratch.moves[c->move].cutter;
      auto run_end = std::find_if(c, candidates.end(), [&](const Candidate& o) {
        return scratch.kind[o.move] == LaneKind::scalar || scratch.moves[o.move].cutter != cutter;
      });
      if (scratch.kind[c->move] != LaneKind::ball && run_end - c > kOtherRun) run_end = c + kOtherRun;
      auto kept = std::remove_if(c, run_end, [&](const Candidate& o) { return !can_cut(o, tile); });
      if (kept != c) mill_tile(std::span<const Candidate>(&*c, static_cast<std::size_t>(kept - c)), tile, scratch, false);
      c = run_end;
    }
  }

  // bound_at_centre for a flat end's, a bull nose's or a profile's move, from the plane_at of
  // FlatLanes, BullLanes or ProfileLanes at the centres of kLanes tiles of a row at once (`at`
  // computes them for the tiles around column col when needed).
  template <class Lanes>
  struct LaneBounds {
    FlatLanes::Plane plane;
    DoubleN bound;
    std::uint32_t move = 0;
    int lane0 = -1;

    Candidate at(const Lanes& lanes, const MoveGeometry& m, const TileRow& row, std::uint32_t index, int col) {
      if (index != move || col / kLanes * kLanes != lane0) {
        move = index, lane0 = col / kLanes * kLanes;
        const DoubleN ux = load_n(&row.lanes.xc[lane0]) - lanes.ax, uy = splat(row.tiles[0].yc - lanes.ay);
        plane = lanes.plane_at(ux, uy);
        bound = plane.z - abs_n(plane.gx) * load_n(&row.lanes.hx[lane0]) - abs_n(plane.gy) * row.tiles[0].hy;
        if (!all_n(plane.has_plane)) {
          // bound_without_plane at once (on bench_mill's bull nose raster, half the tiles a move
          // is bounded over in pass 1 have no plane at their centre: the passes at the edge of
          // the footprint).
          bound = plane.has_plane ? bound : off_path_bound(lanes, m, row, lane0, ux, uy);
        }
      }
      const int l = col - lane0;
      if (plane.has_plane[l]) return {index, true, bound[l], plane.z[l], Vec2(plane.gx[l], plane.gy[l])};
      return {index, false, bound[l], kInf, Vec2(0)};
    }
  };

  // The bounds of one move over the tile at column col, kLanes tiles at a time where the move has
  // a vector form for them.
  struct MoveBounds {
    LaneBounds<FlatLanes> flat;
    LaneBounds<BullLanes> bull;
    LaneBounds<ProfileLanes> profile;

    Candidate at(const BlockScratch& scratch, const TileRow& row, std::uint32_t k, int col) {
      const MoveGeometry& m = scratch.moves[k];
      switch (scratch.kind[k]) {
        case LaneKind::flat: return flat.at(scratch.flats[k], m, row, k, col);
        case LaneKind::bull_nose: return bull.at(scratch.bulls[k], m, row, k, col);
        case LaneKind::profile: return profile.at(scratch.profiles[k], m, row, k, col);
        default: return bound_at_centre(m, row.tiles[static_cast<std::size_t>(col)], k);
      }
    }
  };

  // bound_without_plane for the row's tiles lane0 .. lane0 + kLanes − 1 at once (+infinity where
  // the footprint misses a tile), for a move of another cutter than the ball end: the lowest tip
  // where the cutter has no vector form or a flat bottom (h = 0 out to R0: with it the bull
  // nose's raster of bench_mill took 874 ms against 844, one sitting: two square roots more). Cheaper than the tile's plane,
  // and far stronger than the tip alone for a pointed cutter (a cone's neighbouring passes are
  // d·tan(angle) above their tips at a distance d: on bench_mill's cone raster, 10.4 M of the
  // moves' tiles were bounded in pass 1 with the tip).
  DoubleN near_bound(const BlockScratch& scratch, const TileRow& row, std::uint32_t k, int lane0) const {
    const MoveGeometry& m = scratch.moves[k];
    if (scratch.kind[k] != LaneKind::profile) return splat(m.lowest_tip());
    const ProfileLanes& move = scratch.profiles[k];
    const DoubleN ux = load_n(&row.lanes.xc[lane0]) - move.ax, uy = splat(row.tiles[0].yc - move.ay);
    return off_path_bound(move, m, row, lane0, ux, uy);
  }

  // The lowest tip plus the cutter's height at the distance of the row's tiles (lanes lane0 …, at
  // offsets (ux, uy) from the move's start) from its path: +infinity where the footprint misses a
  // tile. For a move of FlatLanes, BullLanes or ProfileLanes.
  template <class Lanes>
  static DoubleN off_path_bound(const Lanes& move, const MoveGeometry& m, const TileRow& row, int lane0, DoubleN ux,
                                DoubleN uy) {
    const DoubleN distance = sqrt_n(path_distance2(ux, uy, move.vx, move.vy, move.inv_vv));
    const DoubleN gap = max_n(distance - load_n(&row.lanes.half_diagonal[lane0]), splat(0));
    return gap > m.radius ? splat(kInf) : move.low + move.height(min_n(gap, splat(m.radius)));
  }

  // A lower bound of a move's swept surface over a tile where it has no plane at the centre: the
  // lowest tip plus the cutter's height at the tile's distance from the path.
  static double bound_without_plane(const MoveGeometry& m, const Tile& tile) {
    double distance = std::max(0.0, std::sqrt(distance2_point_segment(Vec2(tile.xc, tile.yc), Vec2(m.ax, m.ay),
                                                                       Vec2(m.ax + m.vx, m.ay + m.vy))) -
                                        tile.half_diagonal);
    return distance <= m.radius ? m.lowest_tip() + m.cutter->lower_height(distance) : kInf;
  }

  // Whether the move's footprint (every point within the cutter's radius of its path) holds the
  // whole tile.
  static bool covers_tile(const MoveGeometry& m, const Tile& tile) {
    const double reach = m.radius - tile.half_diagonal;
    return reach > 0 && distance2_point_segment(Vec2(tile.xc, tile.yc), Vec2(m.ax, m.ay),
                                                Vec2(m.ax + m.vx, m.ay + m.vy)) < reach * reach;
  }

  // The bounds of one move over one tile, for any cutter.
  static Candidate bound_at_centre(const MoveGeometry& m, const Tile& tile, std::uint32_t index) {
    Candidate c{index, false, kInf, kInf, Vec2(0)};
    MoveGeometry::Lowest centre;
    if (m.lowest_with_plane(tile.xc, tile.yc, centre, c.gradient)) {
      c.centre_z = centre.z;
      c.has_plane = true;
      c.bound = centre.z - std::abs(c.gradient.x) * tile.hx - std::abs(c.gradient.y) * tile.hy;
      return c;
    }
    c.gradient = Vec2(0);
    c.bound = bound_without_plane(m, tile);
    return c;
  }

  // Whether a flat end's move c may lower row j of a tile, whose highest point is row_top and
  // whose largest height above the tile's plane is row_excess (rows_may_cut for one row, without
  // the ball end's rise).
  bool row_may_cut(const Candidate& c, const Tile& tile, int j, double row_top, double row_excess) const {
    double dy = g_.y(j) - tile.yc;
    double row_bound = c.has_plane ? c.centre_z + c.gradient.y * dy - std::abs(c.gradient.x) * tile.hx : c.bound;
    if (row_bound >= row_top) return false;
    return !tile.plane.valid || above_plane(c, tile, dy, 0) < row_excess;
  }

  // Whether move c may lower each row of the tile, against what the rows hold now: bit r for row
  // t.j0 + r, all rows at once. Rows only get lower, so a row it rejects stays rejected whatever
  // is cut after. For the ball end, its rise across the move (BallLanes::across) at its least on
  // each row is added to the bounds.
  std::uint32_t rows_may_cut(const Candidate& c, const BallLanes* ball, const Tile& tile) const {
    const IndexBox& t = tile.box;
    const TilePlane& p = tile.plane;
    const int rows = t.j1 - t.j0 + 1;
    std::uint32_t may = 0;
    for (int r0 = 0; r0 < rows; r0 += kLanes) {
      const DoubleN dy = (g_.y0 + (lane_index() + (t.j0 + r0)) * g_.cell) - tile.yc;
      DoubleN across = splat(0);
      if (ball && c.has_plane) {
        const DoubleN a = max_n(abs_n(dy * ball->ny) - tile.hx * std::abs(ball->nx), splat(0));
        across = a * a * ball->inv_diameter;
      }
      const DoubleN row_bound =
          c.has_plane ? c.centre_z + c.gradient.y * dy - std::abs(c.gradient.x) * tile.hx + across : splat(c.bound);
      MaskN cuts = (lane_index() + r0 < rows) & (row_bound < load_n(&tile.state.row_top[static_cast<std::size_t>(r0)]));
      if (p.valid) {
        const DoubleN above = c.has_plane ? (c.centre_z - p.z) + (c.gradient.y - p.gradient.y) * dy -
                                                std::abs(c.gradient.x - p.gradient.x) * tile.hx
                                          : c.bound - (p.z + p.gradient.y * dy + std::abs(p.gradient.x) * tile.hx);
        cuts &= above + across < load_n(&tile.state.row_excess[static_cast<std::size_t>(r0)]);
      }
      may |= lane_bits(cuts) << r0;
    }
    return may;
  }

  // kLanes heights of a map row as doubles; of the last `available` < kLanes of a row, the rest
  // -inf (never lowered, never the top).
  static DoubleN load_heights(const float* p, int available) {
    if (available >= kLanes) {
      FloatN f;
      __builtin_memcpy(&f, p, sizeof f);
      return __builtin_convertvector(f, DoubleN);
    }
    DoubleN h = splat(-kInf);
    for (int l = 0; l < available; ++l) h[l] = p[l];
    return h;
  }
  static void store_heights(float* p, DoubleN h, int available) {
    if (available >= kLanes) {
      FloatN f = __builtin_convertvector(h, FloatN);
      __builtin_memcpy(p, &f, sizeof f);
      return;
    }
    for (int l = 0; l < available; ++l) p[l] = static_cast<float>(h[l]);
  }

  // Lowers a tile to the swept surfaces of `cuts` (moves of one cutter), row by row: each row is
  // read once, lowered by every move whose bounds admit it, and its state (measured against the
  // tile's plane) updated once. Which rows a move may lower (RowTest): all of them for the first
  // cut; for a flat end's run, each row by its state after the moves before (its neighbouring
  // passes cut nearly equal surfaces, see cut_others); for the others, every row by its state
  // before the run, all rows of a move at once. Other cutters than the ball end and the flat end
  // skip the points already below the move's supporting plane.
  enum class RowTest { every, fresh, before };
  void mill_tile(std::span<const Candidate> cuts, Tile& tile, const BlockScratch& scratch, bool every_row) {
    if (every_row) return mill_part<RowTest::every>(cuts, tile, scratch);
    if (scratch.kind[cuts.front().move] == LaneKind::flat) return mill_part<RowTest::fresh>(cuts, tile, scratch);
    // A long run (of ball ends) in parts, for mill_part's fixed array.
    for (std::size_t k = 0; k < cuts.size(); k += kPart)
      mill_part<RowTest::before>(cuts.subspan(k, std::min(kPart, cuts.size() - k)), tile, scratch);
  }
  static constexpr std::size_t kPart = 64;
  template <RowTest kTest>
  void mill_part(std::span<const Candidate> cuts, Tile& tile, const BlockScratch& scratch) {
    std::array<std::uint32_t, kPart> may;
    if constexpr (kTest == RowTest::before)
      for (std::size_t k = 0; k < cuts.size(); ++k) {
        const BallLanes* ball = scratch.kind[cuts[k].move] == LaneKind::ball ? &scratch.balls[cuts[k].move] : nullptr;
        may[k] = rows_may_cut(cuts[k], ball, tile);
      }
    const IndexBox& t = tile.box;
    const TilePlane& plane = tile.plane;
    TileState& state = tile.state;
    const double empty = map_.empty_height;
    const int count = t.i1 - t.i0 + 1;
    constexpr int kGroups = kTile / kLanes;
    DoubleN dx[kGroups], x[kGroups];
    for (int g = 0; g < kGroups; ++g) {
      // x computed as ZMapGrid::x does, so that points on a footprint's rim go the same way.
      x[g] = g_.x0 + (lane_index() + (t.i0 + g * kLanes)) * g_.cell;
      dx[g] = x[g] - tile.xc;
    }
    bool changed = false;
    for (int j = t.j0; j <= t.j1; ++j) {
      const double y = g_.y(j), dy = y - tile.yc;
      float* row = &map_.heights[g_.index(t.i0, j)];
      const double tile_row = plane.z + plane.gradient.y * dy;
      DoubleN h[kGroups];
      bool loaded = false;
      // The row's highest point and largest height above P as its moves lower it (in double: a
      // move whose bounds are not below them leaves every point as it is, rounded or not).
      const std::size_t r = static_cast<std::size_t>(j - t.j0);
      double row_top = state.row_top[r], row_excess = state.row_excess[r];
      for (std::size_t k = 0; k < cuts.size(); ++k) {
        const Candidate& c = cuts[k];
        const LaneKind kind = scratch.kind[c.move];
        if constexpr (kTest == RowTest::before) {
          if (!((may[k] >> r) & 1)) continue;
        } else if constexpr (kTest == RowTest::fresh) {
          if (!row_may_cut(c, tile, j, row_top, row_excess)) continue;
        }
        const MoveGeometry& m = scratch.moves[c.move];
        const BallLanes* ball = kind == LaneKind::ball ? &scratch.balls[c.move] : nullptr;
        if (!loaded) {
          for (int g = 0; g < kGroups; ++g) h[g] = load_heights(row + g * kLanes, count - g * kLanes);
          loaded = true;
        }
        if (ball) {
          // Every point of the row: a test per group costs more in mispredicted branches and
          // in the chain through h than the evaluations it saves (measured).
          const double uy = y - ball->ay;
          for (int g = 0; g < kGroups; ++g) {
            // Rounded to float and raised to the empty height once per row, below: heights are
            // floats and never below it, so min(h, round(max(z, empty))) = round(max(min(h, z), empty)).
            h[g] = min_n(h[g], ball->at(x[g] - ball->ax, splat(uy)));
          }
        } else if (kind == LaneKind::flat) {
          // As the ball end: a closed form with one square root, cheaper than a test.
          const FlatLanes& flat = scratch.flats[c.move];
          const double uy = y - flat.ay;
          for (int g = 0; g < kGroups; ++g) h[g] = min_n(h[g], flat.at(x[g] - flat.ax, splat(uy)));
        } else if (kind == LaneKind::bull_nose) {
          // Halley steps and several square roots: only the points above the move's plane.
          const BullLanes& bull = scratch.bulls[c.move];
          const double move_row = (c.has_plane ? c.centre_z : -kInf) + c.gradient.y * dy, uy = y - bull.ay;
          DoubleN ux[kGroups], z[kGroups];
          MaskN above[kGroups];
          for (int g = 0; g < kGroups; ++g) {
            ux[g] = x[g] - bull.ax;
            above[g] = move_row + c.gradient.x * dx[g] < h[g];
          }
          bull.at<kGroups>(ux, splat(uy), above, z);
          for (int g = 0; g < kGroups; ++g) h[g] = min_n(h[g], z[g]);
        } else if (kind == LaneKind::profile) {
          // As the bull nose: only the points above the move's plane.
          const ProfileLanes& profile = scratch.profiles[c.move];
          const double move_row = (c.has_plane ? c.centre_z : -kInf) + c.gradient.y * dy, uy = y - profile.ay;
          for (int g = 0; g < kGroups; ++g)
            h[g] = min_n(h[g], profile.at(x[g] - profile.ax, splat(uy), move_row + c.gradient.x * dx[g] < h[g]));
        } else {
          const double move_row = (c.has_plane ? c.centre_z : -kInf) + c.gradient.y * dy;
          for (int g = 0; g < kGroups; ++g)
            for (int l = 0; l < kLanes; ++l)
              if (move_row + c.gradient.x * dx[g][l] < h[g][l]) {
                double z = m.lowest_above(x[g][l], y);
                h[g][l] = std::min(h[g][l], std::max(static_cast<double>(static_cast<float>(z)), empty));
              }
        }
        if constexpr (kTest == RowTest::fresh) {
          // The other cutters' near-equal surfaces (a flat end's neighbouring passes) leave a
          // row's first cut far from its final shape, often not covering it all: measured again
          // after each move, the row rejects the moves that it has become lower than.
          DoubleN top = h[0], excess = h[0] - (tile_row + plane.gradient.x * dx[0]);
          for (int g = 1; g < kGroups; ++g) {
            top = max_n(top, h[g]);
            excess = max_n(excess, h[g] - (tile_row + plane.gradient.x * dx[g]));
          }
          row_top = max_lane(top);
          if (plane.valid) row_excess = max_lane(excess);
        }
      }
      if (!loaded) continue;
      changed = true;
      DoubleN top = splat(-kInf), excess = splat(-kInf);
      for (int g = 0; g < kGroups; ++g) {
        h[g] = max_n(__builtin_convertvector(__builtin_convertvector(h[g], FloatN), DoubleN), splat(empty));
        store_heights(row + g * kLanes, h[g], count - g * kLanes);
        top = max_n(top, h[g]);
        excess = max_n(excess, h[g] - (tile_row + plane.gradient.x * dx[g]));
      }
      state.row_top[r] = max_lane(top);
      state.row_excess[r] = plane.valid ? max_lane(excess) : -kInf;
    }
    if (changed) state.summarise(t.j1 - t.j0 + 1);
  }

  ZMap& map_;
  const ZMapGrid& g_;
  std::span<const Cutter> cutters_;
  std::span<const CutMove> moves_;
  int tiles_x_, tiles_y_, bins_x_, bins_y_;
  std::vector<std::size_t> bin_start_;
  std::vector<std::uint32_t> bin_moves_;
};

}  // namespace detail

// Mills `moves` (tool-tip segments in the Z-map's frame) into `map`. Throws tridex::Error, before
// changing anything, if a move is not finite or names a missing cutter.
inline void mill(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves,
                 MillOptions options = {}) {
  if (moves.size() > std::numeric_limits<std::uint32_t>::max())
    detail::fail("mill: too many moves in one call (", moves.size(), ")");
  for (std::size_t k = 0; k < moves.size(); ++k) {
    if (!is_finite(moves[k].tip.a) || !is_finite(moves[k].tip.b))
      detail::fail("mill: move ", k, " has a coordinate that is not finite");
    if (moves[k].cutter >= cutters.size())
      detail::fail("mill: move ", k, " uses cutter ", moves[k].cutter, " but only ",
                   cutters.size(), " are given");
  }
  if (map.heights.size() != map.grid.size()) detail::fail("mill: Z-map heights do not match its grid");
  detail::Miller(map, cutters, moves).run(options.threads);
}

}  // namespace tridex

namespace tridex {

// How deep one move would cut into what `map` holds now: the largest height − S(q) over the grid
// points under its footprint (S the move's swept lower surface, zero or less when it cuts
// nothing), and the grid point where that happens. For checks such as "does this rapid meet
// stock?": call it before milling the move. Evaluates every point of the footprint (no skipping):
// meant for the few moves that need checking, not for milling.
struct CutDepth {
  double depth = -std::numeric_limits<double>::infinity();  // mm along the frame's z
  int i = -1, j = -1;                                        // where (−1 when off the grid)
};

// The grid points within `radius` of the move's box across the spindle, clipped to the grid
// (empty when none): the points a cutter of that radius on `tip` can reach.
struct PointRange {
  int i0 = 0, i1 = -1, j0 = 0, j1 = -1;
  bool empty() const { return i0 > i1 || j0 > j1; }
};

inline PointRange footprint_points(const ZMapGrid& g, double radius, const Segment& tip) {
  // In double until clipped: a move far off the grid must not overflow an int.
  double i0 = std::ceil((std::min(tip.a.x, tip.b.x) - radius - g.x0) / g.cell);
  double i1 = std::floor((std::max(tip.a.x, tip.b.x) + radius - g.x0) / g.cell);
  double j0 = std::ceil((std::min(tip.a.y, tip.b.y) - radius - g.y0) / g.cell);
  double j1 = std::floor((std::max(tip.a.y, tip.b.y) + radius - g.y0) / g.cell);
  i0 = std::max(i0, 0.0), j0 = std::max(j0, 0.0);
  i1 = std::min(i1, g.nx - 1.0), j1 = std::min(j1, g.ny - 1.0);
  if (i0 > i1 || j0 > j1) return {};
  return {static_cast<int>(i0), static_cast<int>(i1), static_cast<int>(j0), static_cast<int>(j1)};
}

inline CutDepth cut_depth(const ZMap& map, const Cutter& cutter, const Segment& tip) {
  if (!is_finite(tip.a) || !is_finite(tip.b)) detail::fail("cut_depth: move is not finite");
  const ZMapGrid& g = map.grid;
  const PointRange points = footprint_points(g, cutter.radius(), tip);
  CutDepth deepest;
  if (points.empty()) return deepest;
  detail::MoveGeometry m(cutter, tip);
  for (int j = points.j0; j <= points.j1; ++j)
    for (int i = points.i0; i <= points.i1; ++i) {
      if (map.is_empty(i, j)) continue;
      double depth = map.height(i, j) - m.lowest_above(g.x(i), g.y(j));
      if (depth > deepest.depth) deepest = {depth, i, j};
    }
  return deepest;
}

}  // namespace tridex
