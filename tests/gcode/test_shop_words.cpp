// Words that shop programs write and public programs showed tridex refusing: Haas M97 local
// subprograms, G103 and G154, M-codes with arguments of their own (M19 R, LinuxCNC's I/O
// codes), and Fanuc's modal D. Each is compared with the same program written without it.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

void same_moves(const Result& a, const Result& b) {
  REQUIRE(a.moves.size() == b.moves.size());
  for (std::size_t i = 0; i < a.moves.size(); ++i) {
    CAPTURE(i);
    CHECK(near(a.moves[i].start, b.moves[i].start));
    CHECK(near(a.moves[i].end, b.moves[i].end));
    CHECK(a.moves[i].kind == b.moves[i].kind);
  }
}

}  // namespace

TEST_CASE("Haas M97 P L calls block N P of this program, L times, back at M99") {
  const std::string sub = "N1000\nG91 G1 Z-0.5 F100\nG90 X10\nX0\nM99\n";
  Result called = run_program(
      "G21 G90 G17\nG0 X0 Y0 Z1\nM97 P1000 L2\nG0 Z5\nM97 P1000\nM30\n" + sub, {}, at_origin());
  const std::string body = "G91 G1 Z-0.5 F100\nG90 X10\nX0\n";
  Result inline_ = run_program(
      "G21 G90 G17\nG0 X0 Y0 Z1\n" + body + body + "G0 Z5\n" + body + "M30\n", {}, at_origin());
  same_moves(called, inline_);
  // A local subprogram before the call, nested in an M98 subprogram's file position, and errors.
  Result before = run_program("G21 G90\nG0 X0 Y0 Z1\nGOTO 5\nN7 G1 X3 F100\nM99\nN5 M97 P7\nM30\n",
                              {}, at_origin());
  REQUIRE(before.moves.size() == 2);
  CHECK(near(before.moves[1].end, Vec3(3, 0, 1)));
  Diagnostic d = error_of("G0 X0 Y0 Z1\nM97 P12\nM30\n");
  CHECK(d.line == 2);
  CHECK(d.message.find("M97 P12: no block N12") != std::string::npos);
  CHECK(error_of("M97\nM30\n").message.find("M97 needs P") != std::string::npos);
}

TEST_CASE("Haas G103 (look-ahead) and G154 P (extra work offsets, as G54.1 P)") {
  MachineConfig machine = at_origin();
  machine.work_offsets[MachineConfig::g54_1_key(7)] = Vec3(10, 20, 30);
  Result haas =
      run_program("G21 G90\nG103 P1\nG154 P7 G0 X1 Y2 Z3\nG103\nG1 X4 F100\nM30\n", {}, machine);
  Result fanuc = run_program("G21 G90\nG54.1 P7 G0 X1 Y2 Z3\nG1 X4 F100\nM30\n", {}, machine);
  CHECK(haas.warnings.empty());
  same_moves(haas, fanuc);
  REQUIRE(!haas.moves.empty());
  CHECK(near(haas.moves.back().end, Vec3(14, 22, 33)));
  CHECK(error_of("G154\n").message.find("G154 needs P") != std::string::npos);
  CHECK(error_of("G154 P100\n").message.find("G154 number") != std::string::npos);
}

TEST_CASE("M-codes with arguments of their own: M19 R, LinuxCNC's M62-M68, user M100-M199") {
  MachineConfig linuxcnc = *MachineConfig::bundled("rs274");
  Result io = run_program(
      "G21 G90\nM62 P0\nM65 P1\nM66 P0 L0 Q1\nM68 E0 Q0\nM19 R45\nM52 P1\nG0 X1 Y2 Z3\nM2\n", {},
      linuxcnc);
  Result plain = run_program("G21 G90\nG0 X1 Y2 Z3\nM2\n", {}, linuxcnc);
  same_moves(io, plain);
  // Each code is said once in the warnings.
  CHECK(io.warnings.size() == 6);
  // Other M-codes do not take them, and a word no code uses is still an error.
  Diagnostic d = error_of("G21 G90\nM8 P1\n", {}, linuxcnc);
  CHECK(d.message.find("word P1 is not used") != std::string::npos);
  d = error_of("G21 G90\nM62 P0 G1 X1 I3 F100\n", {}, linuxcnc);
  CHECK(d.message.find("word I3 is not used") != std::string::npos);
}

