// Rotary-indexed 3+2 with a machine model: the same toolpath written four ways (G68.2 + G53.1,
// rotary words with Haas DWO, rotary words under Fanuc TCP, raw rotary words with machine
// coordinates from the kinematics) gives the same moves in the work frame on every bundled
// profile; bad input (an axis the machine lacks, a position outside the limits, an unreachable
// plane, rotary motion during a cut, rotary words without kinematics) is an error at its column.
#include <cmath>
#include <cstdio>

#include "helpers.hpp"
#include "tridex/gcode/kinematics.hpp"
#include "tridex/gcode/machine.hpp"
#include "tridex/gcode/tilted_plane.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace {

std::string num(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%.12f", v);
  return text;
}

std::string xyz(const Vec3& p) { return cat("X", num(p.x), " Y", num(p.y), " Z", num(p.z)); }

std::string rotary_words(const Kinematics& kin, const RotaryPositions& r) {
  std::string words;
  for (const RotaryAxis& a : kin.axes)
    words += cat(" ", a.letter, num(r[static_cast<std::size_t>(rotary_index(a.letter))]));
  return words;
}

MachineConfig with_kinematics(const char* name, const Vec3& g54 = Vec3(0.0)) {
  MachineConfig m;
  m.kinematics = kinematics_profile(name);
  m.work_offsets[MachineConfig::g54_key(1)] = g54;
  return m;
}

void check_same(const std::vector<Move>& a, const std::vector<Move>& b, const char* form) {
  INFO(form);
  REQUIRE(a.size() == b.size());
  for (std::size_t i = 0; i < a.size(); ++i) {
    CHECK(a[i].kind == b[i].kind);
    CHECK(a[i].from_far == b[i].from_far);
    CHECK(near(a[i].start, b[i].start, 1e-6));
    CHECK(near(a[i].end, b[i].end, 1e-6));
    CHECK(near(a[i].axis, b[i].axis, 1e-9));
    CHECK(near(a[i].machine, b[i].machine, 1e-6));
    for (std::size_t k = 0; k < 3; ++k)
      CHECK(a[i].rotary[k] == doctest::Approx(b[i].rotary[k]).epsilon(1e-9));
  }
}

}  // namespace

TEST_CASE("rotary 3+2: G68.2 + G53.1, DWO, TCP and raw rotary words give the same moves") {
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> angle(-180, 180), tilt(5, 30), coord(-40, 40);
  const Vec3 g54(-120, 35, -210);
  for (const std::string& name : kinematics_profile_names()) {
    MachineConfig machine = with_kinematics(name.c_str(), g54);
    const Kinematics& kin = *machine.kinematics;
    for (int n = 0; n < 6; ++n) {
      INFO(name << " case " << n);
      double i = angle(rng), j = tilt(rng), k = angle(rng);
      if (kin.axes.size() == 1) i = 90;  // one B axis reaches the planes tilted about Y
      Vec3 o(coord(rng), coord(rng), coord(rng) / 4);
      Frame feature = fanuc_euler(o, i, j, k);
      RotaryPositions r = orient_tool(kin, feature.rotation[2], {0, 0, 0});
      std::vector<Vec3> path = {Vec3(coord(rng), coord(rng), 5), Vec3(coord(rng), coord(rng), -2),
                                Vec3(coord(rng), coord(rng), -2), Vec3(coord(rng), coord(rng), 5)};
      auto program = [&](const std::string& head, auto point, const std::string& tail) {
        std::string text = cat("G21 G90 G54\n", head);
        for (std::size_t p = 0; p < path.size(); ++p)
          text += cat(p == 0 ? "G0 " : "G1 ", xyz(point(path[p])), p == 1 ? " F300\n" : "\n");
        return cat(text, tail, "M30\n");
      };
      auto in_feature = [](const Vec3& p) { return p; };
      auto in_work = [&](const Vec3& p) { return feature.to_world(p); };
      auto in_machine = [&](const Vec3& p) {
        return machine_from_part(kin, feature.to_world(p) + g54, r) - g54;
      };
      std::string rotary = cat("G0", rotary_words(kin, r), "\n");
      Result tilted = run_program(
          program(cat("G68.2 ", xyz(o), " I", num(i), " J", num(j), " K", num(k), "\nG53.1\n"),
                  in_feature, "G69\n"),
          {}, machine);
      Result dwo = run_program(program(cat(rotary, "G254\n"), in_work, "G255\n"), {}, machine);
      Result tcp = run_program(program(cat("G43.4 H1\n", rotary), in_work, "G49\n"), {}, machine);
      Result raw = run_program(program(rotary, in_machine, ""), {}, machine);
      REQUIRE(tilted.moves.size() == 4);
      CHECK(tilted.moves[0].from_far);
      CHECK(near(tilted.moves[1].end, feature.to_world(path[1]), 1e-9));
      CHECK(near(tilted.moves[1].axis, tool_direction(kin, r), 1e-9));
      check_same(tilted.moves, dwo.moves, "DWO");
      check_same(tilted.moves, tcp.moves, "TCP");
      check_same(tilted.moves, raw.moves, "raw");
      // The machine coordinates reported are where the linear axes stand.
      CHECK(near(raw.moves[2].machine, in_machine(path[2]) + g54, 1e-6));
    }
  }
}

