// G5 / G5.1 splines (gcode/src/spline.cpp) against the closed-form Bézier curves they are: the
// clamped NURBS of order 4 over four points (order 3 over three) with unit weights is the cubic
// (quadratic) Bézier curve, written here in the Bernstein form, independently of the Cox–de Boor
// recursion the interpreter evaluates as LinuxCNC does.
#include <doctest/doctest.h>

#include <algorithm>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace test_splines {

Vec2 bezier(const std::vector<Vec2>& p, double t) {
  double s = 1 - t;
  if (p.size() == 3) return s * s * p[0] + 2 * s * t * p[1] + t * t * p[2];
  return s * s * s * p[0] + 3 * s * s * t * p[1] + 3 * s * t * t * p[2] + t * t * t * p[3];
}

std::vector<Move> moves_of_line(const Result& r, int line) {
  std::vector<Move> out;
  for (const Move& m : r.moves)
    if (m.line == line) out.push_back(m);
  return out;
}

// The pieces join the curve at every step of u (4 × control points steps, LinuxCNC's biarc
// ends), every chord end stays within `tolerance` of the curve, and the path is continuous.
void check_follows(const std::vector<Move>& pieces, const std::vector<Vec2>& control,
                   double tolerance) {
  REQUIRE(!pieces.empty());
  for (std::size_t k = 1; k < pieces.size(); ++k) CHECK(near(pieces[k].start, pieces[k - 1].end));
  std::vector<Vec2> dense;
  for (int k = 0; k <= 20000; ++k) dense.push_back(bezier(control, k / 20000.0));
  for (const Move& m : pieces) {
    double best = 1e9;
    for (const Vec2& q : dense) best = std::min(best, glm::length(Vec2(m.end) - q));
    CHECK(best <= tolerance);
    CHECK(m.end.z == doctest::Approx(pieces.front().start.z));
  }
  const int steps = 4 * static_cast<int>(control.size());
  std::size_t at = 0;
  for (int i = 1; i <= steps; ++i) {
    Vec2 q = bezier(control, static_cast<double>(i) / steps);
    while (at < pieces.size() && glm::length(Vec2(pieces[at].end) - q) > 1e-9) ++at;
    CHECK_MESSAGE(at < pieces.size(), "curve point " << i << " of " << steps << " is no piece end");
  }
}

const MachineConfig kLinuxcnc = *MachineConfig::bundled("linuxcnc");

TEST_CASE("G5: biarcs through the cubic Bezier's points, G1 continuous, end exact") {
  Result r =
      run_program("G21 G17 G90 F100\nG0 X1 Y1 Z-1\nG5 I0 J6 P8 Q-6 X3 Y3\nG1 Z0\n", {}, kLinuxcnc);
  std::vector<Move> pieces = moves_of_line(r, 3);
  // Biarcs (LinuxCNC's pieces) and their chords stay within 0.01 mm of this 10 mm curve.
  check_follows(pieces, {{1, 1}, {1, 7}, {11, -3}, {3, 3}}, 0.01);
  CHECK(near(pieces.back().end, Vec3(3, 3, -1)));
  // The default machine makes the same pieces.
  Result d = run_program("G21 G17 G90 F100\nG0 X1 Y1 Z-1\nG5 I0 J6 P8 Q-6 X3 Y3\nG1 Z0\n");
  std::vector<Move> same = moves_of_line(d, 3);
  REQUIRE(same.size() == pieces.size());
  for (std::size_t k = 0; k < same.size(); ++k) CHECK(near(same[k].end, pieces[k].end));
}

