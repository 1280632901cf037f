// LinuxCNC's G10 L1 / L10 / L11: the program sets a tool table entry (length Z, radius R) that a
// later G43 H and G41 D read; the tool in the spindle keeps its own length (the machine's), so
// the tip lands where the real machine would put it. References are worked by hand: the control
// puts the gauge point the G43 length above the programmed point, the tip lies the loaded tool's
// length below the gauge point. The same codes run against rs274 in test_linuxcnc_diff.cpp
// (tool_table.ngc).
#include <doctest/doctest.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

MachineConfig linuxcnc_lengths() {
  MachineConfig machine = at_origin();
  machine.dialect = Dialect::linuxcnc;
  machine.tool_lengths = {{1, 10.0}};
  return machine;
}

}  // namespace

TEST_CASE("G10 L1: G43 H reads the length the program set; the tool keeps its own") {
  // Gauge 0 + 15 = 15, tip 15 − 10 = 5.
  Result r = run_program("T1 M6\nG10 L1 P1 Z15\nG43 H1\nG0 X0 Y0 Z0\n", {}, linuxcnc_lengths());
  REQUIRE(!r.moves.empty());
  CHECK(near(r.moves.back().end, Vec3(0, 0, 5)));
  // Inches: Z1 is 25.4 mm; a tool the machine has no length for may be given one.
  r = run_program("T1 M6\nG20 G10 L1 P7 Z1\nG43 H7\nG21 G0 X0 Y0 Z0\n", {}, linuxcnc_lengths());
  CHECK(near(r.moves.back().end, Vec3(0, 0, 25.4 - 10)));
}

TEST_CASE("G10 L10 and L11: the length that makes the current position read Z") {
  // At programmed Z0 under H1 = 15 the gauge is at 15; L10 Z2 gives 13, and G43 H1 then reads
  // the same place as Z2: a move to Z0 puts the gauge at 13, the tip at 3.
  Result r =
      run_program("T1 M6\nG10 L1 P1 Z15\nG43 H1\nG0 X0 Y0 Z0\nG10 L10 P1 Z2\nG43 H1\nG0 Z0\n", {},
                  linuxcnc_lengths());
  CHECK(near(r.moves.back().end, Vec3(0, 0, 3)));
  // L10 counts in the active system with G92; L11 in G59.3 (0 here) without them. Under G55
  // Z−4 and G92 (work Z 6 reads 1: offset 5), at programmed Z1 the gauge is at machine
  // 1 + 5 − 4 + 10 = 12 under H1 = 10 (the machine's). L10 Z−2: 12 − 1 − (−2) = 13; L11 Z3:
  // 12 − 3 = 9.
  const std::string setup = "T1 M6\nG43 H1\nG10 L2 P2 Z-4\nG55 G0 X0 Y0 Z6\nG92 Z1\n";
  r = run_program(setup + "G10 L10 P1 Z-2\nG43 H1\nG0 Z0\n", {}, linuxcnc_lengths());
  // Z0 in G55+G92 is machine 1: the gauge 1 + 13 = 14, the tip 4.
  CHECK(near(r.moves.back().end, Vec3(0, 0, 4)));
  r = run_program(setup + "G10 L11 P1 Z3\nG43 H1\nG0 Z0\n", {}, linuxcnc_lengths());
  CHECK(near(r.moves.back().end, Vec3(0, 0, 1 + 9 - 10)));
}

TEST_CASE("G10 L1 R: G41 D offsets by the radius the program set") {
  MachineConfig machine = linuxcnc_lengths();
  Result r = run_program("G0 X0 Y0 Z0\nG10 L1 P2 R1.5\nG41 D2 G1 X10 F100\nG1 X20\nG40 G1 X30\n",
                         {}, machine);
  bool found = false;
  for (const Move& m : r.moves)
    if (m.line == 4) found = near(m.end, Vec3(20, 1.5, 0));
  CHECK(found);
}

TEST_CASE("G10 L1 / L10 / L11: errors") {
  MachineConfig machine = linuxcnc_lengths();
  Diagnostic d = error_of("G10 L1 P1\n", {}, machine);
  CHECK(d.message.find("has no effect") != std::string::npos);
  d = error_of("G10 L1 Z1\n", {}, machine);
  CHECK(d.message.find("needs P") != std::string::npos);
  d = error_of("G10 L10 P1 X1 Z1\n", {}, machine);
  CHECK(d.column == 12);
  CHECK(d.message.find("not simulated") != std::string::npos);
  d = error_of("G10 L1 P1 Q2.5\n", {}, machine);
  CHECK(d.message.find("not an integer") != std::string::npos);
  // Fanuc's G10 L10–L13 are offset registers of another meaning: not read on other machines.
  d = error_of("G10 L1 P1 Z1\n", {}, at_origin());
  CHECK(d.message.find("not supported") != std::string::npos);
}
