// LinuxCNC's U/V/W under --machine linuxcnc: plain linear axes that move nothing tridex
// simulates; read with one warning, their positions (G90 and G91, in program units) readable as
// #5426–#5428 and #<_u> #<_v> #<_w>. On other machines they stay unused words (an error).
#include <doctest/doctest.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

TEST_CASE("U/V/W: plain axes under LinuxCNC, the tool path as without them, one warning") {
  const std::string with =
      "G0 X1 Y2 Z3 W5\nG1 W100 F200\nG0 W0\nG1 X4 U1 V2 F100\nG2 X6 I1 J0 W3\n";
  const std::string without = "G0 X1 Y2 Z3\nG1 F200\nG0\nG1 X4 F100\nG2 X6 I1 J0\n";
  Result a = run_program(with, {}, linuxcnc_at_origin()),
         b = run_program(without, {}, linuxcnc_at_origin());
  REQUIRE(a.moves.size() == b.moves.size());
  for (std::size_t i = 0; i < a.moves.size(); ++i) CHECK(near(a.moves[i].end, b.moves[i].end));
  int warnings = 0;
  for (const Diagnostic& d : a.warnings) warnings += d.message.find("U/V/W") != std::string::npos;
  CHECK(warnings == 1);
  // Fanuc's mills have no U/V/W (its lathes read U/W as incremental X/Z): an unused word.
  Diagnostic d = error_of("G0 X1 Y2 Z3\nG1 W1 F100\n", {}, at_origin());
  CHECK(d.line == 2);
  CHECK(d.message.find("W1") != std::string::npos);
}

TEST_CASE("U/V/W: positions under G90 and G91 and in inches, read back as parameters") {
  // Each X reads the parameters of the block before, in its units.
  Result r = run_program(
      "G21 G0 X0 Y0 Z0 U2 V3 W4\nG91 G0 W1.5 U-1\nG90 G0 X[#5426 + #5427 + #5428]\n"
      "G20 G0 W1\nG0 X#<_w> Y[#<_u> * 25.4]\n",
      {}, linuxcnc_at_origin());
  REQUIRE(r.moves.size() >= 2);
  CHECK(r.moves[r.moves.size() - 2].end.x == doctest::Approx(1 + 3 + 5.5));
  CHECK(near(r.moves.back().end, Vec3(25.4, 25.4, 0), 1e-9));
}
