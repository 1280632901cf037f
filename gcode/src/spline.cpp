// tridex::gcode — LinuxCNC's splines in the XY plane: G5 (cubic) and G5.1 (quadratic B-spline),
// turned into the arcs LinuxCNC's controller moves along.
//
// As LinuxCNC 2.9 computes them (GPL sources read, not copied; the formulas are re-written here):
// - src/emc/rs274ngc/interp_convert.cc, convert_spline: the control points and the errors.
//   G5 from the current point P0 to the end P3: P1 = P0 + (I, J), P2 = P3 + (P, Q); without I and
//   J, P1 mirrors the previous G5's end tangent, P0 − (P, Q) of that block (zero before any G5).
//   G5.1: P1 = P0 + (I, J), end P2. I, J, P and Q are increments in program units.
// - src/emc/rs274ngc/nurbs_additional_functions.cc: the curve, a NURBS of order 4 (G5) or 3 (G5.1)
//   with unit weights and a clamped knot vector, evaluated by the Cox–de Boor recursion
//   (Piegl & Tiller, The NURBS Book, eq. 2.5), and its tangent by a difference over ±1e-5 of u.
// - src/emc/task/emccanon.cc, NURBS_FEED / biarc / arc: the curve is cut at 4 × (control points)
//   equal steps of u, and each step becomes a biarc (two tangent arcs matching the curve's ends and
//   end tangents; Bolton, "Biarc curves", CAD 7(2) 1975), an arc degenerating to a line when its
//   chord runs along its start tangent.
// Standalone rs274 prints only NURBS_FEED for these blocks; the pieces are what the machine cuts.
#include <algorithm>
#include <array>
#include <cmath>

#include "state.hpp"

namespace tridex::gcode {

namespace {

constexpr int kMaxControlPoints = 4;

// A clamped NURBS of `order` over `count` control points with unit weights (the only kind G5 and
// G5.1 make), parameter u in [0, count − order + 1].
struct Nurbs {
  int count = 0;
  int order = 0;
  std::array<Vec2, kMaxControlPoints> points{};
  std::array<double, 2 * kMaxControlPoints> knots{};

  Nurbs(const std::array<Vec2, kMaxControlPoints>& control, int n_points, int k)
      : count(n_points), order(k), points(control) {
    // LinuxCNC's knot_vector_creator: `order` zeros, then 1, 2, …, then u_max repeated.
    const int n = count - 1;
    for (int i = 0; i <= n + order; ++i)
      knots[static_cast<std::size_t>(i)] = i < order ? 0.0 : i <= n ? i - order + 1 : n - order + 2;
  }
  double u_max() const { return count - order + 1; }

  // Cox–de Boor, with LinuxCNC's closed spans [u_i, u_i+1] at order 1 and 0/0 read as 0.
  double basis(int i, int k, double u) const {
    auto t = [&](int j) { return knots[static_cast<std::size_t>(j)]; };
    if (k == 1) return u >= t(i) && u <= t(i + 1) ? 1.0 : 0.0;
    double left = t(i + k - 1) - t(i), right = t(i + k) - t(i + 1);
    double value = 0;
    if (left != 0) value += (u - t(i)) * basis(i, k - 1, u) / left;
    if (right != 0) value += (t(i + k) - u) * basis(i + 1, k - 1, u) / right;
    return value;
  }

  // The rational form, as LinuxCNC divides by the sum of the weighted basis functions.
  Vec2 point(double u) const {
    Vec2 sum(0.0);
    double weight = 0;
    for (int i = 0; i < count; ++i) {
      double b = basis(i, order, u);
      sum += b * points[static_cast<std::size_t>(i)];
      weight += b;
    }
    return sum / weight;
  }