TEST_CASE("rotary 3+2: G43.5 I J K and the remembered G53.1 positions") {
  MachineConfig machine = with_kinematics("ac-trunnion");
  Vec3 d = glm::normalize(Vec3(0, -1, 1));
  Result r = run_program("G43.5 I0 J-1 K1 H1\nG0 X1 Y2 Z3\nG1 Z0 F100\nM30\n", {}, machine);
  REQUIRE(r.moves.size() == 2);
  CHECK(near(r.moves[1].axis, d, 1e-12));
  CHECK(near(tool_direction(*machine.kinematics, r.moves[1].rotary), d, 1e-9));
  CHECK(near(r.moves[1].end, Vec3(1, 2, 0), 1e-12));
  // G53.1 picks A±45 C0 for this plane; after G69 the raw frame keeps those positions.
  r = run_program("G68.2 X0 Y0 Z0 I0 J45 K0\nG53.1\nG69\nG0 X0 Y0 Z10\nM30\n", {}, machine);
  REQUIRE(r.moves.size() == 1);
  RotaryPositions picked{r.moves[0].rotary[0], r.moves[0].rotary[1], r.moves[0].rotary[2]};
  CHECK(std::abs(picked[0]) == doctest::Approx(45));
  CHECK(picked[2] == doctest::Approx(0));
  CHECK(near(tool_direction(*machine.kinematics, picked),
             fanuc_euler(Vec3(0), 0, 45, 0).rotation[2], 1e-9));
  CHECK(near(r.moves[0].end, tip_in_part(*machine.kinematics, Vec3(0, 0, 10), picked), 1e-9));
}

TEST_CASE("rotary 3+2: raw rotary words keep the tip known; TCP indexing leaves it far") {
  MachineConfig machine = with_kinematics("bc-trunnion");
  const Kinematics& kin = *machine.kinematics;
  Result r = run_program("G0 X10 Y0 Z20\nG0 B30\nG1 X12 F100\nM30\n", {}, machine);
  REQUIRE(r.moves.size() == 2);
  CHECK(near(r.moves[1].start, tip_in_part(kin, Vec3(10, 0, 20), {0, 30, 0}), 1e-9));
  CHECK(near(r.moves[1].end, tip_in_part(kin, Vec3(12, 0, 20), {0, 30, 0}), 1e-9));
  CHECK(near(r.moves[1].machine, Vec3(12, 0, 20), 1e-9));
  // Under TCP the indexing leaves the tool far: the next move comes back along the tool.
  r = run_program("G43.4 H1\nG0 X10 Y0 Z20\nG0 B30\nG1 X12 Y0 Z20 F100\nM30\n", {}, machine);
  REQUIRE(r.moves.size() == 2);
  CHECK(r.moves[1].from_far);
  CHECK(near(r.moves[1].end, Vec3(12, 0, 20), 1e-12));
  // Incremental rotary words add to the position.
  r = run_program("G0 B10\nG91 G0 B20\nG90 G0 X0 Y0 Z5\nM30\n", {}, machine);
  CHECK(r.moves[0].rotary[1] == doctest::Approx(30));
}

