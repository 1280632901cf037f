// LinuxCNC's switchable kinematics (docs/src/motion/switchkins.adoc in LinuxCNC): the machine
// file's "kinematics_switches" M-codes. Under the TCP switch X Y Z are the tip on the part, as
// G43.4 reads them (and G43/G49 do not cancel it); under identity they are the joints (raw rotary
// words); a "refuse" switch (LinuxCNC's user kinematics) is an error; the bundled trunnions and
// LinuxCNC's sample machines carry M428/M429(/M430). Also the sample machines' HAL pins.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "helpers.hpp"
#include "tridex/gcode/machine.hpp"

using namespace tridex;
using namespace tridex::gcode;
using namespace tridex::gcode::test;

namespace test_switchkins {

MachineConfig trunnion(const char* name) {
  MachineConfig machine = at_origin(*MachineConfig::bundled(name));
  machine.dialect = Dialect::linuxcnc;
  return machine;
}

// The moves' ends (the tip on the part) of a program on the machine.
std::vector<Vec3> ends(const std::string& text, const MachineConfig& machine) {
  std::vector<Vec3> out;
  for (const Move& m : run_program(text, {}, machine).moves) out.push_back(m.end);
  return out;
}

TEST_CASE("M428 reads X Y Z as the tip on the part (as G43.4), M429 as the joints") {
  const MachineConfig machine = trunnion("ac-trunnion");
  const std::string moves = "G0 X10 Y5 Z20\nG0 A-30 C45\nG1 X12 Y4 Z2 F100\n";
  const std::vector<Vec3> tcp = ends("G21 G90 M428\n" + moves + "M30\n", machine);
  const std::vector<Vec3> g43_4 = ends("G21 G90 G43.4\n" + moves + "M30\n", machine);
  const std::vector<Vec3> raw = ends("G21 G90 M429\n" + moves + "M30\n", machine);
  REQUIRE(!tcp.empty());
  // The cut ends where it is written on the part under TCP, as under G43.4 ...
  CHECK(near(tcp.back(), Vec3(12, 4, 2), 1e-9));
  CHECK(near(g43_4.back(), Vec3(12, 4, 2), 1e-9));
  // ... and elsewhere on the part when the words are joints, the table turned.
  CHECK_FALSE(near(raw.back(), Vec3(12, 4, 2), 1.0));
  const Kinematics& kin = *machine.kinematics;
  CHECK(near(raw.back(), tip_in_part(kin, Vec3(12, 4, 2), {-30, 0, 45}), 1e-9));
}

TEST_CASE("M428: G43/G49 keep it; M429 switches back with the tip where it is") {
  MachineConfig machine = trunnion("ac-trunnion");
  const Result r = run_program(
      "G21 G90 M428\nG0 X0 Y0 Z10\nG0 A-20\nG49 G1 Z5 F100\nG0 Z10\nA0\nM429\nG1 X3 F100\nM30\n",
      {}, machine);
  REQUIRE(r.moves.size() >= 4);
  // After G49 the feed still goes straight down on the part (TCP).
  bool found = false;
  for (const Move& m : r.moves)
    if (m.kind == MoveKind::feed && m.line == 4) {
      CHECK(near(m.end, Vec3(0, 0, 5), 1e-9));
      found = true;
    }
  CHECK(found);
  // Back in identity at A0: the last cut is X3 at the same height.
  CHECK(near(r.moves.back().end, Vec3(3, 0, 10), 1e-9));
  CHECK(r.warnings.empty());
}

TEST_CASE("TCP kinematics: a rapid that turns the table keeps the tip on its line (simultaneous)") {
  const Result r =
      run_program("G21 G90 M428\nG0 X10 Y0 Z30\nG0 X20 A-40 C90\nM30\n", {}, trunnion("xyzac-trt"));
  REQUIRE(r.moves.size() == 2);
  const Move& turn = r.moves.back();
  CHECK(turn.kind == MoveKind::rapid);
  CHECK(turn.pose == PoseLaw::tcp);
  CHECK(near(turn.start, Vec3(10, 0, 30), 1e-9));
  CHECK(near(turn.end, Vec3(20, 0, 30), 1e-9));
}

TEST_CASE("a far tool turned under TCP kinematics stays far where it was: X Y, then Z") {
  // boat-xyzbc.ngc: T1 M6, then `G54 X.. Y.. B.. C..` and `G43 H1 Z5.0`.
  MachineConfig machine = *MachineConfig::bundled("xyzbc-trt");
  const Result r = run_program(
      "G21 G90 M428\nT1 M6\nG0 X-34 Y-2 B-5.5 C64\nG43 H1 Z5\nG1 Z1 F100\nM30\n", {}, machine);
  REQUIRE(r.moves.size() == 2);
  CHECK(r.moves[0].from_far);
  CHECK(near(r.moves[0].end, Vec3(-34, -2, 5), 1e-9));
  CHECK(near(r.moves[1].end, Vec3(-34, -2, 1), 1e-9));
}

TEST_CASE("kinematics switches: M430 (user kinematics) and two in a block are errors") {
  const MachineConfig machine = trunnion("bc-trunnion");
  Diagnostic d = error_of("G21\nM430\n", {}, machine);
  CHECK(d.line == 2);
  CHECK(d.message.find("M430 switches to kinematics of this machine's own") != std::string::npos);
  d = error_of("G21\nM428 M429\n", {}, machine);
  CHECK(d.message.find("both switch the kinematics") != std::string::npos);
  // xyzab-tdr's configuration has no M430: an M-code that moves nothing, as before.
  const Result r = run_program("G21\nM430\nM30\n", {}, trunnion("xyzab-tdr"));
  REQUIRE(r.warnings.size() == 1);
  CHECK(r.warnings[0].message.find("M430 has no effect") != std::string::npos);
}

TEST_CASE("machine file: kinematics_switches and kinematics_at_start") {
  auto machine = [](const char* text) {
    return machine_from_json(nlohmann::json::parse(text), "m.json");
  };
  MachineConfig m = machine(
      R"({"kinematics": "ac-trunnion", "kinematics_switches": {"M100": "tcp", "M101": "identity"},
          "kinematics_at_start": "tcp"})");
  CHECK(m.kinematics_switches.at(100) == KinematicsSwitch::tcp);
  CHECK(m.kinematics_switches.at(101) == KinematicsSwitch::identity);
  CHECK(m.tcp_kinematics_at_start);
  // A file's list replaces its base's: {} reads M428 as an M-code that moves nothing.
  CHECK(
      machine(R"({"base": "ac-trunnion", "kinematics_switches": {}})").kinematics_switches.empty());
  CHECK(MachineConfig::bundled("ac-trunnion")->kinematics_switches.at(430) ==
        KinematicsSwitch::refuse);
  // Starting in TCP: the first cut's X Y Z are on the part.
  m.start_position = Vec3(0.0);
  m.tool_change = ToolChange::in_place;
  CHECK(near(run_program("G21 G0 A-30\nG1 X1 Y2 Z3 F9\n", {}, m).moves.back().end, Vec3(1, 2, 3)));
  auto error = [&](const char* text) { return message_of([&] { machine(text); }); };
  CHECK(error(R"({"kinematics_switches": {"M428": "tcp"}})").find("need \"kinematics\"") !=
        std::string::npos);
  CHECK(error(R"({"kinematics": "ac-trunnion", "kinematics_switches": {"M6": "tcp"}})")
            .find("M6 already has a meaning") != std::string::npos);
  CHECK(error(R"({"kinematics": "ac-trunnion", "kinematics_switches": {"G428": "tcp"}})")
            .find("\"G428\": not an M-code") != std::string::npos);
  CHECK(error(R"({"kinematics": "ac-trunnion", "kinematics_switches": {"M428": "trt"}})")
            .find("\"tcp\", \"identity\" or \"refuse\"") != std::string::npos);
  CHECK(error(R"({"kinematics": "ac-trunnion", "kinematics_at_start": "refuse"})")
            .find("\"tcp\" or \"identity\"") != std::string::npos);
  CHECK(error(R"({"base": "ac-trunnion", "m_codes": [428]})").find("is a kinematics switch") !=
        std::string::npos);
}

TEST_CASE("#<_hal[pin]> from the machine's variables; a missing pin says how to give it") {
  MachineConfig machine = trunnion("xyzab-tdr");
  const Result r = run_program(
      "G21 G90\nG0 X[#<_hal[xyzab_tdr_kins.x-offset]>] Y0 Z[#<_hal[xyzab_tdr_kins.z-offset]>]\n"
      "M30\n",
      {}, machine);
  REQUIRE(!r.moves.empty());
  CHECK(near(r.moves.back().end, Vec3(-20, 0, -10), 1e-9));
  const Diagnostic d = error_of("G21\nG0 X#<_hal[xyzab_tdr_kins.y-offset]>\n", {}, machine);
  CHECK(d.message.find("HAL pin xyzab_tdr_kins.y-offset,") != std::string::npos);
  CHECK(d.message.find("\"#<_hal[xyzab_tdr_kins.y-offset]>\": value") != std::string::npos);
}

}  // namespace test_switchkins
