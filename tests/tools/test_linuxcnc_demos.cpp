// LinuxCNC's public 5-axis demos (issue 34's bar) on their machines, strict: the vismach boat
// (xyzac-trt, xyzbc-trt), the 7-blade impeller (xyzac-trt, no tool selected) and the
// table-dual-rotary demo (xyzab-tdr, #<_hal[...]> pins, G10 L20 P0, G53 with A/B). Each reads,
// simulates watertight and cuts where the program says on the part: under M428 (TCP) the tips
// stay within the part's extents the program states, which the raw-joint reading (M428 ignored)
// leaves far behind. The demos are GPL: read where Debian's linuxcnc-uspace installs them
// (tools/deps/test.txt), never copied here; absent, the cases say SKIPPED. Also the CAMotics rule
// for a program that selects no tool, on small programs of our own.
#include <doctest/doctest.h>

#include <algorithm>
#include <sstream>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace test_linuxcnc_demos {

const fs::path kFiveAxis = "/usr/share/doc/linuxcnc/examples/sample-configs/sim/axis/vismach/5axis";

bool present(const fs::path& file) {
  if (fs::exists(file)) return true;
  MESSAGE("SKIPPED: " << file << " not found (Debian package linuxcnc-uspace)");
  return false;
}

// `tridex simulate` strict at a coarse lattice (and 1 mm Z-map cells: the demos' 1 mm end mill
// would otherwise set them to a fine grid for each of the impeller's 66 directions): its report.
json simulate(const fs::path& dir, const std::vector<std::string>& args, int dexels = 40) {
  std::vector<std::string> all{"simulate",    "--quiet",
                               "--dexel-res", std::to_string(dexels),
                               "--zmap-cell", "1",
                               "-o",          (dir / "out.stl").string(),
                               "--report",    (dir / "report.json").string()};
  all.insert(all.end(), args.begin(), args.end());
  const CommandResult r = run_tridex(all, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  return json::parse(slurp(dir / "report.json"));
}

// The bounding box of the feed moves' tips (`tridex moves`, "end"), and how many turn the tool.
struct Tips {
  Vec3 lo{1e300}, hi{-1e300};
  int turning = 0;
};
Tips feed_tips(const fs::path& dir, const std::vector<std::string>& args) {
  std::vector<std::string> all{"moves"};
  all.insert(all.end(), args.begin(), args.end());
  const CommandResult r = run_tridex(all, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  Tips tips;
  std::istringstream in(r.out);
  for (std::string line; std::getline(in, line);) {
    const json m = json::parse(line);
    if (m["kind"] == "rapid") continue;
    for (int i = 0; i < 3; ++i) {
      tips.lo[i] = std::min(tips.lo[i], m["end"][static_cast<std::size_t>(i)].get<double>());
      tips.hi[i] = std::max(tips.hi[i], m["end"][static_cast<std::size_t>(i)].get<double>());
    }
    tips.turning += m.contains("pose") && m["pose"] == "tcp";
  }
  return tips;
}

bool within(const Tips& t, const Vec3& lo, const Vec3& hi) {
  for (int i = 0; i < 3; ++i)
    if (t.lo[i] < lo[i] || t.hi[i] > hi[i]) return false;
  return true;
}

TEST_CASE("boat-xyzac.ngc on xyzac-trt: M428 is TCP, the tips on the boat; raw joints are not") {
  const fs::path dir = kFiveAxis / "table-rotary-tilting";
  const fs::path program = dir / "demos/boat-xyzac.ngc";
  if (!present(program)) return;
  const fs::path work = scratch("lcnc-boat-ac");
  const std::string tools = (dir / "xyzac-trt.tbl").string();
  const json report =
      simulate(work, {program.string(), "--machine", "xyzac-trt", "--tools", tools});
  CHECK(report["result"]["watertight"] == true);
  CHECK(report["simultaneous"]["moves"].get<int>() > 1000);
  CHECK(report["result"]["removed_mm3"].get<double>() > 1000);
  // The program's header: "Touch Off: Table = -13.25 == Z max neg extent"; the boat is about
  // 96 x 49 mm. Under TCP the tips stay on it ...
  const Tips tcp = feed_tips(work, {program.string(), "--machine", "xyzac-trt"});
  CHECK(tcp.turning > 1000);
  CHECK(within(tcp, Vec3(-51, -27, -13.25 - 1e-9), Vec3(47, 23, 3)));
  CHECK(tcp.lo.z == doctest::Approx(-13.25));
  // ... read as joints (a machine file without the switches: M428 moves nothing), they swing
  // tens of mm off the part with the table.
  write_text(work / "raw.json", R"({"base": "xyzac-trt", "kinematics_switches": {}})");
  const Tips raw = feed_tips(work, {program.string(), "--machine", (work / "raw.json").string()});
  CHECK_FALSE(within(raw, Vec3(-51, -27, -13.25 - 1e-9), Vec3(47, 23, 3)));
  fs::remove_all(work);
}

TEST_CASE("gmoccapy's boat-xyzac.ngc (no M428): TCP from the start, kinematics_at_start") {
  // gmoccapy's table-rotary-tilting: KINEMATICS = xyzac-trt-kins without sparm=identityfirst.
  const fs::path dir =
      "/usr/share/doc/linuxcnc/examples/sample-configs/sim/gmoccapy/"
      "non_trivial_kinematics/table-rotary-tilting";
  const fs::path program = dir / "examples/boat-xyzac.ngc";
  if (!present(program)) return;
  const fs::path work = scratch("lcnc-boat-gm");
  write_text(work / "gm.json", R"({"base": "xyzac-trt", "kinematics_at_start": "tcp"})");
  const std::string machine = (work / "gm.json").string();
  const json report = simulate(
      work, {program.string(), "--machine", machine, "--tools", (dir / "xyzac-trt.tbl").string()});
  CHECK(report["result"]["watertight"] == true);
  const Tips tcp = feed_tips(work, {program.string(), "--machine", machine});
  CHECK(within(tcp, Vec3(-51, -27, -13.25 - 1e-9), Vec3(47, 23, 3)));
  CHECK_FALSE(within(feed_tips(work, {program.string(), "--machine", "xyzac-trt"}),
                     Vec3(-51, -27, -13.25 - 1e-9), Vec3(47, 23, 3)));
  fs::remove_all(work);
}

TEST_CASE("boat-xyzbc.ngc on xyzbc-trt: T1 without Z is length 0, G43 H1 reads it") {
  const fs::path dir = kFiveAxis / "table-rotary-tilting";
  const fs::path program = dir / "demos/boat-xyzbc.ngc";
  if (!present(program)) return;
  const fs::path work = scratch("lcnc-boat-bc");
  const std::string tools = (dir / "xyzbc-trt.tbl").string();
  const json report =
      simulate(work, {program.string(), "--machine", "xyzbc-trt", "--tools", tools});
  CHECK(report["result"]["watertight"] == true);
  CHECK(report["simultaneous"]["moves"].get<int>() > 1000);
  // "Touch Off: Table = -8.3 == Z max neg extent" (the finish reaches -8.35); about 89 x 35 mm.
  const Tips tcp = feed_tips(work, {program.string(), "--machine", "xyzbc-trt"});
  CHECK(tcp.turning > 1000);
  CHECK(within(tcp, Vec3(-46, -21, -8.4), Vec3(46, 17, 3)));
  write_text(work / "raw.json", R"({"base": "xyzbc-trt", "kinematics_switches": {}})");
  const Tips raw = feed_tips(work, {program.string(), "--machine", (work / "raw.json").string()});
  CHECK_FALSE(within(raw, Vec3(-46, -21, -8.4), Vec3(46, 17, 3)));
  fs::remove_all(work);
}

TEST_CASE("impeller-7bl-xyzac.ngc on xyzac-trt: no tool selected, cut with T1 (with a warning)") {
  const fs::path dir = kFiveAxis / "table-rotary-tilting";
  const fs::path program = dir / "demos/impeller-7bl-xyzac.ngc";
  if (!present(program)) return;
  const fs::path work = scratch("lcnc-impeller");
  const std::string tools = (dir / "xyzac-trt.tbl").string();
  const json report =
      simulate(work, {program.string(), "--machine", "xyzac-trt", "--tools", tools}, 16);
  CHECK(report["result"]["watertight"] == true);
  CHECK(report["result"]["removed_mm3"].get<double>() > 100);
  const std::string warnings = report["warnings"].dump();
  CHECK(warnings.find("the program selects no tool: T1 of the tool table, as CAMotics does") !=
        std::string::npos);
  fs::remove_all(work);
}

TEST_CASE("xyzab-tdr-demo.ngc on xyzab-tdr: HAL pins, G10 L20 P0, G53 A B, the TCP square") {
  const fs::path dir = kFiveAxis / "table-dual-rotary";
  const fs::path program = dir / "demos/xyzab-tdr-demo.ngc";
  if (!present(program)) return;
  const fs::path work = scratch("lcnc-tdr");
  const std::string tools = (dir / "xyzab-tdr.tbl").string();
  const json report =
      simulate(work, {program.string(), "--machine", "xyzab-tdr", "--tools", tools});
  CHECK(report["result"]["watertight"] == true);
  CHECK(report["simultaneous"]["moves"].get<int>() >= 10);
  // The square at X1 and X5 from the A faceplate's centre (−20, 0, −10), ±30 in Y and Z, what
  // ever the tables turn to.
  const Tips tips = feed_tips(work, {program.string(), "--machine", "xyzab-tdr"});
  CHECK(within(tips, Vec3(-19 - 1e-6, -30 - 1e-6, -40 - 1e-6),
               Vec3(-15 + 1e-6, 30 + 1e-6, 20 + 1e-6)));
  CHECK(tips.lo.x == doctest::Approx(-19));
  CHECK(tips.hi.x == doctest::Approx(-15));
  fs::remove_all(work);
}

TEST_CASE("a program that selects no tool is cut with T1; one that selects later stays refused") {
  const fs::path work = scratch("lcnc-t1");
  write_text(work / "t.tbl", "T1 P1 D6\nT2 P2 D4\n");
  write_text(work / "none.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nX10\nG0 Z5\nM30\n");
  write_text(work / "late.ngc", "G21 G90\nG0 X0 Y0 Z5\nG1 Z-1 F100\nT2 M6\nX10\nM30\n");
  const std::vector<std::string> common{"--stock", "box:-5,-5,-3,15,5,0",     "--dexel-res",  "24",
                                        "--tools", (work / "t.tbl").string(), "--tool-units", "mm"};
  auto run = [&](const std::string& program, std::vector<std::string> more) {
    std::vector<std::string> args{"simulate", (work / program).string(), "-o",
                                  (work / "o.stl").string()};
    args.insert(args.end(), common.begin(), common.end());
    args.insert(args.end(), more.begin(), more.end());
    return run_tridex(args, work);
  };
  CommandResult r = run("none.ngc", {});
  INFO(r.err);
  CHECK(r.status == 0);
  CHECK(r.err.find("cut with tool 1") != std::string::npos);
  CHECK(r.err.find("--initial-tool 0 to refuse") != std::string::npos);
  r = run("none.ngc", {"--initial-tool", "0"});
  CHECK(r.status == 2);
  CHECK(r.err.find("move with no tool loaded") != std::string::npos);
  r = run("late.ngc", {});
  CHECK(r.status == 2);
  CHECK(r.err.find("move with no tool loaded") != std::string::npos);
  fs::remove_all(work);
}

}  // namespace test_linuxcnc_demos
