// Issue 39's second stop: `tridex regress` over a folder of three programs (bless, a clean rerun,
// one program changed, a new one, one program run alone, a sidecar's settings), check's excess
// region named at the pass that left it, and `diff --html/--png` (with a project as A and no
// --tools: B cuts with the project's table). Coarse lattices: each case well under a second.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace test_regress {

const char* kTools = R"({"1": {"shape": "cylindrical", "diameter": 6, "length": 30}})";

// Faces the top of a 40 x 40 block 1 mm down with a 6 mm flat end, 5 mm apart: each pass alone
// cuts the middle 4 mm of its strip. `raised_y`: the pass at that Y runs 0.3 mm high. Returns the
// text and, in `raised_line`, the 1-based line of the raised pass.
std::string facing(int raised_y = -1, int* raised_line = nullptr) {
  std::vector<std::string> lines = {"G21 G90 G17", "T1 M6", "S8000 M3", "G0 X-5 Y0 Z5",
                                    "G1 Z-1 F500"};
  for (int y = 0; y <= 40; y += 5) {
    if (y > 0)
      lines.push_back("G1 Y" + std::to_string(y) +
                      (y == raised_y       ? " Z-0.7"
                       : y == raised_y + 5 ? " Z-1"
                                           : ""));
    lines.push_back(std::string("G1 X") + ((y / 5) % 2 ? "-5" : "45"));
    if (y == raised_y && raised_line) *raised_line = static_cast<int>(lines.size());
  }
  lines.push_back("G0 Z5");
  lines.push_back("M30");
  std::string text;
  for (const std::string& l : lines) text += l + "\n";
  return text;
}

// A slot along Y at X = `x`, `depth` deep.
std::string slot(double x, double depth) {
  return "G21 G90 G17\nT1 M6\nG0 X" + std::to_string(x) + " Y-5 Z5\nG1 Z-" + std::to_string(depth) +
         " F500\nG1 Y45\nG0 Z5\nM30\n";
}

struct Run {
  CommandResult run;
  json report;
};

Run regress(const fs::path& dir, const std::string& what, bool bless) {
  std::vector<std::string> args = {"regress",     what,
                                   "--baseline",  (dir / "base").string(),
                                   "--tools",     (dir / "tools.json").string(),
                                   "--stock",     "box:0,0,-10,40,40,0",
                                   "--dexel-res", "40",
                                   "--report",    (dir / "report.json").string()};
  if (bless) args.push_back("--bless");
  Run r;
  r.run = run_tridex(args, dir);
  if (fs::exists(dir / "report.json")) r.report = json::parse(slurp(dir / "report.json"));
  fs::remove(dir / "report.json");
  return r;
}

const json& entry(const json& report, const std::string& name) {
  for (const json& p : report["programs"])
    if (fs::path(p["program"].get<std::string>()).filename() == name) return p;
  FAIL("no entry for " << name);
  static const json none;
  return none;
}

// A folder of three programs (one with a sidecar, one file not a program) in `dir`/progs.
fs::path three_programs(const fs::path& dir) {
  const fs::path progs = dir / "progs";
  fs::create_directories(progs);
  write_text(dir / "tools.json", kTools);
  write_text(progs / "a_face.nc", facing());
  write_text(progs / "b_slot.nc", slot(10, 2));
  write_text(progs / "c_slot.ngc", slot(30, 3));
  // A sidecar: c_slot runs on a finer lattice than the command line's.
  write_text(progs / "c_slot.tridex.json", R"({"dexel_res": 50})");
  write_text(progs / "notes.txt", "not a program");
  return progs;
}

