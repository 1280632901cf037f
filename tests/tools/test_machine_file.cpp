// --machine and --subprograms: the bundled machines (the kinematics profiles among them, on every
// command), a machine file's every key changing what a program means, bad machine files refused
// with the file and the key (exit 2), and rotary bad input refused at its file:line:col.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"
#include "errors.hpp"
#include "inputs/program_input.hpp"
#include "tridex/gcode/machine.hpp"

using namespace tridex;
using namespace tridex::test;

namespace {

std::vector<nlohmann::json> moves_of(const CommandResult& r) {
  std::vector<nlohmann::json> moves;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) moves.push_back(nlohmann::json::parse(line));
  return moves;
}

std::string load_error(const fs::path& file) {
  try {
    cli::load_machine(file.string());
  } catch (const cli::InputError& e) {
    return e.what();
  }
  return "";
}

}  // namespace

TEST_CASE("machine files: each key changes what the program means") {
  fs::path dir = scratch("machine");
  write_text(dir / "p.nc", "G21 G90\nG0 X1 Y2 Z3\nT2 M6\nG0 X5 Y5 Z5\nG28\nM10\nM30\n");

  // The default machine: far along the tool axis, a warning for G28's default position and one
  // for the undeclared M10.
  CommandResult r = run_tridex({"moves", (dir / "p.nc").string()}, dir);
  REQUIRE(r.status == 0);
  std::vector<nlohmann::json> m = moves_of(r);
  REQUIRE(m.size() == 2);
  CHECK(m[0]["from_far"] == true);
  CHECK(r.err.find("G28") != std::string::npos);
  CHECK(r.err.find("M10") != std::string::npos);

  // linuxcnc: starts at the origin, M6 in place, G28 to the origin.
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", "rs274"}, dir);
  REQUIRE(r.status == 0);
  m = moves_of(r);
  REQUIRE(m.size() == 3);
  CHECK(m[0]["start"] == nlohmann::json::array({0, 0, 0}));
  CHECK(m[2]["end"] == nlohmann::json::array({0, 0, 0}));
  CHECK(r.err.find("G28") == std::string::npos);

  // A machine file: a start, a tool-change position, a home, an offset, inch, declared M10.
  write_text(dir / "vf2.json", R"({
    "name": "test mill", "units": "inch", "start": [0, 0, 100],
    "tool_change": [0, 0, 200], "home": [0, 0, 300],
    "work_offsets": {"G54": [10, 0, 0]}, "m_codes": [10]})");
  write_text(dir / "q.nc", "G0 X1 Y0 Z0\nT2 M6\nG0 X0\nG28\nM10\nM30\n");
  r = run_tridex({"moves", (dir / "q.nc").string(), "--machine", (dir / "vf2.json").string()}, dir);
  REQUIRE(r.status == 0);
  m = moves_of(r);
  // Work frame = machine − G54: the start (0,0,100) is at (−10,0,100); X1 inch is 25.4 mm.
  REQUIRE(m.size() == 4);
  CHECK(m[0]["start"] == nlohmann::json::array({-10, 0, 100}));
  CHECK(m[0]["end"] == nlohmann::json::array({25.4, 0, 0}));
  CHECK(m[1]["end"] == nlohmann::json::array({-10, 0, 200}));  // the tool change
  CHECK(m[2]["end"] == nlohmann::json::array({0, 0, 200}));    // X0 at the tool-change height
  CHECK(r.err.empty());  // G28 is set and M10 declared: nothing to warn about

  // Forbidden M-codes are errors with the line.
  write_text(dir / "strict.json", R"({"base": "linuxcnc", "forbidden_m_codes": [10]})");
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "strict.json").string()},
                 dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("p.nc:6:1") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("machine files: \"variables\" are what the control holds when the program starts") {
  // A production program's feed in a persistent common, and an input it branches on.
  fs::path dir = scratch("machine-variables");
  write_text(dir / "p.nc",
             "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nIF [#1000 EQ 1] GOTO 9\nG1 Z-1 F#650\nN9 G0 Z5\n"
             "#901001 = 3\nG0 X#901001\nM30\n");
  CommandResult r = run_tridex({"moves", (dir / "p.nc").string()}, dir);
  CHECK(r.status == 2);  // #650 is vacant: no feed rate
  CHECK(r.err.find("p.nc:5:") != std::string::npos);
  write_text(dir / "m.json", R"({"variables": {"#650": 2000, "1000": 0}})");
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "m.json").string()}, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  std::vector<nlohmann::json> m = moves_of(r);
  REQUIRE(m.size() == 4);
  CHECK(m[1]["feed"] == 2000.0);
  CHECK(m[3]["end"][0] == 3.0);
  // The input set: the cut is skipped.
  write_text(dir / "m.json", R"({"variables": {"#650": 2000, "#1000": 1}})");
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "m.json").string()}, dir);
  REQUIRE(r.status == 0);
  CHECK(moves_of(r).size() == 3);
  // LinuxCNC's global named parameters, as the operator sets them by MDI (case and spaces as
  // LinuxCNC reads names); a local name cannot be preset.
  write_text(dir / "n.ngc", "G21 G90\nG0 X0 Y0 Z1\nG1 X#<_td> Y#<_Tool_Dia> F100\nM2\n");
  write_text(dir / "n.json",
             R"({"base": "linuxcnc", "variables": {"#<_td>": 6.35, "#<_tool_ dia>": 3}})");
  r = run_tridex({"moves", (dir / "n.ngc").string(), "--machine", (dir / "n.json").string()}, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(moves_of(r).back()["end"] == nlohmann::json::array({6.35, 3, 1}));
  write_text(dir / "n.json", R"({"base": "linuxcnc", "variables": {"#<td>": 6.35}})");
  r = run_tridex({"moves", (dir / "n.ngc").string(), "--machine", (dir / "n.json").string()}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("\"#<td>\" is not a global named parameter") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE(
    "machine files: \"arc_radius_tolerance_mm\" is how far an arc's end may lie off its circle") {
  fs::path dir = scratch("machine-arc");
  // 0.00254 mm off (an inch program posted to 4 decimals): within the default 0.02 mm.
  write_text(dir / "p.nc",
             "G20 G17 G90\nG0 X21.5179 Y2. Z0.1\nG3 X19.6618 I-0.928 J0. F10.\nM30\n");
  write_text(dir / "tight.json", R"({"arc_radius_tolerance_mm": 0.002})");
  write_text(dir / "bad.json", R"({"arc_radius_tolerance_mm": 0})");
  CHECK(run_tridex({"moves", (dir / "p.nc").string()}, dir).status == 0);
  CommandResult r = run_tridex(
      {"moves", (dir / "p.nc").string(), "--machine", (dir / "tight.json").string()}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("p.nc:3:") != std::string::npos);
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "bad.json").string()}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("\"arc_radius_tolerance_mm\": must be a positive number") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("machine files: T alone loads the tool where the control does so") {
  fs::path dir = scratch("machine-t");
  write_text(dir / "p.nc", "T3\nG0 X0 Y0 Z5\nG1 Z0 F100\nM30\n");
  write_text(dir / "t.json", R"({"base": "linuxcnc", "tool_loads_on_t": true})");
  CommandResult r =
      run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "t.json").string()}, dir);
  REQUIRE(r.status == 0);
  CHECK(moves_of(r).back()["tool"] == 3);
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", "rs274"}, dir);
  CHECK(moves_of(r).back()["tool"] == 0);
  fs::remove_all(dir);
}

