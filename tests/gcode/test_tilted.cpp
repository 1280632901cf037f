#include <doctest/doctest.h>

#include <cmath>

#include "helpers.hpp"
#include "tridex/gcode/grouping.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

Mat3 euler_zxz(double a, double b, double c) {
  return about(Vec3(0, 0, 1), a) * about(Vec3(1, 0, 0), b) * about(Vec3(0, 0, 1), c);
}

Mat3 haas_xyz(double i, double j, double k) {
  return about(Vec3(0, 0, 1), k) * about(Vec3(0, 1, 0), j) * about(Vec3(1, 0, 0), i);
}

std::string g682(const Vec3& o, double a, double b, double c) {
  return "G68.2 X" + fmt(o.x) + " Y" + fmt(o.y) + " Z" + fmt(o.z) + " I" + fmt(a) + " J" + fmt(b) +
         " K" + fmt(c) + "\n";
}

}  // namespace

TEST_CASE("G68.2: the four checks of docs/design.md") {
  struct Check {
    double a, b, c;
    Vec3 axis;
  } checks[] = {{90, 90, 0, Vec3(1, 0, 0)},
                {-90, 90, 0, Vec3(-1, 0, 0)},
                {0, 90, 0, Vec3(0, -1, 0)},
                {180, 90, 0, Vec3(0, 1, 0)}};
  for (const Check& check : checks) {
    Result r = run_program("G21 G90\n" + g682(Vec3(0.0), check.a, check.b, check.c) +
                           "G53.1\nG0 X0 Y0 Z10\nM30\n");
    REQUIRE(r.moves.size() == 1);
    CHECK(near(r.moves[0].axis, check.axis, 1e-12));
    CHECK(near(r.moves[0].end, 10.0 * check.axis, 1e-9));
    CHECK(near(r.moves[0].start, r.moves[0].end + MachineConfig::kDefaultFar * check.axis, 1e-6));
  }
}

TEST_CASE("G68.2 on random Euler angles: axis formula, points O + R·p, arcs and cycles") {
  std::mt19937_64 rng(9);
  std::uniform_real_distribution<double> angle(-180, 180), coord(-50, 50);
  MachineConfig machine;
  machine.work_offsets[1] = Vec3(3, -4, 5);  // output frame = G54; G55 differs
  machine.work_offsets[2] = Vec3(13, -2, 1);
  for (int trial = 0; trial < 100; ++trial) {
    double a = std::stod(fmt(angle(rng))), b = std::stod(fmt(angle(rng) / 2)),
           c = std::stod(fmt(angle(rng)));
    Vec3 o(std::stod(fmt(coord(rng))), std::stod(fmt(coord(rng))), std::stod(fmt(coord(rng))));
    Mat3 R = euler_zxz(a, b, c);
    double ra = a * std::acos(-1.0) / 180, rb = b * std::acos(-1.0) / 180;
    Vec3 expected_axis(std::sin(ra) * std::sin(rb), -std::cos(ra) * std::sin(rb), std::cos(rb));
    Vec3 g55 = machine.work_offsets[2] - machine.work_offsets[1];
    auto world = [&](const Vec3& p) { return g55 + o + R * p; };
    std::string program = "G21 G90 G17 G55 F200\n" + g682(o, a, b, c) +
                          "G53.1\nG0 X10 Y0 Z5\nG1 Z0\nG3 X0 Y10 I-10 J0\n"
                          "G98 G81 X20 Y20 Z-3 R2\nX-20\nG80\nG69\nG91 G28 Z0\nM30\n";
    Result r = run_program(program, InterpreterOptions{}, machine);
    REQUIRE(r.moves.size() >= 8);
    for (const Move& m : r.moves) CHECK(near(m.axis, expected_axis, 1e-9));
    CHECK(near(r.moves[0].end, world(Vec3(10, 0, 5)), 1e-9));
    CHECK(near(r.moves[1].end, world(Vec3(10, 0, 0)), 1e-9));
    // The arc: every point on the feature circle of radius 10 about (0,0,0).
    std::size_t k = 2;
    for (; k < r.moves.size() && r.moves[k].kind == MoveKind::arc; ++k) {
      Vec3 local = glm::transpose(R) * (r.moves[k].end - g55 - o);
      CHECK(std::abs(local.z) < 1e-9);
      CHECK(glm::length(Vec2(local)) == doctest::Approx(10).epsilon(1e-9));
    }
    CHECK(near(r.moves[k - 1].end, world(Vec3(0, 10, 0)), 1e-9));
    // The drilling cycle: up to R (the tool is below it), XY, R, bottom, R; then the second hole.
    std::vector<Vec3> cycle;
    for (; k < r.moves.size(); ++k)
      if (r.moves[k].kind == MoveKind::cycle) cycle.push_back(r.moves[k].end);
    std::vector<Vec3> want = {Vec3(0, 10, 2),   Vec3(20, 20, 2),   Vec3(20, 20, 2),
                              Vec3(20, 20, -3), Vec3(20, 20, 2),   Vec3(-20, 20, 2),
                              Vec3(-20, 20, 2), Vec3(-20, 20, -3), Vec3(-20, 20, 2)};
    REQUIRE(cycle.size() == want.size());
    for (std::size_t i = 0; i < want.size(); ++i) CHECK(near(cycle[i], world(want[i]), 1e-9));
  }
}

