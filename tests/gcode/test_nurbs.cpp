// G5.2 / G5.3 NURBS (gcode/src/spline.cpp) against de Boor's algorithm in homogeneous coordinates
// (Piegl & Tiller, The NURBS Book, A3.1 and §4.2: the rational curve is the projection of a
// B-spline over (w x, w y, w)), written here independently of the Cox–de Boor basis sums the
// interpreter evaluates as LinuxCNC does, on random control points, weights and orders.
#include <doctest/doctest.h>

#include <algorithm>
#include <random>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

struct ControlPoint {
  Vec2 p;
  double w;
};

// de Boor: the point at u of the clamped curve of `order` whose inner knots are 1, 2, …
// (LinuxCNC's knot vector: `order` zeros, 1 … count − order, then count − order + 1 repeated).
Vec2 de_boor(const std::vector<ControlPoint>& control, int order, double u) {
  const int n = static_cast<int>(control.size()) - 1, p = order - 1;
  const double u_max = n - p + 1;
  auto knot = [&](int i) { return std::clamp(static_cast<double>(i - p), 0.0, u_max); };
  int span = std::min(static_cast<int>(std::floor(u)) + p, n);  // knot(span) <= u < knot(span + 1)
  std::vector<glm::dvec3> d;
  for (int j = 0; j <= p; ++j) {
    const ControlPoint& c = control[static_cast<std::size_t>(span - p + j)];
    d.emplace_back(c.p * c.w, c.w);
  }
  for (int r = 1; r <= p; ++r)
    for (int j = p; j >= r; --j) {
      int i = span - p + j;
      double alpha = (u - knot(i)) / (knot(i + p + 1 - r) - knot(i));
      d[static_cast<std::size_t>(j)] =
          (1 - alpha) * d[static_cast<std::size_t>(j - 1)] + alpha * d[static_cast<std::size_t>(j)];
    }
  return Vec2(d[static_cast<std::size_t>(p)]) / d[static_cast<std::size_t>(p)].z;
}

std::vector<Move> moves_of_line(const Result& r, int line) {
  std::vector<Move> out;
  for (const Move& m : r.moves)
    if (m.line == line) out.push_back(m);
  return out;
}

// The G5.3 pieces: a continuous path at the curve's Z, through the curve's points at the
// 4 × (control points) equal steps of u where LinuxCNC's biarcs join, every chord end within
// `tolerance` (mm) of the curve, ending exactly on the last control point.
void check_follows(const std::vector<Move>& pieces, const std::vector<ControlPoint>& control,
                   int order, double tolerance) {
  REQUIRE(!pieces.empty());
  CHECK(near(Vec3(Vec2(pieces.front().start), 0), Vec3(control.front().p, 0), 1e-9));
  CHECK(near(Vec3(Vec2(pieces.back().end), 0), Vec3(control.back().p, 0), 1e-9));
  for (std::size_t k = 1; k < pieces.size(); ++k) CHECK(near(pieces[k].start, pieces[k - 1].end));
  const double u_max = static_cast<double>(control.size()) - order + 1;
  std::vector<Vec2> dense;
  for (int k = 0; k <= 20000; ++k) dense.push_back(de_boor(control, order, u_max * k / 20000));
  double worst = 0;
  for (const Move& m : pieces) {
    double best = 1e9;
    for (const Vec2& q : dense) best = std::min(best, glm::length(Vec2(m.end) - q));
    worst = std::max(worst, best);
    CHECK(m.end.z == pieces.front().start.z);
  }
  CHECK(worst <= tolerance);
  const int steps = 4 * static_cast<int>(control.size());
  std::size_t at = 0;
  for (int i = 1; i <= steps; ++i) {
    Vec2 q = de_boor(control, order, u_max * i / steps);
    while (at < pieces.size() && glm::length(Vec2(pieces[at].end) - q) > 1e-7) ++at;
    CHECK_MESSAGE(at < pieces.size(), "curve point " << i << " of " << steps << " is no piece end");
  }
}

const MachineConfig kRs274Machine = *MachineConfig::bundled("rs274");

}  // namespace

TEST_CASE(
    "G5.2/G5.3: biarcs through the de Boor curve's points, random points, weights and orders") {
  std::mt19937_64 rng(52);
  std::uniform_real_distribution<double> coordinate(-20, 20), weight(0.3, 3);
  for (int trial = 0; trial < 40; ++trial) {
    int order = 3 + static_cast<int>(rng() % 3);
    int count = order + static_cast<int>(rng() % 6);
    auto printable = [&] { return std::round(coordinate(rng) * 1e4) / 1e4; };
    std::vector<ControlPoint> control{{Vec2(printable(), printable()), 1.0}};
    std::string text =
        cat("G21 G17 G90 F100\nG0 X", fmt(control[0].p.x), " Y", fmt(control[0].p.y), " Z-1\n");
    for (int i = 1; i < count; ++i) {
      ControlPoint c{Vec2(printable(), printable()), std::round(weight(rng) * 1e3) / 1e3};
      control.push_back(c);
      text += cat(i == 1 ? "G5.2 " : "", "X", fmt(c.p.x), " Y", fmt(c.p.y), " P", fmt(c.w),
                  i == 1 ? cat(" L", order) : std::string(), "\n");
    }
    text += "G5.3\nG1 Z0\n";
    CAPTURE(text);
    Result r = run_program(text, {}, kRs274Machine);
    int line_g53 = count + 2;
    // Biarcs cut to arc_tolerance chords stayed within 0.14 mm of these curves in a 40 mm field:
    // the joins are the exact check; this bound catches a piece that leaves the curve.
    check_follows(moves_of_line(r, line_g53), control, order, 0.3);
    // After G5.3 the tool stands on the last control point; no motion mode is left.
    REQUIRE(!r.moves.empty());
    CHECK(near(r.moves.back().end, Vec3(control.back().p, 0)));
  }
}

