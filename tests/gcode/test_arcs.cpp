#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

struct ArcCase {
  int plane;  // 17, 18, 19
  bool ccw;
  Vec2 centre;  // in the plane's (u, v) = G17 (X,Y), G18 (Z,X), G19 (Y,Z)
  double radius;
  double a0;      // start angle
  double sweep;   // (0, 2π]
  double w0, w1;  // helix: normal coordinate at start and end
};

std::array<int, 3> axes(int plane) {
  if (plane == 18) return {2, 0, 1};
  if (plane == 19) return {1, 2, 0};
  return {0, 1, 2};
}

Vec3 point(const ArcCase& c, double angle, double w) {
  auto [u, v, n] = axes(c.plane);
  Vec3 p;
  p[u] = c.centre.x + c.radius * std::cos(angle);
  p[v] = c.centre.y + c.radius * std::sin(angle);
  p[n] = w;
  return p;
}

ArcCase random_arc(std::mt19937_64& rng) {
  std::uniform_real_distribution<double> u01(0, 1);
  ArcCase c;
  c.plane = 17 + static_cast<int>(rng() % 3);
  c.ccw = rng() % 2;
  c.centre = Vec2(u01(rng) * 100 - 50, u01(rng) * 100 - 50);
  c.radius = 0.5 + u01(rng) * 40;
  c.a0 = u01(rng) * 2 * std::numbers::pi;
  c.sweep = 0.05 + u01(rng) * (2 * std::numbers::pi - 0.1);
  c.w0 = u01(rng) * 10;
  c.w1 = rng() % 2 ? c.w0 : c.w0 - u01(rng) * 5;
  return c;
}

std::string header(const ArcCase& c, const Vec3& start) {
  return "G21 G90 G" + std::to_string(c.plane) + " F100\nG0 X" + fmt(start.x) + " Y" +
         fmt(start.y) + " Z" + fmt(start.z) + "\n";
}

// Exact decimal text: the points are rounded to the 4 decimals the program carries.
Vec3 rounded(const Vec3& p) {
  return Vec3(std::stod(fmt(p.x)), std::stod(fmt(p.y)), std::stod(fmt(p.z)));
}

}  // namespace

TEST_CASE("arcs (I/J/K): on the circle, within the chord tolerance, turning the right way") {
  std::mt19937_64 rng(3);
  for (int trial = 0; trial < 300; ++trial) {
    ArcCase c = random_arc(rng);
    auto [u, v, n] = axes(c.plane);
    double a1 = c.a0 + (c.ccw ? c.sweep : -c.sweep);
    Vec3 start = rounded(point(c, c.a0, c.w0));
    Vec3 end = rounded(point(c, a1, c.w1));
    // Centre offsets from the rounded start; the rounded end lies within 1e-4 of the circle.
    Vec2 offset = c.centre - Vec2(start[u], start[v]);
    const char* letters = "IJK";
    std::string program = header(c, start) + (c.ccw ? "G3" : "G2") + " X" + fmt(end.x) + " Y" +
                          fmt(end.y) + " Z" + fmt(end.z) + " " + letters[u] + fmt(offset.x) + " " +
                          letters[v] + fmt(offset.y) + "\nM30\n";
    Vec2 centre =
        Vec2(start[u], start[v]) + Vec2(std::stod(fmt(offset.x)), std::stod(fmt(offset.y)));
    InterpreterOptions options;
    Result r = run_program(program, options, at_origin());
    REQUIRE(r.moves.size() >= 2);
    CHECK(near(r.moves.back().end, end, 1e-12));
    double turned = 0, r0 = glm::length(Vec2(start[u], start[v]) - centre);
    for (std::size_t k = 1; k < r.moves.size(); ++k) {
      const Move& m = r.moves[k];
      CHECK(m.kind == MoveKind::arc);
      CHECK(near(m.start, r.moves[k - 1].end));
      Vec2 a = Vec2(m.start[u], m.start[v]) - centre, b = Vec2(m.end[u], m.end[v]) - centre;
      CHECK(glm::length(b) == doctest::Approx(r0).epsilon(0).scale(0).epsilon(1e-3));
      // Sagitta of the chord: the midpoint must stay within the tolerance of the circle.
      double mid = glm::length(0.5 * (a + b));
      CHECK(0.5 * (glm::length(a) + glm::length(b)) - mid <= options.arc_tolerance + 1e-9);
      double step = std::atan2(a.x * b.y - a.y * b.x, glm::dot(a, b));
      CHECK((c.ccw ? step > 0 : step < 0));
      turned += std::abs(step);
      // Helix: the normal coordinate moves in proportion to the angle.
      CHECK(m.end[n] <= std::max(c.w0, c.w1) + 1e-4);
      CHECK(m.end[n] >= std::min(c.w0, c.w1) - 1e-4);
    }
    CHECK(turned == doctest::Approx(c.sweep).epsilon(1e-4));
  }
}