  Vec2 tangent(double u) const {
    constexpr double kDu = 1e-5;
    double lo = std::max(0.0, u - kDu), hi = std::min(u_max(), u + kDu);
    Vec2 d = (point(hi) - point(lo)) / (hi - lo);
    double h = glm::length(d);
    return h != 0 ? d / h : d;
  }
};

}  // namespace

void Interpreter::State::spline(bool quadratic) {
  const char* name = quadratic ? "G5.1" : "G5";
  if (comp_side != 0)
    error(motion_column, std::string(name) + " with cutter radius compensation on: LinuxCNC refuses "
                                             "it (G40 first)");
  require_feed();
  if (feed_mode == FeedMode::inverse_time)  // its length is known only once its biarcs are made
    error(motion_column, std::string(name) + " in inverse time feed (G93) is not supported: G94 first");
  if (plane != 170) error(motion_column, std::string(name) + " is a spline in the XY plane only (G17)");
  for (char c : {'Z', 'A', 'B', 'C'})
    if (w.has(c))
      error(w.col(c), std::string(name) + " may not move " + c + " (LinuxCNC's splines stay in XY)");

  Vec3 start = comp_programmed_current ? comp_programmed : to_program(pos);
  comp_programmed_current = false;
  std::array<Vec2, kMaxControlPoints> control{};
  control[0] = Vec2(start);
  Vec2 first(0.0);  // P1 − P0
  if (quadratic) {
    if (!w.has('I') || !w.has('J')) error(motion_column, "G5.1 needs both I and J");
    first = Vec2(length('I'), length('J'));
  } else if (w.has('I') || w.has('J')) {
    if (!w.has('I') || !w.has('J'))
      error(w.col(w.has('I') ? 'I' : 'J'), "G5 needs both I and J, or neither (to mirror the "
                                           "previous G5's end)");
    first = Vec2(length('I'), length('J'));
  } else {
    first = spline_mirror * unit;
  }
  Vec3 end = start;
  for (int i = 0; i < 2; ++i) {
    char c = kAxisLetter[i];
    if (w.has(c)) end[i] = incremental ? start[i] + length(c) : length(c);
  }
  control[1] = control[0] + first;
  int count = 3;
  if (quadratic) {
    control[2] = Vec2(end);
  } else {
    if (!w.has('P') || !w.has('Q')) error(motion_column, "G5 needs both P and Q (the end tangent)");
    double p = w.take('P'), q = w.take('Q');
    control[2] = Vec2(end) + Vec2(p, q) * unit;
    control[3] = Vec2(end);
    spline_mirror = Vec2(-p, -q);
    count = 4;
  }

  if (far) {  // the far rule, as for arcs: only the lateral position changes
    pos = to_machine(end);
    return;
  }

  // emccanon's NURBS_FEED: 4 × (control points) equal steps of u, a biarc each.
  Nurbs curve(control, count, count);
  const int steps = 4 * count;
  Vec2 p0 = control[0], t0 = curve.tangent(0);
  for (int i = 1; i <= steps; ++i) {
    double u = curve.u_max() * i / steps;
    Vec2 p1 = i == steps ? Vec2(end) : curve.point(u);
    Vec2 t1 = curve.tangent(u);
    biarc(p0, t0, p1, t1, start[2]);
    p0 = p1;
    t0 = t1;
  }
  pos = to_machine(end);
}

// Two arcs from `p0` (tangent `t0`) to `p4` (tangent `t4`) meeting tangentially, with equal
// tangent lengths (emccanon's biarc with r = 1); a straight piece where no such pair exists (the
// end tangents parallel or pointing away: LinuxCNC then emits nothing and jumps).
void Interpreter::State::biarc(const Vec2& p0, const Vec2& t0, const Vec2& p4, const Vec2& t4, double z) {
  Vec2 v = p0 - p4;
  double c = glm::dot(v, v);
  double b = 2 * glm::dot(v, t0 + t4);
  double a = 2 * (glm::dot(t0, t4) - 1);
  double root = std::sqrt(std::max(0.0, b * b - 4 * a * c));
  double beta1 = (-b - root) / 2 / a, beta2 = (-b + root) / 2 / a;
  double beta = std::max(beta1, beta2);
  if (a == 0 || (beta1 > 0 && beta2 > 0) || !std::isfinite(beta)) {
    spline_piece(p0, p4, t0, z);  // along the chord
    return;
  }
  Vec2 p1 = p0 + beta * t0, p3 = p4 - beta * t4;
  Vec2 p2 = 0.5 * (p1 + p3);  // (p1 β + p3 α) / (α + β) with α = β
  Vec2 tm = p3 - p2;
  double h = glm::length(tm);
  if (h != 0) tm /= h;
  spline_piece(p0, p2, t0, z);
  spline_piece(p2, p4, tm, z);
}

// emccanon's arc(): the circle through `from` and `to` tangent to `tangent` at `from`, or a line
// when the chord runs along the tangent (|2 (chord × tangent)| ≤ 1e-6 program units).
void Interpreter::State::spline_piece(const Vec2& from, const Vec2& to, const Vec2& tangent, double z) {
  Vec2 d = to - from;
  if (glm::length(d) <= 1e-9) return;
  Vec3 end(to.x, to.y, z);
  double den = 2 * (d.y * tangent.x - d.x * tangent.y);
  if (std::abs(den) <= 1e-6 * unit) {
    Vec3 m = to_machine(end);
    emit(MoveKind::feed, pos, m, feed);
    pos = m;
    return;
  }
  double rho = glm::dot(d, d) / den;  // signed radius: > 0 turns left (counter-clockwise)
  Vec2 centre = from + rho * Vec2(-tangent.y, tangent.x);
  Vec3 start(from.x, from.y, z);
  bool ccw = rho > 0;
  arc_chords(start, end, centre, ccw, arc_sweep(start, end, centre, ccw), feed);
}

}  // namespace tridex::gcode
