#include <doctest/doctest.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

TEST_CASE("G0/G1 random walk, absolute and incremental, matches an accumulated reference") {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> coord(-200, 200);
  for (int trial = 0; trial < 20; ++trial) {
    std::string program = "G21 G17 F500\n";
    std::vector<Vec3> expected;
    Vec3 p(0.0);
    bool incremental = false;
    for (int i = 0; i < 200; ++i) {
      if (rng() % 5 == 0) {
        incremental = !incremental;
        program += incremental ? "G91\n" : "G90\n";
      }
      std::string words;
      for (int a = 0; a < 3; ++a) {
        if (rng() % 3 == 0) continue;
        double v = std::round(coord(rng) * 1000) / 1000;
        words += std::string(" ") + "XYZ"[a] + fmt(v);
        p[a] = incremental ? p[a] + v : v;
      }
      program += ((rng() % 2) ? "G0" : "G1") + words + "\n";
      if (!words.empty()) expected.push_back(p);
    }
    program += "M30\n";
    Result r = run_program(program, {}, at_origin());
    REQUIRE(r.moves.size() == expected.size());
    for (std::size_t k = 0; k < expected.size(); ++k) {
      CHECK(near(r.moves[k].end, expected[k], 1e-9));
      CHECK(near(r.moves[k].start, k ? expected[k - 1] : Vec3(0.0), 1e-9));
    }
    CHECK(near(r.moves.back().end, p, 1e-9));
  }
}

TEST_CASE("units, feed, spindle and tool travel on every move") {
  Result r = run_program(
      "G20 G90\nT3 M6\nS1000 M3\nG1 X1 Y2 Z-0.5 F10\nM4 S500\nG0 X2\nM5\nT7\nG1 X3\nM6\nG1 "
      "X4\nM30\n",
      {}, at_origin());
  REQUIRE(r.moves.size() == 4);
  CHECK(near(r.moves[0].end, Vec3(25.4, 50.8, -12.7)));
  CHECK(r.moves[0].feed == doctest::Approx(254));
  CHECK(r.moves[0].spindle == 1000);
  CHECK(r.moves[0].tool == 3);
  CHECK(r.moves[0].kind == MoveKind::feed);
  CHECK(r.moves[1].kind == MoveKind::rapid);
  CHECK(r.moves[1].feed == 0);
  CHECK(r.moves[1].spindle == -500);
  CHECK(r.moves[2].spindle == 0);
  CHECK(r.moves[2].tool == 3);  // T7 only selects
  CHECK(r.moves[3].tool == 7);
  CHECK(r.tools == std::set<int>{3, 7});
  CHECK(r.tool_lines.at(3) == 2);
  CHECK(r.tool_lines.at(7) == 10);
  CHECK(std::string(to_string(MoveKind::cycle)) == "cycle");
}

TEST_CASE("work offsets: table, G54.1 P, G10 L2/L20; output in the G54 frame") {
  MachineConfig machine;
  machine.work_offsets[MachineConfig::g54_key(1)] = Vec3(100, 0, 0);
  machine.work_offsets[MachineConfig::g54_key(2)] = Vec3(200, 10, 0);
  machine.work_offsets[MachineConfig::g54_1_key(7)] = Vec3(0, 0, -50);
  Result r = run_program(
      "G90 G54 G0 X1 Y1 Z1\nG55 X1 Y1 Z1\nG54.1 P7 X1 Y1 Z1\nG10 L2 P3 X5 Y6 Z7\nG56 X0 Y0 Z0\n"
      "G10 L20 P7 Z-60\nG54.1 P7 X0 Y0 Z0\nM30\n",
      {}, at_origin(machine));
  REQUIRE(r.moves.size() == 5);
  CHECK(near(r.moves[0].end, Vec3(1, 1, 1)));
  CHECK(near(r.moves[1].end, Vec3(101, 11, 1)));    // G55 point, seen from G54
  CHECK(near(r.moves[2].end, Vec3(-99, 1, -49)));   // G54.1 P7
  CHECK(near(r.moves[3].end, Vec3(-95, 6, 7)));     // G56 set by G10 L2 P3
  CHECK(near(r.moves[4].end, Vec3(-100, 0, -60)));  // G10 L20 on the active system
}