TEST_CASE("rotary 3+2: G92 and G52 in raw form shift machine coordinates, rotaries turned or not") {
  // Raw X Y Z are the machine's linear axes: G92 makes the linear axes' position (not the tip's
  // place on the turned part) read as its words, and G52 shifts them. The reference is the same
  // program with the offsets worked out by hand.
  for (const char* name : {"ac-trunnion", "bc-trunnion", "b-head-c-table", "head-head"}) {
    INFO(name);
    MachineConfig machine = with_kinematics(name, Vec3(3, -4, 5));
    const Kinematics& kin = *machine.kinematics;
    RotaryPositions turned{};
    for (const RotaryAxis& a : kin.axes)
      turned[static_cast<std::size_t>(rotary_index(a.letter))] = 25;
    std::string index = cat("G0", rotary_words(kin, turned), "\n");
    Result by_hand =
        run_program(cat("G0 X10 Y2 Z20\n", index, "G1 X15 Y1 Z18 F100\nM30\n"), {}, machine);
    Result g92 = run_program(
        cat("G0 X10 Y2 Z20\n", index, "G92 X0 Y0 Z0\nG1 X5 Y-1 Z-2 F100\nM30\n"), {}, machine);
    Result g52 = run_program(
        cat("G52 X7 Y-3 Z1\nG0 X3 Y5 Z19\n", index, "G1 X8 Y4 Z17 F100\nM30\n"), {}, machine);
    REQUIRE(by_hand.moves.size() == 2);
    REQUIRE(g92.moves.size() == 2);
    REQUIRE(g52.moves.size() == 2);
    CHECK(near(g92.moves[1].end, by_hand.moves[1].end, 1e-9));
    CHECK(near(g92.moves[1].machine, by_hand.moves[1].machine, 1e-9));
    CHECK(near(g52.moves[1].end, by_hand.moves[1].end, 1e-9));
    const Vec3 g54(3, -4, 5);  // moves are reported from the G54 zero
    CHECK(near(by_hand.moves[1].end, tip_in_part(kin, Vec3(15, 1, 18) + g54, turned) - g54, 1e-9));
  }
}

TEST_CASE("rotary 3+2: bad input is an error at its line and column") {
  MachineConfig ac = with_kinematics("ac-trunnion");
  Diagnostic d = error_of("G0 X0\nG0 X1 B10\n", {}, ac);
  CHECK(d.line == 2);
  CHECK(d.column == 7);
  CHECK(d.message.find("no B axis") != std::string::npos);
  d = error_of("G0 A-130 C0\n", {}, ac);
  CHECK(d.column == 4);
  CHECK(d.message.find("limits") != std::string::npos);
  d = error_of("G68.2 X0 Y0 Z0 I0 J150 K0\n G53.1\n", {}, ac);
  CHECK(d.line == 2);
  CHECK(d.column == 2);
  CHECK(d.message.find("G53.1") != std::string::npos);
  d = error_of("G2 X1 Y0 I0.5 A10 F100\n", {}, ac);
  CHECK(d.column == 15);
  CHECK(d.message.find("need G0 or G1") != std::string::npos);
  // A turn under DWO or from far along the axis has no simultaneous reading: refused, even
  // lenient.
  d = error_of("G0 X0 Y0 Z0\nG254\nG1 X1 A10 F100\n", {}, ac);
  CHECK(d.line == 3);
  CHECK(d.message.find("DWO") != std::string::npos);
  // Without kinematics a rotary word is an error naming the machine file, even lenient.
  for (bool is_lenient : {false, true}) {
    InterpreterOptions options;
    options.lenient = is_lenient;
    d = error_of("G0 X0 Y0 Z0\nG0 C90\n", options);
    CHECK(d.line == 2);
    CHECK(d.column == 4);
    CHECK(d.message.find("kinematics") != std::string::npos);
  }
}

