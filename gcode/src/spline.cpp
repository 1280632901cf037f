// tridex::gcode — LinuxCNC's splines in the XY plane: G5 (cubic), G5.1 (quadratic B-spline) and
// G5.2/G5.3 (NURBS), turned into the arcs LinuxCNC's controller moves along.
//
// As LinuxCNC 2.9 computes them (GPL sources read, not copied; the formulas are re-written here):
// - src/emc/rs274ngc/interp_convert.cc, convert_spline: the control points and the errors.
//   G5 from the current point P0 to the end P3: P1 = P0 + (I, J), P2 = P3 + (P, Q); without I and
//   J, P1 mirrors the previous G5's end tangent, P0 − (P, Q) of that block (zero before any G5).
//   G5.1: P1 = P0 + (I, J), end P2. I, J, P and Q are increments in program units.
// - interp_convert.cc, convert_nurbs: G5.2 blocks gather control points X Y with weights P and the
//   order L; G5.3 hands them to the controller.
// - src/emc/rs274ngc/nurbs_additional_functions.cc: the curve, a NURBS of order 4 (G5), 3 (G5.1)
//   or L (G5.2) with a clamped uniform knot vector, evaluated by the Cox–de Boor recursion
//   (Piegl & Tiller, The NURBS Book, eq. 2.5) in rational form (eq. 4.2), and its tangent by a
//   difference over ±1e-5 of u.
// - src/emc/task/emccanon.cc, NURBS_FEED / biarc / arc: the curve is cut at 4 × (control points)
//   equal steps of u, and each step becomes a biarc (two tangent arcs matching the curve's ends and
//   end tangents; Bolton, "Biarc curves", CAD 7(2) 1975), an arc degenerating to a line when its
//   chord runs along its start tangent. tridex cuts those arcs into chords within
//   InterpreterOptions::arc_tolerance, as every arc.
// Standalone rs274 prints only NURBS_FEED for these blocks; the pieces are what the machine cuts.
#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "state.hpp"

namespace tridex::gcode {

namespace {

// A clamped NURBS of `order` over its control points (LinuxCNC's G5 and G5.1 make unit weights,
// G5.2 the block's P), parameter u in [0, count − order + 1].
class Nurbs {
 public:
  Nurbs(std::vector<Interpreter::State::NurbsPoint> control, int k)
      : points_(std::move(control)), order_(k) {
    // LinuxCNC's knot_vector_creator: `order` zeros, then 1, 2, …, then u_max repeated.
    const int n = count() - 1;
    for (int i = 0; i <= n + order_; ++i)
      knots_.push_back(i < order_ ? 0.0 : i <= n ? i - order_ + 1 : n - order_ + 2);
  }
  int count() const { return static_cast<int>(points_.size()); }
  double u_max() const { return count() - order_ + 1; }
  Vec2 first() const { return points_.front().p; }

