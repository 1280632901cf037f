// The machining time against totals computed by hand: lines, arcs, canned cycles, dwells, inch
// feeds, rapids at one rate and per axis, a max feed; per tool and per direction; the machine
// file's keys; the report's object from `groups` and `simulate`.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>
#include <sstream>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"
#include "errors.hpp"
#include "checks/machining_time.hpp"
#include "inputs/program_input.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "tridex/gcode/machine.hpp"

using namespace tridex;
using namespace tridex::test;
using json = nlohmann::json;

namespace {

// The program's time as tridex reads it, with the tool starting at the origin.
cli::MachiningTime time_of(const std::string& program,
                           gcode::Dialect dialect = gcode::Dialect::linuxcnc,
                           gcode::MachineRates rates = {}) {
  gcode::MachineConfig machine;
  machine.dialect = dialect;
  machine.start_position = Vec3(0.0);
  machine.tool_change = gcode::ToolChange::in_place;
  machine.rates = rates;
  gcode::Interpreter interpreter({}, machine);
  cli::MachiningTimer timer(machine);
  std::istringstream in(program);
  interpreter.run(
      in, "t.nc", [&](const gcode::Move& m) { timer.add(m); },
      [&](const gcode::Dwell& d) { timer.add(d); });
  return timer.time();
}

constexpr double kRapid = gcode::MachineRates::kDefaultRapid;

}  // namespace

TEST_CASE("machining time: lines, an arc by its length and a dwell") {
  cli::MachiningTime t = time_of(
      "G21 G90 G17\n"
      "T1 M6\n"
      "G0 X30 Y40\n"              // 50 mm at the rapid rate
      "G1 Z-5 F300\n"             // 5 mm at 300 mm/min: 1 s
      "G1 X60 Y80 F600\n"         // 50 mm at 600: 5 s
      "G4 P2.5\n"                 // 2.5 s (LinuxCNC: seconds)
      "G2 X80 Y80 I10 J0 F100\n"  // half a circle of radius 10: 10π mm at 100
      "G0 Z10\n");                // 15 mm at the rapid rate
  double arc = 60 * 10 * std::numbers::pi / 100;
  CHECK(t.rapid_s == doctest::Approx(60 * 65 / kRapid));
  // The arc's chords are within the arc tolerance (1 µm) of the arc: their length is within 1e-4.
  CHECK(t.feed_s == doctest::Approx(1 + 5 + arc).epsilon(1e-4));
  CHECK(t.dwell_s == doctest::Approx(2.5));
  CHECK(t.total_s() == doctest::Approx(60 * 65 / kRapid + 6 + arc + 2.5).epsilon(1e-4));
  REQUIRE(t.by_tool.size() == 1);
  CHECK(t.by_tool.at(1) == doctest::Approx(t.total_s()));
  REQUIRE(t.by_direction.size() == 1);
  CHECK(t.by_direction[0].first == Vec3(0, 0, 1));
  CHECK(t.untimed_approaches == 0);
}

TEST_CASE("machining time: inch feeds are converted") {
  cli::MachiningTime t = time_of("G20 G90\nG1 X1 F10\nG0 X2\nG4 P1\n");
  CHECK(t.feed_s == doctest::Approx(6.0));  // 1 in at 10 in/min
  CHECK(t.rapid_s == doctest::Approx(60 * 25.4 / kRapid));
  CHECK(t.dwell_s == doctest::Approx(1.0));
}

TEST_CASE("machining time: a canned cycle by its pieces, with its dwell at each hole's bottom") {
  // From (0,0,10): hole 1 rapids 10 mm across and 8 down to R, feeds 7 mm, dwells, rapids 15 up to
  // the initial level; hole 2 the same. P is sticky.
  cli::MachiningTime t =
      time_of("G21 G90 G17\nG0 Z10\nG98 G82 X10 Y0 Z-5 R2 P0.5 F120\nX20\nG80\n");
  CHECK(t.rapid_s == doctest::Approx(60 * (10 + 2 * (10 + 8 + 15)) / kRapid));
  CHECK(t.feed_s == doctest::Approx(2 * 3.5));
  CHECK(t.dwell_s == doctest::Approx(2 * 0.5));
  // G89 dwells too and comes out at feed; G81 does not dwell.
  t = time_of("G21 G90 G17\nG0 Z10\nG99 G89 X10 Y0 Z-5 R2 P1 F120\nG80\n");
  CHECK(t.feed_s == doctest::Approx(2 * 3.5));
  CHECK(t.dwell_s == doctest::Approx(1.0));
  t = time_of("G21 G90 G17\nG0 Z10\nG81 X10 Y0 Z-5 R2 F120\nG80\n");
  CHECK(t.dwell_s == 0);
}

