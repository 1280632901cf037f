// tridex — simultaneous 5-axis moves on the triple dexel: the material a cutter removes while
// its axis turns, cut from the dexel rays directly (docs/design.md, "Simultaneous moves").
//
// A Z-map (zmap.hpp) needs one spindle direction; a move whose tool axis turns has none. Its
// removal is computed ray by ray on the triple dexel instead, after the 3+2 maps are intersected
// (removal commutes with intersection: the order does not change the result).
//
// The exact primitive is a cutter with a FIXED axis translated along a segment: the swept solid
// is convex (a Minkowski sum of convex sets), so each dexel ray meets it in one interval. For the
// quadric pieces of a profile (a ball on the axis, frusta: flat, cone, chamfer, the shank) it is
// closed form (detail/sweep_interval.hpp). Otherwise (the bull nose's torus), with the signed
// distance D to the cutter (convex, detail/sweep_distance.hpp), a ray point x(u) lies in the
// sweep iff F(u) = min over s in [0, 1] of D(x(u) − s·(to − from)) ≤ 0, and F is convex in u:
// golden-section search finds a point where it is ≤ 0 (or its minimum) and bisection its zeros, to
// `precision`, with no sampling that could miss a contact.
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
// until e ≤ the tolerance (or a cap, and the band achieved is reported). plan_sweep_parts() does
// the same for the cutter's tip and shank apart, closed form under TCP, and drops the sub-steps
// that cannot reach material (docs/design.md, "Simultaneous moves").
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <optional>
#include <span>
#include <utility>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/detail/sweep_distance.hpp"
#include "tridex/detail/sweep_interval.hpp"
#include "tridex/detail/sweep_rows.hpp"
#include "tridex/dexel.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/geometry.hpp"

