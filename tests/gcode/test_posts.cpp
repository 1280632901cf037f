// Programs as the posts and shops of issue 30 write them (Fusion 360's Fanuc and Haas posts, a
// Fanuc horizontal machining centre's macro programs): what Fanuc and Haas read and LinuxCNC
// refuses, each compared with rs274 where LinuxCNC reads the program (rs274 from the Debian
// package linuxcnc-uspace; skipped, with a message, where it is absent).
#include <doctest/doctest.h>

#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <unistd.h>

#include "helpers.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;
namespace fs = std::filesystem;

namespace test_posts {

bool contains(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

// What rs274 prints for `program` (its canonical calls and its error), or nullopt without rs274.
std::optional<std::string> rs274_output(const std::string& program) {
  if (std::system("command -v rs274 > /dev/null 2>&1") != 0) {
    MESSAGE("SKIPPED: rs274 not found (install linuxcnc-uspace): no comparison with LinuxCNC");
    return std::nullopt;
  }
  const fs::path dir = fs::temp_directory_path() / ("tridex-posts-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  std::ofstream(dir / "p.ngc") << program;
  // rs274 keeps its tool table in $HOME/.tool.mmap: runs of other test processes at the same time
  // under one HOME would share it (test_linuxcnc_diff.cpp's run_rs274), so this one gets its own.
  const std::string command =
      "cd '" + dir.string() + "' && HOME='" + dir.string() + "' rs274 -g p.ngc > out.txt 2>&1";
  [[maybe_unused]] int status = std::system(command.c_str());
  std::ifstream in(dir / "out.txt");
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  fs::remove_all(dir);
  return text;
}

MachineConfig haas_at_origin() {
  MachineConfig m = at_origin();
  m.dialect = Dialect::haas;
  return m;
}

// Fanuc (0i-MF operator's manual B-64604EN, "G code list") puts G80-G89 in group 09 and G00-G03
// in group 01; Haas's manual lists "G80 Canned Cycle Cancel (Group 09)". So G80 leaves the
// group-01 mode that was in force, and Fusion's Fanuc and Haas posts write a bare Z after it.
TEST_CASE("G80 on Fanuc and Haas returns to the group-01 mode; LinuxCNC refuses, as rs274") {
  const std::string program =
      "G20 G90 G17\nG00 X0 Y0 Z0.1969\nG98 G81 X1 Y1 Z-0.2072 R0.1575 F53.2\nG80\nZ0.5906\nM30\n";
  for (const MachineConfig& machine : {at_origin(), haas_at_origin()}) {
    Result r = run_program(program, {}, machine);
    REQUIRE(!r.moves.empty());
    CHECK(r.moves.back().kind == MoveKind::rapid);  // G00 was in force before the cycle
    CHECK(near(r.moves.back().end, Vec3(1, 1, 0.5906) * 25.4, 1e-9));
  }
  // G01 in force before the cycle: the bare Z after G80 is a feed.
  Result feed = run_program("G21 G90\nG0 Z5\nG1 X0 Y0 F100\nG81 X1 Y1 Z-2 R1\nG80\nZ8\nM30\n", {},
                            at_origin());
  CHECK(feed.moves.back().kind == MoveKind::feed);
  CHECK(feed.moves.back().end.z == doctest::Approx(8));
  // A cycle with no group-01 code before it leaves none: still refused.
  CHECK(contains(error_of("G21 G90\nG81 X1 Y1 Z-2 R1 F100\nG80\nZ8\n", {}, at_origin()).message,
                 "without an active motion mode"));
  // LinuxCNC's cycles are motion modes: G80 leaves none (rs274: "Cannot use axis values without
  // a g code that uses them"), lenient or not.
  InterpreterOptions lenient;
  lenient.lenient = true;
  CHECK(contains(error_of(program, {}, linuxcnc_at_origin()).message,
                 "without an active motion mode"));
  CHECK(contains(error_of(program, lenient, linuxcnc_at_origin()).message,
                 "without an active motion mode"));
  if (auto out = rs274_output(program)) CHECK(contains(*out, "Cannot use axis values"));
  // Fanuc's #4001 (group 01) reads the G00 under the cycle.
  Result modal = run_program(
      "G21 G90\nG0 Z5\nG81 X1 Y1 Z-2 R1 F100\n#100 = #4001\nG80\nG0 X#100\nM30\n", {}, at_origin());
  CHECK(modal.moves.back().end.x == doctest::Approx(0));
}

// Fanuc's G53 is one-shot positioning at rapid traverse whatever the group-01 mode (0i-MF
// operator's manual, "Machine coordinate system selection (G53)"); Haas's "G53 Non-Modal Machine
// Coordinate Selection" likewise. LinuxCNC wants G0 or G1 in force (rs274: "Must use g0 or g1
// with g53").
TEST_CASE("G53 on Fanuc and Haas is a rapid in any mode; LinuxCNC wants G0 or G1, as rs274") {
  MachineConfig fanuc = at_origin();
  fanuc.g53_literal = true;
  const std::string after_cycle = "G21 G90\nG0 Z5\nG81 X1 Y1 Z-2 R1 F100\nG80\nG90 G53 X12\nM30\n";
  Result r = run_program(after_cycle, {}, fanuc);
  CHECK(r.moves.back().kind == MoveKind::rapid);
  CHECK(r.moves.back().end.x == doctest::Approx(12));
  const std::string under_arc = "G21 G90\nG0 X0 Y0 Z1\nG2 X1 Y1 I0.5 J0.5 F10\nG53 Z0\nM2\n";
  Result arc = run_program(under_arc, {}, fanuc);
  CHECK(arc.moves.back().kind == MoveKind::rapid);
  Result feed = run_program("G21 G90\nG1 X0 Y0 Z1 F10\nG53 Z0\nM2\n", {}, fanuc);
  CHECK(feed.moves.back().kind == MoveKind::rapid);  // LinuxCNC would feed here
  CHECK(contains(error_of(under_arc, {}, linuxcnc_at_origin()).message, "G53 needs G0 or G1"));
  if (auto out = rs274_output(under_arc)) CHECK(contains(*out, "Must use g0 or g1 with g53"));
}

// LinuxCNC's rule for an I/J/K arc's radii is its interpreter's (interp_arc.cc, interp_internal.hh:
// CENTER_ARC_RADIUS_TOLERANCE 2·0.01·√2 mm / 2·0.001·√2 in, 100 times that, 0.1 % of the radius),
// which rs274 runs; Fanuc's is parameter 3410 (tridex: 20 increments of IS-B in the input unit).
TEST_CASE("arc end radius tolerance: each dialect's default, the machine file's value over it") {
  // A 35 in arc whose radii differ by 0.001 in (an inch Fusion post's rounding): within Fanuc's
  // 0.0020 in under G20, and within LinuxCNC's rule.
  const std::string inch = "G20 G17 G90 F10\nG0 X35 Y0 Z0\nG3 X0 Y35.001 I-35 J0\nM2\n";
  CHECK(run_program(inch, {}, at_origin()).moves.back().end.y == doctest::Approx(35.001 * 25.4));
  CHECK(!run_program(inch, {}, haas_at_origin()).moves.empty());
  CHECK(!run_program(inch, {}, linuxcnc_at_origin()).moves.empty());
  if (auto out = rs274_output(inch)) CHECK(contains(*out, "ARC_FEED"));
  // 0.003 in is beyond Fanuc's 0.0020 in; under G21 the bound is 0.020 mm.
  Diagnostic d = error_of("G20 G17 G90 F10\nG0 X35 Y0 Z0\nG3 X0 Y35.003 I-35 J0\nM2\n");
  CHECK(contains(d.message, "parameter 3410"));
  CHECK(contains(error_of("G21 G17 G90 F100\nG0 X10 Y0 Z0\nG3 X0 Y10.03 I-10 J0\n").message,
                 "by more than 0.02 mm"));
  // The machine's own tolerance wins in every dialect, LinuxCNC's too.
  MachineConfig tight = linuxcnc_at_origin();
  tight.arc_radius_tolerance = 0.01;
  Diagnostic t = error_of(inch, {}, tight);
  CHECK(contains(t.message, "by more than 0.01 mm (the machine file's arc_radius_tolerance_mm)"));
}

// Newer Fanuc controls (Series 30i/0i-F) name programs beside O numbers, and a program's first
// line may be its name; a Macro B shop writes `O7997A(NestedShtCutoff)` and `OCIRCLE(Circle)`.
// LinuxCNC has no program names (rs274: "Unknown word starting with c").
TEST_CASE("program names that are not numbers open a Fanuc or Haas program; LinuxCNC refuses") {
  for (const char* name :
       {"O7997A(NestedShtCutoff)", "OCIRCLE(Circle)", "<CIRCLE>", "o12ab ; lower case"}) {
    CAPTURE(name);
    const std::string program = std::string("%\n") + name + "\nG21 G90 G0 X1 Y2 Z3\nM30\n%\n";
    Result r = run_program(program, {}, at_origin());
    REQUIRE(r.moves.size() == 1);
    CHECK(near(r.moves[0].end, Vec3(1, 2, 3)));
    CHECK(!run_program(program, {}, haas_at_origin()).moves.empty());
    CHECK(contains(error_of(program, {}, linuxcnc_at_origin()).message, "no program names"));
  }
  // Met later, the main program ran into another program, as with an O number.
  CHECK(contains(error_of("G0 X1\nOCIRCLE\nG0 X2\nM30\n", {}, at_origin()).message,
                 "runs into OCIRCLE without M2/M30"));
  // LinuxCNC's o-word written without its space stays an o-word, as rs274 reads it.
  const std::string osub = "o100sub\nG0 X1\no100endsub\no100call\nM2\n";
  CHECK(run_program(osub, {}, linuxcnc_at_origin()).moves.back().end.x == doctest::Approx(1));
  if (auto out = rs274_output(osub)) CHECK(contains(*out, "STRAIGHT_TRAVERSE(1.0000"));
  // Words after a name are no program name: refused as before.
  CHECK(contains(error_of("OCIRCLE G0 X1\nM30\n", {}, at_origin()).message, "unexpected"));
  if (auto out = rs274_output("OCIRCLE (Circle)\nG0 X1\nM2\n"))
    CHECK(contains(*out, "Unknown word starting with c"));
}

// Fanuc: "G65 must be specified before any argument" (0i-MF operator's manual, "Custom macro",
// "Argument specification"); a code written before G65 is a code of the block. An HMC's programs
// call `G54 G65 P140001 X… I… Z… W… T… C… R… M…`: G54 is set, then the macro runs.
TEST_CASE("G65 with mode codes before it: the modes are set, then the macro called") {
  const std::string macro = "O140001\nG0 X#24 Y#4 Z#26\n#500 = #23 + #20 + #3 + #18 + #13\nM99\n";
  const std::string program =
      "G21 G90\nG10 L2 P1 X100 Y0 Z0\nG55\nG0 X0 Y0 Z10\n"
      "G54 G65 P140001 X180.95 I155 Z499.984 W600 T13.16 C10 R8922.7 M0.07\n"
      "G0 X#500\nM30\n" +
      macro;
  Result r = run_program(program, {}, at_origin());
  REQUIRE(r.moves.size() >= 3);
  // The macro's move, in G54 (X offset 100): X180.95 Y155 Z499.984.
  CHECK(near(r.moves[r.moves.size() - 2].end, Vec3(280.95, 155, 499.984), 1e-9));
  CHECK(r.moves.back().end.x == doctest::Approx(100 + 600 + 13.16 + 10 + 8922.7 + 0.07));
  // A code after G65 would be an argument, and G is none; a motion code beside G65 is refused.
  CHECK(contains(error_of("G65 P140001 G54 X1\nM30\n" + macro, {}, at_origin()).message,
                 "G54 beside G65"));
  CHECK(contains(error_of("G1 G65 P140001 X1\nM30\n" + macro, {}, at_origin()).message,
                 "G1 beside G65"));
}

// A horizontal machining centre: a B table about Y, pallets and a B clamp, work offsets set from
// the fixture's persistent variables with a B word.
TEST_CASE("hmc-b-table: G10 L2 P1 with B shifts B's zero; M60/M71/M10/M11 pass quietly") {
  MachineConfig hmc = *MachineConfig::bundled("hmc-b-table");
  hmc.start_position = Vec3(0, 0, 500);
  hmc.variables[901004] = 0.25;
  const std::string program =
      "O1000 (HMC)\nG21 G90 G17\nM60\nM71\nT1 M6\n"
      "G10 L2 P1 X10 Y20 Z30 B#901004\nG54\nM11\nG0 B90\nM10\n"
      "G0 X0 Y0 Z100\nM11\nG0 B0\nM10\nG0 X5\nM30\n";
  Result r = run_program(program, {}, hmc);
  CHECK(r.warnings.empty());
  // The fixture sits 0.25° turned on the table: at B0 the part is square to the spindle (the
  // tool along the part's +Z) and the machine coordinates are the work offset's.
  CHECK(r.moves.back().rotary[1] == doctest::Approx(0));
  CHECK(near(r.moves.back().axis, Vec3(0, 0, 1), 1e-12));
  CHECK(near(r.moves.back().machine, Vec3(15, 20, 130), 1e-9));
  // G28 B0 returns the machine's B to its zero: the fixture then stands turned back by 0.25°.
  Result home = run_program(
      "G21 G90\nT1 M6\nG10 L2 P1 X10 Y20 Z30 B0.25\nG54\nG0 B90\n"
      "G91 G28 B0\nG90 G0 X5 Y0 Z100\nM30\n",
      {}, hmc);
  CHECK(home.moves.back().rotary[1] == doctest::Approx(-0.25));
  // The machine's angle, offset added, meets the axis's limits.
  MachineConfig limited = hmc;
  limited.kinematics->axes[0].limits = std::array<double, 2>{-90, 90};
  CHECK(contains(error_of(program, {}, limited).message, "rotary position B90.25 is outside"));
  // Without the axis a rotary offset would turn the part unseen: refused as before.
  CHECK(
      contains(error_of("G10 L2 P1 B0.25\nM30\n", {}, at_origin()).message, "rotary work offset"));
}

}  // namespace test_posts
