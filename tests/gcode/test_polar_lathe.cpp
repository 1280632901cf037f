// LinuxCNC's polar words (@ radius, ^ angle) against the same points written as X and Y, their
// errors, and the codes tridex refuses by name (lathe codes). The rs274 differential corpus
// (tests/data/gcode/linuxcnc/polar_words.ngc) checks them against LinuxCNC.
#include <doctest/doctest.h>

#include <cmath>
#include <fstream>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {
MachineConfig linuxcnc() { return *MachineConfig::bundled("linuxcnc"); }

// The end points of the program's moves.
std::vector<Vec3> ends(const std::string& text) {
  std::vector<Vec3> points;
  for (const Move& m : run_program(text, {}, linuxcnc()).moves) points.push_back(m.end);
  return points;
}

Vec3 polar(double radius, double degrees, double z) {
  double t = glm::radians(degrees);
  return Vec3(radius * std::cos(t), radius * std::sin(t), z);
}
}  // namespace

TEST_CASE("polar: @ and ^ under G90 and G91 give the points written out") {
  // G90: a word left out keeps the current radius or angle; G91: @ adds to the radius, ^ turns.
  std::vector<Vec3> p =
      ends("G21 G90 F100\nG0 X10 Y0 Z1\nG1 @20 ^30\n^75\n@12.5\nG91 @5\n^-40\n@-3 ^10 Z0.5\nM2\n");
  REQUIRE(p.size() == 7);
  CHECK(near(p[1], polar(20, 30, 1), 1e-9));
  CHECK(near(p[2], polar(20, 75, 1), 1e-9));
  CHECK(near(p[3], polar(12.5, 75, 1), 1e-9));
  CHECK(near(p[4], polar(17.5, 75, 1), 1e-9));
  CHECK(near(p[5], polar(17.5, 35, 1), 1e-9));
  CHECK(near(p[6], polar(14.5, 45, 1.5), 1e-9));
  // Program units and the program origin (G52 moves it).
  p = ends("G20 G90 F10\nG52 X1 Y2\nG0 @1 ^90 Z0\nM2\n");
  CHECK(near(p.back(), Vec3(25.4, 2 * 25.4 + 25.4, 0), 1e-9));
  // An arc to a polar end point.
  p = ends("G21 G90 F100\nG0 X15 Y0 Z0\nG3 ^90 I-15 J0\nM2\n");
  CHECK(near(p.back(), Vec3(0, 15, 0), 1e-9));
}

TEST_CASE("polar: G91 drilling repeats step along the circle") {
  // Five holes 72 degrees apart on a 25 mm radius, the first one step from X25 Y0.
  Result r =
      run_program("G21 G90 F100\nG0 X25 Y0 Z5\nG91 G81 ^72 R-4 Z-4 L5\nM2\n", {}, linuxcnc());
  std::vector<Vec3> bottoms;
  for (const Move& m : r.moves)
    if (m.kind == MoveKind::cycle && m.feed > 0) bottoms.push_back(m.end);
  REQUIRE(bottoms.size() == 5);
  for (int k = 0; k < 5; ++k)
    CHECK(near(bottoms[static_cast<std::size_t>(k)], polar(25, 72.0 * (k + 1), -3), 1e-9));
}

TEST_CASE("polar: errors name the word and the rule") {
  MachineConfig m = linuxcnc();
  CHECK(error_of("G0 X1 Y1 Z1\nG0 @1 ^2\n", {}, at_origin()).message.find("LinuxCNC") !=
        std::string::npos);
  Diagnostic d = error_of("G0 X1 Y1 Z1\nG0 @1 X2\n", {}, m);
  CHECK((d.line == 2 && d.column == 7));
  CHECK(error_of("G0 X1 Y1 Z1\nG18 G0 @1 ^2\n", {}, m).message.find("G17") != std::string::npos);
  CHECK(error_of("G0 X1 Y1 Z1\nG53 G0 @1 ^2\n", {}, m).message.find("G53") != std::string::npos);
  CHECK(error_of("G0 X1 Y1 Z1\nG80 @1\n", {}, m).message.find("motion") != std::string::npos);
  CHECK(error_of("G0 X0 Y0 Z1\nG0 @1\n", {}, m).message.find("origin") != std::string::npos);
  CHECK(error_of("G0 X0 Y0 Z1\nG91 G0 ^10\n", {}, m).message.find("origin") != std::string::npos);
}

TEST_CASE("lathe codes are errors that name them, even lenient") {
  InterpreterOptions lenient;
  lenient.lenient = true;
  for (const char* code : {"G7", "G33 Z-1 K0.1", "G76 P0.05 Z-1 I-0.01 J0.01 K0.03", "G70 Q1",
                           "G71 Q1", "G72 Q1", "G96 D2500 S200"}) {
    Diagnostic d = error_of(std::string("G0 X0 Y0 Z0\n") + code + "\nM2\n", lenient, linuxcnc());
    CHECK(d.line == 2);
    CHECK_MESSAGE(d.message.find("is a lathe code") != std::string::npos, d.message);
  }
  // LinuxCNC's installed lathe demo (read in place, GPL): refused at its first turning cycle.
  const char* demo = "/usr/share/linuxcnc/ncfiles/lathe_g70_71_demo.ngc";
  if (std::ifstream in{demo}; in) {
    Interpreter interpreter({}, linuxcnc());
    try {
      interpreter.run(in, demo, [](const Move&) {});
      FAIL("lathe_g70_71_demo.ngc was accepted");
    } catch (const GcodeError& e) {
      CHECK(e.where.line == 28);
      CHECK(e.where.column == 1);
      CHECK(e.where.message == "G71.1 is a lathe code: tridex simulates milling machines");
    }
  }
  // Fanuc's G76 is a mill's fine boring cycle: not called a lathe code there.
  CHECK(error_of("G0 X0 Y0 Z0\nG76 X1 Z-1 R1 Q0.1\n", {}, at_origin()).message.find("lathe") ==
        std::string::npos);
}