TEST_CASE(
    "Fanuc keeps D for the next G41/G42 (T4 D04 M06), D0 before any; LinuxCNC refuses it as rs274 "
    "does") {
  MachineConfig machine = at_origin();
  machine.tool_diameters = {{1, 6.0}, {4, 10.0}};
  const std::string path = "G0 X-20 Y0 Z1\nG1 Z-1 F100\nX0\nY20\nG40 X-20 Y30\nM30\n";
  Result modal = run_program("G21 G90 G17\nT1 D4 M6\nG41\n" + path, {}, machine);
  Result given = run_program("G21 G90 G17\nT1 M6\nG41 D4\n" + path, {}, machine);
  Result no_d = run_program("G21 G90 G17\nT1 M6\nG41\n" + path, {}, machine);
  same_moves(modal, given);
  // D4 (radius 5) offsets the cut along Y 5 mm to the left of X0; with no D yet the control holds
  // D0 and does not offset (Haas: "a nonzero D code must be specified"), with a warning.
  bool at_minus_5 = false;
  for (const Move& m : modal.moves)
    at_minus_5 |= m.kind == MoveKind::feed && std::abs(m.end.x + 5) < 1e-9 && m.end.y > 10;
  CHECK(at_minus_5);
  bool at_zero = false;
  for (const Move& m : no_d.moves)
    at_zero |= m.kind == MoveKind::feed && std::abs(m.end.x) < 1e-9 && m.end.y > 10;
  CHECK(at_zero);
  REQUIRE(!no_d.warnings.empty());
  CHECK(no_d.warnings.front().message.find("D0") != std::string::npos);
  MachineConfig linuxcnc = *MachineConfig::bundled("rs274");
  linuxcnc.tool_diameters = machine.tool_diameters;
  CHECK(error_of("G21 G90\nT1 D4 M6\n", {}, linuxcnc).message.find("word D4 is not used") !=
        std::string::npos);
}

TEST_CASE(
    "A0/B0/C0 on a machine without kinematics: the axis stays at zero (4-axis posts' tool "
    "starts)") {
  Result with_a = run_program("G21 G90\nT1 M6\nG0 X1 Y2 Z5 A0.\nG1 Z-1 B0 F100\nG91 G0 A0\nM30\n",
                              {}, at_origin());
  Result without =
      run_program("G21 G90\nT1 M6\nG0 X1 Y2 Z5\nG1 Z-1 F100\nG91\nM30\n", {}, at_origin());
  same_moves(with_a, without);
  REQUIRE(with_a.warnings.size() == 2);  // once per letter
  CHECK(with_a.warnings[0].message.find("rotary word A0 read as the axis staying at zero") !=
        std::string::npos);
  // Any other angle needs the kinematics, and so does A0 once G53.1 has turned the tool.
  CHECK(error_of("G21 G90\nG0 X1 A10\n", {}, at_origin()).message.find("kinematics") !=
        std::string::npos);
  Diagnostic d = error_of("G21 G90\nG68.2 X0 Y0 Z0 I0 J30 K0\nG53.1\nG0 X1 A0\n", {}, at_origin());
  CHECK(d.line == 4);
  CHECK(d.message.find("kinematics") != std::string::npos);
}