TEST_CASE("machining time: dwell words by dialect") {
  // Fanuc: P in milliseconds, X in seconds; LinuxCNC: P in seconds.
  cli::MachiningTime t = time_of("G4 P1500\nG4 X2.\n", gcode::Dialect::fanuc);
  CHECK(t.dwell_s == doctest::Approx(3.5));
  t = time_of("G4 P1500\n", gcode::Dialect::linuxcnc);
  CHECK(t.dwell_s == doctest::Approx(1500));
  t = time_of("G90 G0 Z10\nG98 G82 X10 Z-5 R2 P250 F120\nG80\n", gcode::Dialect::fanuc);
  CHECK(t.dwell_s == doctest::Approx(0.25));
}

TEST_CASE("machining time: rapids per axis, a max feed, per tool and per direction") {
  gcode::MachineConfig machine;
  gcode::MachineRates& rates = machine.rates;
  rates.rapid_mm_per_min = Vec3(6000, 2000, 1000);
  rates.rapid_per_axis = true;
  rates.max_feed_mm_per_min = 500;
  cli::MachiningTimer timer(machine);
  gcode::Move m;
  m.kind = gcode::MoveKind::rapid;
  m.tool = 1;
  m.end = Vec3(30, 40, 0);  // Y limits: 40 / 2000 min
  timer.add(m);
  m.kind = gcode::MoveKind::feed;
  m.tool = 2;
  m.start = m.end;
  m.end = m.start + Vec3(0, 0, -10);
  m.feed = 1000;  // capped at 500: 1.2 s
  timer.add(m);
  m.axis = glm::normalize(Vec3(0, -1, 1));
  m.feed = 100;  // 6 s, another direction
  timer.add(m);
  m.from_far = true;  // not timed: where it starts is a stand-in
  timer.add(m);
  m.from_far = false;
  m.pose = gcode::PoseLaw::tcp;  // the axis turns: no direction of its own, counted apart
  m.axis = glm::normalize(Vec3(1, -1, 1));
  m.feed = 300;  // 10 mm: 2 s
  timer.add(m);
  timer.add(gcode::Dwell{7, 2, Vec3(0, 0, 1), 3.0});
  const cli::MachiningTime& t = timer.time();
  CHECK(t.rapid_s == doctest::Approx(1.2));
  CHECK(t.feed_s == doctest::Approx(7.2 + 2));
  CHECK(t.capped_feeds == 1);
  CHECK(t.untimed_approaches == 1);
  CHECK(t.by_tool.at(1) == doctest::Approx(1.2));
  CHECK(t.by_tool.at(2) == doctest::Approx(1.2 + 6 + 2 + 3));
  REQUIRE(t.by_direction.size() == 2);
  CHECK(t.by_direction[0].second == doctest::Approx(1.2 + 1.2 + 3));
  CHECK(t.by_direction[1].second == doctest::Approx(6.0));
  CHECK(t.simultaneous_moves == 1);
  CHECK(t.simultaneous_s == doctest::Approx(2.0));
  json j = cli::machining_time_json(timer);
  CHECK(j["total_s"].get<double>() == doctest::Approx(13.4));
  CHECK(j["simultaneous"]["moves"] == 1);
  CHECK(j["simultaneous"]["s"].get<double>() == doctest::Approx(2.0));
  CHECK(j["rapid_rate_mm_per_min"] == json::array({6000.0, 2000.0, 1000.0}));
  CHECK(j["rapid_rate_source"] == "default");
}

