// `tridex check` on simultaneous 5-axis programs (tests/data/gcode/five_axis): the moves whose
// tool turns are milled by the dexel sweep before the comparison (the right program passes
// against its own result), a gouge they make is located at their line as other gouges are, and
// a rapid turn of the table through the material is a rapid cut.
#include <doctest/doctest.h>

#include <string>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"

namespace test_simultaneous_check {

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

const std::string kData = std::string(TRIDEX_SOURCE_DIR) + "/tests/data/gcode/five_axis/";
const std::string kStock = "box:-30,-30,-10,30,30,0";

// c_groove.ngc with the turning cut at depth `z` (line 8: G1 C90, the table turning under a
// standing 6 mm flat end).
std::string groove(const std::string& z) {
  return "(a C-turning groove)\n(on ac-trunnion)\nG21 G90 G17 G40 G49 G80\nT1 M6\nS8000 M3\n"
         "G0 X20 Y0 Z10 A0 C0\nG1 Z" +
         z + " F300\nG1 C90 F500\nG1 Z10\nM5\nM2\n";
}

// ac-trunnion's kinematics without its parts: the groove (2 mm below the work zero, which lies on
// the platter) would meet the platter, a machine collision that fails check.
std::vector<std::string> machine_args(const fs::path& dir) {
  write_text(dir / "bare.json", R"({"base": "ac-trunnion", "components": []})");
  return {"--machine",    (dir / "bare.json").string(),
          "--tools",      kData + "tools.tbl",
          "--tool-units", "mm",
          "--stock",      kStock,
          "--dexel-cell", "0.6",
          "--report",     (dir / "report.json").string()};
}

CommandResult check_text(const fs::path& dir, const std::string& text) {
  write_text(dir / "p.ngc", text);
  std::vector<std::string> args{"check",
                                (dir / "p.ngc").string(),
                                "--design",
                                (dir / "design.stl").string(),
                                "--lattice-only",
                                "--tolerance",
                                "0.1"};
  for (const std::string& a : machine_args(dir)) args.push_back(a);
  return run_tridex(args, dir);
}

CommandResult check(const fs::path& dir, const std::string& z) {
  return check_text(dir, groove(z));
}

// A scratch folder holding the design: the right groove's simulated result.
fs::path with_design(const std::string& name) {
  fs::path dir = scratch(name);
  write_text(dir / "good.ngc", groove("-2"));
  std::vector<std::string> made{"simulate", (dir / "good.ngc").string(), "-o",
                                (dir / "design.stl").string(), "-q"};
  for (const std::string& a : machine_args(dir)) made.push_back(a);
  CommandResult design = run_tridex(made, dir);
  INFO(design.err);
  REQUIRE(design.status == 0);
  return dir;
}

TEST_CASE("check: simultaneous moves are milled before the comparison, gouges at their line") {
  fs::path dir = with_design("simultaneous-check");

  // The same program passes: the turning cut is milled (without it the groove would be excess).
  CommandResult same = check(dir, "-2");
  INFO(same.out);
  INFO(same.err);
  CHECK(same.status == 0);
  json report = json::parse(slurp(dir / "report.json"));
  CHECK(report["verdict"] == "pass");
  CHECK(report["gouges"].empty());
  CHECK(report["excess"].empty());

  // 0.5 mm too deep: the turning move gouges the groove's floor along its arc, and the gouge
  // names its line (8) beside the plunge's (7).
  CommandResult deep = check(dir, "-2.5");
  INFO(deep.out);
  CHECK(deep.status == 3);
  report = json::parse(slurp(dir / "report.json"));
  CHECK(report["verdict"] == "fail");
  REQUIRE(!report["gouges"].empty());
  const json& gouge = report["gouges"][0];
  CHECK(gouge["depth_mm"].get<double>() == doctest::Approx(0.5).epsilon(0.4 / 0.5));
  const std::string lines = gouge["lines"].dump();
  CHECK(lines.find("8") != std::string::npos);
  CHECK(deep.out.find("p.ngc:8") != std::string::npos);

  // 0.5 mm too shallow: the floor is excess, nearest the turning move.
  CommandResult shallow = check(dir, "-1.5");
  INFO(shallow.out);
  CHECK(shallow.status == 3);
  report = json::parse(slurp(dir / "report.json"));
  REQUIRE(!report["excess"].empty());
  CHECK(report["excess"][0]["lines"].dump().find("8") != std::string::npos);

  fs::remove_all(dir);
}

TEST_CASE("check: a rapid turn of the table through the stock is a rapid cut") {
  fs::path dir = with_design("simultaneous-check-rapid");
  json report;
  // A rapid turn of the table (G0 C180, raw: no move of its own) with the tool still 2 mm deep
  // sweeps it through the stock: a rapid cut, at the line of the move after it (10).
  std::string text = groove("-2");
  const std::string turn = "G1 C90 F500\n";
  text.insert(text.find(turn) + turn.size(), "G0 C180\n");
  CommandResult rapid = check_text(dir, text);
  INFO(rapid.out);
  CHECK(rapid.status == 3);
  report = json::parse(slurp(dir / "report.json"));
  REQUIRE(report["rapid_cuts"].size() == 1);
  CHECK(report["rapid_cuts"][0]["line"] == 10);
  CHECK(report["rapid_cuts"][0]["depth_mm"].get<double>() == doctest::Approx(2).epsilon(0.1));
  // Turned above the stock, it cuts nothing.
  text = groove("-2");
  text.insert(text.find(turn) + turn.size(), "G1 Z10\nG0 C180\n");
  rapid = check_text(dir, text);
  report = json::parse(slurp(dir / "report.json"));
  CHECK(report["rapid_cuts"].empty());
  fs::remove_all(dir);
}

}  // namespace test_simultaneous_check