TEST_CASE("G10 L2/L20 with rotary words: 0 changes nothing; LinuxCNC's plain axes take any") {
  const std::string after = "T1 M6\nG54 G0 X1 Y2 Z10\nG1 Z-1 F100\nM30\n";
  Result with_b = run_program("G21 G90\nG10 L2 P1 X5 Y0 Z0 B0\n" + after, {}, at_origin());
  Result without = run_program("G21 G90\nG10 L2 P1 X5 Y0 Z0\n" + after, {}, at_origin());
  same_moves(with_b, without);
  REQUIRE(!with_b.moves.empty());
  CHECK(near(with_b.moves.back().end, Vec3(6, 2, -1)));
  MachineConfig linuxcnc = *MachineConfig::bundled("rs274");
  same_moves(run_program("G21 G90\nG10 L20 P1 X0 A30 C5\n" + after, {}, linuxcnc),
             run_program("G21 G90\nG10 L20 P1 X0\n" + after, {}, linuxcnc));
  Diagnostic d = error_of("G21 G90\nG10 L2 P1 X0 B15\n", {}, at_origin());
  CHECK(d.column == 14);
  CHECK(d.message.find("G10 B15: a rotary work offset other than 0 is simulated only on a "
                       "machine whose kinematics has that axis") != std::string::npos);
}

TEST_CASE("six-digit variables (#901001 in pallet programs); machine presets for the rest") {
  Result r = run_program("G21 G90\n#901001 = 7\nG0 X#901001 Y0 Z1\nM30\n", {}, at_origin());
  REQUIRE(r.moves.size() == 1);
  CHECK(near(r.moves[0].end, Vec3(7, 0, 1)));
  CHECK(error_of("#1000000 = 1\n").message.find("[0, 999999]") != std::string::npos);
  MachineConfig machine = at_origin();
  machine.variables = {{650, 2000}, {901001, 4}};
  r = run_program("G21 G90\nG0 X0 Y0 Z1\nG1 X#901001 F#650\nM30\n", {}, machine);
  REQUIRE(r.moves.size() == 2);
  CHECK(r.moves[1].feed == 2000);
  CHECK(near(r.moves[1].end, Vec3(4, 0, 1)));
}

TEST_CASE(
    "G52 under a tilted plane: read when it leaves the offset as it is (LinuxCNC's TWP demo)") {
  const std::string tilt =
      "G21 G90\nT1 M6\nG68.2 X50 Y50 Z-50 I0 J30 K0\nG53.1\nG0 X0 Y0 Z100\nG0 X-50\n";
  Result cleared = run_program(tilt + "G52 X0 Y0 Z0\nG0 X0\nG69\nM30\n", {}, at_origin());
  Result plain = run_program(tilt + "G0 X0\nG69\nM30\n", {}, at_origin());
  same_moves(cleared, plain);
  Diagnostic d = error_of(tilt + "G52 X5\n", {}, at_origin());
  CHECK(d.line == 7);
  CHECK(d.message.find("G52 changes the local offset under a tilted plane") != std::string::npos);
}