TEST_CASE("machining time: the machine file's rates, refused when bad, in the reports") {
  fs::path dir = scratch("machining-time");
  write_text(dir / "p.nc",
             "G21 G90\nG0 X0 Y0 Z5\nT1 M6\nG1 Z-1 F60\nG1 X20 F1200\nG4 P2\nG0 Z25\nM30\n");
  write_text(dir / "m.json",
             R"({"base": "rs274", "rapid_rate_mm_per_min": 3000, "max_feed_mm_per_min": 600})");
  gcode::MachineRates rates = cli::load_machine((dir / "m.json").string()).rates;
  CHECK(rates.rapid_mm_per_min == Vec3(3000));
  CHECK(rates.max_feed_mm_per_min == 600);
  CHECK(rates.source == (dir / "m.json").string());

  // From the origin: rapid 5 (tool 0) and 26 mm at 3000; feed 6 mm at 60 (6 s) and 20 mm capped at
  // 600 (2 s); dwell 2 s.
  CommandResult r =
      run_tridex({"groups", (dir / "p.nc").string(), "--machine", (dir / "m.json").string()}, dir);
  INFO(r.out, r.err);
  REQUIRE(r.status == 0);
  json mt = json::parse(r.out)["machining_time"];
  CHECK(mt["rapid_s"].get<double>() == doctest::Approx(60 * 31 / 3000.0));
  CHECK(mt["feed_s"].get<double>() == doctest::Approx(8.0));
  CHECK(mt["dwell_s"].get<double>() == doctest::Approx(2.0));
  CHECK(mt["feeds_capped"] == 1);
  CHECK(mt["rapid_rate_mm_per_min"] == 3000.0);
  CHECK(mt["rapid_rate_source"] == (dir / "m.json").string());
  REQUIRE(mt["by_tool"].size() == 2);
  CHECK(mt["by_tool"][0]["tool"] == 0);
  CHECK(mt["by_tool"][0]["s"].get<double>() == doctest::Approx(0.1));
  CHECK(mt["total_s"].get<double>() == doctest::Approx(10.62));
  CHECK(mt["by_direction"][0]["direction"] == json::array({0.0, 0.0, 1.0}));
  CHECK(!mt.contains("simultaneous"));  // only where the tool axis turns during a move

  // simulate and check report the same object and print it.
  write_text(dir / "tools.json", R"({"1": {"shape": "cylindrical", "diameter": 6}})");
  r = run_tridex(
      {"simulate", (dir / "p.nc").string(), "--machine", (dir / "m.json").string(), "--tools",
       (dir / "tools.json").string(), "--stock", "box:-10,-10,-5,30,10,0", "--dexel-cell", "1",
       "--report", (dir / "report.json").string(), "-o", (dir / "made.stl").string()},
      dir);
  REQUIRE(r.status == 0);
  CHECK(json::parse(slurp(dir / "report.json"))["machining_time"] == mt);
  const std::string line =
      "machining time 10.6 s (feed 8.0 s, rapid 0.6 s, dwell 2.0 s) with rapids at 3000 mm/min "
      "(from ";
  CHECK(r.out.find(line) != std::string::npos);
  r = run_tridex({"check", (dir / "p.nc").string(), "--design", (dir / "made.stl").string(),
                  "--machine", (dir / "m.json").string(), "--tools", (dir / "tools.json").string(),
                  "--stock", "box:-10,-10,-5,30,10,0", "--dexel-cell", "1", "--lattice-only",
                  "--report", (dir / "check.json").string()},
                 dir);
  INFO(r.out, r.err);
  REQUIRE(r.status == 0);
  CHECK(json::parse(slurp(dir / "check.json"))["machining_time"] == mt);
  CHECK(r.out.find(line) != std::string::npos);

  for (const char* bad :
       {R"({"rapid_rate_mm_per_min": -1})", R"({"rapid_rate_mm_per_min": [1000, 2000]})",
        R"({"rapid_rate_mm_per_min": "fast"})", R"({"max_feed_mm_per_min": 0})"}) {
    write_text(dir / "bad.json", bad);
    try {
      cli::load_machine((dir / "bad.json").string());
      FAIL(bad);
    } catch (const cli::InputError& e) {
      std::string message = e.what();
      CHECK(message.find("bad.json") != std::string::npos);
      CHECK(message.find("_mm_per_min\"") != std::string::npos);
    }
  }
  fs::remove_all(dir);
}

namespace {

// The program's time on the machine a machine file describes (its kinematics and rates).
cli::MachiningTime time_on(const std::string& machine_file, const std::string& program) {
  gcode::MachineConfig machine = gcode::machine_from_json(json::parse(machine_file), "m.json");
  gcode::Interpreter interpreter({}, machine);
  cli::MachiningTimer timer(machine);
  std::istringstream in(program);
  interpreter.run(in, "t.nc", [&](const gcode::Move& m) { timer.add(m); });
  return timer.time();
}

// An A/C trunnion (A tilts the table about X) whose Z is six times slower than X and Y.
constexpr const char* kTrunnion =
    R"({"base": "ac-trunnion", "start": [0, 0, 0], "tool_change": "in_place",
        "rapid_rate_mm_per_min": [6000, 6000, 1000], "rapid_rate_deg_per_min": {"A": 3600, "C": 7200}})";

}  // namespace