TEST_CASE("rotary 3+2, lenient: every line read otherwise is counted, past the 1000-warning cap") {
  // 1500 cuts that turn A (simultaneous moves: read as such, no warning), then 1200 moves under a
  // plane not normal to the tool: the warnings stop at 1000, the summary counts every line and
  // says along which direction they were read.
  MachineConfig ac = with_kinematics("ac-trunnion");
  std::string text = "G0 X0 Y0 Z0\n";
  for (int k = 1; k <= 1500; ++k) text += cat("G1 X", k % 7, " A", k % 2 == 0 ? 10 : 20, " F100\n");
  text += "G0 A0\nG68.2 X0 Y0 Z0 I0 J30 K0\n";
  for (int k = 0; k < 1200; ++k) text += cat("G1 X", k % 5, " Y1 Z-1\n");
  text += "M30\n";
  InterpreterOptions lenient;
  lenient.lenient = true;
  Result r = run_program(text, lenient, ac);
  REQUIRE(r.moves.size() == 1 + 1500 + 1200);
  CHECK(near(r.moves[1500].axis, tool_direction(*ac.kinematics, {10, 0, 0}), 1e-12));  // A10
  CHECK(r.moves[1500].pose == PoseLaw::joints);
  CHECK(r.moves[1500].rotary_start[0] == 20);
  auto summary = [&](const std::string& start) {
    for (const Diagnostic& d : r.warnings)
      if (d.message.rfind(start, 0) == 0) return d.message;
    return std::string();
  };
  CHECK(summary("lenient mode read 1200 × move under an ambiguous tilted plane along the current "
                "direction (0, 0, 1) "
                "(lines 1504, 1505, 1506, 1507, 1508, …)") != "");
  CHECK(r.warnings.size() == 1000 + 1);  // capped per line; one summary (the plane)
}

// G1 turning A/B/C: a simultaneous move carrying its start's rotary positions and its pose law
// (docs/gcode.md, "Simultaneous 5-axis"): raw rotary words keep the machine coordinates and curve
// the tip on the part; under TCP the tip runs straight; a G1 with rotary words alone is a move.
TEST_CASE("rotary: simultaneous moves carry their start and their pose law") {
  MachineConfig ac = with_kinematics("ac-trunnion");
  Result r = run_program("G0 X20 Y0 Z-2 A0 C0\nG1 C90 F500\nG1 X10 A10 C100\nM30\n", {}, ac);
  REQUIRE(r.moves.size() == 3);
  const Move& turn = r.moves[1];
  CHECK(turn.pose == PoseLaw::joints);
  CHECK(near(turn.start, Vec3(20, 0, -2), 1e-9));
  CHECK(near(turn.end, tip_in_part(*ac.kinematics, Vec3(20, 0, -2), {0, 0, 90}), 1e-9));
  CHECK(turn.rotary_start[2] == 0);
  CHECK(turn.rotary[2] == 90);
  CHECK(near(turn.machine, Vec3(20, 0, -2), 1e-9));
  CHECK(r.moves[2].rotary_start[2] == 90);
  CHECK(r.moves[2].rotary[0] == 10);
  CHECK(r.moves[0].pose == PoseLaw::fixed);
  // Under TCP (G43.4) the tip's part coordinates are programmed: the law is tcp.
  r = run_program("G43.4\nG0 X0 Y0 Z5 A0 C0\nG1 Z-1 F300\nG1 X10 A10 C45\nM30\n", {}, ac);
  REQUIRE(r.moves.size() >= 2);
  CHECK(r.moves.back().pose == PoseLaw::tcp);
  CHECK(near(r.moves.back().start, Vec3(0, 0, -1), 1e-9));
  CHECK(near(r.moves.back().end, Vec3(10, 0, -1), 1e-9));
}

TEST_CASE("rotary: Haas's G234 (TCPC) is read as G43.4 on the Haas dialect, cancelled by G49") {
  MachineConfig haas = with_kinematics("ac-trunnion");
  haas.dialect = Dialect::haas;
  const std::string body = " H1\nG0 X0 Y0 Z5 A0 C0\nG1 Z-1 F300\nG1 X10 A10 C45\n";
  Result tcpc = run_program(cat("G234", body, "G49\nG1 C60\nM30\n"), {}, haas);
  Result fanuc = run_program(cat("G43.4", body, "G49\nG1 C60\nM30\n"), {}, haas);
  REQUIRE(tcpc.moves.size() == 4);
  check_same(tcpc.moves, fanuc.moves, "G234 against G43.4");
  CHECK(tcpc.moves[2].pose == PoseLaw::tcp);
  CHECK(near(tcpc.moves[2].end, Vec3(10, 0, -1), 1e-9));
  // G49 ends TCPC: the next turn is in raw joints.
  CHECK(tcpc.moves[3].pose == PoseLaw::joints);
  // Without TCPC the same words are raw: the tip curves on the part.
  Result raw = run_program(cat("G43", body, "M30\n"), {}, haas);
  REQUIRE(raw.moves.size() == 3);
  CHECK(raw.moves[2].pose == PoseLaw::joints);
  // Another control has no G234: an unknown code, refused where it would change the path.
  MachineConfig fanuc_machine = with_kinematics("ac-trunnion");
  Diagnostic d = error_of(cat("G234", body, "M30\n"), {}, fanuc_machine);
  CHECK(d.line == 1);
  CHECK(d.message.find("G234") != std::string::npos);
}