TEST_CASE("program start and home returns: far along the tool axis, approach straight down") {
  Result r = run_program(
      "G90 G21 G17\nG0 X10 Y20\nG43 Z5 H1\nG1 Z-1 F100\nG91 G28 Z0\nG90 G0 X50 Y50\nZ3\nM30\n");
  REQUIRE(r.moves.size() == 4);
  const double far = MachineConfig::kDefaultFar;
  CHECK(near(r.moves[0].start, Vec3(10, 20, 5 + far)));  // the approach from far above
  CHECK(near(r.moves[0].end, Vec3(10, 20, 5)));
  CHECK(near(r.moves[1].end, Vec3(10, 20, -1)));
  CHECK(near(r.moves[2].start, r.moves[2].end));         // G28's intermediate point: where it is
  CHECK(near(r.moves[3].start, Vec3(50, 50, 3 + far)));  // G28 retracted; X Y stayed far
  CHECK(near(r.moves[3].end, Vec3(50, 50, 3)));
  CHECK(r.warnings.empty());  // Z alone: the top of Z's travel, no guess
  r = run_program("G0 X10 Y20 Z5\nG28\nG91 G28 X0\nG30 Y0\nM30\n");
  REQUIRE(r.warnings.size() == 2);  // X and Y went to default references: once per code
  CHECK(r.warnings[0].line == 2);
  CHECK(r.warnings[0].message.find("default reference") != std::string::npos);
  CHECK(r.warnings[1].line == 4);
  CHECK(r.warnings[1].message.find("G30") != std::string::npos);
}

TEST_CASE("G28 X Y with a vertical tool rapids to home X Y; G53 moves in machine coordinates") {
  MachineConfig machine;
  machine.set_home(Vec3(-10, -20, 0));
  machine.work_offsets[1] = Vec3(100, 100, -100);
  Result r = run_program(
      "G0 X0 Y0 Z10\nG28 X5 Y5\nZ3\nG53 G0 X0 Y0\nG53 Z0\nX1 Y1\nZ2\nG28 Y0\nX0 Y0 Z1\nM30\n",
      InterpreterOptions{}, machine);
  REQUIRE(r.moves.size() == 9);
  CHECK(near(r.moves[1].end, Vec3(5, 5, 10)));        // intermediate point
  CHECK(near(r.moves[2].end, Vec3(-110, -120, 10)));  // home X Y (machine -> G54), same height
  CHECK(near(r.moves[3].end, Vec3(-110, -120, 3)));
  CHECK(near(r.moves[4].end, Vec3(-100, -100, 3)));                     // G53 X0 Y0
  CHECK(near(r.moves[5].start, Vec3(1, 1, 2 + machine.far_distance)));  // after G53 Z: far
  CHECK(near(r.moves[6].end, Vec3(1, 0, 2)));     // G28 Y0: intermediate point,
  CHECK(near(r.moves[7].end, Vec3(1, -120, 2)));  // then home Y at the same height
  CHECK(near(r.moves[8].end, Vec3(0, 0, 1)));
  CHECK(r.warnings.empty());
  Diagnostic d = error_of("G68.2 X0 Y0 Z0 I0 J30 K0\nG53.1\nG0 X0 Y0 Z5\nG53 X0\n");
  CHECK(d.line == 4);
  CHECK(d.message.find("kinematics") != std::string::npos);
}

TEST_CASE("G30 uses the second reference; M6 retracts; M2 and M30 end the program") {
  Result r = run_program("G0 X0 Y0 Z1\nG30 Z5\nG0 Z2\nT2 M6\nG0 X1 Y1 Z2\nM2\nG0 X9\n");
  REQUIRE(r.moves.size() == 4);
  CHECK(near(r.moves[1].end, Vec3(0, 0, 5)));
  CHECK(r.moves[2].start.z > 1000);
  CHECK(r.moves[3].start.z > 1000);  // the tool change left the tool far
  CHECK(r.moves[3].tool == 2);
}

