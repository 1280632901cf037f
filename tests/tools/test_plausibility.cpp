// Plausibility warnings (issue 31): setups a new user gets wrong, each present when it should be
// and absent when the setup is right; the start tool of a program with no tool change; LinuxCNC
// as its users run it; the summary in a shop's words.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"
#include "pipeline/plausibility.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace test_plausibility {

const char* kTools = R"({"1": {"shape": "cylindrical", "diameter": 6}})";

// A face and a pocket in a 70 x 70 x 20 block, in inches (G20 when `units`).
std::string inch_program(bool units) {
  return std::string(units ? "G20\n" : "") +
         "G90 G17\nT1 M6\nS8000 M3\nG0 X0.5 Y0.5 Z0.2\nG1 Z-0.05 F20\nG1 X2.2\nG1 Y2.2\n"
         "G1 X0.5\nG1 Y0.5\nG0 Z0.5\nM30\n";
}

bool has(const std::string& text, const std::string& part) {
  return text.find(part) != std::string::npos;
}

TEST_CASE("plausibility: a program that sets no units is read in mm, and said to be tiny") {
  fs::path dir = scratch("plaus-units");
  write_text(dir / "tools.json", kTools);
  write_text(dir / "bare.nc", inch_program(false));
  write_text(dir / "inch.nc", inch_program(true));
  const std::vector<std::string> rest{"--tools",     (dir / "tools.json").string(),
                                      "--stock",     "box:0,0,-20,70,70,0",
                                      "--dexel-res", "96",
                                      "--report",    (dir / "r.json").string()};
  auto run = [&](const std::string& program) {
    std::vector<std::string> args{"simulate", (dir / program).string()};
    args.insert(args.end(), rest.begin(), rest.end());
    return run_tridex(args, dir);
  };
  CommandResult bare = run("bare.nc");
  REQUIRE(bare.status == 0);
  CHECK(has(bare.err, "the program sets no units (no G20 or G21): read in mm"));
  CHECK(has(bare.err, "against a 70 x 70 x 20 mm stock (an inch program read in mm?)"));
  CHECK(has(bare.err, "give G20 or G21 in the program, or \"units\" in a machine file"));
  const json report = json::parse(slurp(dir / "r.json"));
  CHECK(has(report["warnings"].dump(), "sets no units"));

  CommandResult inch = run("inch.nc");
  REQUIRE(inch.status == 0);
  CHECK(!has(inch.err, "sets no units"));
  CHECK(inch.err.empty());  // a right setup: no warning at all
  // A machine file's "units" says so too.
  write_text(dir / "inch.json", R"({"units": "inch"})");
  std::vector<std::string> args{"simulate", (dir / "bare.nc").string(), "--machine",
                                (dir / "inch.json").string()};
  args.insert(args.end(), rest.begin(), rest.end());
  CommandResult stated = run_tridex(args, dir);
  REQUIRE(stated.status == 0);
  CHECK(!has(stated.err, "sets no units"));
  fs::remove_all(dir);
}

TEST_CASE("plausibility: a stock made up from the moves is said, with its box") {
  fs::path dir = scratch("plaus-stock");
  write_text(dir / "tools.json", kTools);
  write_text(dir / "p.nc", inch_program(true));
  CommandResult made_up = run_tridex({"simulate", (dir / "p.nc").string(), "--tools",
                                      (dir / "tools.json").string(), "--dexel-res", "64"},
                                     dir);
  REQUIRE(made_up.status == 0);
  CHECK(has(made_up.err, "no stock given: a box made up from the cutting moves, "));
  CHECK(has(made_up.err, "give --stock box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX"));
  CommandResult given =
      run_tridex({"simulate", (dir / "p.nc").string(), "--tools", (dir / "tools.json").string(),
                  "--dexel-res", "64", "--stock", "box:0,0,-20,70,70,0"},
                 dir);
  REQUIRE(given.status == 0);
  CHECK(!has(given.err, "no stock given"));
  fs::remove_all(dir);
}

