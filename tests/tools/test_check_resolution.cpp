// What check's lattice resolves (issue 31, tools/cli/pipeline/resolution.hpp): without
// --dexel-res/--dexel-cell the spacing is refined until the deepest gouge a tool can hide between
// the samples is within the gouge tolerance, and the report and stdout say so; when --max-memory
// cannot hold that lattice, or a spacing given cannot resolve the tolerance, check exits 2.
//
// The part: a 40 x 2 x 3 bar (few rays: each case runs in well under a second) faced 1 mm down
// with a 10 mm flat end, then a spring pass with a 0.8 mm ball end (R 0.4) along it at the faced
// height, or 0.05 mm below (a gouge). At the default 320 cells (0.125 mm, Z-map cell 0.04 mm) the
// ball can hide 0.027 mm between the samples, more than ±0.02 mm.
#include <doctest/doctest.h>

#include <cmath>
#include <cstdio>
#include <nlohmann/json.hpp>

#include "command_harness.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace test_check_resolution {

// Faces the bar's top 1 mm down with T1, then runs T2 along it with its tip at `ball_z`; a
// 40 x 40 block (`wide`) is faced in ten passes instead.
std::string program(double ball_z, bool wide = false) {
  std::string text = "G21 G90 G17\nT1 M6\nS8000 M3\n";
  if (wide) {
    text += "G0 X-8 Y-2 Z5\nG1 Z-1 F500\n";
    for (int pass = 0; pass <= 9; ++pass) {
      const double y = -2 + 5 * pass;
      text += "G1 X" + std::string(pass % 2 ? "-8" : "48") + " Y" + std::to_string(y) + "\n";
      if (pass < 9) text += "G1 Y" + std::to_string(y + 5) + "\n";
    }
  } else {
    text += "G0 X-8 Y1 Z5\nG1 Z-1 F500\nG1 X48\n";
  }
  char ball[160];
  std::snprintf(ball, sizeof ball, "G0 Z5\nT2 M6\nG0 X-2 Y%d\nG1 Z%.3f F300\nG1 X42\nG0 Z5\nM30\n",
                wide ? 20 : 1, ball_z);
  return text + ball;
}

struct Setup {
  fs::path dir;
  std::string stock = "box:0,0,-3,40,2,0";
  Setup(const std::string& name, double ball_z, bool wide = false) : dir(scratch(name)) {
    write_text(dir / "tools.json", R"({"1": {"shape": "cylindrical", "diameter": 10},
                                       "2": {"shape": "ballnose", "diameter": 0.8}})");
    write_text(dir / "part.nc", program(ball_z, wide));
    if (wide) stock = "box:0,0,-3,40,40,0";
    write_text(dir / "design.stl", box_stl_text(0, 0, -3, 40, wide ? 40 : 2, -1));
  }
  ~Setup() { fs::remove_all(dir); }
  CommandResult check(std::vector<std::string> extra) const {
    fs::remove(dir / "report.json");
    std::vector<std::string> args = {"check",    (dir / "part.nc").string(),
                                     "--tools",  (dir / "tools.json").string(),
                                     "--stock",  stock,
                                     "--design", (dir / "design.stl").string(),
                                     "--report", (dir / "report.json").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_tridex(args, dir);
  }
  json report() const { return json::parse(slurp(dir / "report.json")); }
};

TEST_CASE("check refines the lattice for its tolerance and finds a 0.05 mm gouge") {
  Setup clean("check-resolution-clean", -1);
  CommandResult pass = clean.check({});
  CHECK(pass.status == 0);
  json report = clean.report();
  const json& resolution = report["resolution"];
  // Refined from the default 40 / 320 mm, to a spacing whose bound is within ±0.02 mm.
  CHECK(resolution["refined_from_mm"].get<double>() == doctest::Approx(0.125).epsilon(1e-3));
  CHECK(resolution["dexel_cell_mm"].get<double>() < 0.1);
  CHECK(resolution["missable_gouge_mm"].get<double>() <= 0.02);
  CHECK(resolution["missable_gouge_mm"].get<double>() > 0.015);  // not refined past the need
  CHECK(resolution["tool"] == 2);
  CHECK(pass.out.find("verdict: pass at ±0.02 mm") != std::string::npos);
  CHECK(pass.out.find("(refined from 0.125 mm for the tolerance)") != std::string::npos);
  CHECK(pass.out.find("by at most 0.0") != std::string::npos);

  Setup gouged("check-resolution-gouge", -1.05);
  CommandResult fail = gouged.check({});
  CHECK(fail.status == 3);
  report = gouged.report();
  REQUIRE(!report["gouges"].empty());
  CHECK(report["gouges"][0]["depth_mm"].get<double>() == doctest::Approx(0.05).epsilon(0.1));
  CHECK(report["gouges"][0]["lines"].size() >= 1);
  CHECK(fail.out.find("verdict: FAIL at ±0.02 mm") != std::string::npos);
}

// On a 40 x 40 block the refined lattice needs about 400 MiB (measured 416 MiB with 57 MiB held
// by the process before any work): refused under 350 MiB before anything is milled.
TEST_CASE("check exits 2 when --max-memory cannot hold the lattice its tolerance needs") {
  Setup s("check-resolution-memory", -1, true);
  CommandResult r = s.check({"--max-memory", "350M"});
  CHECK(r.status == 2);
  CHECK(r.err.find("check at a gouge tolerance of 0.02 mm needs a dexel spacing of 0.0") !=
        std::string::npos);
  CHECK(r.err.find("(at 0.125 mm the lattice can miss a gouge of 0.0") != std::string::npos);
  CHECK(r.err.find("which needs an estimated") != std::string::npos);
  CHECK(r.err.find("more than --max-memory 350 MiB") != std::string::npos);
  CHECK(r.err.find("--tolerance") != std::string::npos);
  CHECK(!fs::exists(s.dir / "report.json"));
}

TEST_CASE("check refuses a --dexel-res that cannot resolve its tolerance") {
  Setup s("check-resolution-given", -1);
  // 40 / 160 = 0.25 mm: the ball can hide about 0.075 mm between the samples.
  CommandResult coarse = s.check({"--dexel-res", "160"});
  CHECK(coarse.status == 2);
  CHECK(coarse.err.find("--dexel-res 160: a dexel spacing of 0.25 mm can miss a gouge of 0.0") !=
        std::string::npos);
  CHECK(coarse.err.find("(tool 2, 0.8 mm ball end)") != std::string::npos);
  CHECK(!fs::exists(s.dir / "report.json"));
  // A tolerance it resolves is accepted; so is --lattice-only, which says what it can miss.
  CommandResult loose = s.check({"--dexel-res", "160", "--tolerance", "0.08"});
  CHECK(loose.status == 0);
  CHECK(s.report()["resolution"]["missable_gouge_mm"].get<double>() < 0.08);
  CommandResult samples = s.check({"--dexel-res", "160", "--lattice-only"});
  CHECK(samples.status == 0);
  CHECK(samples.out.find("--lattice-only: the verdict holds on the lattice's samples") !=
        std::string::npos);
  CHECK(s.report()["resolution"]["lattice_only"] == true);
  // A cutter narrower than the samples' spacing can hide a whole cut: no tolerance resolves it.
  CommandResult wide = s.check({"--dexel-res", "40", "--tolerance", "5"});
  CHECK(wide.status == 2);
  CHECK(wide.err.find("any depth (tool 2, 0.8 mm ball end") != std::string::npos);
}

}  // namespace test_check_resolution