  // The rational form: Σ N_i w_i P_i / Σ N_i w_i (The NURBS Book, eq. 4.2), over the N_i that
  // are not zero at u.
  Vec2 point(double u) const {
    const std::size_t lo = basis(u);
    Vec2 sum(0.0);
    double weight = 0;
    for (std::size_t j = 0; j < basis_.size() && lo + j < points_.size(); ++j) {
      const Interpreter::State::NurbsPoint& c = points_[lo + j];
      sum += basis_[j] * c.weight * c.p;
      weight += basis_[j] * c.weight;
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

 private:
  // Cox–de Boor (The NURBS Book, eq. 2.5), raising the order from 1, with LinuxCNC's closed
  // spans [u_i, u_i+1] at order 1 and 0/0 read as 0: the same sums as LinuxCNC's recursive Nmix.
  // Only N_i with u_i <= u <= u_i+order can be non-zero: the spans holding u, [first, last] (two
  // or more where u is on a knot), and the order − 1 before them. So the work per point is
  // O(order²), whatever the number of control points. basis_[j] = N_lo+j,order(u); returns lo.
  std::size_t basis(double u) const {
    auto t = [&](std::size_t j) { return knots_[j]; };
    const auto index = [&](auto it) { return static_cast<std::size_t>(it - knots_.begin()); };
    std::size_t first = index(std::lower_bound(knots_.begin(), knots_.end(), u));  // t(first) >= u
    first = first == 0 ? 0 : first - 1;  // t(first + 1) >= u
    std::size_t last = index(std::upper_bound(knots_.begin(), knots_.end(), u));  // t(last) > u
    last = std::min(last == 0 ? 0 : last - 1, knots_.size() - 2);                 // t(last) <= u
    const std::size_t k_max = static_cast<std::size_t>(order_);
    const std::size_t lo = first >= k_max - 1 ? first - (k_max - 1) : 0;
    basis_.assign(last + 2 - lo, 0.0);  // i in [lo, last + 1]; N_last+1 stays 0 at every order
    for (std::size_t i = first; i <= last; ++i) basis_[i - lo] = 1.0;
    for (std::size_t k = 2; k <= k_max; ++k)
      for (std::size_t i = lo; i <= last && i + k < knots_.size(); ++i) {
        double left = t(i + k - 1) - t(i), right = t(i + k) - t(i + 1);
        double value = 0;
        if (left != 0) value += (u - t(i)) * basis_[i - lo] / left;
        if (right != 0) value += (t(i + k) - u) * basis_[i + 1 - lo] / right;
        basis_[i - lo] = value;  // basis_[i + 1 − lo] is still of order k − 1 for the next i
      }
    return lo;
  }

  std::vector<Interpreter::State::NurbsPoint> points_;
  int order_;
  std::vector<double> knots_;
  mutable std::vector<double> basis_;
};

}  // namespace

void Interpreter::State::spline(bool quadratic) {
  const char* name = quadratic ? "G5.1" : "G5";
  if (comp.side != 0)
    error(context.motion_column, std::string(name) +
                                     " with cutter radius compensation on: LinuxCNC refuses "
                                     "it (G40 first)");
  require_feed();
  if (modal.feed_mode ==
      FeedMode::inverse_time)  // its length is known only once its biarcs are made
    error(context.motion_column,
          std::string(name) + " in inverse time feed (G93) is not supported: G94 first");
  if (modal.plane != kG17)
    error(context.motion_column, std::string(name) + " is a spline in the XY plane only (G17)");
  for (char c : {'Z', 'A', 'B', 'C'})
    if (w.has(c))
      error(w.col(c),
            std::string(name) + " may not move " + c + " (LinuxCNC's splines stay in XY)");

  Vec3 start = comp.programmed_current ? comp.programmed : to_program(tool.pos);
  comp.programmed_current = false;
  std::vector<NurbsPoint> control(quadratic ? 3 : 4);
  control[0].p = Vec2(start);
  Vec2 first(0.0);  // P1 − P0
  if (quadratic) {
    if (!w.has('I') || !w.has('J')) error(context.motion_column, "G5.1 needs both I and J");
    first = Vec2(length('I'), length('J'));
  } else if (w.has('I') || w.has('J')) {
    if (!w.has('I') || !w.has('J'))
      error(w.col(w.has('I') ? 'I' : 'J'),
            "G5 needs both I and J, or neither (to mirror the "
            "previous G5's end)");
    first = Vec2(length('I'), length('J'));
  } else {
    first = splines.mirror * modal.unit;
  }
  Vec3 end = start;
  for (int i = 0; i < 2; ++i) {
    char c = kAxisLetter[i];
    if (w.has(c)) end[i] = modal.incremental ? start[i] + length(c) : length(c);
  }
  control[1].p = control[0].p + first;
  if (quadratic) {
    control[2].p = Vec2(end);
  } else {
    if (!w.has('P') || !w.has('Q'))
      error(context.motion_column, "G5 needs both P and Q (the end tangent)");
    double p = w.take('P'), q = w.take('Q');
    control[2].p = Vec2(end) + Vec2(p, q) * modal.unit;
    control[3].p = Vec2(end);
    splines.mirror = Vec2(-p, -q);
  }

  if (tool.far) {  // the far rule, as for arcs: only the lateral position changes
    tool.pos = to_machine(end);
    return;
  }

  const int order = quadratic ? 3 : 4;
  nurbs_feed(std::move(control), order, Vec2(end), start[2]);
  tool.pos = to_machine(end);
}

// A G5.2 block: one control point (X Y, weight P) of the NURBS that G5.3 cuts. As LinuxCNC 2.9's
// convert_nurbs: the first block puts the current point first (weight 1, or the P of a block
// without X and Y); X and Y are read against the current point, which stays where it is until
// G5.3 (G91: increments from it, not from the previous control point); L sets the order, 3 by
// default (LinuxCNC takes L only from 4 on).
void Interpreter::State::nurbs_point() {
  if (comp.side != 0)
    error(context.motion_column,
          "G5.2 with cutter radius compensation on: its curve is not offset (G40 first)");
  if (modal.plane != kG17)
    error(context.motion_column, "G5.2 is a NURBS in the XY plane only (G17)");
  for (char c : {'Z', 'A', 'B', 'C'})
    if (w.has(c))
      error(w.col(c), std::string("G5.2 may not move ") + c + " (its control points are in XY)");
  if (w.has('X') != w.has('Y'))
    error(w.col(w.has('X') ? 'X' : 'Y'), "a G5.2 control point needs both X and Y");
  require_feed();
  bool point = w.has('X');
  double weight = 0;
  if (w.has('P')) {
    weight = w.take('P');
    if (!(weight > 0))
      error(w.col('P'), "G5.2 weight P" + format_number(weight) + " must be positive");
  }
  if (splines.nurbs_points.empty()) {
    Vec3 start = comp.programmed_current ? comp.programmed : to_program(tool.pos);
    splines.nurbs_points.push_back({Vec2(start), !point && weight > 0 ? weight : 1.0});
    splines.nurbs_order = 3;
  } else if (!point) {
    error(context.motion_column,
          "G5.2 needs X and Y (a control point): P alone weighs only the first point");
  }
  if (w.has('L')) {
    // LinuxCNC ignores L below 4 (order 3 stays): an L1 or L2 is refused rather than misread.
    splines.nurbs_order = static_cast<int>(integer('L', "G5.2 order L", 3, kMaxNurbsOrder));
  }
  if (!point) return;
  if (!w.has('P'))
    error(context.motion_column, "a G5.2 control point needs its weight P (positive)");
  Vec3 start = to_program(tool.pos);
  Vec2 at(length('X'), length('Y'));
  if (modal.incremental) at += Vec2(start);
  splines.nurbs_points.push_back({at, weight});
}

// G5.3: the NURBS of the G5.2 blocks before it is cut, as LinuxCNC's NURBS_FEED does, and the
// tool stands at its last control point (Z unchanged). No motion mode is left active.
void Interpreter::State::nurbs_end(int column) {
  if (modal.motion != kG5_2) error(column, "G5.3 without G5.2 before it (LinuxCNC refuses it)");
  if (static_cast<int>(splines.nurbs_points.size()) < splines.nurbs_order)
    error(column,
          "G5.3: " + std::to_string(splines.nurbs_points.size()) +
              " control points, fewer than the order L = " + std::to_string(splines.nurbs_order));
  Vec3 start = to_program(tool.pos);
  Vec3 end(splines.nurbs_points.back().p, start[2]);
  if (!tool.far)
    nurbs_feed(std::move(splines.nurbs_points), splines.nurbs_order, Vec2(end), start[2]);
  splines.nurbs_points.clear();
  tool.pos = to_machine(end);
  modal.motion = -1;
}

// emccanon's NURBS_FEED: 4 × (control points) equal steps of u, a biarc each, the last ending
// exactly on `end` (the last control point).
void Interpreter::State::nurbs_feed(std::vector<NurbsPoint> control, int order, const Vec2& end,
                                    double z) {
  Nurbs curve(std::move(control), order);
  const int steps = 4 * curve.count();
  Vec2 p0 = curve.first(), t0 = curve.tangent(0);  // where the tool stands, exactly
  for (int i = 1; i <= steps; ++i) {
    double u = curve.u_max() * i / steps;
    Vec2 p1 = i == steps ? end : curve.point(u);
    Vec2 t1 = curve.tangent(u);
    biarc(p0, t0, p1, t1, z);
    p0 = p1;
    t0 = t1;
  }
}

// Two arcs from `p0` (tangent `t0`) to `p4` (tangent `t4`) meeting tangentially, with equal
// tangent lengths (emccanon's biarc with r = 1); a straight piece where no such pair exists (the
// end tangents parallel or pointing away: LinuxCNC then emits nothing and jumps).
void Interpreter::State::biarc(const Vec2& p0, const Vec2& t0, const Vec2& p4, const Vec2& t4,
                               double z) {
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
void Interpreter::State::spline_piece(const Vec2& from, const Vec2& to, const Vec2& tangent,
                                      double z) {
  Vec2 d = to - from;
  if (glm::length(d) <= 1e-9) return;
  Vec3 end(to.x, to.y, z);
  double den = 2 * (d.y * tangent.x - d.x * tangent.y);
  if (std::abs(den) <= 1e-6 * modal.unit) {
    Vec3 m = to_machine(end);
    emit(MoveKind::feed, tool.pos, m, modal.feed);
    tool.pos = m;
    return;
  }
  double rho = glm::dot(d, d) / den;  // signed radius: > 0 turns left (counter-clockwise)
  Vec2 centre = from + rho * Vec2(-tangent.y, tangent.x);
  Vec3 start(from.x, from.y, z);
  bool ccw = rho > 0;
  arc_chords(start, end, centre, ccw, arc_sweep(start, end, centre, ccw), modal.feed);
}

}  // namespace tridex::gcode
