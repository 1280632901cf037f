// Cutter radius compensation (gcode/src/comp.cpp) against geometry computed here: offset lines
// one radius from the programmed contour, convex corners rounded about the programmed corner,
// concave corners cut where the offsets meet, and the errors LinuxCNC gives. The move-for-move
// agreement with LinuxCNC is test_linuxcnc_diff.cpp's (tests/data/gcode/linuxcnc/comp/).
#include <doctest/doctest.h>

#include <cmath>
#include <string>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using tridex::gcode::test::at_origin;
using tridex::gcode::test::error_of;
using tridex::gcode::test::near;
using tridex::gcode::test::Result;
using tridex::gcode::test::run_program;

namespace {

MachineConfig with_tools() {
  MachineConfig m = at_origin();
  m.dialect = Dialect::linuxcnc;
  m.tool_diameters = {{1, 6.0}, {2, 20.0}, {3, 0.0}, {4, -6.0}};
  return m;
}

// Distance from p to the segment ab in XY.
double to_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  Vec2 d = b - a;
  double t = std::clamp(glm::dot(p - a, d) / glm::dot(d, d), 0.0, 1.0);
  return glm::length(p - (a + t * d));
}

// Distance from p to the closed polygon's boundary.
double to_polygon(const Vec2& p, const std::vector<Vec2>& polygon) {
  double best = 1e300;
  for (std::size_t i = 0; i < polygon.size(); ++i)
    best = std::min(best, to_segment(p, polygon[i], polygon[(i + 1) % polygon.size()]));
  return best;
}

}  // namespace

TEST_CASE("G42 outside a square: every point one radius from the contour, corners rounded") {
  // Counter-clockwise round the square [0,40]² with the tool on the right: outside it.
  Result r = run_program(
      "G21 G17 G90 F300\nT1 M6\nG0 X-20 Y-20 Z-1\nG42 D1 G1 X0 Y0\nG1 X40 Y0\nG1 X40 Y40\n"
      "G1 X0 Y40\nG1 X0 Y0\nG1 X20 Y0\nG40 G1 X20 Y-20\nM2\n",
      {}, with_tools());
  const std::vector<Vec2> square{{0, 0}, {0, 40}, {40, 40}, {40, 0}};
  int on_contour = 0, corner_arc_points = 0;
  for (const Move& m : r.moves) {
    if (m.line < 5 || m.line > 9) continue;  // the entry (line 4) and the exit (line 10) cross over
    Vec2 p(m.end.x, m.end.y);
    CHECK_MESSAGE(std::abs(to_polygon(p, square) - 3.0) < 1e-9,
                  "line " << m.line << " " << p.x << " " << p.y);
    bool inside = p.x > 0 && p.x < 40 && p.y > 0 && p.y < 40;
    CHECK(!inside);
    ++on_contour;
    if (m.kind == MoveKind::arc) ++corner_arc_points;
  }
  CHECK(on_contour > 10);
  CHECK(corner_arc_points > 3 * 10);  // three convex corners, each an arc of many chords
  // The side after the corner at (40, 0) runs at x = 43, between the corners' arcs.
  bool found = false;
  for (const Move& m : r.moves)
    if (m.line == 6 && m.kind == MoveKind::feed) {
      CHECK(near(m.start, Vec3(43, 0, -1), 1e-9));
      CHECK(near(m.end, Vec3(43, 40, -1), 1e-9));
      found = true;
    }
  CHECK(found);
}

TEST_CASE("G41 inside a square: concave corners end where the offset lines meet") {
  Result r = run_program(
      "G21 G17 G90 F300\nT2 M6\nG0 X20 Y20 Z-1\nG41 D2 G1 X0 Y0\nG1 X40\nG1 Y40\nG1 X0\nG1 Y0\n"
      "G40 G1 X20 Y20\nM2\n",
      {}, with_tools());
  // Radius 10: the inner square [10, 30]²; no arcs (every corner is concave).
  std::vector<Vec3> ends;
  for (const Move& m : r.moves) {
    CHECK(m.kind != MoveKind::arc);
    if (m.line >= 5 && m.line <= 8) ends.push_back(m.end);
  }
  REQUIRE(ends.size() == 4);
  CHECK(near(ends[0], Vec3(30, 10, -1), 1e-9));
  CHECK(near(ends[1], Vec3(30, 30, -1), 1e-9));
  CHECK(near(ends[2], Vec3(10, 30, -1), 1e-9));
  CHECK(near(ends[3], Vec3(10, 0, -1), 1e-9));  // the last line waits for no next move: its end
  CHECK(near(r.moves.back().end, Vec3(20, 20, -1), 1e-9));
}