TEST_CASE("plausibility: a metric .tbl read in inches, and a tbl whose units nothing stated") {
  fs::path dir = scratch("plaus-tbl");
  write_text(dir / "metric.tbl", "T1 P1 D10 Z+40 ;10 mm end mill\n");
  write_text(dir / "p.nc",
             "G21 G90 G17\nT1 M6 G43 H1\nS8000 M3\nG0 X10 Y10 Z5\nG1 Z-1 F200\nG1 X50\nG0 Z5\n"
             "M30\n");
  std::vector<std::string> args{
      "simulate", (dir / "p.nc").string(), "--tools",     (dir / "metric.tbl").string(),
      "--stock",  "box:0,0,-20,60,60,0",   "--dexel-res", "96"};
  CommandResult inches = run_tridex(args, dir);
  REQUIRE(inches.status == 0);
  CHECK(has(inches.err, "nothing states the tool table's units: read in inches"));
  CHECK(has(inches.err, "its diameters look metric (T1 D10 (254 mm))"));
  CHECK(has(inches.err, "tool 1 is a 254 mm cutter, wider than the 60 x 60 x 20 mm stock"));
  args.insert(args.end(), {"--tool-units", "mm"});
  CommandResult mm = run_tridex(args, dir);
  REQUIRE(mm.status == 0);
  CHECK(mm.err.empty());
  // LinuxCNC as its users run it: the tip starts far above the work (a homed machine) and M6
  // lifts the quill, so a program that descends after G43 finds no rapid in the material; and
  // a picture of nothing left is not listed as written.
  args.insert(args.end(), {"--machine", "linuxcnc", "--png", (dir / "p.png").string()});
  CommandResult linuxcnc = run_tridex(args, dir);
  REQUIRE(linuxcnc.status == 0);
  CHECK(!has(linuxcnc.err, "rapid move(s) cut material"));
  CHECK(has(linuxcnc.out, "-> " + (dir / "p.png").string()));
  // A program that cuts through the whole block leaves nothing to draw.
  write_text(dir / "through.nc",
             "G21 G90 G17\nT1 M6 G43 H1\nG0 X30 Y30 Z5\nG1 Z-30 F200\n"
             "G0 Z5\nM30\n");
  fs::remove(dir / "p.png");
  CommandResult all_gone =
      run_tridex({"simulate", (dir / "through.nc").string(), "--tools",
                  (dir / "metric.tbl").string(), "--stock", "box:0,0,-20,60,60,0", "--dexel-res",
                  "96", "--machine", "linuxcnc", "--png", (dir / "p.png").string()},
                 dir);
  REQUIRE(all_gone.status == 0);
  CHECK(!has(all_gone.err, "rapid move(s) cut material"));
  CHECK(has(all_gone.err, "was not written"));
  CHECK(!fs::exists(dir / "p.png"));
  CHECK(!has(all_gone.out, "p.png"));
  fs::remove_all(dir);
}

