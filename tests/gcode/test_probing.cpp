// LinuxCNC's straight probes G38.2–G38.5 under the linuxcnc machine, read as its rs274 does run
// standalone (motion.cpp, probe): a feed to the programmed point, then 0.254 mm back towards the
// start; the rs274 differential test (probing.ngc) checks the same against rs274 itself. Here:
// the two pieces against hand-computed points, #5061–#5063/#5070, the warning, the errors.
#include <doctest/doctest.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {
const MachineConfig kProbingMachine = *MachineConfig::bundled("linuxcnc");
}

TEST_CASE("G38.2-G38.5 under linuxcnc: to the point, 0.254 mm back, #5061-#5063 set, one warning") {
  Result r = run_program(
      "G21 G90 F100\nG0 X1 Y2 Z3\nG38.2 X4 Y6 Z3\nG38.4 Z-1\n"
      "G0 X#5061 Y#5062 Z[#5063 + 10 + #5070]\nM2\n",
      {}, kProbingMachine);
  REQUIRE(r.moves.size() == 6);
  CHECK(near(r.moves[1].end, Vec3(4, 6, 3)));
  CHECK(r.moves[1].kind == MoveKind::feed);
  CHECK(r.moves[1].feed == doctest::Approx(100));
  // Back along (−3, −4)/5 by 0.254.
  CHECK(near(r.moves[2].end, Vec3(4 - 0.6 * 0.254, 6 - 0.8 * 0.254, 3), 1e-12));
  CHECK(near(r.moves[3].end, Vec3(4 - 0.6 * 0.254, 6 - 0.8 * 0.254, -1), 1e-12));
  CHECK(near(r.moves[4].end, Vec3(4 - 0.6 * 0.254, 6 - 0.8 * 0.254, -1 + 0.254), 1e-12));
  CHECK(near(r.moves[5].end, Vec3(4 - 0.6 * 0.254, 6 - 0.8 * 0.254, 9), 1e-12));
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].line == 3);
  CHECK(r.warnings[0].message.find("0.254 mm") != std::string::npos);
  // Inches: 0.01 in back (the same 0.254 mm), and G38 is modal.
  Result in = run_program("G20 G90 F10\nG0 X0 Y0 Z1\nG38.3 Z0\nX1\nM2\n", {}, kProbingMachine);
  REQUIRE(in.moves.size() == 5);
  CHECK(near(in.moves[2].end, Vec3(0, 0, 0.254), 1e-12));
  CHECK(near(in.moves[3].end, Vec3(25.4, 0, 0.254), 1e-12));
  CHECK(near(in.moves[4].end, Vec3(25.4 - 0.254, 0, 0.254), 1e-12));
}

TEST_CASE("G38.x errors as rs274's, at the block; the default machine still refuses probing") {
  const std::string start = "G21 G90 F100\nG0 X0 Y0 Z0\n";
  CHECK(error_of(start + "G38.2 Z0\n", {}, kProbingMachine).message.find("too close") !=
        std::string::npos);
  CHECK(error_of(start + "G38.4 X0\n", {}, kProbingMachine).message.find("too close") !=
        std::string::npos);
  for (const Move& m : run_program(start + "G38.3 Z0\nG38.5 Z0\n", {}, kProbingMachine).moves)
    CHECK(near(m.end, Vec3(0.0)));  // they may stand still, and then do not back off
  Diagnostic no_feed = error_of("G21 G90\nG0 X0 Y0 Z0\nG38.2 Z-1\n", {}, kProbingMachine);
  CHECK(no_feed.line == 3);
  CHECK(no_feed.column == 1);
  CHECK(no_feed.message.find("zero feed") != std::string::npos);
  MachineConfig with_tool = kProbingMachine;
  with_tool.tool_diameters = {{1, 2.0}};
  Diagnostic comp = error_of(start + "G41 D1 G1 X5\nG38.2 X9\n", {}, with_tool);
  CHECK(comp.line == 4);
  CHECK(comp.message.find("cutter radius compensation") != std::string::npos);
  Diagnostic fanuc = error_of(start + "G38.2 Z-1\n", {}, at_origin());
  CHECK(fanuc.column == 1);
  CHECK(fanuc.message.find("is not simulated") != std::string::npos);
}