TEST_CASE("compensation by zero, by a diameter (G41.1) and by a negative diameter") {
  const char* contour = "G1 X30 Y0\nG1 X30 Y30\nG40 G1 X50 Y50\nM2\n";
  auto run = [&](const std::string& on) {
    return run_program(
        std::string("G21 G17 G90 F300\nT1 M6\nG0 X-10 Y-10 Z0\n") + on + " G1 X0 Y0\n" + contour,
        {}, with_tools());
  };
  Result plain = run("G40");
  Result zero = run("G41 D3");
  REQUIRE(zero.moves.size() == plain.moves.size());
  for (std::size_t i = 0; i < plain.moves.size(); ++i)
    CHECK(near(zero.moves[i].end, plain.moves[i].end));
  Result by_table = run("G41 D1");
  Result by_diameter = run("G41.1 D6");
  REQUIRE(by_table.moves.size() == by_diameter.moves.size());
  for (std::size_t i = 0; i < by_table.moves.size(); ++i)
    CHECK(near(by_table.moves[i].end, by_diameter.moves[i].end, 1e-12));
  // A negative diameter offsets to the other side.
  Result right = run("G42 D1"), flipped = run("G41 D4");
  REQUIRE(right.moves.size() == flipped.moves.size());
  for (std::size_t i = 0; i < right.moves.size(); ++i)
    CHECK(near(right.moves[i].end, flipped.moves[i].end, 1e-12));
  // The entry (G41, radius 3, from (-10, -10) to (0, 0)) ends one radius to its left,
  // perpendicular to it; the turn onto +X is convex there, so an arc follows to (0, 3).
  const Move& entry = by_table.moves[1];
  CHECK(entry.line == 4);
  CHECK(near(entry.end, Vec3(-3 / std::sqrt(2.0), 3 / std::sqrt(2.0), 0), 1e-9));
  CHECK(by_table.moves[2].kind == MoveKind::arc);
}

TEST_CASE("cutter compensation errors, each at its block") {
  MachineConfig m = with_tools();
  const std::string start = "G21 G17 G90 F300\nT1 M6\nG0 X0 Y0 Z0\n";
  struct Case {
    std::string text;
    int line;
    const char* words;
  };
  const Case cases[] = {
      {start + "G41 D1 G1 X2 Y0\nM2\n", 4, "not longer than the tool radius"},
      {start + "G41 D1 G1 X20 Y0\nG3 X20 Y4 I0 J2\nM2\n", 5, "not less than the arc radius"},
      {start + "G41 D2 G1 X20 Y0\nG1 X20 Y5\nG1 X0 Y5\nM2\n", 6, "gouging"},
      {start + "G19 G41 D1\nM2\n", 4, "XY (G17) or XZ (G18) plane"},
      {start + "G41 D1\nG42 D1\nM2\n", 5, "already on"},
      {start + "G41 D1 G1 X20 Y0\nG40\nG2 X40 Y0 R5\nM2\n", 6, "must be straight"},
      {start + "G41 D1 G1 X20 Y0\nT2 M6\nM2\n", 5, "tool change"},
      {start + "G41 D1 G1 X20 Y0\nG28\nM2\n", 5, "G28"},
      {start + "G41 D1 G1 X20 Y0\nG81 X5 Y5 Z-1 R1\nM2\n", 5, "canned cycle"},
      {start + "G41 D1 G1 X20 Y0\nG19\nM2\n", 5, "plane"},
      {start + "G41 D9 G1 X20 Y0\nM2\n", 4, "tool 9 is not in the tool table"},
      {start + "G41.1 G1 X20 Y0\nM2\n", 4, "needs D"},
  };
  for (const Case& c : cases) {
    CAPTURE(c.text);
    Diagnostic d = error_of(c.text, {}, m);
    CHECK(d.line == c.line);
    CHECK_MESSAGE(d.message.find(c.words) != std::string::npos, d.message);
  }
}

TEST_CASE("lenient mode runs G41/G42 like strict mode; #4007 reads the mode") {
  const std::string text =
      "G21 G17 G90 F300\nT1 M6\nG0 X-10 Y-10 Z0\nG41 D1 G1 X0 Y0\n"
      "#1 = #4007\nG1 X[#1] Y0\nG1 Y30\nG40 G1 X-10 Y40\nM2\n";
  InterpreterOptions lenient;
  lenient.lenient = true;
  Result strict = run_program(text, {}, with_tools()),
         loose = run_program(text, lenient, with_tools());
  REQUIRE(strict.moves.size() == loose.moves.size());
  for (std::size_t i = 0; i < strict.moves.size(); ++i)
    CHECK(near(strict.moves[i].end, loose.moves[i].end));
  CHECK(loose.warnings.empty());
  // #4007 = 41 while G41 is on: the side runs to X41, offset up by the radius to y = 3.
  bool at_41 = false;
  for (const Move& m : strict.moves) at_41 |= near(m.end, Vec3(41 - 3, 3, 0), 1e-9);
  CHECK(at_41);
}

TEST_CASE("probing (G38.x, Fanuc's G31 skip) is an error that names it, even lenient") {
  InterpreterOptions lenient;
  lenient.lenient = true;
  for (const char* code : {"G38.2", "G38.3", "G38.4", "G38.5", "G31"}) {
    Diagnostic d =
        error_of(std::string("G0 X0 Y0 Z0\n") + code + " Z-10 F100\nM2\n", lenient, at_origin());
    CHECK(d.line == 2);
    CHECK_MESSAGE(
        d.message.find(std::string(code) + " (probing) is not simulated") != std::string::npos,
        d.message);
  }
}