TEST_CASE("a post's reorientation sequence positions without cutting") {
  Result r = run_program(
      "G21 G90 G17\nT1 M6\nG0 X0 Y0\nG43 Z20 H1\nG1 Z-1 F100\nX5\n"
      "G91 G28 Z0\nG90 G69\nT2 M6\n" +
      g682(Vec3(0, 0, 10), 90, 45, -90) +
      "G53.1\nG0 X1 Y2\nG43 Z5 H2\nG1 Z0 F100\nG69\nG91 G28 Z0\nM30\n");
  // Tool 1: approach, plunge, cut, G28's intermediate point. Tool 2: approach, plunge, G28's.
  REQUIRE(r.moves.size() == 7);
  Vec3 tilted = euler_zxz(90, 45, -90) * Vec3(0, 0, 1);
  CHECK(near(r.moves[4].axis, tilted, 1e-12));
  CHECK(r.moves[4].tool == 2);
  CHECK(r.moves[4].kind == MoveKind::rapid);
  CHECK(near(r.moves[4].start - r.moves[4].end, MachineConfig::kDefaultFar * tilted, 1e-6));
  Vec3 feature_point = Vec3(0, 0, 10) + euler_zxz(90, 45, -90) * Vec3(1, 2, 5);
  CHECK(near(r.moves[4].end, feature_point, 1e-9));
  CHECK(r.tools == std::set<int>{1, 2});
}

TEST_CASE("G68.2 without G53.1: ambiguous direction is an error, unless the tool is normal") {
  Diagnostic d = error_of("G21 G90\nG0 X0 Y0 Z50\n" + g682(Vec3(0.0), 0, 30, 0) + "G0 X1 Y1 Z5\n");
  CHECK(d.line == 4);
  CHECK(d.column == 1);
  CHECK(d.message.find("ambiguous") != std::string::npos);
  // A rotation about Z alone keeps the feature plane normal to the tool.
  Result r = run_program("G21 G90\n" + g682(Vec3(0.0), 30, 0, 0) + "G0 X1 Y0 Z5\nM30\n");
  REQUIRE(r.moves.size() == 1);
  CHECK(
      near(r.moves[0].end, Vec3(std::cos(std::acos(-1.0) / 6), std::sin(std::acos(-1.0) / 6), 5)));
  InterpreterOptions lenient;
  lenient.lenient = true;
  r = run_program("G21 G90\nG0 X0 Y0 Z50\n" + g682(Vec3(0.0), 0, 30, 0) + "G0 X1 Y1 Z5\nM30\n",
                  lenient);
  CHECK(near(r.moves.back().axis, Vec3(0, 0, 1)));
  REQUIRE(r.warnings.size() == 2);  // the line's, then the run's summary of the cause
  CHECK(r.warnings[0].line == 4);
  CHECK(r.warnings[1].message ==
        "lenient mode read 1 × move under an ambiguous tilted plane along the current direction "
        "(0, 0, 1) (lines 4)");
  CHECK(error_of("G53.1\n").message.find("without") != std::string::npos);
  MachineConfig two;
  two.work_offsets[2] = Vec3(1, 2, 3);
  d = error_of(g682(Vec3(0.0), 0, 30, 0) + "G55\n", InterpreterOptions{}, two);
  CHECK(d.message.find("tilted") != std::string::npos);
  CHECK(error_of("G68.2 P2 X0 Y0 Z0 I0 J0 K0\n").column == 1);  // several-block form needs Q
}

TEST_CASE("Haas G268 Q123 / G253 / G269: R = Rz(K)·Ry(J)·Rx(I)") {
  std::mt19937_64 rng(13);
  std::uniform_real_distribution<double> angle(-90, 90), coord(-20, 20);
  for (int trial = 0; trial < 100; ++trial) {
    double i = std::stod(fmt(angle(rng))), j = std::stod(fmt(angle(rng))),
           k = std::stod(fmt(angle(rng)));
    Vec3 o(std::stod(fmt(coord(rng))), std::stod(fmt(coord(rng))), std::stod(fmt(coord(rng))));
    Mat3 R = haas_xyz(i, j, k);
    Result r = run_program("G21 G90\nG268 X" + fmt(o.x) + " Y" + fmt(o.y) + " Z" + fmt(o.z) + " I" +
                           fmt(i) + " J" + fmt(j) + " K" + fmt(k) +
                           " Q123\nG253\nG0 X1 Y2 Z3\nG269\nG91 G28 Z0\nM30\n");
    REQUIRE(r.moves.size() >= 1);
    CHECK(near(r.moves[0].axis, R * Vec3(0, 0, 1), 1e-12));
    CHECK(near(r.moves[0].end, o + R * Vec3(1, 2, 3), 1e-9));
  }
  CHECK(error_of("G268 X0 Y0 Z0 I0 J0 K0 Q121\n").message.find("Q121") != std::string::npos);
}