TEST_CASE("rejected blocks name line, column and word") {
  Diagnostic d = error_of("G0 X1 Y1 Z1\nG1 X2 X3 F10\n");
  CHECK(d.line == 2);
  CHECK(d.column == 7);
  CHECK(d.message.find("repeated") != std::string::npos);
  d = error_of("G0 G1 X1\n");
  CHECK(d.column == 4);
  CHECK(d.message.find("conflicts") != std::string::npos);
  d = error_of("G0 X1 Y1 Z1\nG41 D1\n");  // no tool table: D1 has no diameter
  CHECK(d.column == 5);
  CHECK(d.message.find("tool 1 is not in the tool table") != std::string::npos);
  d = error_of("G0 X1 I5\n");
  CHECK(d.column == 7);
  d = error_of("X1 Y2\n");
  CHECK(d.message.find("motion") != std::string::npos);
  d = error_of("G0 X0 Y0 Z0\nG1 X5\n");
  CHECK(d.message.find("feed") != std::string::npos);
  d = error_of("G0 X0 Y0 Z0 A10\n");
  CHECK(d.column == 13);
  d = error_of("T1.5 M6\n");
  CHECK(d.column == 1);
  d = error_of("G0 X1 Y1 Z1 E5\n");
  CHECK(d.message.find("E5") != std::string::npos);
  CHECK(d.to_string() == "test.nc:1:13: word E5 is not used by any code in this block");
}

TEST_CASE("lenient mode turns unsupported words into warnings and skips them") {
  InterpreterOptions options;
  options.lenient = true;
  Result r =
      run_program("G0 X1 Y1 Z1\nG61.1\nG1 X2 F100 E4\nG1 X3 E5\nM30\n", options, at_origin());
  CHECK(r.moves.size() == 3);
  REQUIRE(r.warnings.size() == 5);  // three skips, then one summary line per kind of word
  CHECK(r.warnings[0].line == 2);
  CHECK(r.warnings[3].message.find("skipped 1 × code G61.1 (lines 2)") != std::string::npos);
  CHECK(r.warnings[4].message.find("skipped 2 × unused word E (lines 3, 4)") != std::string::npos);
  // What would change the path is never skipped: an unknown code beside coordinates, a rotary
  // word, a rotated coordinate system.
  for (const char* text :
       {"G0 X1 Y1 Z1\nG16 X2\nM30\n", "G0 X1 Y1 Z1\nG0 X2 B90\nM30\n", "G10 L2 P1 X0 R30\nM30\n"}) {
    Diagnostic d = error_of(text, options, at_origin());
    CAPTURE(d.message);
    CHECK((d.message.find("cannot be skipped") != std::string::npos ||
           d.message.find("needs a machine file with \"kinematics\"") != std::string::npos));
  }
}

TEST_CASE("truncated programs warn; a stream is read with constant memory") {
  Result r = run_program("G0 X1 Y1 Z1\nG1 X2 F1", {}, at_origin());
  CHECK(r.moves.size() == 2);
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].message.find("truncated") != std::string::npos);
  // A long program through a generating stream buffer: no copy of it is ever held.
  struct Generator : std::streambuf {
    long long left;
    std::string block;
    long long n = 0;
    explicit Generator(long long count) : left(count) {}
    int_type underflow() override {
      if (left-- <= 0) return traits_type::eof();
      ++n;
      block = "G1 F100 X" + std::to_string(n % 100) + " Y" + std::to_string(n % 7) + "\n";
      setg(block.data(), block.data(), block.data() + block.size());
      return traits_type::to_int_type(block[0]);
    }
  } generator(200000);
  std::istream in(&generator);
  Interpreter interpreter({}, at_origin());
  long long count = 0;
  interpreter.run(in, "gen", [&](const Move&) { ++count; });
  CHECK(count == 200000);
  CHECK(interpreter.blocks() == 200000);
}