TEST_CASE(
    "A/B/C on a LinuxCNC machine without kinematics are plain axes, as in rs274; elsewhere "
    "errors") {
  MachineConfig linuxcnc = *MachineConfig::bundled("rs274");
  Result r = run_program(
      "G21 G90 F100\nG0 X1 Y2 Z3 A90\nG1 X4 B45 C10\nG0 A0\nG2 X6 Y2 I1 J0 C5\nM2\n", {}, linuxcnc);
  REQUIRE(r.moves.size() >= 3);
  CHECK(near(r.moves[0].end, Vec3(1, 2, 3)));
  CHECK(near(r.moves[1].end, Vec3(4, 2, 3)));
  CHECK(near(r.moves.back().end, Vec3(6, 2, 3)));
  for (const Move& m : r.moves) CHECK(near(m.axis, Vec3(0, 0, 1)));  // the tool never tilts
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].line == 2);
  CHECK(r.warnings[0].column == 13);
  CHECK(r.warnings[0].message.find("does not tilt") != std::string::npos);
  // Without --machine (and on a machine file without kinematics) they stay an error at the word.
  Diagnostic d = error_of("G21 G90 F100\nG0 X1 Y2 Z3 A90\n", {}, at_origin());
  CHECK(d.column == 13);
  CHECK(d.message.find("kinematics") != std::string::npos);
}

TEST_CASE(
    "G28/G30 with X Y and a rotary word at zero return X and Y too (a 4-axis post's G28 X0. Y0. "
    "A0.)") {
  // LinuxCNC without kinematics (as rs274: STRAIGHT_TRAVERSE to the origin), in G90 and G91.
  MachineConfig linuxcnc = *MachineConfig::bundled("rs274");
  Result r =
      run_program("G20 G90 G17\nG0 X1 Y1 Z.5 A0\nG91 G28 Z0\nG28 X0 Y0 A0\nM2\n", {}, linuxcnc);
  REQUIRE(!r.moves.empty());
  CHECK(near(r.moves.back().end, Vec3(0, 0, 0), 1e-9));
  r = run_program("G21 G90\nG0 X10 Y10 Z5 A30\nG28 X4 Y4 A0\nG0 Z7\nM2\n", {}, linuxcnc);
  REQUIRE(r.moves.size() >= 3);
  CHECK(near(r.moves[1].end, Vec3(4, 4, 5), 1e-9));  // the intermediate point
  CHECK(near(r.moves[2].end, Vec3(0, 0, 5), 1e-9));  // the named axes go home
  // With a kinematic model and the axis already at zero, X and Y go to the machine file's home
  // as without the word; turned away from zero, the tool turns back and the tip goes far.
  MachineConfig ac = with_kinematics("ac-trunnion");
  ac.home = Vec3(0, 0, 0);
  ac.home_is_default = false;
  r = run_program("G21 G90\nG0 X10 Y10 Z5 A0\nG91 G28 X0 Y0 A0\nG90\nM2\n", {}, ac);
  REQUIRE(!r.moves.empty());
  CHECK(near(r.moves.back().end, Vec3(0, 0, 5), 1e-9));
  r = run_program("G21 G90\nG0 X10 Y10 Z5 A20\nG91 G28 X0 Y0 A0\nG90 G0 X1 Y1 Z1\nM2\n", {}, ac);
  REQUIRE(!r.moves.empty());
  CHECK(near(r.moves.back().axis, Vec3(0, 0, 1), 1e-9));
  CHECK(r.moves.back().start.z > 1 + 100);  // from far above
}