TEST_CASE("regress: bless, a clean rerun, one program changed, left shallower alone") {
  const fs::path dir = scratch("regress");
  const fs::path progs = three_programs(dir);
  // Without a baseline folder: bad input.
  CHECK(regress(dir, progs.string(), false).run.status == 2);
  Run blessed = regress(dir, progs.string(), true);
  CHECK(blessed.run.status == 0);
  REQUIRE(blessed.report["programs"].size() == 3);
  for (const char* name : {"a_face.nc", "b_slot.nc", "c_slot.ngc"}) {
    CAPTURE(name);
    CHECK(entry(blessed.report, name)["status"] == "new");
    CHECK(entry(blessed.report, name)["blessed"] == true);
    CHECK(fs::exists(dir / "base" / (std::string(name) + ".dexel")));
    CHECK(fs::exists(dir / "base" / (std::string(name) + ".json")));
  }
  const json stored = json::parse(slurp(dir / "base" / "c_slot.ngc.json"));
  CHECK(stored["settings"]["dexel_res"] == 50);

  Run clean = regress(dir, progs.string(), false);
  CHECK(clean.run.status == 0);
  CHECK(clean.report["verdict"] == "same");
  CHECK(clean.report["counts"]["same"] == 3);
  CHECK(clean.run.out.find("3 program(s): 3 same, 0 changed, 0 new, 0 error(s)") !=
        std::string::npos);

  // b_slot cut 0.5 mm deeper (line 4): changed, named with its line; the others the same.
  write_text(progs / "b_slot.nc", slot(10, 2.5));
  Run changed = regress(dir, progs.string(), false);
  CHECK(changed.run.status == 3);
  const json& b = entry(changed.report, "b_slot.nc");
  CHECK(b["status"] == "changed");
  REQUIRE(!b["regions"].empty());
  CHECK(b["regions"][0]["kind"] == "removed");
  CHECK(b["regions"][0]["volume_mm3"].get<double>() > 10);
  const std::string line5 = (progs / "b_slot.nc").string() + ":5";  // G1 Y45, 2.5 mm deep
  CHECK(b["regions"][0]["lines"].dump().find(line5) != std::string::npos);
  CHECK(entry(changed.report, "a_face.nc")["status"] == "same");
  const std::size_t row = changed.run.out.find("\nb_slot.nc ");
  REQUIRE(row != std::string::npos);
  CHECK(changed.run.out.substr(row, changed.run.out.find('\n', row + 1) - row).find("CHANGED") !=
        std::string::npos);

  // Shallower than its baseline: material left, named by the nearest pass.
  write_text(progs / "b_slot.nc", slot(10, 1.5));
  Run left = regress(dir, (progs / "b_slot.nc").string(), false);  // one program alone
  CHECK(left.run.status == 3);
  REQUIRE(left.report["programs"].size() == 1);
  const json& l = entry(left.report, "b_slot.nc");
  REQUIRE(!l["regions"].empty());
  CHECK(l["regions"][0]["kind"] == "left");
  CHECK(l["regions"][0]["lines"].dump().find(line5) != std::string::npos);
  CHECK(l["regions"][0]["tools"] == json::array({1}));

  fs::remove_all(dir);
}

TEST_CASE("regress: a new program fails until blessed; a program that does not run") {
  const fs::path dir = scratch("regress-new");
  const fs::path progs = three_programs(dir);
  REQUIRE(regress(dir, progs.string(), true).run.status == 0);
  // A program without a baseline: "new", which fails until blessed.
  write_text(progs / "b_slot.nc", slot(10, 2));
  write_text(progs / "d_new.nc", slot(20, 1));
  Run fresh = regress(dir, progs.string(), false);
  CHECK(fresh.run.status == 3);
  CHECK(entry(fresh.report, "d_new.nc")["status"] == "new");
  CHECK(entry(fresh.report, "b_slot.nc")["status"] == "same");
  CHECK(!fs::exists(dir / "base" / "d_new.nc.dexel"));
  CHECK(regress(dir, (progs / "a_face.nc").string(), false).run.status == 0);

  // A program that does not run: an error (exit 2), the others still compared.
  write_text(progs / "d_new.nc", "G21 G90\nG2 X10 Y0 R-\n");
  Run error = regress(dir, progs.string(), false);
  CHECK(error.run.status == 2);
  CHECK(entry(error.report, "d_new.nc")["status"] == "error");
  CHECK(entry(error.report, "a_face.nc")["status"] == "same");
  fs::remove_all(dir);
}