TEST_CASE("machining time: rapids on a tilted plane move the machine's axes, not the part's") {
  // The plane tilted 30° about X: the trunnion turns the table by A so that the plane lies
  // level, and a rapid along the plane's Y moves only the machine's Y: 40 mm at 6000 mm/min =
  // 0.4 s. Along the part's axes it would be 40·cos 30° in Y and 40·sin 30° = 20 mm in Z, 1.2 s.
  // The approach after the turn comes from far (not timed); the retract is 10 mm of machine Z.
  const std::string program =
      "G21 G90 G17\n"
      "G0 X0 Y0 Z30\n"  // 30 mm of Z at 1000: 1.8 s
      "G68.2 X0 Y0 Z0 I0 J30 K0\n"
      "G53.1\n"
      "G0 X0 Y0 Z10\n"  // from far: not timed
      "G0 Y40\n"        // machine Y 40: 0.4 s
      "G1 Z0 F600\n"    // 10 mm at 600: 1 s
      "G0 Z10\n";       // machine Z 10 at 1000: 0.6 s
  cli::MachiningTime t = time_on(kTrunnion, program);
  CHECK(t.untimed_approaches == 1);
  CHECK(t.rapid_s == doctest::Approx(1.8 + 0.4 + 0.6));
  CHECK(t.feed_s == doctest::Approx(1.0));
  CHECK(t.untimed_turns == 0);
}

TEST_CASE("machining time: rapids in raw rotary form, with the turn at the rotary rate") {
  // Without TCP the program's X Y Z are the machine's: turning A by 15° (0.25 s at 3600°/min)
  // with 100 mm of Y (1 s at 6000 mm/min) takes 1 s, where the part sees that move tilted, with
  // tens of mm along Z (seconds at Z's rate). C180 at 7200°/min with 12 mm of X: 1.5 s.
  // (A block that only turns makes no move: its turn is timed with the next rapid's.)
  const std::string program =
      "G21 G90\n"
      "G0 X0 Y0 Z30\n"  // 1.8 s
      "G0 Y100 A15\n"   // max(1 s, 0.25 s)
      "G0 X12 C180\n";  // max(0.12 s, 1.5 s)
  cli::MachiningTime t = time_on(kTrunnion, program);
  CHECK(t.rapid_s == doctest::Approx(1.8 + 1 + 1.5));
  CHECK(t.untimed_turns == 0);

  // Without a rotary rate the turns are not timed, and counted.
  t = time_on(
      R"({"base": "ac-trunnion", "start": [0, 0, 0], "rapid_rate_mm_per_min": [6000, 6000, 1000]})",
      program);
  CHECK(t.rapid_s == doctest::Approx(1.8 + 1 + 0.12));
  CHECK(t.untimed_turns == 2);
}

TEST_CASE("machining time: the rotary rates in the machine file") {
  gcode::MachineRates rates =
      gcode::machine_from_json(json::parse(R"({"rapid_rate_deg_per_min": 5400})"), "m.json").rates;
  CHECK(rates.rapid_deg_per_min == std::array<double, 3>{5400, 5400, 5400});
  // Read in either order with the linear rates (a JSON object's keys are unordered).
  gcode::MachineConfig machine = gcode::machine_from_json(
      json::parse(R"({"rapid_rate_mm_per_min": 8000, "rapid_rate_deg_per_min": {"B": 900}})"),
      "m.json");
  CHECK(machine.rates.rapid_deg_per_min == std::array<double, 3>{0, 900, 0});
  CHECK(machine.rates.rapid_mm_per_min == Vec3(8000));
  cli::MachiningTimer timer(machine);
  CHECK(cli::machining_time_json(timer)["rapid_rate_deg_per_min"] == json{{"B", 900.0}});
  for (const char* bad :
       {R"({"rapid_rate_deg_per_min": 0})", R"({"rapid_rate_deg_per_min": {"X": 100}})",
        R"({"rapid_rate_deg_per_min": {"A": -5}})", R"({"rapid_rate_deg_per_min": [1, 2]})"}) {
    try {
      gcode::machine_from_json(json::parse(bad), "bad.json");
      FAIL(bad);
    } catch (const gcode::MachineError& e) {
      std::string message = e.what();
      CHECK(message.find("bad.json: \"rapid_rate_deg_per_min\"") != std::string::npos);
    }
  }
}