TEST_CASE("Fanuc G68 X Y R turns the program's XY about a centre; G69 ends it") {
  // A slot, an arc and a drilled hole, written once under G68 and once with every point turned
  // by hand about the centre (the arc's centre offsets turned as vectors).
  const double cx = 10, cy = 5, degrees = 30;
  const double c = std::cos(degrees * std::acos(-1.0) / 180),
               s = std::sin(degrees * std::acos(-1.0) / 180);
  auto exact = [](double v) {
    char text[40];
    std::snprintf(text, sizeof text, "%.10f", v);
    return std::string(text);
  };
  auto turned = [&](double x, double y) {
    return cat(" X", exact(cx + c * (x - cx) - s * (y - cy)), " Y",
               exact(cy + s * (x - cx) + c * (y - cy)));
  };
  auto turned_offset = [&](double i, double j) {
    return cat(" I", exact(c * i - s * j), " J", exact(s * i + c * j));
  };
  const std::string head = "G21 G90 G17\nT1 M6\nG0 X0 Y0 Z5\n";
  const std::string tail = "G69\nG0 X0 Y0\nM30\n";
  Result rotated = run_program(head +
                                   "G68 X10 Y5 R30\nG0 X20 Y5\nG1 Z-1 F100\nX30 Y8\n"
                                   "G3 X30 Y18 I0 J5\nG81 X25 Y0 Z-3 R2\nG80\n" +
                                   tail,
                               {}, at_origin());
  Result by_hand = run_program(head + "G0" + turned(20, 5) + "\nG1 Z-1 F100\nG1" + turned(30, 8) +
                                   "\nG3" + turned(30, 18) + turned_offset(0, 5) + "\nG81" +
                                   turned(25, 0) + " Z-3 R2\nG80\n" + tail,
                               {}, at_origin());
  REQUIRE(rotated.moves.size() == by_hand.moves.size());
  for (std::size_t i = 0; i < rotated.moves.size(); ++i) {
    CAPTURE(i);
    CHECK(near(rotated.moves[i].end, by_hand.moves[i].end, 1e-6));
    CHECK(near(rotated.moves[i].axis, Vec3(0, 0, 1)));
  }
  // Without X Y the centre is the current point; errors at their word.
  Result here =
      run_program("G21 G90\nG0 X10 Y5 Z5\nG68 R90\nG0 X11 Y5\nG69\nM30\n", {}, at_origin());
  REQUIRE(!here.moves.empty());
  CHECK(near(here.moves.back().end, Vec3(10, 6, 5), 1e-9));
  CHECK(
      error_of("G21 G90\nG0 X0 Y0 Z5\nG68 X1 Y1\n", {}, at_origin()).message.find("G68 needs R") !=
      std::string::npos);
  CHECK(error_of("G21 G90\nG18\nG68 X1 Y1 R5\n", {}, at_origin()).message.find("G17") !=
        std::string::npos);
  CHECK(error_of("G21 G90\nG68 X1 Y1 R5\nG68 X0 Y0 R5\n", {}, at_origin())
            .message.find("G69 first") != std::string::npos);
  // LinuxCNC has no G68.
  CHECK(error_of("G21 G90\nG68 X1 Y1 R5\n", {}, linuxcnc_at_origin()).message.find("G68") !=
        std::string::npos);
}

TEST_CASE("Fanuc/Haas external output (POPEN, DPRNT, BPRNT, PCLOS) moves nothing") {
  // A probing report as Haas and Fanuc programs write it: the same moves as without it.
  const std::string moves = "G0 X10 Y10 Z5\nG1 Z-1 F100\nX20\n";
  Result with = run_program("G21 G90 G17\nPOPEN\n" + moves +
                                "DPRNT[MEASURED*X#5021[44]*Y#5022[44]]\nN20 BPRNT[TOOL#4120[20]]\n"
                                "dprnt [**LINE*2*]  (spaces and a comment after)\nPCLOS\nM30\n",
                            {}, at_origin());
  Result without = run_program("G21 G90 G17\n" + moves + "M30\n", {}, at_origin());
  same_moves(with, without);
  CHECK(with.warnings.empty());
  // Errors at the statement: no text, brackets not closed, words after it.
  CHECK(error_of("DPRNT X1\n").message.find("DPRNT and BPRNT need their text in [ ]") !=
        std::string::npos);
  const Diagnostic open = error_of("G21\nDPRNT[X#5021[44]\n");
  CHECK(open.line == 2);
  CHECK(open.column == 6);
  CHECK(open.message.find("not closed") != std::string::npos);
  CHECK(error_of("POPEN G1 X1\n").message.find("after the statement") != std::string::npos);
}