TEST_CASE("machine files: \"g53\" says whether G53 Z retracts far or goes where it says") {
  fs::path dir = scratch("machine-g53");
  write_text(dir / "p.nc", "G21 G90\nG0 X1 Y2 Z3\nG53 G0 Z50\nG0 X4\nG1 Z1 F100\nM30\n");
  write_text(dir / "far.json", R"({"base": "rs274", "g53": "far"})");
  write_text(dir / "literal.json", R"({"g53": "literal", "start": [0, 0, 100]})");
  CommandResult r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", "rs274"}, dir);
  REQUIRE(r.status == 0);
  auto m = moves_of(r);
  REQUIRE(m.size() == 4);
  CHECK(m[1]["end"] == nlohmann::json::array({1, 2, 50}));  // machine Z50, straight up
  CHECK(m[2]["end"] == nlohmann::json::array({4, 2, 50}));
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "literal.json").string()},
                 dir);
  REQUIRE(r.status == 0);
  CHECK(moves_of(r)[1]["end"] == nlohmann::json::array({1, 2, 50}));
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "far.json").string()}, dir);
  REQUIRE(r.status == 0);
  m = moves_of(r);
  REQUIRE(m.size() == 2);  // G53 Z retracts far: X4 stays up there, G1 Z1 comes down along Z
  CHECK(m[1]["end"] == nlohmann::json::array({4, 2, 1}));
  write_text(dir / "bad.json", R"({"g53": "machine"})");
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "bad.json").string()}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("\"g53\"") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("machine files: --subprograms finds called programs") {
  fs::path dir = scratch("machine-subs");
  fs::create_directories(dir / "macros");
  write_text(dir / "macros" / "O9810.nc", "O9810\nG0 X#24 Y#25 Z1\nM99\n");
  write_text(dir / "p.nc", "G65 P9810 X4 Y5\nM30\n");
  CommandResult r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", "rs274"}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("O9810") != std::string::npos);
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", "rs274", "--subprograms",
                  (dir / "macros").string()},
                 dir);
  REQUIRE(r.status == 0);
  CHECK(moves_of(r)[0]["end"] == nlohmann::json::array({4, 5, 1}));
  // The machine file's own folders, relative to the file.
  write_text(dir / "m.json", R"({"base": "linuxcnc", "subprograms": ["macros"]})");
  r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "m.json").string()}, dir);
  CHECK(r.status == 0);
  fs::remove_all(dir);
}