TEST_CASE("arcs: the R form gives the same path as the I/J/K form") {
  std::mt19937_64 rng(5);
  for (int trial = 0; trial < 300; ++trial) {
    ArcCase c = random_arc(rng);
    if (c.sweep > 2 * std::numbers::pi - 0.05) continue;
    auto [u, v, n] = axes(c.plane);
    (void)n;
    double a1 = c.a0 + (c.ccw ? c.sweep : -c.sweep);
    Vec3 start = point(c, c.a0, c.w0), end = point(c, a1, c.w1);
    Vec2 offset = c.centre - Vec2(start[u], start[v]);
    char text[512];
    const char* letters = "IJK";
    std::snprintf(text, sizeof text, "G0 X%.12f Y%.12f Z%.12f\n%s X%.12f Y%.12f Z%.12f ", start.x,
                  start.y, start.z, c.ccw ? "G3" : "G2", end.x, end.y, end.z);
    std::string base = "G21 G90 G" + std::to_string(c.plane) + " F100\n" + text;
    char ijk[128], r[64];
    std::snprintf(ijk, sizeof ijk, "%c%.12f %c%.12f\nM30\n", letters[u], offset.x, letters[v],
                  offset.y);
    std::snprintf(r, sizeof r, "R%.12f\nM30\n", c.sweep > std::numbers::pi ? -c.radius : c.radius);
    Result a = run_program(base + ijk, {}, at_origin());
    Result b = run_program(base + r, {}, at_origin());
    REQUIRE(a.moves.size() == b.moves.size());
    for (std::size_t k = 0; k < a.moves.size(); ++k)
      CHECK(near(a.moves[k].end, b.moves[k].end, 1e-6));
  }
}

TEST_CASE("arcs: full circles, G90.1 centres, G20, and the chord tolerance option") {
  InterpreterOptions options;
  Result r = run_program("G17 G90 F100\nG0 X10 Y0 Z0\nG2 I-10 J0\nM30\n", options, at_origin());
  CHECK(near(r.moves.back().end, Vec3(10, 0, 0)));
  double turned = 0;
  for (std::size_t k = 1; k < r.moves.size(); ++k) {
    Vec2 a(r.moves[k].start), b(r.moves[k].end);
    turned += std::atan2(a.x * b.y - a.y * b.x, glm::dot(a, b));
  }
  CHECK(turned == doctest::Approx(-2 * std::numbers::pi));
  std::size_t fine = r.moves.size();
  options.arc_tolerance = 0.1;
  r = run_program("G17 G90 F100\nG0 X10 Y0 Z0\nG2 I-10 J0\nM30\n", options, at_origin());
  CHECK(r.moves.size() < fine / 5);
  // Absolute centre (G90.1) and inches.
  r = run_program("G20 G17 G90 G90.1 F10\nG0 X1 Y0 Z0\nG3 X0 Y1 I0 J0\nM30\n", {}, at_origin());
  CHECK(near(r.moves.back().end, Vec3(0, 25.4, 0)));
  for (const Move& m : r.moves) CHECK(glm::length(Vec2(m.end)) == doctest::Approx(25.4));
}

TEST_CASE("arcs: bad arcs are errors with their position") {
  Diagnostic d = error_of("G17 G90 F100\nG0 X10 Y0 Z0\nG2 X0 Y10.1 I-10 J0\n");
  CHECK(d.line == 3);
  CHECK(d.column == 1);
  CHECK(d.message.find("radius") != std::string::npos);
  d = error_of("G17 G90 F100\nG0 X10 Y0 Z0\nG2 X0 Y0 I0 J0\n");
  CHECK(d.message.find("zero-radius") != std::string::npos);
  d = error_of("G17 G90 F100\nG0 X10 Y0 Z0\nG2 X0 Y0\n");
  CHECK(d.message.find("needs") != std::string::npos);
  d = error_of("G17 G90 F100\nG0 X10 Y0 Z0\nG2 X0 Y0 R0\n");
  CHECK(d.message.find("zero-radius") != std::string::npos);
  d = error_of("G17 G90 F100\nG0 X10 Y0 Z0\nG2 X-10 Y0 R2\n");
  CHECK(d.message.find("too small") != std::string::npos);
  d = error_of("G17 G90 F100\nG0 X10 Y0 Z0\nG2 R5\n");
  CHECK(d.message.find("full circle") != std::string::npos);
  d = error_of("G17 G90 F100\nG0 X10 Y0 Z0\nG2 X0 Y0 I-5 K3\n");
  CHECK(d.message.find("K3") != std::string::npos);  // K is not a G17 centre word
  d = error_of("G17 G90 F100\nG0 X10 Y0 Z0\nG2 X0 Y0 I-5 R5\n");
  CHECK(d.message.find("both") != std::string::npos);
  d = error_of("G17 G90\nG0 X10 Y0 Z0\nG2 X0 Y0 I-5\n");
  CHECK(d.message.find("feed") != std::string::npos);
  // Z never set: the tool is still far along +Z, so the arc only moves it laterally (the far
  // rule) and the approach comes down at the arc's end; a helix from there has no known start.
  Result r = run_program("G17 G90 F100\nG0 X10 Y0\nG2 X0 Y0 I-5\nG1 Z-1\nM30\n");
  REQUIRE(r.moves.size() == 1);
  CHECK(r.moves[0].from_far);
  CHECK(near(r.moves[0].end, Vec3(0, 0, -1)));
  d = error_of("G17 G90 F100\nG0 X10 Y0\nG2 X0 Y0 Z-1 I-5\n");
  CHECK(d.message.find("retracted") != std::string::npos);
}