TEST_CASE(
    "G5.2: the first block's P weighs the start; G91 reads from the start; inches; default order "
    "3") {
  // A first block without X Y: its P is the start point's weight.
  Result r = run_program("G21 G17 G90 F100\nG0 X0 Y0 Z-1\nG5.2 P3\nX10 Y10 P1\nX20 Y0 P0.5\nG5.3\n",
                         {}, kRs274Machine);
  check_follows(moves_of_line(r, 6), {{{0, 0}, 3}, {{10, 10}, 1}, {{20, 0}, 0.5}}, 3, 0.2);
  // G91: each point is an increment from the start (the current point does not move until G5.3).
  Result g91 =
      run_program("G20 G17 G91 F10\nG0 X1 Y1 Z-0.1\nG5.2 X1 Y1 P1\nX2 Y0 P2\nX3 Y1 P1\nG5.3\n", {},
                  kRs274Machine);
  const double in = 25.4;
  check_follows(moves_of_line(g91, 6),
                {{{in, in}, 1}, {{2 * in, 2 * in}, 1}, {{3 * in, in}, 2}, {{4 * in, 2 * in}, 1}}, 3,
                1.0);
  // Two control points after the start and the default order 3: the quadratic Bezier, which
  // G5.1 cuts as the same pieces.
  Result nurbs = run_program("G21 G17 G90 F100\nG0 X0 Y0 Z-1\nG5.2 X2 Y4 P1\nX6 Y0 P1\nG5.3\n", {},
                             kRs274Machine);
  Result g51 = run_program("G21 G17 G90 F100\nG0 X0 Y0 Z-1\nG5.1 I2 J4 X6 Y0\n", {}, kRs274Machine);
  std::vector<Move> a = moves_of_line(nurbs, 5), b = moves_of_line(g51, 3);
  REQUIRE(a.size() == b.size());
  for (std::size_t k = 0; k < a.size(); ++k) CHECK(near(a[k].end, b[k].end, 1e-9));
}

TEST_CASE("G5.2/G5.3 errors at the word, as rs274 gives them or where it would misread") {
  const std::string start = "G21 G17 G90 F100\nG0 X0 Y0 Z-1\n";
  struct Case {
    std::string blocks;
    int line, column;
    std::string text;
  };
  for (const Case& c : std::vector<Case>{
           {"G5.2 X1 P1", 3, 6, "both X and Y"},
           {"G5.2 Y1 P1", 3, 6, "both X and Y"},
           {"G5.2 X1 Y1", 3, 1, "weight P"},
           {"G5.2 X1 Y1 P0", 3, 12, "must be positive"},
           {"G5.2 X1 Y1 P1\nX2 Y2 P-1", 4, 7, "must be positive"},
           {"G5.2 X1 Y1 P1\nP2", 4, 1, "P alone"},
           {"G5.2 X1 Y1 P1 L2", 3, 15, "order L"},
           {"G5.2 X1 Y1 P1 Z1", 3, 15, "may not move Z"},
           {"G18 G5.2 X1 Y1 P1", 3, 5, "XY plane only"},
           {"G41 D1 G1 X5\nG5.2 X1 Y1 P1", 4, 1, "cutter radius compensation"},
           {"G5.3", 3, 1, "without G5.2"},
           {"G5.2 X1 Y1 P1\nG1 X3\nG5.3", 5, 1, "without G5.2"},
           {"G5.2 X1 Y1 P1 L4\nX2 Y0 P1\nG5.3", 5, 1, "fewer than the order L = 4"},
           {"G5.2 X1 Y1 P1\nX2 Y0 P1\nG5.3 X4", 5, 1, "no motion code or coordinates"},
           {"G5.2 X1 Y1 P1\nX2 Y0 P1\nG5.3\nX4 Y4", 6, 1, "without an active motion mode"},
       }) {
    CAPTURE(c.blocks);
    MachineConfig machine = kRs274Machine;
    machine.tool_diameters = {{1, 2.0}};
    Diagnostic d = error_of(start + c.blocks + "\n", {}, machine);
    CHECK(d.line == c.line);
    CHECK(d.column == c.column);
    CHECK_MESSAGE(d.message.find(c.text) != std::string::npos, d.message);
  }
  Diagnostic no_feed = error_of("G21 G17 G90\nG0 X0 Y0 Z-1\nG5.2 X1 Y1 P1\n", {}, kRs274Machine);
  CHECK(no_feed.message.find("feed") != std::string::npos);
  // Points a G5.3 never ended are dropped, as by LinuxCNC: said, never silent.
  Result dropped = run_program(start + "G5.2 X1 Y1 P1\nX2 Y0 P1\nG1 X5\n", {}, kRs274Machine);
  CHECK(std::any_of(dropped.warnings.begin(), dropped.warnings.end(), [](const Diagnostic& d) {
    return d.line == 5 && d.message.find("no G5.3") != std::string::npos;
  }));
  // Outside LinuxCNC's dialect G5.2 is no code tridex reads.
  CHECK(error_of(start + "G5.2 X1 Y1 P1\nX2 Y0 P1\nG5.3\n").message.find("--machine linuxcnc") !=
        std::string::npos);
}