TEST_CASE(
    "Fanuc/Haas G10 L10/L11 set H's length geometry and wear (G91: by R); L12/L13 D's, read by "
    "G41/G42") {
  MachineConfig machine = at_origin();
  machine.tool_lengths = {{1, 100.0}, {2, 80.0}};
  machine.tool_diameters = {{1, 6.0}};
  // Geometry 102 for a tool 100 long puts the tip 2 above the programmed point; wear −0.5 and then
  // −0.25 more (G91) 1.5 and 1.25 above it; offset 2 untouched.
  const std::string cut = "G43 H1 G0 Z5\nG1 Z-1 F100\n";
  Result set =
      run_program("G21 G90 G17\nT1 M6\nG0 X0 Y0\n" + cut + "G10 L10 P1 R102.\n" + cut +
                      "G10 L11 P1 R-0.5\n" + cut + "G91 G10 L11 P1 R-0.25\nG90\n" + cut +
                      "G91 G10 L10 P1 R-2.\nG90\n" + cut + "G10 L10 P2 R81.\n" + cut + "M30\n",
                  {}, machine);
  auto shifted = [](double dz) {
    return "G43 H1 G0 Z" + std::to_string(5 + dz) + "\nG1 Z" + std::to_string(-1 + dz) + " F100\n";
  };
  Result moved =
      run_program("G21 G90 G17\nT1 M6\nG0 X0 Y0\n" + shifted(0) + shifted(2) + shifted(1.5) +
                      shifted(1.25) + shifted(-0.75) + shifted(-0.75) + "M30\n",
                  {}, machine);
  same_moves(set, moved);
  // Inches: R is in program units.
  Result inches =
      run_program("G20 G90 G17\nT1 M6\nG0 X0 Y0\nG10 L10 P1 R4.\nG43 H1 G0 Z1\nM30\n", {}, machine);
  REQUIRE(!inches.moves.empty());
  CHECK(inches.moves.back().end.z == doctest::Approx(25.4 + (4 * 25.4 - 100)));
  // Cutter radius offsets (a radius on Fanuc): G41 D1 offsets by geometry + wear, a geometry
  // never written being the tool table's radius; the same cut as a tool table saying so.
  const std::string contour =
      "G0 X-5 Y-5 Z5\nG1 Z-1 F100\nG41 D1 G1 X0 Y0\nY10\nX10\nG40 G1 X15 Y15\nM30\n";
  auto with_diameter = [&](double diameter) {
    MachineConfig table = machine;
    table.tool_diameters = {{1, diameter}};
    return run_program("G21 G90 G17\nT1 M6\n" + contour, {}, table);
  };
  same_moves(run_program("G21 G90 G17\nT1 M6\nG10 L12 P1 R3.5\nG10 L13 P1 R-0.01\n" + contour, {},
                         machine),
             with_diameter(6.98));
  same_moves(run_program("G21 G90 G17\nT1 M6\nG10 L13 P1 R-0.1\n" + contour, {}, machine),
             with_diameter(5.8));
  same_moves(run_program("G21 G90 G17\nT1 M6\nG10 L12 P1 R2.\nG91 G10 L12 P1 R0.5\nG90\n" + contour,
                         {}, machine),
             with_diameter(5));
  // A wear with no geometry needs the tool's diameter.
  const Diagnostic no_tool = error_of(
      "G21 G90 G17\nT1 M6\nG10 L13 P2 R-0.1\nG0 X0 Y0 Z5\nG41 D2 G1 X5 F100\n", {}, machine);
  CHECK(no_tool.line == 5);
  CHECK(no_tool.message.find("G10 L13 at line 3") != std::string::npos);
  CHECK(no_tool.message.find("not in the tool table") != std::string::npos);
  // Errors: no P, no R, axis words, an L that is no tool offset.
  CHECK(error_of("G10 L10 R5.\n").message.find("needs P") != std::string::npos);
  CHECK(error_of("G10 L11 P1\n").message.find("needs R") != std::string::npos);
  CHECK(error_of("G10 L10 P1 R5. Z1.\n").message.find("takes R only") != std::string::npos);
  CHECK(error_of("G10 L14 P1 R5.\n").message.find("L10-L13 for tool offsets") != std::string::npos);
}