TEST_CASE(
    "after G40 the next move counts from the programmed point, after a tool change from the tip") {
  // LinuxCNC: G40 makes the programmed point current (a Z move then also returns X/Y to it); a
  // tool change resynchronises with where the tool is (useful-subroutines.ngc relies on it).
  const std::string head =
      "G21 G17 G90 F300\nT1 M6\nG0 X-10 Y-10 Z0\nG41 D1 G1 X0 Y0\nG1 X20 Y0\nG0 Z5\nG40\n";
  Result plain = run_program(head + "G0 Z10\nM2\n", {}, with_tools());
  CHECK(near(plain.moves.back().end, Vec3(20, 0, 10), 1e-9));
  Result changed = run_program(head + "T2 M6\nG0 Z10\nM2\n", {}, with_tools());
  CHECK(near(changed.moves.back().end, Vec3(20, 3, 10), 1e-9));
}

TEST_CASE(
    "Fanuc and Haas start-up (type A): the entry ends perpendicular to the next move's start") {
  for (const Dialect dialect : {Dialect::fanuc, Dialect::haas}) {
    CAPTURE(static_cast<int>(dialect));
    MachineConfig m = with_tools();
    m.dialect = dialect;
    // A hole of radius 8 milled from its centre with a D6 (r = 3): the entry ends at (-5, 0),
    // perpendicular to the circle's start, and the tool runs round at radius 5 (LinuxCNC finds no
    // corner there: the entry's offset line y = -3 meets that circle only for r <= 2.5).
    Result hole = run_program(
        "G21 G17 G90 F300\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-2\nG41 D1 G1 X-8 Y0\nG3 I8 J0\n"
        "G40 G1 X0 Y0\nM30\n",
        {}, m);
    int on_circle = 0;
    for (const Move& move : hole.moves) {
      if (move.line == 5) CHECK(near(move.end, Vec3(-5, 0, -2)));
      if (move.line != 6) continue;
      CHECK(std::abs(std::hypot(move.end.x, move.end.y) - 5) < 1e-9);
      ++on_circle;
    }
    CHECK(on_circle > 20);
    CHECK(near(hole.moves.back().end, Vec3(0, 0, -2)));
    // Line to line, turning left under G41: the entry ends at (7, 0), beside the next move's
    // start, with no corner to cut back; an entry shorter than the radius is fine.
    Result corner = run_program(
        "G21 G17 G90 F300\nT1 M6\nG0 X0 Y0 Z-1\nG41 D1 G1 X10 Y0\nG1 Y10\nG40 G1 X20\nM30\n", {},
        m);
    REQUIRE(corner.moves.size() >= 3);
    CHECK(near(corner.moves[1].end, Vec3(7, 0, -1)));
    CHECK(near(corner.moves[2].end, Vec3(7, 10, -1)));
    Result short_entry = run_program(
        "G21 G17 G90 F300\nT1 M6\nG0 X0 Y0 Z-1\nG41 D1 G1 X1 Y0\nG1 X20\nG40 G1 Y-10\nM30\n", {},
        m);
    REQUIRE(short_entry.moves.size() >= 3);
    CHECK(near(short_entry.moves[1].end, Vec3(1, 3, -1)));
    CHECK(near(short_entry.moves[2].end, Vec3(20, 3, -1)));
    // A move with no motion in the plane after G41 goes as programmed; the next one is the entry.
    Result plunge = run_program(
        "G21 G17 G90 F300\nT1 M6\nG0 X0 Y0 Z5\nG41 D1\nG1 Z-1\nG1 X1 Y0\nG1 X20\nG40 G1 "
        "Y-10\nM30\n",
        {}, m);
    REQUIRE(plunge.moves.size() == short_entry.moves.size() + 1);
    CHECK(near(plunge.moves[1].end, Vec3(0, 0, -1)));
    for (std::size_t i = 1; i < short_entry.moves.size(); ++i)
      CHECK(near(plunge.moves[i + 1].end, short_entry.moves[i].end));
    // G41 given again with the same side and radius changes nothing; another radius is refused.
    Result again = run_program(
        "G21 G17 G90 F300\nT1 M6\nG0 X0 Y0 Z-1\nG41 D1 G1 X1 Y0\nG41 G1 X20\nG40 G1 Y-10\nM30\n",
        {}, m);
    REQUIRE(again.moves.size() == short_entry.moves.size());
    for (std::size_t i = 0; i < again.moves.size(); ++i)
      CHECK(near(again.moves[i].end, short_entry.moves[i].end));
    CHECK(error_of("G21 G17 G90 F300\nT1 M6\nG0 X0 Y0 Z-1\nG41 D1 G1 X1 Y0\nG41 D2 G1 X20\n", {}, m)
              .message.find("changes the side or the radius") != std::string::npos);
  }
  // LinuxCNC keeps its own rule: the same short entry is refused.
  CHECK(
      error_of("G21 G17 G90 F300\nT1 M6\nG0 X0 Y0 Z-1\nG41 D1 G1 X1 Y0\nG1 X20\n", {}, with_tools())
          .message.find("not longer than the tool radius") != std::string::npos);
}