// check: an excess region names the pass nearest it, the pass that ran high.
TEST_CASE("check: a planted excess names the pass that left it") {
  const fs::path dir = scratch("check-excess-lines");
  write_text(dir / "tools.json", kTools);
  int raised = 0;
  write_text(dir / "face.nc", facing(20, &raised));
  REQUIRE(raised > 0);
  // The design: the faced block, its top at Z -1.
  write_text(dir / "design.stl", box_stl_text(0, 0, -10, 40, 40, -1));
  CommandResult r =
      run_tridex({"check", (dir / "face.nc").string(), "--tools", (dir / "tools.json").string(),
                  "--stock", "box:0,0,-10,40,40,0", "--design", (dir / "design.stl").string(),
                  "--dexel-res", "80", "--tolerance", "0.05", "--report",
                  (dir / "report.json").string(), "--html", (dir / "page.html").string()},
                 dir);
  CHECK(r.status == 3);
  const json report = json::parse(slurp(dir / "report.json"));
  REQUIRE(!report["excess"].empty());
  const json& excess = report["excess"][0];
  CHECK(excess["depth_mm"].get<double>() == doctest::Approx(0.3).epsilon(0.1));
  CHECK(excess["lines"].dump().find(std::to_string(raised)) != std::string::npos);
  CHECK(excess["tools"] == json::array({1}));
  CHECK(excess["nearest_mm"].get<double>() < 0.05);
  CHECK(r.out.find("face.nc:" + std::to_string(raised)) != std::string::npos);
  CHECK(slurp(dir / "page.html").find("nearest line") != std::string::npos);
  fs::remove_all(dir);
}

// diff --html and --png, with a project as A and no --tools: B cuts with the project's table.
TEST_CASE("diff --html and --png; a project A lends B its tool table") {
  const fs::path dir = scratch("diff-html");
  write_text(dir / "face.nc", facing());
  int raised = 0;
  write_text(dir / "raised.nc", facing(20, &raised));
  write_text(dir / "face.camotics",
             std::string(R"({"files": ["face.nc"], "tools": )") + kTools +
                 R"(, "workpiece": {"automatic": false, "bounds": {"min": [0, 0, -10],
                 "max": [40, 40, 0]}}})");
  auto diff = [&](const std::string& b, const std::vector<std::string>& extra) {
    std::vector<std::string> args = {
        "diff",     (dir / "face.camotics").string(), b, "--dexel-res", "40",
        "--report", (dir / "report.json").string()};
    args.insert(args.end(), extra.begin(), extra.end());
    return run_tridex(args, dir);
  };
  CHECK(diff((dir / "face.nc").string(), {}).status == 0);  // B has the project's tools
  CommandResult r =
      diff((dir / "raised.nc").string(), {"--tolerance", "0.1", "--html", (dir / "d.html").string(),
                                          "--png", (dir / "d.png").string()});
  CHECK(r.status == 3);
  const json report = json::parse(slurp(dir / "report.json"));
  REQUIRE(!report["regions"].empty());
  CHECK(report["regions"][0]["kind"] == "left_by_b");
  CHECK(report["regions"][0]["lines_b"].dump().find(std::to_string(raised)) != std::string::npos);
  const std::string page = slurp(dir / "d.html");
  CHECK(page.find("left_by_b") != std::string::npos);
  CHECK(page.find("\"file_b\"") != std::string::npos);
  CHECK(slurp(dir / "d.png").substr(1, 3) == "PNG");
  fs::remove_all(dir);
}

}  // namespace test_regress
