#include <doctest/doctest.h>

#include <fstream>

#include "helpers.hpp"
#include "tridex/gcode/grouping.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

TEST_CASE("codes without effect on the path are accepted; stops and dwells move nothing") {
  Result r = run_program(
      "%\nO42 (name)\nN1 G15 G40 G49 G61 G80 G94 G97 G91.1\nG64 P0.01 Q0.01\nG0 X0 Y0 "
      "Z5\nM0\nM1\nM8\nM7\n"
      "M9\nG4 P1.5\nG4 X2\nG44 H3\nG43 H1\nG49\nG1 X1 F10\nM30\n%\nG0 X99\n",
      {}, at_origin());
  REQUIRE(r.moves.size() == 2);
  CHECK(r.warnings.empty());
  CHECK(near(r.moves[1].end, Vec3(1, 0, 5)));
  // Look-ahead and smoothing modes of Fanuc and Haas posts; a UTF-8 byte order mark.
  r = run_program("\xEF\xBB\xBFG5.1 Q1 R5\nG8 P1\nG187 P3 E0.01\nG0 X0 Y0 Z5\nG5.1 Q0\nM30\n");
  CHECK(r.moves.size() == 1);
  CHECK(r.warnings.empty());
  CHECK(error_of("G5.1 Q1 G8 P1\n").message.find("conflicts") != std::string::npos);
  // Text after the closing '%' is never read; a program without any still ends at M30.
  r = run_program("G0 X0 Y0 Z5\nM30\nG0 X1\n", {}, at_origin());
  CHECK(r.moves.size() == 1);
  CHECK(r.warnings.empty());
}

TEST_CASE("block delete: skipped by default, executed when the switch is off") {
  InterpreterOptions options;
  CHECK(run_program("G0 X1 Y1 Z1\n/G0 X2\nM30\n", options, at_origin()).moves.size() == 1);
  options.block_delete = false;
  CHECK(run_program("G0 X1 Y1 Z1\n/G0 X2\nM30\n", options, at_origin()).moves.size() == 2);
}

TEST_CASE("G53.6 orients like G53.1; G269 cancels G268; G69 cancels G68.2") {
  Result r = run_program(
      "G68.2 X0 Y0 Z0 I0 J90 K0\nG53.6\nG0 X0 Y0 Z3\nG69\nG0 X1 Y-3 Z0\n"
      "G268 X0 Y0 Z0 I0 J90 K0 Q123\nG253\nG0 X0 Y0 Z2\nG269\nG0 X2 Y0 Z0\nM30\n");
  REQUIRE(r.moves.size() == 4);
  CHECK(near(r.moves[0].axis, Vec3(0, -1, 0), 1e-12));
  CHECK(near(r.moves[0].end, Vec3(0, -3, 0), 1e-9));
  CHECK(near(r.moves[1].end, Vec3(1, -3, 0), 1e-9));   // G69: work coordinates again
  CHECK(near(r.moves[2].axis, Vec3(1, 0, 0), 1e-12));  // Ry(90)·z = +X
  CHECK(near(r.moves[2].end, Vec3(2, 0, 0), 1e-9));
  CHECK(near(r.moves[3].end, Vec3(2, 0, 0), 1e-9));
  CHECK(near(r.moves[3].start, r.moves[2].end, 1e-9));
}

TEST_CASE("LinuxCNC: G53.1, G53.3 and G53.6 leave G0 the motion mode; Fanuc's keep it") {
  // LinuxCNC's TWP remap turns the rotaries with a G0 block of its own (remap.py, g53n_core), and
  // its demos then move with bare X Y Z (incremental_repetition_g533.ngc).
  MachineConfig linuxcnc;
  linuxcnc.dialect = Dialect::linuxcnc;
  for (const char* orient : {"G53.1", "G53.6", "G53.3 X0 Y0 Z30"}) {
    CAPTURE(orient);
    Result r =
        run_program(std::string("G21 G90 G0 X0 Y0 Z50\nG1 X1 F100\nG68.2 X10 Y0 Z0 Q121 I0 J90\n") +
                        orient + "\nX5 Y5 Z20\nG1 X6\nM2\n",
                    InterpreterOptions{}, linuxcnc);
    const Move& bare = r.moves[r.moves.size() - 2];
    CHECK(bare.kind == MoveKind::rapid);
    CHECK(near(bare.axis, Vec3(1, 0, 0), 1e-12));  // Q121 J90: the tool along +X
    // Ry(90°) takes the plane's x, y, z to −Z, +Y, +X: (5, 5, 20) lands at (10, 0, 0) + (20, 5,
    // −5).
    CHECK(near(bare.end, Vec3(30, 5, -5), 1e-9));
    CHECK(r.moves.back().kind == MoveKind::feed);
  }
  // Fanuc's G53.1 is no motion code: the G1 before it goes on.
  Result fanuc = run_program(
      "G21 G90 G0 X0 Y0 Z50\nG1 X1 F100\nG68.2 X10 Y0 Z0 I0 J90 K0\nG53.1\nX5 Y5 Z20\nM30\n");
  CHECK(fanuc.moves.back().kind == MoveKind::feed);
}

