// Tool length offsets (G43 H, G43 alone, G44 H, G43.1, G49, MachineConfig::tool_lengths): the
// program names the point (active offset) below the spindle's gauge point, the tip lies the
// loaded tool's length below the gauge point. References are worked by hand from those two
// statements; the same programs run against rs274 in test_linuxcnc_diff.cpp (tool_lengths.ngc).
#include <doctest/doctest.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using tridex::gcode::test::at_origin;
using tridex::gcode::test::error_of;
using tridex::gcode::test::near;
using tridex::gcode::test::run_program;

namespace {

MachineConfig with_lengths() {
  MachineConfig machine = at_origin();
  machine.tool_lengths = {{1, 50.0}, {2, 80.0}};
  return machine;
}

}  // namespace

TEST_CASE("tool length: G43 H of the loaded tool puts the tip at the programmed point") {
  auto r =
      run_program("G21 G90\nT1 M6\nG43 H1\nG0 X1 Y2 Z3\nG1 F100 Z-1\nM2\n", {}, with_lengths());
  REQUIRE(r.moves.size() == 2);
  CHECK(near(r.moves[0].end, Vec3(1, 2, 3)));
  CHECK(near(r.moves[1].end, Vec3(1, 2, -1)));
}

TEST_CASE(
    "tool length: under G49 the program names the gauge point; the tip is the tool's length "
    "below") {
  auto r = run_program("G21 G90 G49\nT2 M6\nG0 X1 Y2 Z3\nM2\n", {}, with_lengths());
  REQUIRE(r.moves.size() == 1);
  CHECK(near(r.moves[0].end, Vec3(1, 2, 3 - 80)));
}

TEST_CASE("tool length: another tool's offset, G44, G43 without H, and a tool change under G43") {
  // G43 H2 with tool 1 loaded: the program names a point 80 below the gauge, the tip is 50 below.
  auto r = run_program(
      "G21\nT1 M6\nG43 H2\nG0 X0 Y0 Z0\nG44 H1\nG0 Z0\nG43\nG0 Z0\nT2 M6\nG0 X5\n"
      "G49\nG0 X6\nM2\n",
      {}, with_lengths());
  REQUIRE(r.moves.size() == 5);
  CHECK(near(r.moves[0].end, Vec3(0, 0, 30)));    // Z0 + 80 − 50
  CHECK(near(r.moves[1].end, Vec3(0, 0, -100)));  // G44: Z − 50 − 50
  CHECK(near(r.moves[2].end, Vec3(0, 0, 0)));     // G43 alone: the loaded tool 1
  CHECK(near(r.moves[3].end, Vec3(5, 0, -30)));   // T2 in place: the gauge stays, the tip 30 lower
  CHECK(near(r.moves[4].end, Vec3(6, 0, -30)));   // G49 moves nothing: the position reads 50 higher
}

TEST_CASE("tool length: G53 and G28 name the gauge point") {
  MachineConfig machine = with_lengths();
  machine.g53_literal = true;
  machine.set_home(Vec3(0, 0, 100));
  auto r = run_program("G21\nT1 M6\nG43 H1\nG0 X1 Y1 Z1\nG53 G0 Z10\nG28\nM2\n", {}, machine);
  REQUIRE(r.moves.size() == 3);
  CHECK(near(r.moves[1].end, Vec3(1, 1, 10 - 50)));
  CHECK(near(r.moves[2].end, Vec3(0, 0, 100 - 50)));
}

TEST_CASE("tool length: G92 and G10 L20 read the programmed point, not the tip") {
  MachineConfig machine = with_lengths();
  machine.dialect = Dialect::linuxcnc;
  // G43 H2 with tool 1: the tip is 30 above the programmed point.
  auto r = run_program(
      "G21\nT1 M6\nG43 H2\nG0 X0 Y0 Z10\nG92 Z0\nG0 Z5\nG92.1\nG10 L20 P1 Z0\nG0 Z-5\nM2\n", {},
      machine);
  REQUIRE(r.moves.size() == 3);
  CHECK(near(r.moves[0].end, Vec3(0, 0, 40)));
  CHECK(near(r.moves[1].end, Vec3(0, 0, 45)));
  // G92.1: the programmed point (machine 15, tip 45) reads Z15; G10 L20 makes it read Z0.
  CHECK(near(r.moves[2].end, Vec3(0, 0, 40)));
}

TEST_CASE("tool length: G43.1 Z (LinuxCNC) takes the length written and moves nothing") {
  MachineConfig machine = with_lengths();
  machine.dialect = Dialect::linuxcnc;
  auto r = run_program("G21\nT1 M6\nG0 X0 Y0 Z0\nG43.1 Z20\nG0 X1\nM2\n", {}, machine);
  REQUIRE(r.moves.size() == 2);
  CHECK(near(r.moves[0].end, Vec3(0, 0, -50)));
  CHECK(near(r.moves[1].end, Vec3(1, 0, -50)));
  Diagnostic fanuc = error_of("G21\nG43.1 Z20\n", {}, with_lengths());  // Fanuc has no G43.1
  CHECK(fanuc.line == 2);
  CHECK(fanuc.message.find("linuxcnc") != std::string::npos);
  Diagnostic sideways = error_of("G21\nG43.1 X1 Z2\n", {}, machine);
  CHECK(sideways.message.find("sideways") != std::string::npos);
}

TEST_CASE("tool length: without tool lengths every tool length code leaves the path alone") {
  MachineConfig machine = at_origin();
  machine.dialect = Dialect::linuxcnc;
  auto r = run_program(
      "G21\nT1 M6\nG43 H7\nG0 X1 Y1 Z1\nG43.1 Z9\nG0 Z2\nG44 H3\nG0 Z3\nG49\nG0 Z4\nM2\n", {},
      machine);
  REQUIRE(r.moves.size() == 4);
  for (std::size_t i = 0; i < 4; ++i)
    CHECK(r.moves[i].end.z == doctest::Approx(static_cast<double>(i + 1)));
}

TEST_CASE("tool length: an offset of a tool without a length is an error naming the H word") {
  Diagnostic d = error_of("G21\nT1 M6\nG43 H5\n", {}, with_lengths());
  CHECK(d.line == 3);
  CHECK(d.column == 5);
  CHECK(d.message.find("tool 5 has no length") != std::string::npos);
  // H0 is no offset, as on both controls.
  auto r = run_program("G21\nT1 M6\nG43 H0\nG0 X0 Y0 Z0\nM2\n", {}, with_lengths());
  REQUIRE(r.moves.size() == 1);
  CHECK(near(r.moves[0].end, Vec3(0, 0, -50)));
}

TEST_CASE("tool length: changing it under cutter compensation is an error") {
  MachineConfig machine = with_lengths();
  machine.tool_diameters = {{1, 6.0}};
  Diagnostic d = error_of("G21\nT1 M6\nG0 X0 Y0 Z0\nG41 D1\nG1 F100 X10\nG43 H1\n", {}, machine);
  CHECK(d.line == 6);
}