TEST_CASE("Fanuc/Haas tool offset variables are the registers G10 L10-L13 write, by dialect") {
  MachineConfig fanuc = at_origin();
  fanuc.tool_lengths = {{1, 100.0}, {2, 80.0}};
  fanuc.tool_diameters = {{1, 6.0}};
  MachineConfig haas = fanuc;
  haas.dialect = Dialect::haas;
  const std::string no_tool = "G21 G90 G17\nG0 X0 Y0\n", head = no_tool + "T1 M6\n",
                    cut = "G43 H1 G0 Z5\nG1 Z-1 F100\n";
  auto program = [&](const std::string& setting) { return head + setting + cut + "M30\n"; };
  // Each write against the G10 that sets the same register: geometry 102, then wear −0.5 (the
  // read-modify-write of a tool-wear macro through #4120, the tool's number).
  const std::string g10 =
      program("G10 L10 P1 R102.\nG10 L11 P1 R-0.25\nG91 G10 L11 P1 R-0.25\nG90\n");
  Result by_g10 = run_program(g10, {}, fanuc);
  same_moves(
      run_program(
          program("#11001 = 102.\n#10001 = -0.25\n#[10000 + #4120] = #[10000 + #4120] - 0.25\n"),
          {}, fanuc),
      by_g10);
  same_moves(run_program(program("#2201 = 102.\n#2001 = -0.5\n"), {}, fanuc),
             by_g10);  // memory C, 1-200
  same_moves(run_program(program("#2001 = 102.\n#2201 = -0.5\n"), {}, haas),
             by_g10);  // Haas swaps them
  same_moves(run_program(program("G10 L10 P1 R102.\nG10 L1 P1 R-0.5\n"), {}, haas),
             by_g10);  // Haas's L1: wear
  same_moves(run_program(g10, {}, haas), by_g10);
  // The same text on the other control: #2001 = 102. is a wear there, 102 more than the geometry.
  Result wear = run_program(program("#2001 = 102.\n"), {}, fanuc);
  REQUIRE(!wear.moves.empty());
  CHECK(wear.moves.back().end.z == doctest::Approx(-1 + 102));
  // Reads (no tool in the spindle: the tip is the programmed point): the machine's length until
  // written, then what was written; wear 0; in program units.
  Result read = run_program(
      no_tool +
          "G0 Z[#11001 / 10]\n#11001 = 102.\n#10001 = 0.5\nG0 Z[#11001 + #10001 - 100]\n"
          "G20\nG0 Z#10001\nM30\n",
      {}, fanuc);
  REQUIRE(read.moves.size() >= 3);
  CHECK(read.moves[read.moves.size() - 3].end.z == doctest::Approx(10));
  CHECK(read.moves[read.moves.size() - 2].end.z == doctest::Approx(2.5));
  CHECK(read.moves.back().end.z == doctest::Approx(0.5));
  Result haas_read = run_program(no_tool + "G0 Z[#2001 - #2201 - 90]\nM30\n", {}, haas);
  REQUIRE(!haas_read.moves.empty());
  CHECK(haas_read.moves.back().end.z == doctest::Approx(10));
  // Haas's #10000s are general-purpose variables: they move no tool.
  Result general = run_program(no_tool + "#10001 = 7.\nG0 Z#10001\nM30\n", {}, haas);
  REQUIRE(!general.moves.empty());
  CHECK(general.moves.back().end.z == doctest::Approx(7));
  // D registers: read back as written; Fanuc's unwritten geometry is the tool's radius; a G41/G42
  // using a written one is refused at its D, naming the write; Haas's unwritten one is unknown.
  Result d = run_program(
      no_tool + "G0 Z#13001\n#13001 = 2.5\n#12001 = -0.1\nG0 Z[#13001 + #12001]\nM30\n", {}, fanuc);
  REQUIRE(d.moves.size() >= 2);
  CHECK(d.moves[d.moves.size() - 2].end.z == doctest::Approx(3));
  CHECK(d.moves.back().end.z == doctest::Approx(2.4));
  Result by_g10_d = run_program(
      no_tool + "G10 L12 P2 R1.5\nG10 L13 P2 R-0.05\nG0 Z[#13002 + #12002]\nM30\n", {}, fanuc);
  REQUIRE(!by_g10_d.moves.empty());
  CHECK(by_g10_d.moves.back().end.z == doctest::Approx(1.45));
  // Haas's D registers hold a diameter or a radius after its setting 40: unknown, a G41/G42 using a
  // written one is refused at its D, naming the write; the machine file's "d_offsets" tells.
  const Diagnostic used = error_of(head + "#2401 = 6.\nG41 D1 G1 X5 F100\n", {}, haas);
  CHECK(used.line == 5);
  CHECK(used.message.find("#2401 at line 4") != std::string::npos);
  CHECK(used.message.find("\"d_offsets\"") != std::string::npos);
  const std::string contour =
      "G0 X-5 Y-5 Z5\nG1 Z-1 F100\nG41 D1 G1 X0 Y0\nY10\nX10\nG40 G1 X15 Y15\nM30\n";
  MachineConfig haas_diameter = haas, haas_radius = haas;
  haas_diameter.d_offsets = DOffsets::diameter;
  haas_radius.d_offsets = DOffsets::radius;
  same_moves(run_program(head + "#2401 = 6.\n#2601 = -0.2\n" + contour, {}, haas_diameter),
             run_program(head + "G10 L12 P1 R2.9\n" + contour, {}, fanuc));
  same_moves(run_program(head + "#2401 = 6.\n" + contour, {}, haas_radius),
             run_program(head + "G10 L12 P1 R6.\n" + contour, {}, fanuc));
  // An unwritten D geometry reads as the table's diameter or radius, as the machine's hold.
  Result as_diameter = run_program(no_tool + "G0 Z[#2401 + #13001]\nM30\n", {}, haas_diameter);
  REQUIRE(!as_diameter.moves.empty());
  CHECK(as_diameter.moves.back().end.z == doctest::Approx(6));
  MachineConfig fanuc_diameter = fanuc;
  fanuc_diameter.d_offsets = DOffsets::diameter;
  Result fanuc_read = run_program(no_tool + "G0 Z#13001\nM30\n", {}, fanuc_diameter);
  REQUIRE(!fanuc_read.moves.empty());
  CHECK(fanuc_read.moves.back().end.z == doctest::Approx(6));
  // What the control holds at the start (the machine file's "variables") is its registers.
  MachineConfig preset = haas;
  preset.variables = {{2001, 102.0}, {2201, -0.5}, {2401, 6.0}};
  same_moves(run_program(program(""), {}, preset), by_g10);
  CHECK(error_of(head + "G41 D1 G1 X5 F100\n", {}, preset)
            .message.find("#2401 in the machine file") != std::string::npos);
  const Diagnostic unknown = error_of(head + "G0 Z#2401\n", {}, haas);
  CHECK(unknown.line == 4);
  CHECK(unknown.message.find("setting 40") != std::string::npos);
  // G54.1 P1's Z: #7003 (P1-P48) and #14003 (P1-P300); #11001 is no work offset.
  Result extended = run_program(
      no_tool + "#14003 = -5.\n#11003 = 9.\nG54.1 P1\nG0 Z0\nG0 Z#7003\nM30\n", {}, fanuc);
  REQUIRE(extended.moves.size() >= 2);
  CHECK(extended.moves[extended.moves.size() - 2].end.z == doctest::Approx(-5));
  CHECK(extended.moves.back().end.z == doctest::Approx(-10));
  // Offsets are held to a word's range, as G10 R is.
  const Diagnostic huge = error_of(no_tool + "#11001 = [100000 * 100000]\n", {}, fanuc);
  CHECK(huge.line == 3);
  CHECK(huge.message.find("#11001 = 1e+10: out of range") != std::string::npos);
  CHECK(error_of(no_tool + "#5223 = [100000 * 100000]\n", {}, fanuc).message.find("out of range") !=
        std::string::npos);
  // LinuxCNC's #2001 is a plain parameter.
  MachineConfig linuxcnc = linuxcnc_at_origin();
  linuxcnc.tool_lengths = fanuc.tool_lengths;
  Result plain = run_program(head + "#2001 = 102.\nG43 H1 G0 Z5\nG0 Z#2001\nM30\n", {}, linuxcnc);
  REQUIRE(plain.moves.size() >= 2);
  CHECK(plain.moves.back().end.z == doctest::Approx(102));
}