namespace tridex {

// A cutter cut at `height` above its tip (a sweep needs a finite solid; cutter.hpp's cutters
// continue upward without end, which only a fixed direction allows).
struct SweepCutter {
  Cutter cutter;
  double height = 0;  // > cutter.profile_height()
  // 0: a profile arc off the axis (the bull nose's torus) is searched (exact, slow). > 0: it is
  // replaced by inscribed chords of at most this sagitta, cut in closed form, and the sagitta
  // joins the band (plan_sweep_parts).
  double chord = 0;
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

// The part of a cutter a sweep step moves. A turning cutter's points move the more the farther
// they are from the tip, so plan_sweep_parts() sub-steps the tip (the profile and a radius of
// the side above it; a ball end's ball alone, which turning does not change) apart from the
// shank above it, and drops the shank's sub-steps that cannot reach material.
enum class SweepPart : std::uint8_t { whole, tip, shank };

// One swept piece: part `part` of cutter `cutter` (an index into the caller's cutters) with
// unit axis `axis` translated from tip `from` to tip `to`.
struct SweepStep {
  Vec3 from{0.0}, to{0.0};
  Vec3 axis{0.0, 0.0, 1.0};
  std::uint32_t cutter = 0;
  SweepPart part = SweepPart::whole;
};

// Bounds on a move's pose as a function of its parameter s ∈ [0, 1] (per unit s).
// turn_rate must also bound |d² axis / ds²| by its square, as rotations about fixed axes at
// constant rates do (the sum of their rates: plan_sweep_parts's ball bound relies on it).
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

// A cutter's parts as sweep_remove cuts them (SweepPart): each part's heights above the tip and
// its convex pieces, when all are quadrics (detail/sweep_interval.hpp: closed-form intervals);
// otherwise `closed` is false and the distance search below is used.
struct SweepPartShape {
  double lo = 0, hi = 0;  // the part: the cutter between these heights
  double top = 0;         // the highest point of its pieces (a ball end's whole ball reaches 2R)
  bool closed = true;
  double chord_error = 0;  // how far the cutter may stand outside the pieces (SweepCutter::chord)
  std::vector<detail::SweepPiece> pieces;
  std::vector<detail::SweepPieceSpan> spans;  // of the pieces
  bool empty() const { return !(hi > lo); }
};

struct SweepShape {
  std::array<SweepPartShape, 3> parts;  // by SweepPart
  bool ball_tip = false;                // the tip is one ball on the axis: turning moves it not
  double ball_centre = 0;               // its centre's height above the tip
};

// The tip part is the profile and one radius of side above it (a ball end: the ball alone), the
// shank the rest: the material a cut reaches is mostly within the tip, whose points move least.
inline SweepShape sweep_shape(const SweepCutter& c) {
  SweepShape shape;
  const double r = c.cutter.radius();
  const bool ball = c.cutter.shape() == CutterShape::ball && c.height >= 2 * r;
  const double split = std::min(c.height, ball ? r : c.cutter.profile_height() + r);
  const double heights[3][2] = {{0, c.height}, {0, split}, {split, c.height}};
  for (std::size_t p = 0; p < 3; ++p) {
    SweepPartShape& part = shape.parts[p];
    part.lo = heights[p][0], part.hi = heights[p][1], part.top = part.hi;
    if (part.empty()) continue;
    part.closed = detail::sweep_pieces(c.cutter, c.height, part.lo, part.hi, c.chord, part.pieces,
                                       part.chord_error);
    if (!part.closed) part.pieces.clear();
    for (const detail::SweepPiece& piece : part.pieces) {
      part.top = std::max(part.top, piece.hi);
      part.spans.push_back(detail::sweep_piece_span(piece));
    }
  }
  const auto& tip = shape.parts[1].pieces;
  shape.ball_tip = ball && tip.size() == 1 && tip[0].ball;
  if (shape.ball_tip) shape.ball_centre = tip[0].centre;
  return shape;
}

// The box around part `part` of cutter `c` swept with axis `axis` from tip `from` to tip `to`.
inline Aabb sweep_part_bounds(const SweepCutter& c, const SweepPartShape& part, const Vec3& from,
                              const Vec3& to, const Vec3& axis) {
  Aabb box;
  Vec3 lateral;
  for (int i = 0; i < 3; ++i)
    lateral[i] = c.cutter.radius() * std::sqrt(std::max(0.0, 1.0 - axis[i] * axis[i]));
  for (const Vec3& tip : {from, to})
    for (const Vec3& end : {tip + part.lo * axis, tip + part.top * axis}) {
      box.extend(end - lateral);
      box.extend(end + lateral);
    }
  return box;
}

// The box around cutter `c` in one sub-step (both end poses; the sweep is their convex hull).
inline Aabb sweep_step_bounds(const SweepCutter& c, const SweepStep& step) {
  const SweepPartShape& part = sweep_shape(c).parts[static_cast<std::size_t>(step.part)];
  return sweep_part_bounds(c, part, step.from, step.to, step.axis);
}

// The interval [enter, exit] of the ray x(u) = point + u·e_axis, u ∈ [lo, hi], inside the
// sweep of `step`, to within `precision` (mm, on the side of more removal); nullopt if none. The
// cutter is taken between heights part_lo and part_hi (the part's distance: the largest of the
// cutter's and of the two slabs', still convex and 1-Lipschitz, ≤ 0 exactly on the part).
inline std::optional<std::pair<double, double>> ray_sweep_interval(
    const SweepCutter& c, const SweepStep& step, const Vec3& point, int axis, double lo, double hi,
    double precision, double part_lo = 0,
    double part_hi = std::numeric_limits<double>::infinity()) {
  auto distance = [&](const Vec3& tip, const Vec3& x) {
    const double h = glm::dot(x - tip, step.axis);
    return std::max({c.distance(tip, step.axis, x), part_lo - h, h - part_hi});
  };
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
    if (length <= precision) return distance(step.from, x);
    auto along = [&](double s) { return distance(step.from + s * travel, x); };
    return detail::convex_minimum(along, 0.0, 1.0, precision / length).second;
  };
  auto inside = [&](double u) {
    const Vec3 x = at(u);
    if (length <= precision) return distance(step.from, x) <= 0;
    auto along = [&](double s) { return distance(step.from + s * travel, x); };
    return detail::convex_minimum(along, 0.0, 1.0, precision / length, length).second <= 0;
  };
  const auto [u_in, f_in] = detail::convex_minimum(f, lo, hi, precision, 1.0);
  if (f_in > 0) return std::nullopt;
  const double enter = inside(lo) ? lo : detail::convex_crossing(inside, u_in, lo, precision);
  const double exit = inside(hi) ? hi : detail::convex_crossing(inside, u_in, hi, precision);
  return std::pair{enter, exit};
}

// Where material may lie, for dropping sub-steps that cannot reach any: per grid, tiles of
// kTile × kTile rays with the least entry and the greatest exit of their intervals. Removal only
// shrinks rays, so a box whose rays' tiles hold nothing within it stays empty through sweep_remove;
// and a sweep inside such a box would remove nothing from any ray.
class SweepMaterial {
 public:
  static constexpr int kTile = 16;
  explicit SweepMaterial(const TripleDexel& d) : origin_(d.origin), spacing_(d.spacing) {
    for (int a = 0; a < 3; ++a) {
      const DexelGrid& g = d.grids[static_cast<std::size_t>(a)];
      Tiles& t = tiles_[static_cast<std::size_t>(a)];
      t.nu = g.nu, t.nv = g.nv, t.tu = (g.nu + kTile - 1) / kTile;
      const int tv = (g.nv + kTile - 1) / kTile;
      t.extent.assign(
          static_cast<std::size_t>(t.tu) * static_cast<std::size_t>(tv),
          {std::numeric_limits<float>::infinity(), -std::numeric_limits<float>::infinity()});
      for (int iv = 0; iv < g.nv; ++iv)
        for (int iu = 0; iu < g.nu; ++iu) {
          const auto ray = g.ray(iu, iv);
          if (ray.empty()) continue;
          auto& e = t.extent[static_cast<std::size_t>((iv / kTile) * t.tu + iu / kTile)];
          e.first = std::min(e.first, ray.front().enter);
          e.second = std::max(e.second, ray.back().exit);
        }
    }
  }
  bool may_touch(const Aabb& box) const {
    for (int a = 0; a < 3; ++a) {
      const Tiles& t = tiles_[static_cast<std::size_t>(a)];
      const int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
      const int u0 = first(box.min[u], u), u1 = last(box.max[u], u, t.nu);
      const int v0 = first(box.min[v], v), v1 = last(box.max[v], v, t.nv);
      for (int tv = v0 / kTile; u0 <= u1 && v0 <= v1 && tv <= v1 / kTile; ++tv)
        for (int tu = u0 / kTile; tu <= u1 / kTile; ++tu) {
          const auto& e = t.extent[static_cast<std::size_t>(tv * t.tu + tu)];
          if (e.first <= box.max[a] && e.second >= box.min[a]) return true;
        }
    }
    return false;
  }

