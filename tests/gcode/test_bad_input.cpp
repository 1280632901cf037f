// Bad input: every malformed program is a GcodeError with a position, never a crash. The fuzz
// findings of gcode/fuzz/run.sh are the named cases at the end; their inputs are kept under
// tests/data/gcode/fuzz/.
#include <doctest/doctest.h>

#include <fstream>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {
std::string file_text(const std::string& name) {
  std::ifstream in(std::string(TRIDEX_TEST_DATA) + "/gcode/" + name, std::ios::binary);
  REQUIRE(in);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// Runs a program strictly and leniently; either it runs or it throws GcodeError with a line.
void survives(const std::string& text) {
  for (bool lenient : {false, true}) {
    InterpreterOptions options;
    options.lenient = lenient;
    options.max_blocks = 100000;
    try {
      Result r = run_program(text, options);
      for (const Move& m : r.moves) {
        CHECK(is_finite(m.start));
        CHECK(is_finite(m.end));
        CHECK(glm::length(m.axis) == doctest::Approx(1));
      }
    } catch (const GcodeError& e) {
      CHECK(e.where.line >= 1);
      CHECK(e.where.file == "test.nc");
      CHECK(std::string(e.what()).rfind("test.nc:", 0) == 0);
    }
  }
}
}  // namespace

TEST_CASE("bad input: positions of common mistakes") {
  Diagnostic d = error_of("G0 X0 Y0 Z0\nG1 X1 (unclosed\n");
  CHECK((d.line == 2 && d.column == 7));
  d = error_of("G0 X0 Y0 Z0\nG1 X1.2.3 F1\n");
  CHECK((d.line == 2 && d.column == 5));
  d = error_of("G0 X99999999999\n");
  CHECK(d.message.find("out of range") != std::string::npos);
  d = error_of("G0 XNaN\n");
  CHECK(d.column == 4);
  d = error_of("G1 G2 X1\n");
  CHECK(d.message.find("conflicts") != std::string::npos);
  d = error_of("G17 G18\n");
  CHECK(d.column == 5);
  d = error_of("M3 M4\n");
  CHECK(d.column == 4);
  d = error_of("G0 X0 Y0 Z0\nG2 X1 Y1 F10\n");
  CHECK(d.message.find("needs") != std::string::npos);
  d = error_of("G54.1 P301\n");
  CHECK(d.column == 7);
  d = error_of("G10 L2 P9 X0\n");
  CHECK(d.message.find("P9") != std::string::npos);
  d = error_of("G0 X0 Y0 Z0\n" + std::string(70000, ' ') + "\n");
  CHECK(d.line == 2);
  CHECK(d.message.find("longer") != std::string::npos);
  d = error_of("G4\n");
  CHECK(d.message.find("G4") != std::string::npos);
  d = error_of(std::string("G0 X0 Y0 Z0\nG1 X\0 F1\n", 21));
  CHECK(d.line == 2);
}

TEST_CASE("bad input: truncations of a real program run or fail cleanly at every cut") {
  std::string program = file_text("linuxcnc/cycles.ngc") + file_text("linuxcnc/arcs_planes.ngc");
  for (std::size_t cut = 0; cut < program.size(); cut += 7) survives(program.substr(0, cut));
}

TEST_CASE("bad input: random binary garbage and random word soup") {
  std::mt19937_64 rng(29);
  for (int i = 0; i < 300; ++i) {
    std::string text(rng() % 200, ' ');
    for (char& c : text) c = static_cast<char>(rng() % 256);
    survives(text);
  }
  const char* words[] = {"G0",   "G1",  "G2",   "G3",   "G81", "G83", "G68.2", "G53.1",
                         "G69",  "G91", "G90",  "G28",  "G53", "M98", "M99",   "O1",
                         "X1",   "Y-2", "Z3.5", "I1",   "J-1", "K2",  "R1",    "R-2",
                         "Q0.5", "P1",  "L2",   "F100", "T1",  "M6",  "\n"};
  for (int i = 0; i < 2000; ++i) {
    std::string text;
    int n = static_cast<int>(rng() % 40);
    for (int k = 0; k < n; ++k) text += std::string(words[rng() % std::size(words)]) + " ";
    survives(text);
  }
}

TEST_CASE("fuzz: G911111111 — a code too large for an int is an unsupported code, not UB") {
  Diagnostic d = error_of(file_text("fuzz/crash-huge-g-code.nc"));
  CHECK(d.line == 4);
  CHECK(d.message.find("unsupported code G911111111") != std::string::npos);
  survives(file_text("fuzz/crash-huge-g-code.nc"));
}

TEST_CASE("max_blocks bounds endless subprogram loops") {
  InterpreterOptions options;
  options.max_blocks = 1000;
  std::string loop = "O1\nM98 P2 L9999\nM30\nO2\nM98 P3 L9999\nM99\nO3\nG4 P0\nM99\n";
  CHECK_THROWS_AS(run_program(loop, options), GcodeError);
}

TEST_CASE("fuzz: G73 with an R plane 780 km up and Q3 — too many pecks is an error, not a hang") {
  InterpreterOptions lenient;
  lenient.lenient = true;
  // The fuzzer's input opens with an unknown G221 beside coordinates: not skippable, even lenient.
  std::string text = file_text("fuzz/timeout-far-r-plane-pecks.nc");
  Diagnostic d = error_of(text, lenient);
  CHECK(d.line == 2);
  CHECK(d.message.find("cannot be skipped") != std::string::npos);
  // Without it (and the Q that G89 does not take), the peck cycle is what stops the run.
  text.replace(text.find("G221 "), 5, "");
  text.replace(text.find("G89 X55 Y50 R1 Q3"), 17, "G89 X55 Y50 R1");
  d = error_of(text, lenient);
  CAPTURE(d.message);
  CHECK(d.line == 6);
  CHECK(d.message.find("would peck") != std::string::npos);
  survives(file_text("fuzz/timeout-far-r-plane-pecks.nc"));
  // A sensible deep hole still pecks.
  CHECK_NOTHROW(run_program("G21 G90 G17 F100\nG0 X0 Y0 Z5\nG83 X1 Y1 Z-30 R2 Q0.5\nG80\nM2\n"));
}