TEST_CASE("after G69 the tool stays tilted; a tilted retract needs all coordinates to return") {
  std::string setup = "G21 G90\n" + g682(Vec3(0.0), 0, 90, 0) + "G53.1\nG0 X0 Y0 Z10\nG69\n";
  Result r = run_program(setup + "G0 X0 Y-20 Z0\nG91 G28 Y0\nG90 G0 X0 Y-5 Z0\nM30\n");
  REQUIRE(r.moves.size() == 4);
  CHECK(near(r.moves[1].axis, Vec3(0, -1, 0), 1e-12));
  CHECK(near(r.moves[1].end, Vec3(0, -20, 0), 1e-9));
  CHECK(near(r.moves[3].start, Vec3(0, -5 - MachineConfig::kDefaultFar, 0), 1e-6));
  // Tilted 45° in Y-Z: after the retract, Y alone does not say where along the tool it is.
  std::string oblique = "G21 G90\n" + g682(Vec3(0.0), 0, 45, 0) + "G53.1\nG0 X0 Y0 Z10\nG69\n";
  Diagnostic d = error_of(oblique + "G91 G28 Z0\nG90 G0 X1\nG0 Y-5\n");
  CHECK(d.line == 8);
  CHECK(d.message.find("retracted") != std::string::npos);
  r = run_program(oblique + "G91 G28 Z0\nG90 G0 X1\nG0 Y-5 Z2\nM30\n");
  Vec3 axis(0, -std::sqrt(0.5), std::sqrt(0.5));
  CHECK(near(r.moves.back().start, Vec3(1, -5, 2) + MachineConfig::kDefaultFar * axis, 1e-6));
  // Homing the rotary axes turns the spindle back to +Z.
  r = run_program(setup + "G28 A0 C0\nG0 X1 Y1 Z1\nM30\n");
  CHECK(near(r.moves.back().axis, Vec3(0, 0, 1)));
  CHECK(near(r.moves.back().start, Vec3(1, 1, 1 + MachineConfig::kDefaultFar), 1e-6));
}

TEST_CASE("grouping by direction: one group per direction, in order of first appearance") {
  std::mt19937_64 rng(17);
  std::normal_distribution<double> gauss;
  for (int trial = 0; trial < 50; ++trial) {
    std::vector<Vec3> directions;
    int count = 1 + static_cast<int>(rng() % 6);
    while (static_cast<int>(directions.size()) < count) {
      Vec3 d = glm::normalize(Vec3(gauss(rng), gauss(rng), gauss(rng)));
      bool distinct = true;
      for (const Vec3& e : directions) distinct = distinct && glm::dot(d, e) < std::cos(0.01);
      if (distinct) directions.push_back(d);
    }
    std::vector<Move> moves;
    for (int i = 0; i < 500; ++i) {
      Move m;
      m.line = i;
      m.tool = static_cast<int>(rng() % 3);
      m.axis = directions[rng() % directions.size()];
      // A perturbation far below the 1e-3 degree tolerance.
      m.axis = glm::normalize(m.axis + 1e-8 * Vec3(gauss(rng), gauss(rng), gauss(rng)));
      m.start = Vec3(gauss(rng), gauss(rng), gauss(rng));
      m.end = Vec3(gauss(rng), gauss(rng), gauss(rng));
      moves.push_back(m);
    }
    std::vector<MoveGroup> groups = group_by_direction(moves);
    // Brute force: distinct directions in order of first appearance.
    std::vector<Vec3> order;
    for (const Move& m : moves) {
      bool seen = false;
      for (const Vec3& e : order) seen = seen || glm::dot(e, m.axis) > std::cos(0.001);
      if (!seen) order.push_back(m.axis);
    }
    REQUIRE(groups.size() == order.size());
    std::size_t total = 0;
    for (std::size_t g = 0; g < groups.size(); ++g) {
      CHECK(glm::dot(groups[g].axis, order[g]) > 1 - 1e-12);
      CHECK(near(groups[g].frame.to_local(groups[g].frame.origin + groups[g].axis), Vec3(0, 0, 1),
                 1e-12));
      int last_line = -1;
      for (const Move& m : groups[g].moves) {
        CHECK(glm::dot(m.axis, groups[g].axis) > std::cos(glm::radians(1e-3)));
        CHECK(m.line > last_line);
        CHECK(groups[g].tools.count(m.tool) == 1);
        last_line = m.line;
      }
      total += groups[g].moves.size();
    }
    CHECK(total == moves.size());
  }
  CHECK_THROWS_AS(group_by_direction({}, -1), tridex::Error);
  std::vector<Move> bad(1);
  bad[0].axis = Vec3(0.0);
  CHECK_THROWS_AS(group_by_direction(bad), tridex::Error);
}