TEST_CASE("G30 P2 is the second reference; P3 is rejected") {
  MachineConfig machine;
  machine.set_reference2(Vec3(7, 8, 0));
  Result r = run_program("G0 X0 Y0 Z1\nG30 P2 X0 Y0\nG0 Z4\nM30\n", InterpreterOptions{}, machine);
  CHECK(near(r.moves.back().end, Vec3(7, 8, 4)));
  CHECK(error_of("G30 P3\n").column == 5);
}

TEST_CASE("read_moves reads a file like run() does; options are validated") {
  std::string path = std::string(TRIDEX_TEST_DATA) + "/gcode/linuxcnc/cycles.ngc";
  std::vector<Move> moves = read_moves(path);
  std::ifstream in(path);
  std::string text((std::istreambuf_iterator<char>(in)), {});
  Result r = run_program(text);
  REQUIRE(moves.size() == r.moves.size());
  for (std::size_t i = 0; i < moves.size(); ++i) CHECK(near(moves[i].end, r.moves[i].end));
  CHECK_THROWS_AS(read_moves("/nonexistent/program.nc"), tridex::Error);
  InterpreterOptions bad;
  bad.arc_tolerance = 0;
  CHECK_THROWS_AS(Interpreter{bad}, tridex::Error);
  MachineConfig bad_machine;
  bad_machine.work_offsets[1] = Vec3(std::nan(""), 0, 0);
  CHECK_THROWS_AS((Interpreter{InterpreterOptions{}, bad_machine}), tridex::Error);
}

TEST_CASE("a whole program grouped: each group's moves seen in its frame move along local z") {
  Result r = run_program(
      "G21 G90 F100\nG0 X0 Y0 Z5\nG1 Z-1\nX10\nG91 G28 Z0\nG90\n"
      "G68.2 X0 Y0 Z0 I90 J90 K0\nG53.1\nG0 X0 Y0 Z5\nG1 Z0\nX3\nG69\nG91 G28 Z0\nG90\n"
      "G68.2 X0 Y0 Z0 I0 J0 K0\nG53.1\nG0 X2 Y2 Z3\nM30\n");
  std::vector<MoveGroup> groups = group_by_direction(r.moves, 0.0);
  REQUIRE(groups.size() == 2);
  CHECK(near(groups[0].axis, Vec3(0, 0, 1)));
  CHECK(near(groups[1].axis, Vec3(1, 0, 0), 1e-12));
  CHECK(groups[0].moves.size() == 5);  // approach, plunge, cut, G28, and the last approach
  for (const MoveGroup& g : groups)
    for (const Move& m : g.moves) {
      // A plunge along the tool axis changes only the local z.
      Vec3 a = g.frame.to_local(m.start), b = g.frame.to_local(m.end);
      if (m.line == 3 || m.line == 10) CHECK(std::abs(a.x - b.x) + std::abs(a.y - b.y) < 1e-9);
    }
}

TEST_CASE("M98 jumps across a file much larger than the line buffer") {
  std::string padding;
  for (int i = 0; i < 20000; ++i) padding += "(padding line " + std::to_string(i) + ")\n";
  std::string program = "O1\nG0 X0 Y0 Z1\nM98 P9 L2\nG0 X5\n" + padding + "M30\n" + padding +
                        "O9\nG91 G0 X1\nG90 M99\n";
  Result r = run_program(program);
  REQUIRE(r.moves.size() == 4);
  CHECK(near(r.moves[1].end, Vec3(1, 0, 1)));
  CHECK(near(r.moves[2].end, Vec3(2, 0, 1)));
  CHECK(near(r.moves[3].end, Vec3(5, 0, 1)));
  CHECK(r.moves[1].line == 4 + 2 * 20000 + 3);  // line numbers survive the jumps
  CHECK(r.moves[3].line == 4);
}

TEST_CASE("G20 applies to the G68.2 origin but not to its angles") {
  Result r = run_program("G20 G90\nG68.2 X1 Y0 Z0 I0 J90 K0\nG53.1\nG0 X0 Y0 Z1\nM30\n");
  REQUIRE(r.moves.size() == 1);
  CHECK(near(r.moves[0].end, Vec3(25.4, -25.4, 0), 1e-9));
}
