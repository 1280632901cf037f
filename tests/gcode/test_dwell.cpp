// Dwells in the stream: G4 and the pause at a hole's bottom (G82, G86, G89), with their line,
// tool and spindle direction, in the dialect's time unit; the moves are the same with or without
// a dwell sink.
#include <doctest/doctest.h>

#include <sstream>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

struct Stream {
  std::vector<Move> moves;
  std::vector<Dwell> dwells;
};

Stream run_with_dwells(const std::string& text, MachineConfig machine) {
  std::istringstream in(text);
  Interpreter interpreter({}, machine);
  Stream s;
  interpreter.run(
      in, "test.nc", [&](const Move& m) { s.moves.push_back(m); },
      [&](const Dwell& d) { s.dwells.push_back(d); });
  return s;
}

}  // namespace

TEST_CASE(
    "dwell: G4 in seconds (LinuxCNC) or milliseconds and X seconds (Fanuc), with line, tool and "
    "axis") {
  MachineConfig linuxcnc = at_origin();
  linuxcnc.dialect = Dialect::linuxcnc;
  Stream s = run_with_dwells("T3 M6\nG1 X1 F100\nG4 P1.5\n", linuxcnc);
  REQUIRE(s.dwells.size() == 1);
  CHECK(s.dwells[0].line == 3);
  CHECK(s.dwells[0].tool == 3);
  CHECK(s.dwells[0].axis == Vec3(0, 0, 1));
  CHECK(s.dwells[0].seconds == doctest::Approx(1.5));

  MachineConfig fanuc = at_origin();
  s = run_with_dwells("G4 P1500\nG4 X2.\nG4 P0\n", fanuc);
  REQUIRE(s.dwells.size() == 2);  // a zero dwell is no dwell
  CHECK(s.dwells[0].seconds == doctest::Approx(1.5));
  CHECK(s.dwells[1].seconds == doctest::Approx(2.0));
  CHECK(s.moves.empty());  // G4 X is a time, not a move
}

TEST_CASE("dwell: G82, G86 and G89 pause at each hole's bottom, P sticky; G81 and G85 do not") {
  MachineConfig machine = at_origin();
  machine.dialect = Dialect::linuxcnc;
  const std::string cycles = "G0 Z10\nG98 G82 X1 Z-2 R1 P0.25 F100\nX2\nX3 P0.5\nG80\n";
  Stream s = run_with_dwells(cycles, machine);
  REQUIRE(s.dwells.size() == 3);
  CHECK(s.dwells[0].line == 2);
  CHECK(s.dwells[1].line == 3);
  CHECK(s.dwells[1].seconds == doctest::Approx(0.25));
  CHECK(s.dwells[2].seconds == doctest::Approx(0.5));
  // The moves do not change with the sink (nor with the cycle's dwell).
  Result plain = run_program(cycles, {}, machine);
  REQUIRE(plain.moves.size() == s.moves.size());
  for (std::size_t k = 0; k < s.moves.size(); ++k) {
    CHECK(plain.moves[k].start == s.moves[k].start);
    CHECK(plain.moves[k].end == s.moves[k].end);
  }
  for (const char* code : {"G86", "G89"})
    CHECK(run_with_dwells(std::string("G0 Z10\n") + code + " X1 Z-2 R1 P1 F100\nG80\n", machine)
              .dwells.size() == 1);
  for (const char* code : {"G81", "G85"})
    CHECK(run_with_dwells(std::string("G0 Z10\n") + code + " X1 Z-2 R1 F100\nG80\n", machine)
              .dwells.empty());
}