// LinuxCNC 2.9 (interp_arc.cc; each case checked with rs274) cuts an I/J/K arc whose end radius
// differs from its start radius as a spiral up to 0.02·√2 mm (G21) or 0.002·√2 in (G20), and up to
// 100 times that within 0.1 % of the radius; the machine's arc_radius_tolerance (0.02 mm unless
// set) stays for other machines.
TEST_CASE("arcs: LinuxCNC's spiral tolerance on --machine linuxcnc") {
  const MachineConfig linuxcnc = *MachineConfig::bundled("linuxcnc");
  // Radius 10 → 10.02 mm: within 0.02·√2 mm.
  const std::string small = "G21 G17 G90 F100\nG0 X10 Y0 Z0\nG3 X0 Y10.02 I-10 J0\n";
  Result r = run_program(small, {}, linuxcnc);
  REQUIRE(!r.moves.empty());
  CHECK(near(r.moves.back().end, Vec3(0, 10.02, 0)));
  // Fanuc's rule: a spiral up to the machine's arc_radius_tolerance (0.02 mm unless set), an
  // alarm beyond; a program posted to 4 decimals of an inch is 0.00254 mm off.
  const std::string inch4 = "G20 G17 G90 F10\nG0 X21.5179 Y2. Z0.1\nG3 X19.6618 I-0.928 J0.\n";
  Result fanuc = run_program(inch4);
  REQUIRE(!fanuc.moves.empty());
  CHECK(near(fanuc.moves.back().end, Vec3(19.6618, 2, 0.1) * 25.4));
  MachineConfig tight;
  tight.arc_radius_tolerance = 0.002;
  CHECK(error_of(inch4, {}, tight).message.find("by more than 0.002 mm") != std::string::npos);
  CHECK(error_of("G21 G17 G90 F100\nG0 X10 Y0 Z0\nG3 X0 Y10.03 I-10 J0\n")
            .message.find("by more than 0.02 mm") != std::string::npos);
  // 10 → 10.03 mm: over 0.0283 mm and over 0.1 % of the radius.
  Diagnostic d = error_of("G21 G17 G90 F100\nG0 X10 Y0 Z0\nG3 X0 Y10.03 I-10 J0\n", {}, linuxcnc);
  CHECK(d.message.find("spiral tolerance") != std::string::npos);
  // Radius 100 → 100.05 mm: over 0.0283 mm but within 0.1 %.
  CHECK(!run_program("G21 G17 G90 F100\nG0 X100 Y0 Z0\nG3 X0 Y100.05 I-100 J0\n", {}, linuxcnc)
             .moves.empty());
  // In inches the bound is 0.002·√2 in: 1 → 1.0025 in is within, 1 → 1.003 in is not.
  CHECK(!run_program("G20 G17 G90 F10\nG0 X1 Y0 Z0\nG3 X0 Y1.0025 I-1 J0\n", {}, linuxcnc)
             .moves.empty());
  CHECK(error_of("G20 G17 G90 F10\nG0 X1 Y0 Z0\nG3 X0 Y1.003 I-1 J0\n", {}, linuxcnc)
            .message.find("spiral") != std::string::npos);
}

