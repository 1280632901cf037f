// `tridex simulate` on simultaneous 5-axis programs (tests/data/gcode/five_axis, LinuxCNC-style
// raw rotary words and TCP on the ac-trunnion profile): they read and simulate watertight, the
// C-turning groove removes d(2φrR + πR²) within the lattice's error, the report and --certify
// say how many moves were swept by which tool within which band, and 1 and 2 threads agree.
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"

namespace test_simultaneous_simulate {

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

const std::string kData = std::string(TRIDEX_SOURCE_DIR) + "/tests/data/gcode/five_axis/";

CommandResult simulate(const fs::path& dir, const std::string& program, const std::string& name,
                       std::vector<std::string> more) {
  std::vector<std::string> args{"simulate",     kData + program,
                                "--machine",    "ac-trunnion",
                                "--tools",      kData + "tools.tbl",
                                "--tool-units", "mm",
                                "--stock",      "box:-30,-30,-10,30,30,0",
                                "--dexel-cell", "0.3",
                                "--report",     (dir / (name + ".json")).string(),
                                "-o",           (dir / (name + ".stl")).string()};
  args.insert(args.end(), more.begin(), more.end());
  return run_tridex(args, dir);
}

TEST_CASE("simulate: a C-turning groove removes d(2φrR + πR²), the same on 1 and 2 threads") {
  fs::path dir = scratch("simultaneous-groove");
  CommandResult one = simulate(dir, "c_groove.ngc", "one", {"--threads", "1", "--certify"});
  INFO(one.err);
  REQUIRE(one.status == 0);
  CHECK(one.out.find("certify: tool 1: 1 simultaneous move") != std::string::npos);
  CommandResult two = simulate(dir, "c_groove.ngc", "two", {"--threads", "2", "--quiet"});
  REQUIRE(two.status == 0);
  const json a = json::parse(slurp(dir / "one.json")), b = json::parse(slurp(dir / "two.json"));
  CHECK(a["result"]["watertight"] == true);
  // A 6 mm flat end 2 mm deep at radius 20 while C turns 90°.
  const double r = 20, radius = 3, depth = 2, phi = std::numbers::pi / 2;
  const double expected = depth * (2 * phi * r * radius + std::numbers::pi * radius * radius);
  const double removed = a["result"]["removed_mm3"].get<double>();
  INFO("removed " << removed << " expected " << expected);
  // Issue 34's bar: within 0.5 % (measured -0.07 % at this 0.3 mm spacing; -0.26 % before the
  // removal was measured surface against surface, -0.85 % at 0.25 mm).
  CHECK(std::abs(removed - expected) < 0.005 * expected);
  const json& sweeps = a["simultaneous"];
  CHECK(sweeps["moves"] == 1);
  CHECK(sweeps["by_tool"]["1"]["moves"] == 1);
  CHECK(sweeps["band_mm"].get<double>() <= sweeps["tolerance_mm"].get<double>());
  CHECK(a["result"]["volume_mm3"] == b["result"]["volume_mm3"]);
  CHECK(slurp(dir / "one.stl") == slurp(dir / "two.stl"));
  fs::remove_all(dir);
}

TEST_CASE("simulate: 3+2 passes with raw and TCP simultaneous cuts, watertight") {
  fs::path dir = scratch("simultaneous-tilt");
  CommandResult r = simulate(dir, "tilt_turn.ngc", "tilt", {"--threads", "2"});
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.err.find("warning") == std::string::npos);
  CHECK(r.out.find("simultaneous 5-axis: T2 4 moves") != std::string::npos);
  const json report = json::parse(slurp(dir / "tilt.json"));
  CHECK(report["result"]["watertight"] == true);
  CHECK(report["simultaneous"]["by_tool"]["2"]["moves"] == 4);
  // The 3+2 moves alone are grouped by direction; the simultaneous ones are in no group.
  long long grouped = 0;
  for (const json& g : report["groups"]) grouped += g["moves"].get<long long>();
  CHECK(grouped == report["segments"].get<long long>());
  // `groups` counts them apart, by tool; `moves` gives each its start's joints and pose law.
  CommandResult g =
      run_tridex({"groups", kData + "tilt_turn.ngc", "--machine", "ac-trunnion"}, dir);
  REQUIRE(g.status == 0);
  const json groups = json::parse(g.out);
  CHECK(groups["simultaneous"]["moves"] == 4);
  CHECK(groups["simultaneous"]["by_tool"]["2"] == 4);
  CommandResult m = run_tridex({"moves", kData + "tilt_turn.ngc", "--machine", "ac-trunnion"}, dir);
  REQUIRE(m.status == 0);
  CHECK(m.out.find("\"pose\":\"tcp\"") != std::string::npos);
  CHECK(m.out.find("\"pose\":\"joints\",\"rotary_start\":{\"A\":0.0,\"C\":0.0}") !=
        std::string::npos);
  fs::remove_all(dir);
}

}  // namespace test_simultaneous_simulate