TEST_CASE("machine files: kinematics by profile name or as an object") {
  fs::path dir = scratch("machine-kinematics");
  write_text(dir / "a.json", R"({"kinematics": "bc-trunnion"})");
  gcode::MachineConfig m = cli::load_machine((dir / "a.json").string());
  REQUIRE(m.kinematics.has_value());
  CHECK(m.kinematics->find('B') != nullptr);
  CHECK(m.kinematics->find('C') != nullptr);
  CHECK(m.kinematics->find('A') == nullptr);
  write_text(dir / "b.json", R"({"kinematics": {"type": "table-table", "axes": [
      {"letter": "A", "on": "table", "direction": [2, 0, 0], "pivot": [0, 0, -50],
       "limits": [-30, 90]}]}})");
  m = cli::load_machine((dir / "b.json").string());
  REQUIRE(m.kinematics.has_value());
  REQUIRE(m.kinematics->axes.size() == 1);
  CHECK(m.kinematics->axes[0].direction.x == doctest::Approx(1.0));
  CHECK((*m.kinematics->axes[0].limits)[1] == 90.0);
  CHECK(!cli::load_machine("default").kinematics.has_value());

  // moves: each move's rotary positions and machine coordinates; groups: each group's positions.
  write_text(dir / "p.nc",
             "G0 X10 Y0 Z20\nG1 X12 F100\nG28 G91 Z0\nG90 G0 B90 C0\n"
             "G0 X5 Y0 Z20\nG1 X6 F100\nM30\n");
  CommandResult r =
      run_tridex({"moves", (dir / "p.nc").string(), "--machine", (dir / "a.json").string()}, dir);
  REQUIRE(r.status == 0);
  std::vector<nlohmann::json> moves = moves_of(r);
  REQUIRE(moves.size() == 5);  // G28's intermediate point is a zero-length rapid
  CHECK(moves[1]["rotary"] == nlohmann::json({{"B", 0.0}, {"C", 0.0}}));
  CHECK(moves[1]["machine"] == nlohmann::json::array({12, 0, 20}));
  CHECK(moves[4]["rotary"] == nlohmann::json({{"B", 90.0}, {"C", 0.0}}));
  gcode::RotaryPositions b90{0, 90, 0};
  Vec3 tip = gcode::tip_in_part(*gcode::kinematics_profile("bc-trunnion"), Vec3(6, 0, 20), b90);
  for (int i = 0; i < 3; ++i) {
    CHECK(moves[4]["machine"][i].get<double>() == doctest::Approx(Vec3(6, 0, 20)[i]));
    CHECK(moves[4]["end"][i].get<double>() == doctest::Approx(tip[i]));
  }
  r = run_tridex({"groups", (dir / "p.nc").string(), "--machine", (dir / "a.json").string()}, dir);
  REQUIRE(r.status == 0);
  nlohmann::json groups = nlohmann::json::parse(r.out)["groups"];
  REQUIRE(groups.size() == 2);
  CHECK(groups[1]["rotary"] == nlohmann::json::array({{{"B", 90.0}, {"C", 0.0}}}));
  // Without kinematics the same program is refused at the rotary word (exit 2).
  r = run_tridex({"moves", (dir / "p.nc").string()}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find(":4:8:") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("machine files: a bundled kinematics profile is a --machine name on every command") {
  fs::path dir = scratch("machine-profile-names");
  write_text(dir / "tools.json",
             R"({"1": {"units": "mm", "shape": "ballnose", "diameter": 6, "length": 30}})");
  for (const std::string& name : gcode::kinematics_profile_names()) {
    INFO(name);
    CHECK(gcode::bundled_machine_names().find(name) != std::string::npos);  // --help lists it
    // The name is the default machine with that profile: as {"kinematics": NAME}.
    write_text(dir / "m.json", "{\"kinematics\": \"" + name + "\"}");
    gcode::MachineConfig by_name = cli::load_machine(name),
                         by_file = cli::load_machine((dir / "m.json").string());
    REQUIRE(by_name.kinematics.has_value());
    CHECK(by_name.kinematics->axes.size() == by_file.kinematics->axes.size());
    CHECK(!by_name.start_position.has_value());  // the default machine's far start
    write_text(dir / "base.json", "{\"base\": \"" + name + "\", \"units\": \"mm\"}");
    CHECK(cli::load_machine((dir / "base.json").string()).kinematics.has_value());
    // A program indexing the profile's second axis, run through every command.
    const gcode::Kinematics& kin = *by_name.kinematics;
    const char letter = kin.axes.back().letter;
    write_text(dir / "p.nc", std::string("G21 G90 G54 T1 M6 S9000 M3\nG0 ") + letter +
                                 "30\nG0 X5 Y5 Z20\nG1 Z-1 F300\nG1 X15\nG0 Z20\nM30\n");
    const std::string program = (dir / "p.nc").string();
    CommandResult r = run_tridex({"moves", program, "--machine", name}, dir);
    INFO(r.err);
    REQUIRE(r.status == 0);
    std::vector<nlohmann::json> moves = moves_of(r);
    REQUIRE(moves.size() == 4);
    CHECK(moves[1]["rotary"][std::string(1, letter)] == 30.0);
    r = run_tridex({"groups", program, "--machine", name}, dir);
    REQUIRE(r.status == 0);
    CHECK(nlohmann::json::parse(r.out)["groups"].size() == 1);
    const std::vector<std::string> mill{"--machine",    name,
                                        "--tools",      (dir / "tools.json").string(),
                                        "--stock",      "box:-20,-20,-20,20,20,0",
                                        "--dexel-cell", "1",
                                        "--quiet"};
    std::vector<std::string> args{"simulate", program, "-o", (dir / "out.stl").string()};
    args.insert(args.end(), mill.begin(), mill.end());
    r = run_tridex(args, dir);
    INFO(r.err);
    CHECK(r.status == 0);
    // The design is the result on the same lattice: compared on its samples.
    args = {"check", program, "--design", (dir / "out.stl").string(), "--lattice-only"};
    args.insert(args.end(), mill.begin(), mill.end());
    r = run_tridex(args, dir);
    CHECK(
        (r.status == 0 || r.status == 3));  // read; its findings (a rapid, a near miss) are its own
  }
  // Without the name, the same program is refused at its rotary word.
  CommandResult r = run_tridex({"moves", (dir / "p.nc").string()}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("p.nc:2:") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("rotary bad input through the command: file:line:col, exit 2; lenient says each line") {
  fs::path dir = scratch("machine-rotary-bad");
  const std::string program = (dir / "p.nc").string();
  struct Case {
    const char* text;
    const char* at;  // file:line:col after the program's path
    const char* expected;
  } cases[] = {
      {"G0 X0 Y0 Z50\nG0 A-130 C0\n",
       ":2:4: ", "outside the A axis's limits [-120, 120]"},  // ac-trunnion
      {"G0 X0 Y0 Z50\nG0 C10 B5\n", ":2:8: ", "the machine has no B axis"},
      {"G68.2 X0 Y0 Z0 I0 J150 K0\n G53.1\n", ":2:2: ", "G53.1"},  // beyond A's limits
      {"G0 X0 Y0 Z0\nG2 X1 Y0 I0.5 A10 F100\n", ":2:15: ", "need G0 or G1"},
  };
  for (const Case& c : cases) {
    write_text(program, std::string(c.text) + "M30\n");
    CommandResult r = run_tridex(
        {"moves", program, "--machine", "ac-trunnion", "-o", (dir / "m.jsonl").string()}, dir);
    INFO(c.text << " -> " << r.err);
    CHECK(r.status == 2);
    CHECK(r.err.find(program + c.at) != std::string::npos);
    CHECK(r.err.find(c.expected) != std::string::npos);
    CHECK(!fs::exists(dir / "m.jsonl"));
  }
  // A cut that turns A is a simultaneous move, strict or lenient: no warning, its start's rotary
  // positions and its pose law in the record.
  write_text(program, "G0 X0 Y0 Z0\nG1 X1 A10 F100\nG1 X2 A20\nM30\n");
  CommandResult r = run_tridex({"moves", program, "--machine", "ac-trunnion"}, dir);
  REQUIRE(r.status == 0);
  CHECK(r.err.find("rotary motion during a cut") == std::string::npos);
  std::vector<nlohmann::json> moves = moves_of(r);
  REQUIRE(moves.size() == 3);
  CHECK(moves[1]["rotary"]["A"] == 10.0);
  CHECK(moves[1]["rotary_start"]["A"] == 0.0);
  CHECK(moves[1]["pose"] == "joints");
  CHECK(moves[2]["rotary"]["A"] == 20.0);
  CHECK(moves[2]["rotary_start"]["A"] == 10.0);
  CHECK(!moves[0].contains("pose"));
  fs::remove_all(dir);
}

TEST_CASE("machine files: bad files name the file, the key and the value") {
  fs::path dir = scratch("machine-bad");
  struct Case {
    const char* text;
    const char* expected;
  } cases[] = {
      {"[1, 2]", "JSON object"},
      {"{\"dialect\": \"heidenhain\"}", "\"dialect\""},
      {"{\"start\": [0, 0]}", "\"start\""},
      {"{\"start\": [0, 0, \"a\"]}", "\"start\""},
      {"{\"tool_change\": 5}", "\"tool_change\""},
      {"{\"work_offsets\": {\"G60\": [0, 0, 0]}}", "G60"},
      {"{\"work_offsets\": {\"G54.1 P301\": [0, 0, 0]}}", "G54.1 P301"},
      {"{\"m_codes\": [1.5]}", "\"m_codes\""},
      {"{\"m_codes\": [10], \"forbidden_m_codes\": [10]}", "M10"},
      {"{\"variables\": [650]}", "\"variables\""},
      {"{\"variables\": {\"#x\": 1}}", "\"#x\" is not a variable number"},
      {"{\"variables\": {\"#1000000\": 1}}", "\"#1000000\" is not a variable number"},
      {"{\"variables\": {\"#650\": \"fast\"}}", "must be a number"},
      {"{\"far_distance\": -1}", "\"far_distance\""},
      {"{\"units\": \"cm\"}", "\"units\""},
      {"{\"base\": \"okuma\"}", "\"base\""},
      {"{\"kinematic\": {}}", "unknown key"},
      {"{\"kinematics\": \"xyz-trunnion\"}", "kinematics: is not a bundled profile"},
      {"{\"kinematics\": 5}", "kinematics"},
      {"{\"kinematics\": {\"type\": \"table-table\", \"axes\": [{\"letter\": \"D\", \"on\": "
       "\"table\", \"direction\": [1, 0, 0], \"pivot\": [0, 0, 0]}]}}",
       "kinematics.axes[0].letter"},
      {"{\"start\": [0, 0, 1e999]}", "1e999 is out of range"},
      {"{", "JSON"},
      {"{\"units\": \"mm\", \"units\": \"inch\"}", "key \"units\" appears twice"},
  };
  for (const Case& c : cases) {
    fs::path file = dir / "m.json";
    write_text(file, c.text);
    std::string message = load_error(file);
    INFO(c.text << " -> " << message);
    CHECK(message.find(file.string()) != std::string::npos);
    CHECK(message.find(c.expected) != std::string::npos);
  }
  CHECK(load_error(dir / "missing.json").find("neither a bundled machine") != std::string::npos);
  CHECK(load_error(dir).find("neither a bundled machine") != std::string::npos);  // a folder
  // Through the command: exit 2, no output written.
  write_text(dir / "p.nc", "G0 X0 Y0 Z0\nM30\n");
  write_text(dir / "m.json", "{\"dialect\": 3}");
  CommandResult r = run_tridex({"moves", (dir / "p.nc").string(), "--machine",
                                (dir / "m.json").string(), "-o", (dir / "out.jsonl").string()},
                               dir);
  CHECK(r.status == 2);
  CHECK(!fs::exists(dir / "out.jsonl"));
  fs::remove_all(dir);
}

TEST_CASE("tools: G41/G42 D take the tool's diameter from --tools or the project's table") {
  fs::path dir = scratch("comp_tools");
  write_text(dir / "p.ngc",
             "G21 G17 G90 F300\nT1 M6\nG0 X-10 Y-10 Z0\nG41 D1 G1 X0 Y0\nG1 X0 Y20\n"
             "G40 G1 X-10 Y30\nM2\n");
  write_text(dir / "t.json", R"({"1": {"shape": "cylindrical", "diameter": 8, "length": 30}})");
  // Without a table the offset is unknown: exit 2 naming the tool.
  CommandResult r = run_tridex({"moves", (dir / "p.ngc").string(), "--machine", "rs274"}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("tool 1 is not in the tool table") != std::string::npos);
  r = run_tridex({"moves", (dir / "p.ngc").string(), "--machine", "rs274", "--tools",
                  (dir / "t.json").string()},
                 dir);
  REQUIRE(r.status == 0);
  // The side X0 Y0 -> X0 Y20 runs one radius (4 mm) to its left: x = -4.
  bool side = false;
  for (const nlohmann::json& m : moves_of(r))
    side |= m["line"] == 5 && m["end"][0] == -4 && m["end"][1] == 20;
  CHECK(side);
}

TEST_CASE(
    "machine files: the Haas dialect (\"dialect\": \"haas\", --machine haas) reads Haas's offset "
    "registers; \"d_offsets\"") {
  fs::path dir = scratch("haas-dialect");
  // #2001 is H1's geometry on Haas and its wear on Fanuc: the alarm says what the program read.
  write_text(dir / "p.nc", "G21 G90\n#2001 = 50.\n#3000 = #2001 + #2201\n");
  write_text(dir / "t.json",
             R"({"1": {"shape": "cylindrical", "diameter": 6, "tool-length": 80}})");
  write_text(dir / "haas.json", R"({"dialect": "haas"})");
  for (const std::string& machine :
       {std::string("haas"), (dir / "haas.json").string(), std::string("default")}) {
    CAPTURE(machine);
    CommandResult r = run_tridex({"moves", (dir / "p.nc").string(), "--machine", machine, "--tools",
                                  (dir / "t.json").string()},
                                 dir);
    CHECK(r.status == 2);
    CHECK(r.err.find(machine == "default" ? "#3000 = 130" : "#3000 = 50") != std::string::npos);
  }
  // Its D registers (#2401) hold a diameter or a radius after its setting 40: "d_offsets" says
  // which, and an unwritten one then reads as the tool table's (6 or 3); without it, refused.
  write_text(dir / "d.nc", "G21 G90\n#3000 = #2401\n");
  write_text(dir / "diameter.json", R"({"dialect": "haas", "d_offsets": "diameter"})");
  write_text(dir / "radius.json", R"({"base": "haas", "d_offsets": "radius"})");
  write_text(dir / "bad.json", R"({"base": "haas", "d_offsets": "diametre"})");
  for (const auto& [machine, expected] :
       {std::pair<std::string, std::string>{"diameter.json", "#3000 = 6"},
        {"radius.json", "#3000 = 3"},
        {"haas", "\"d_offsets\""},
        {"bad.json", "\"d_offsets\": \"radius\" or \"diameter\", got \"diametre\""}}) {
    CAPTURE(machine);
    const std::string path = machine == "haas" ? machine : (dir / machine).string();
    CommandResult r = run_tridex(
        {"moves", (dir / "d.nc").string(), "--machine", path, "--tools", (dir / "t.json").string()},
        dir);
    CHECK(r.status == 2);
    CHECK(r.err.find(expected) != std::string::npos);
  }
}

TEST_CASE("--tools with tool lengths: G43 H names the tip, G49 the gauge point (.tbl and JSON)") {
  fs::path dir = scratch("tool-lengths");
  write_text(dir / "p.ngc", "G21 G90\nG53 G0 Z0\nT1 M6\nG0 X1 Y1\nG43 H1\nG0 X2\nG0 Z5\nM2\n");
  write_text(dir / "t.tbl", "T1 P1 D0.125 Z+0.5 ;1/8 end mill\n");
  write_text(dir / "t.json",
             R"({"1": {"shape": "cylindrical", "diameter": 3.175, "tool-length": 12.7}})");
  for (const char* table : {"t.tbl", "t.json"}) {
    CAPTURE(table);
    CommandResult r = run_tridex({"moves", (dir / "p.ngc").string(), "--machine", "rs274",
                                  "--tools", (dir / table).string()},
                                 dir);
    REQUIRE(r.status == 0);
    auto m = moves_of(r);
    REQUIRE(m.size() == 4);  // the G53 Z0 where the machine starts, then three
    // The gauge point at machine Z0: the tip 12.7 mm below, where G43 H1 keeps it; Z5 is the tip.
    CHECK(m[1]["end"] == nlohmann::json::array({1, 1, -12.7}));
    CHECK(m[2]["end"] == nlohmann::json::array({2, 1, -12.7}));
    CHECK(m[3]["end"] == nlohmann::json::array({2, 1, 5}));
  }
  // A metric machine (LinuxCNC's LINEAR_UNITS = mm): the same .tbl written in mm.
  write_text(dir / "mm.tbl", "T1 P1 D3.175 Z+12.7 ;1/8 end mill\n");
  write_text(dir / "metric.json", R"({"base": "rs274", "linear_units": "mm"})");
  CommandResult metric =
      run_tridex({"moves", (dir / "p.ngc").string(), "--machine", (dir / "metric.json").string(),
                  "--tools", (dir / "mm.tbl").string()},
                 dir);
  REQUIRE(metric.status == 0);
  auto mm = moves_of(metric);
  REQUIRE(mm.size() == 4);
  CHECK(mm[1]["end"] == nlohmann::json::array({1, 1, -12.7}));
  write_text(dir / "typo.json", R"({"base": "linuxcnc", "linear_units": "metric"})");
  CommandResult typo = run_tridex(
      {"moves", (dir / "p.ngc").string(), "--machine", (dir / "typo.json").string()}, dir);
  CHECK(typo.status == 2);
  CHECK(typo.err.find("\"linear_units\": \"mm\" or \"inch\", got \"metric\"") != std::string::npos);
  write_text(dir / "bad.tbl", "T1 P1 D0.125 Z+0.5\nT2 P2 Dx\n");
  CommandResult r =
      run_tridex({"moves", (dir / "p.ngc").string(), "--tools", (dir / "bad.tbl").string()}, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("bad.tbl:2:7: \"Dx\"") != std::string::npos);
  fs::remove_all(dir);
}