TEST_CASE("plausibility: a program with no tool change runs with the start tool, said so") {
  fs::path dir = scratch("plaus-start-tool");
  write_text(dir / "tools.json", kTools);
  write_text(dir / "p.nc", "G21 G90\nG0 X10 Y10 Z5\nG1 Z-1 F100\nG1 X40\nG0 Z5\nM30\n");
  std::vector<std::string> args{
      "simulate", (dir / "p.nc").string(), "--tools",     (dir / "tools.json").string(),
      "--stock",  "box:0,0,-10,50,50,0",   "--dexel-res", "64"};
  // It selects no tool at all: cut with the table's T1, as CAMotics does (issue 34, LinuxCNC's
  // impeller demo); --initial-tool 0 refuses it.
  CommandResult plain = run_tridex(args, dir);
  CHECK(plain.status == 0);
  CHECK(has(plain.err, "the program selects no tool: T1 of the tool table, as CAMotics does"));
  args.insert(args.end(), {"--initial-tool", "0"});
  CommandResult refused = run_tridex(args, dir);
  CHECK(refused.status == 2);
  CHECK(has(refused.err, "p.nc:3: a feed move with no tool loaded"));
  CHECK(has(refused.err, "--initial-tool N"));
  args.resize(args.size() - 2);
  args.insert(args.end(), {"--initial-tool", "1"});
  CommandResult started = run_tridex(args, dir);
  REQUIRE(started.status == 0);
  CHECK(has(started.err, "move(s) before any tool change were cut with tool 1"));
  CHECK(has(started.out, "tools: T1 6 mm flat"));
  // A machine file's "initial_tool"; and a CAMotics project starts with tool 1, as CAMotics.
  args.resize(args.size() - 2);
  write_text(dir / "m.json", R"({"initial_tool": 1})");
  args.insert(args.end(), {"--machine", (dir / "m.json").string()});
  CHECK(run_tridex(args, dir).status == 0);
  write_text(dir / "p.camotics", std::string(R"({"files": ["p.nc"], "tools": )") + kTools +
                                     R"(, "workpiece": {"automatic": false, "bounds": )" +
                                     R"({"min": [0, 0, -10], "max": [50, 50, 0]}}})");
  CommandResult project = run_tridex({"simulate", (dir / "p.camotics").string()}, dir);
  CHECK(project.status == 0);
  CHECK(has(project.err, "CAMotics' convention for a project"));
  // A tool the table does not hold is named.
  write_text(dir / "m.json", R"({"initial_tool": 4})");
  CommandResult absent = run_tridex(args, dir);
  CHECK(absent.status == 2);
  CHECK(has(absent.err, "with tool 4, the tool the control starts with, which is not in the"));
  fs::remove_all(dir);
}

TEST_CASE("plausibility: the bundled example warns of nothing, and says its tools and angles") {
  fs::path dir = scratch("plaus-example");
  const fs::path examples = fs::path(TRIDEX_SOURCE_DIR) / "gcode" / "examples";
  CommandResult r = run_tridex(
      {"simulate", (examples / "mold_3plus2.camotics").string(), "--dexel-res", "64"}, dir);
  REQUIRE(r.status == 0);
  CHECK(r.err.empty());
  CHECK(has(r.out, "tools: T1 10 mm flat end (\"10 mm flat end\"), T2 8 mm ball end"));
  CHECK(has(r.out, "directions: +z, "));
  CHECK(has(r.out, "(G68.2 I"));
  CommandResult twin =
      run_tridex({"simulate", (examples / "mold_3plus2_bc.nc").string(), "--machine", "bc-trunnion",
                  "--tools", (examples / "mold_3plus2.tools.json").string(), "--stock",
                  "box:0,0,0,100,80,50", "--dexel-res", "64"},
                 dir);
  REQUIRE(twin.status == 0);
  CHECK(twin.err.empty());
  CHECK(has(twin.out, "(B90 C"));
  fs::remove_all(dir);
}

TEST_CASE("plausibility: G20/G21 are found outside comments, and in every program of the corpus") {
  fs::path dir = scratch("plaus-scan");
  auto sets = [&](const std::string& text) {
    write_text(dir / "p.nc", text);
    return cli::program_sets_units(dir / "p.nc");
  };
  CHECK(sets("G90 G21\n"));
  CHECK(sets("n10 g 2 1 x0\n"));  // spaces inside a word, lower case
  CHECK(sets("G020\n"));
  CHECK(sets("G0X0G20\n"));
  CHECK(!sets("G90 (G21 in a comment)\n"));
  CHECK(!sets("G90 ; G20 after a semicolon\n"));
  CHECK(!sets("G210 G2 X1 Y1 I1\n"));
  CHECK(!sets("G21.1\n"));
  // The rs274 corpus and the public programs state their units: no warning on any of them.
  int programs = 0;
  for (const char* folder : {"linuxcnc", "public"})
    for (const auto& entry :
         fs::recursive_directory_iterator(fs::path(TRIDEX_TEST_DATA) / "gcode" / folder)) {
      const std::string ext = entry.path().extension().string();
      if (ext != ".ngc" && ext != ".nc") continue;
      CAPTURE(entry.path().string());
      CHECK(cli::program_sets_units(entry.path()));
      ++programs;
    }
  CHECK(programs >= 20);
  fs::remove_all(dir);
}

}  // namespace test_plausibility