TEST_CASE(
    "G5 without I and J mirrors the previous G5's P and Q; inches and G91 read as rs274 does") {
  std::string head = "G20 G17 G90 F10\nG0 X0 Y0 Z-0.1\nG5 I0 J0.5 P0.3 Q-0.2 X1 Y1\n";
  Result mirrored = run_program(head + "G91 G5 P0.2 Q0.4 X1 Y-0.5\n", {}, kLinuxcnc);
  Result explicit_ij = run_program(head + "G91 G5 I-0.3 J0.2 P0.2 Q0.4 X1 Y-0.5\n", {}, kLinuxcnc);
  std::vector<Move> a = moves_of_line(mirrored, 4), b = moves_of_line(explicit_ij, 4);
  REQUIRE(a.size() == b.size());
  for (std::size_t k = 0; k < a.size(); ++k) CHECK(near(a[k].end, b[k].end));
  const double in = 25.4;
  check_follows(a, {{in, in}, {0.7 * in, 1.2 * in}, {2.2 * in, 0.9 * in}, {2 * in, 0.5 * in}},
                0.03);
}

TEST_CASE(
    "G5.1: biarcs through the quadratic Bezier's points; Fanuc's G5.1 Q1 stays a smoothing mode") {
  Result r = run_program("G21 G17 G90 F100\nG0 X0 Y0 Z-1\nG5.1 I2 J4 X6 Y0\n", {}, kLinuxcnc);
  check_follows(moves_of_line(r, 3), {{0, 0}, {2, 4}, {6, 0}}, 0.01);
  Result fanuc = run_program("G21 G17 G90 F100\nG0 X0 Y0 Z-1\nG5.1 Q1\nG1 X5\n");
  REQUIRE(fanuc.moves.size() == 2);
  CHECK(fanuc.moves.back().kind == MoveKind::feed);
  // Fanuc's G05 P10000 (high-speed machining on) stays an unsupported mode, not a spline.
  CHECK(error_of("G21 G17 G90 F100\nG0 X0 Y0 Z-1\nG05 P10000\n")
            .message.find("unsupported code G5") != std::string::npos);
  Result spline = run_program("G21 G17 G90 F100\nG0 X0 Y0 Z-1\nG5.1 I2 J4 X6 Y0\n");
  CHECK(moves_of_line(spline, 3).size() == moves_of_line(r, 3).size());
}

TEST_CASE("G5/G5.1 errors as rs274 gives them, at the word") {
  const std::string start = "G21 G17 G90 F100\nG0 X0 Y0 Z-1\n";
  struct Case {
    std::string block;
    int column;
    std::string text;
  };
  for (const Case& c : std::vector<Case>{
           {"G18 G5 I1 J1 P1 Q1 X2", 5, "XY plane only"},
           {"G5 I1 J1 P1 Q1 X2 Z1", 19, "may not move Z"},
           {"G5 I1 P1 Q1 X2", 4, "both I and J, or neither"},
           {"G5 I1 J1 P1 X2", 1, "both P and Q"},
           {"G5 X2 Y1", 1, "both P and Q"},
           {"G5.1 I1 X2", 1, "both I and J"},
           {"G41 D1 G1 X5\nG5 I1 J1 P1 Q1 X9", 1, "cutter radius compensation"},
       }) {
    CAPTURE(c.block);
    MachineConfig machine = kLinuxcnc;
    machine.tool_diameters = {{1, 2.0}};
    Diagnostic d = error_of(start + c.block + "\n", {}, machine);
    CHECK(d.column == c.column);
    CHECK(d.message.find(c.text) != std::string::npos);
  }
  // A block under modal G5 without P and Q: rs274 refuses it too.
  Diagnostic modal = error_of(start + "G5 I0 J1 P1 Q1 X2 Y2\nX3 Y3\n", {}, kLinuxcnc);
  CHECK(modal.line == 4);
  CHECK(modal.message.find("both P and Q") != std::string::npos);
  Diagnostic no_feed = error_of("G21 G17 G90\nG0 X0 Y0 Z-1\nG5 I0 J1 P1 Q1 X2 Y2\n", {}, kLinuxcnc);
  CHECK(no_feed.message.find("feed") != std::string::npos);
}

}  // namespace test_splines