 private:
  struct Tiles {
    int nu = 0, nv = 0, tu = 0;
    std::vector<std::pair<float, float>> extent;
  };
  int first(double x, int axis) const {
    return static_cast<int>(std::max(0.0, std::ceil((x - origin_[axis]) / spacing_)));
  }
  int last(double x, int axis, int n) const {
    return static_cast<int>(std::min(n - 1.0, std::floor((x - origin_[axis]) / spacing_)));
  }
  Vec3 origin_;
  double spacing_;
  std::array<Tiles, 3> tiles_;
};

namespace detail {

// plan_sweep_parts for a straight tip (TCP): the band of a sub-step of length Δ in s is closed
// form, so sub-steps halve from the whole move, dropping those whose grown box holds no material.
template <class PoseAt, class MayTouch>
void plan_straight_part(PoseAt& pose_at, double omega, const SweepCutter& c,
                        const SweepShape& shape, SweepPart which, double tolerance,
                        std::uint32_t cutter, MayTouch& may_touch, SweepPlan& plan) {
  const SweepPartShape& part = shape.parts[static_cast<std::size_t>(which)];
  const bool ball = which == SweepPart::tip && shape.ball_tip;
  const double reach = std::hypot(c.cutter.radius(), part.top), centre = shape.ball_centre;
  auto band = [&](double delta) {
    return part.chord_error +
           (ball ? centre * omega * omega * delta * delta / 8 : reach * omega * delta / 2);
  };
  // As plan_sweep_parts's sampled branch: chords too coarse for the tolerance cannot be made up
  // by sub-steps, so those stop at a sixteenth of it (the band then says what was achieved).
  const double enough = part.chord_error + std::max(tolerance - part.chord_error, tolerance / 16);
  // The fewest equal sub-steps n that fit (the band falls with their length): a power of two
  // found by doubling, then the least n below it by bisection.
  long n = 1;
  while (n < kMaxSubSteps && band(1.0 / static_cast<double>(n)) > enough) n *= 2;
  long lo = n / 2 + 1, hi = n;
  while (lo < hi) {
    const long m = lo + (hi - lo) / 2;
    if (band(1.0 / static_cast<double>(m)) > enough)
      lo = m + 1;
    else
      hi = m;
  }
  n = hi;
  // Halves of the n sub-steps, [i0, i1] of them, dropped whole where they cannot reach material.
  auto visit = [&](auto& self, long i0, long i1) -> void {
    const double s0 = static_cast<double>(i0) / static_cast<double>(n);
    const double s1 = static_cast<double>(i1) / static_cast<double>(n);
    const ToolPose p0 = pose_at(s0), p1 = pose_at(s1), mid = pose_at(0.5 * (s0 + s1));
    Vec3 from = p0.tip, to = p1.tip;
    if (ball) {  // the ball's centre on its chord, the step's tip below it on the middle axis
      from += centre * (p0.axis - mid.axis);
      to += centre * (p1.axis - mid.axis);
    }
    const double e = band(s1 - s0);
    if (!may_touch(sweep_part_bounds(c, part, from, to, mid.axis).inflated(e))) return;
    if (i1 - i0 > 1) {
      self(self, i0, i0 + (i1 - i0) / 2);
      self(self, i0 + (i1 - i0) / 2, i1);
      return;
    }
    plan.band = std::max(plan.band, e);
    plan.steps.push_back({from, to, mid.axis, cutter, which});
  };
  visit(visit, 0L, n);
}

}  // namespace detail

// The sub-steps of one move for the tip and the shank of cutter `c` apart (SweepPart), each
// with e ≤ `tolerance` (or the band achieved at the cap), dropping those whose box grown by e
// `may_touch(Aabb)` says holds no material (SweepMaterial). Under a straight tip (TCP) the band
// is closed form: a point at distance ≤ ρ from the tip strays from the sub-step's middle-axis
// copy by at most ρ·Ω·Δ/2 (Ω = bounds.turn_rate, Δ the sub-step's length in s), and a ball's
// centre, c above the tip, from its chord by c·Ω²·Δ²/8, since |axis''| ≤ Ω² for rotations about
// fixed axes at constant rates (a ball's sweep is the same whatever its axis: it needs no more
// sub-steps than its centre's path). Otherwise each part is planned as plan_sweep plans a move.
// A part cut as inscribed chords (SweepCutter::chord) adds their sagitta to its band.
template <class PoseAt, class MayTouch>
SweepPlan plan_sweep_parts(PoseAt&& pose_at, const PoseBounds& bounds, const SweepCutter& c,
                           const SweepShape& shape, double tolerance, std::uint32_t cutter,
                           MayTouch&& may_touch) {
  detail::require_positive(tolerance, "sweep tolerance");
  SweepPlan plan;
  for (SweepPart which : {SweepPart::tip, SweepPart::shank}) {
    const SweepPartShape& part = shape.parts[static_cast<std::size_t>(which)];
    if (part.empty()) continue;
    if (bounds.tip_straight) {
      detail::plan_straight_part(pose_at, bounds.turn_rate, c, shape, which, tolerance, cutter,
                                 may_touch, plan);
      continue;
    }
    const bool ball = which == SweepPart::tip && shape.ball_tip;
    const double centre = ball ? shape.ball_centre : 0.0;
    auto centre_at = [&](double s) {  // a ball is swept along its centre's path
      ToolPose p = pose_at(s);
      p.tip += centre * p.axis;
      return p;
    };
    const PoseBounds b{bounds.tip_speed + centre * bounds.turn_rate, bounds.turn_rate, false};
    const double reach = ball ? 0.0 : std::hypot(c.cutter.radius(), part.top);
    const double geometric = std::max(tolerance - part.chord_error, tolerance / 16);
    SweepPlan p = plan_sweep(centre_at, b, reach, geometric, cutter);
    p.band += part.chord_error;
    for (SweepStep step : p.steps) {
      step.from -= centre * step.axis, step.to -= centre * step.axis, step.part = which;
      if (!may_touch(sweep_part_bounds(c, part, step.from, step.to, step.axis).inflated(p.band)))
        continue;
      plan.band = std::max(plan.band, p.band);
      plan.steps.push_back(step);
    }
  }
  return plan;
}

namespace detail {

// The interval of the ray through `point` along `axis` in the sweep of `step` (part `part` of
// cutter `c`) where it may meet material, which lies within [lo, hi] on this ray: closed form for
// quadric pieces (detail::sweep_pieces_hull), else the search (within [lo, hi], `precision`).
inline std::optional<std::pair<double, double>> sweep_step_interval(
    const SweepCutter& c, const SweepPartShape& part, const SweepStep& step, const Vec3& point,
    int axis, double lo, double hi, double precision, std::uint64_t only = ~std::uint64_t{0}) {
  if (!part.closed)
    return ray_sweep_interval(c, step, point, axis, lo, hi, precision, part.lo, part.hi);
  const Vec3 travel = step.to - step.from;
  const double margin = 1e-6 * (1 + part.top + glm::length(travel) + c.cutter.radius());
  return sweep_pieces_hull(
      part.pieces, part.spans, margin, step.from, travel, step.axis, point, axis, lo, hi,
      [](std::size_t) { return 0.0; }, only);
}

inline SweepStepCut sweep_step_cut(const SweepCutter& c, const SweepPartShape& part,
                                   const SweepStep& s) {
  SweepStepCut cut;
  cut.box = sweep_part_bounds(c, part, s.from, s.to, s.axis);
  cut.part = &part;
  if (part.closed && part.pieces.size() == 1 && part.pieces[0].ball) {
    cut.capsule = true;
    cut.c0 = s.from + part.pieces[0].centre * s.axis;
    cut.c1 = cut.c0 + (s.to - s.from);
    cut.radius = part.pieces[0].radius;
  }
  return cut;
}

// The bound of a group of steps (more than one) of one closed cutter part `part`
// (detail/sweep_rows.hpp). Ball tips: the capsule around the chord of their centres, grown by
// the members' centres' largest distance from it. Other parts: a member's tip path lies within
// δ of the chord of the group's tips (both ends do: distance to a segment is convex) and its
// axis within |a − a_m| of the middle member's a_m, which moves a point at distance r from the
// tip by at most r·|a − a_m| (the part is symmetric about its axis: a rotation taking a_m to a,
// by θ with 2 sin(θ/2) = |a − a_m|). So every member lies in the sweep, along the chord with axis
// a_m, of the part's pieces, each grown (sweep_grown_piece) by δ + reach·max |a − a_m|, its reach
// the farthest of its points from the tip, plus a margin far above rounding and the conic
// solve's slack (sweep_group_grow).
inline void sweep_group_bound(const SweepPartShape& part, std::span<const SweepStep> steps,
                              std::span<const SweepStepCut> cuts,
                              std::span<const std::uint32_t> members, SweepGroup& g) {
  const SweepStepCut& first = cuts[members.front()];
  if (first.capsule) {
    g.bound = SweepBound::capsule;
    g.c0 = first.c0, g.c1 = cuts[members.back()].c1;
    double far = 0;
    for (std::uint32_t s : members)
      far = std::max({far, distance_to_segment(cuts[s].c0, g.c0, g.c1),
                      distance_to_segment(cuts[s].c1, g.c0, g.c1)});
    g.radius = first.radius + far + 1e-6 * (1 + first.radius + far);
    return;
  }
  if (part.pieces.empty()) return;  // the box bound
  g.bound = SweepBound::pieces;
  g.part = &part;
  g.c0 = steps[members.front()].from, g.c1 = steps[members.back()].to;
  g.axis = steps[members[members.size() / 2]].axis;
  for (std::uint32_t s : members) {
    g.tip = std::max({g.tip, distance_to_segment(steps[s].from, g.c0, g.c1),
                      distance_to_segment(steps[s].to, g.c0, g.c1)});
    g.turn = std::max(g.turn, glm::length(steps[s].axis - g.axis));
  }
}

// How far group `g` grows a piece whose farthest point from the tip is `reach` (sweep_group_bound).
inline double sweep_group_grow(const SweepGroup& g, double reach) {
  const double e = g.tip + reach * g.turn;
  return e + 1e-5 * (1 + reach + e);
}

// The interval of group `g`'s SweepBound::pieces bound on the ray through `point` along `axis`
// where it may meet material within [lo, hi], or part of it that meets `current`; `only` gets the
// bits of the pieces its members may need (detail::sweep_pieces_hull). Kept out of sweep_ray's
// loop, which a ball's capsules run fastest alone (balls at 2·10^4 segments: 18 % slower inlined).
[[gnu::noinline]] inline std::optional<std::pair<double, double>> sweep_group_hull(
    const SweepGroup& g, std::span<const DexelInterval> current, const Vec3& point, int axis,
    double lo, double hi, std::uint64_t& only) {
  const Vec3 travel = g.c1 - g.c0;
  const SweepPartShape& part = *g.part;
  const double margin =
      1e-6 * (1 + part.top + glm::length(travel) + glm::length(g.box.max - g.box.min));
  only = 0;
  return sweep_pieces_hull(
      part.pieces, part.spans, margin, g.c0, travel, g.axis, point, axis, lo, hi,
      [&](std::size_t k) { return sweep_group_grow(g, part.spans[k].reach); }, ~std::uint64_t{0},
      &only, [&](const std::pair<double, double>& b) { return sweep_bound_meets(b, current); });
}

// Ray (iu, iv) of grid `axis` less the sweeps of the steps of the groups listed for it
// (detail/sweep_rows.hpp). A group whose bound cannot meet the material left is skipped whole;
// each sweep is subtracted as soon as it is found; one whose box holds no material left is not
// computed. Intervals are closed form (or found to `precision` within the material left), and
// subtraction in any order gives the same set. `rows_of[s]`: the rows (v indices) step s's box
// covers, as sweep_rows lists them (none where it covers no column).
inline void sweep_ray(std::span<const DexelInterval> ray, const TripleDexel& d, int axis, int iu,
                      int iv, std::span<const SweepCutter> cutters,
                      std::span<const SweepStep> steps, std::span<const SweepStepCut> cuts,
                      const SweepGroups& groups, std::span<const std::pair<int, int>> rows_of,
                      std::span<const std::uint32_t> listed, double precision,
                      std::vector<DexelInterval>& current, std::vector<DexelInterval>& out) {
  const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
  Vec3 point = d.origin;
  point[u] += d.spacing * iu;
  point[v] += d.spacing * iv;
  current.assign(ray.begin(), ray.end());
  for (std::uint32_t g : listed) {
    const SweepGroup& group = groups.groups[g];
    if (current.empty()) break;
    if (point[u] < group.box.min[u] || point[u] > group.box.max[u]) continue;
    std::uint64_t only = ~std::uint64_t{0};
    if (group.count > 1 &&
        !sweep_group_may_cut(group, current, point, axis, [&](double lo, double hi) {
          return sweep_group_hull(group, current, point, axis, lo, hi, only);
        }))
      continue;
    for (std::uint32_t k = group.first; k < group.first + group.count; ++k) {
      const std::uint32_t s = groups.members[k];
      const SweepStepCut& cut = cuts[s];
      const Aabb& box = cut.box;
      if (current.empty()) break;
      if (iv < rows_of[s].first || iv > rows_of[s].second) continue;
      if (point[u] < box.min[u] || point[u] > box.max[u]) continue;
      std::optional<std::pair<double, double>> removed;
      if (cut.capsule) {  // as cheap as the test below, which it does not need
        removed = capsule_interval(cut.c0, cut.c1, cut.radius, point, axis);
      } else {
        double lo = box.max[axis], hi = box.min[axis];  // the material left within the box
        for (const DexelInterval& span : current)
          if (span.exit >= box.min[axis] && span.enter <= box.max[axis]) {
            lo = std::min(lo, std::max<double>(span.enter, box.min[axis]));
            hi = std::max(hi, std::min<double>(span.exit, box.max[axis]));
          }
        if (!(lo <= hi)) continue;
        const SweepStep& step = steps[s];
        removed = sweep_step_interval(cutters[step.cutter], *cut.part, step, point, axis, lo, hi,
                                      precision, only);
      }
      // A cut that rounds to a point removes nothing, but inside a span would split it into two
      // touching ones (no valid dexel): in program order it may land in a gap, in another not.
      const DexelInterval cut_out{static_cast<float>(removed ? removed->first : 0.0),
                                  static_cast<float>(removed ? removed->second : 0.0)};
      if (removed && cut_out.enter < cut_out.exit) subtract_one(current, cut_out);
    }
  }
  out.insert(out.end(), current.begin(), current.end());
}

}  // namespace detail

// Removes the sweeps of `steps` (each with its cutter) from every ray of `d`, to within
// `precision` mm where a part's interval is searched (closed-form ones are exact). Rays are
// independent, each takes its steps (grouped, detail/sweep_rows.hpp) in an order fixed by the
// steps alone, and the grids are rebuilt in ray order, so the result does not depend on `threads`.
inline void sweep_remove(TripleDexel& d, std::span<const SweepCutter> cutters,
                         std::span<const SweepStep> steps, unsigned threads,
                         double precision = 1e-4) {
  detail::require_positive(precision, "sweep precision");
  std::vector<SweepShape> shapes;
  for (const SweepCutter& c : cutters) shapes.push_back(sweep_shape(c));
  std::vector<detail::SweepStepCut> cuts;
  cuts.reserve(steps.size());
  bool closed = true;  // every part closed form: removal in any order gives the same rays
  for (const SweepStep& s : steps) {
    if (s.cutter >= cutters.size()) detail::fail("sweep_remove: step names cutter ", s.cutter);
    const SweepPartShape& part = shapes[s.cutter].parts[static_cast<std::size_t>(s.part)];
    closed = closed && part.closed;
    cuts.push_back(detail::sweep_step_cut(cutters[s.cutter], part, s));
  }
  // Groups may grow a few spacings past one step's box: rays list them, not their steps.
  const detail::SweepGroups groups = detail::sweep_groups(
      cuts, 3 * cutters.size(),
      [&](std::size_t s) { return 3 * steps[s].cutter + static_cast<std::size_t>(steps[s].part); },
      [&](std::size_t key) {
        return shapes[key / 3].parts[key % 3].pieces.size() > 1 ? detail::kSweepGroupPieces
                                                                : detail::kSweepGroup;
      },
      8 * d.spacing, closed,
      [&](std::span<const std::uint32_t> members, detail::SweepGroup& g) {
        const SweepStep& step = steps[members.front()];
        detail::sweep_group_bound(shapes[step.cutter].parts[static_cast<std::size_t>(step.part)],
                                  steps, cuts, members, g);
      });
  std::vector<std::pair<int, int>> rows_of(steps.size());
  for (int axis = 0; axis < 3; ++axis) {
    const DexelGrid& old = d.grids[static_cast<std::size_t>(axis)];
    const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
    for (std::size_t s = 0; s < cuts.size(); ++s) {  // none where the box misses every column
      rows_of[s] = detail::sweep_index_range(d, cuts[s].box, v, old.nv);
      const auto [u0, u1] = detail::sweep_index_range(d, cuts[s].box, u, old.nu);
      if (u0 > u1) rows_of[s] = {1, 0};
    }
    const detail::SweepRows rows =
        detail::sweep_rows(d, axis, groups.groups.size(),
                           [&](std::size_t g) -> const Aabb& { return groups.groups[g].box; });
    DexelGrid next = detail::build_grid(
        d.lattice(), axis, threads, [&](std::size_t r, std::vector<DexelInterval>& out) {
          const int iu = static_cast<int>(r % static_cast<std::size_t>(old.nu));
          const int iv = static_cast<int>(r / static_cast<std::size_t>(old.nu));
          const auto listed = rows.at(iu, iv);
          if (listed.empty()) {
            const auto ray = old.ray(r);
            out.insert(out.end(), ray.begin(), ray.end());
            return;
          }
          thread_local std::vector<DexelInterval> scratch;
          detail::sweep_ray(old.ray(r), d, axis, iu, iv, cutters, steps, cuts, groups, rows_of,
                            listed, precision, scratch, out);
        });
    d.grids[static_cast<std::size_t>(axis)] = std::move(next);
  }
}

}  // namespace tridex