// LinuxCNC's G2/G3 P: the number of turns. rs274 prints `G3 X10 Y0 I-10 J0 Z-6 P3` as
// ARC_FEED(…, 3, -6, …): three full circles about (0, 0) while Z falls 6 mm (interp_find.cc
// find_turn: the arc plus (P − 1)·2π). Before, P was refused as a word no code used, and
// lagun-linuxcnc's pocket_circ.ngc (a helical plunge `G3 … Z… P1`) stopped there.
TEST_CASE("arcs: LinuxCNC's P on G2/G3 winds P − 1 full circles before the end") {
  const MachineConfig linuxcnc = linuxcnc_at_origin();
  // The angle turned about `centre` in XY, signed (counter-clockwise positive), and the Z the
  // tool reaches when it has turned half of it.
  auto turned = [](const Result& r, int line, const Vec2& centre, double& z_halfway) {
    double total = 0, half = 0;
    for (const Move& m : r.moves)
      if (m.line == line) {
        Vec2 a = Vec2(m.start) - centre, b = Vec2(m.end) - centre;
        total += std::atan2(a.x * b.y - a.y * b.x, glm::dot(a, b));
      }
    z_halfway = std::nan("");
    for (const Move& m : r.moves)
      if (m.line == line) {
        Vec2 a = Vec2(m.start) - centre, b = Vec2(m.end) - centre;
        half += std::atan2(a.x * b.y - a.y * b.x, glm::dot(a, b));
        if (std::abs(half) >= std::abs(total) / 2 - 1e-12) {
          z_halfway = m.end.z;
          break;
        }
      }
    return total;
  };
  const double pi = std::numbers::pi;
  double z_half = 0;
  Result r = run_program(
      "G21 G17 G90 F100\nG0 X10 Y0 Z0\nG3 X10 Y0 I-10 J0 Z-6 P3\n"
      "G2 X0 Y10 I-10 J0 Z-8 P2\nG3 X-10 Y0 R10 P2\nM2\n",
      {}, linuxcnc);
  CHECK(turned(r, 3, Vec2(0, 0), z_half) == doctest::Approx(6 * pi));
  CHECK(z_half == doctest::Approx(-3).epsilon(0.01));  // the rise shared over all three turns
  CHECK(near(r.moves.back().end, Vec3(-10, 0, -8)));
  // Clockwise from 0° to 90°: 270°, and one more circle.
  CHECK(turned(r, 4, Vec2(0, 0), z_half) == doctest::Approx(-3.5 * pi));
  CHECK(turned(r, 5, Vec2(0, 0), z_half) == doctest::Approx(2.5 * pi));  // the R form too
  // P1 is the plain arc.
  r = run_program("G21 G17 G90 F100\nG0 X10 Y0 Z0\nG3 X0 Y10 I-10 J0 P1\nM2\n", {}, linuxcnc);
  CHECK(turned(r, 3, Vec2(0, 0), z_half) == doctest::Approx(pi / 2));
  // Inverse time: the block takes 1/F minutes over its whole length (find_arc_length).
  r = run_program("G21 G17 G90 G93\nG0 X10 Y0 Z0\nG3 X10 Y0 I-10 J0 P2 F2\nM2\n", {}, linuxcnc);
  CHECK(r.moves.back().feed == doctest::Approx(2 * (4 * pi * 10)));
  // Under cutter compensation (rs274: G41.1 D2 then this arc prints ARC_FEED(…, 2, …)).
  MachineConfig comp = linuxcnc;
  r = run_program(
      "G21 G17 G90 F100\nG0 X20 Y0 Z0\nG41.1 D2\nG1 X10 Y0\nG3 X10 Y0 I-10 J0 P2\n"
      "G1 X10 Y-5\nG40\nG0 X30\nM2\n",
      {}, comp);
  double around = 0;  // the chords on the offset circle (radius 9), not the corner arcs at X10 Y0
  for (const Move& m : r.moves)
    if (m.line == 5 && std::abs(glm::length(Vec2(m.start)) - 9) < 1e-6 &&
        std::abs(glm::length(Vec2(m.end)) - 9) < 1e-6)
      around += std::atan2(m.start.x * m.end.y - m.start.y * m.end.x,
                           glm::dot(Vec2(m.start), Vec2(m.end)));
  CHECK(around == doctest::Approx(4 * pi));
  // rs274's errors: P an integer of 1 or more.
  CHECK(error_of("G21 G17 F100\nG0 X10 Y0 Z0\nG3 X10 Y0 I-10 P1.5\n", {}, linuxcnc)
            .message.find("integer") != std::string::npos);
  CHECK(error_of("G21 G17 F100\nG0 X10 Y0 Z0\nG3 X10 Y0 I-10 P0\n", {}, linuxcnc)
            .message.find("integer in [1") != std::string::npos);
  // Fanuc has no such word: P on an arc is still a word no code of the block uses.
  CHECK(error_of("G21 G17 F100\nG0 X10 Y0 Z0\nG3 X10 Y0 I-10 P2\n", {}, at_origin())
            .message.find("P2") != std::string::npos);
}
