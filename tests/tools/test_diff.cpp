// tridex diff and tridex lint (issue 39): one-block post bugs planted in the bundled example's
// tilted-plane operations, each found at its line in B; the same program, two independent blocks
// swapped and an arc split in two give no difference. Coarse lattice (50 cells) to stay fast.
#include <doctest/doctest.h>

#include <algorithm>
#include <nlohmann/json.hpp>

#include "checks/line_alignment.hpp"
#include "checks/lint.hpp"
#include "command_harness.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace test_diff {

const fs::path kExamples = fs::path(TRIDEX_SOURCE_DIR) / "gcode" / "examples";

std::vector<std::string> split(const std::string& text) {
  std::vector<std::string> lines;
  std::istringstream in(text);
  for (std::string line; std::getline(in, line);) lines.push_back(line);
  return lines;
}

std::string join(const std::vector<std::string>& lines) {
  std::string text;
  for (const std::string& line : lines) text += line + "\n";
  return text;
}

// The example's header and its operations from the first tilted plane on (a few hundred lines).
std::vector<std::string> example_excerpt() {
  const std::vector<std::string> all = split(slurp(kExamples / "mold_3plus2.nc"));
  std::vector<std::string> out(all.begin(), all.begin() + 8);
  auto first =
      std::find(all.begin(), all.end(), "(+X TILTED 20 DEG FACE THE BEVEL, 10 MM FLAT END)");
  REQUIRE(first != all.end());
  out.insert(out.end(), first, all.end());
  return out;
}

// 0-based index of the first line equal to `text` at or after `from`.
std::size_t find_line(const std::vector<std::string>& lines, const std::string& text,
                      std::size_t from = 0) {
  auto it = std::find(lines.begin() + static_cast<std::ptrdiff_t>(from), lines.end(), text);
  REQUIRE(it != lines.end());
  return static_cast<std::size_t>(it - lines.begin());
}

struct DiffOutcome {
  CommandResult run;
  json report;
};

DiffOutcome run_diff(const fs::path& dir, const std::vector<std::string>& b) {
  write_text(dir / "clean.nc", join(example_excerpt()));
  write_text(dir / "bug.nc", join(b));
  DiffOutcome o;
  o.run =
      run_tridex({"diff", (dir / "clean.nc").string(), (dir / "bug.nc").string(), "--tools",
                  (kExamples / "mold_3plus2.tools.json").string(), "--stock", "box:0,0,0,100,80,50",
                  "--dexel-res", "50", "--report", (dir / "report.json").string()},
                 dir);
  if (fs::exists(dir / "report.json")) o.report = json::parse(slurp(dir / "report.json"));
  fs::remove(dir / "report.json");
  return o;
}

// Some region names B's 1-based `line` among its lines.
bool region_names(const json& report, int line) {
  for (const json& region : report["regions"])
    for (const json& l : region["lines_b"])
      if (l.get<int>() == line) return true;
  return false;
}

// The lint of B names `line` with `code`.
bool lint_names(const json& report, int line, const std::string& code) {
  for (const json& f : report["lint"])
    if (f["line"].get<int>() == line && f["code"] == code) return true;
  return false;
}

TEST_CASE("diff: the same program twice, and two independent blocks swapped, are the same part") {
  const fs::path dir = scratch("diff-same");
  DiffOutcome same = run_diff(dir, example_excerpt());
  CHECK(same.run.status == 0);
  CHECK(same.report["regions"].empty());
  CHECK(same.report["lint"].empty());
  CHECK(same.report["verdict"] == "same");

  // The slot (T2) and the circular groove (T3): each loads its tool and sets its own plane.
  std::vector<std::string> b = example_excerpt();
  const std::size_t slot = find_line(b, "(+X TILTED 20 DEG SLOT, 8 MM BALL END)");
  const std::size_t groove = find_line(b, "(+X TILTED 20 DEG CIRCULAR GROOVE, 4 MM BALL END)");
  const std::size_t wave = find_line(b, "(+X TILTED 20 DEG ENGRAVE A WAVE, 2 MM BALL END)");
  std::rotate(b.begin() + static_cast<std::ptrdiff_t>(slot),
              b.begin() + static_cast<std::ptrdiff_t>(groove),
              b.begin() + static_cast<std::ptrdiff_t>(wave));
  DiffOutcome swapped = run_diff(dir, b);
  CHECK(swapped.run.status == 0);
  CHECK(swapped.report["regions"].empty());
  CHECK(swapped.report["lint"].empty());
  CHECK(swapped.report["changed_lines"]["b"].get<int>() > 0);  // the texts do differ
  fs::remove_all(dir);
}

TEST_CASE("diff: an arc split into two arcs is the same part") {
  const fs::path dir = scratch("diff-split");
  std::vector<std::string> b = example_excerpt();
  // From (30.72, 6.5) about (26.64, 6.5), clockwise through the bottom to (22.56, 6.5).
  const std::size_t arc = find_line(b, "G2 X22.56 Y6.5 I-4.08 J0. F1800");
  b[arc] = "G2 X26.64 Y2.42 I-4.08 J0. F1800";
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(arc) + 1, "G2 X22.56 Y6.5 I0. J4.08");
  DiffOutcome o = run_diff(dir, b);
  CHECK(o.run.status == 0);
  CHECK(o.report["regions"].empty());
  fs::remove_all(dir);
}

TEST_CASE("diff: a G68.2 angle's sign flipped, and two angles swapped, at the G68.2 line") {
  const fs::path dir = scratch("diff-plane");
  const std::string plane = "G68.2 X100.0 Y40.0 Z22.0 I90.0 J70.0 K0.0";
  for (const std::string& bug : {std::string("G68.2 X100.0 Y40.0 Z22.0 I90.0 J-70.0 K0.0"),
                                 std::string("G68.2 X100.0 Y40.0 Z22.0 I70.0 J90.0 K0.0")}) {
    CAPTURE(bug);
    std::vector<std::string> b = example_excerpt();
    const std::size_t at = find_line(b, plane);
    b[at] = bug;
    DiffOutcome o = run_diff(dir, b);
    CHECK(o.run.status == 3);
    REQUIRE(!o.report["regions"].empty());
    CHECK(region_names(o.report, static_cast<int>(at) + 1));
    const json& region = o.report["regions"][0];
    CHECK(region["volume_mm3"].get<double>() > 1);
    CHECK(region["deepest_point"].size() == 3);
    CHECK(!region["lines_a"].empty());
  }
  fs::remove_all(dir);
}

TEST_CASE("diff: a tool change moved past a cut names the tool change and both tools") {
  const fs::path dir = scratch("diff-tool");
  std::vector<std::string> b = example_excerpt();
  const std::size_t slot = find_line(b, "(+X TILTED 20 DEG SLOT, 8 MM BALL END)");
  const std::size_t change = find_line(b, "T2 M6", slot);
  b.erase(b.begin() + static_cast<std::ptrdiff_t>(change));
  const std::size_t cut = find_line(b, "G1 X17.28 F1500.0", slot);
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(cut) + 1, "T2 M6");  // the slot cut with T1
  DiffOutcome o = run_diff(dir, b);
  CHECK(o.run.status == 3);
  CHECK(region_names(o.report, static_cast<int>(cut) + 2));
  bool tools = false;
  for (const json& region : o.report["regions"])
    tools =
        tools || (region["tools_a"] == json::array({2}) && region["tools_b"] == json::array({1}));
  CHECK(tools);
  fs::remove_all(dir);
}

TEST_CASE("diff: post errors that the lint finds at their line (no or any volume change)") {
  const fs::path dir = scratch("diff-lint");
  struct Planted {
    std::string original, bug, code;
    bool insert = false;  // the bug is a new line before `original`
  };
  const Planted planted[] = {
      {"G2 X30.72 Y6.5 I4.08 J0.", "G2 X30.72 Y6.5 I26.64 J6.5", "arc_centre_mode"},
      {"G0 Z2.0", "G20", "units_change", true},
      {"G43 Z15.0 H2", "Z15.0", "g43_missing"},
      {"G0 Z2.0", "G0 Z2", "integer_coordinate"},
  };
  for (const Planted& p : planted) {
    CAPTURE(p.bug);
    std::vector<std::string> b = example_excerpt();
    const std::size_t at = find_line(b, p.original);
    if (p.insert)
      b.insert(b.begin() + static_cast<std::ptrdiff_t>(at), p.bug);
    else
      b[at] = p.bug;
    DiffOutcome o = run_diff(dir, b);
    CHECK(o.run.status == 3);
    CHECK(lint_names(o.report, static_cast<int>(at) + 1, p.code));
    CHECK(o.run.out.find("bug.nc:" + std::to_string(at + 1) + ": " + p.code) != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("lint: quiet on the bundled examples and the test corpus, standalone and as text") {
  const fs::path dir = scratch("lint-quiet");
  CommandResult r = run_tridex({"lint", (kExamples / "mold_3plus2.nc").string()}, dir);
  CHECK(r.status == 0);
  CHECK(r.out.find("0 lint finding") != std::string::npos);
  std::vector<fs::path> files = {kExamples / "mold_3plus2.nc", kExamples / "mold_3plus2_bc.nc"};
  for (const auto& entry :
       fs::recursive_directory_iterator(fs::path(TRIDEX_SOURCE_DIR) / "tests" / "data" / "gcode"))
    if (entry.is_regular_file() && entry.path().extension() != ".md") files.push_back(entry.path());
  for (const fs::path& file : files) {
    CAPTURE(file);
    // The simultaneous 5-axis programs need their machine's rotary axes: linted by the command.
    if (file.parent_path().filename() == "five_axis") {
      if (file.extension() != ".ngc") continue;
      CommandResult five = run_tridex({"lint", file.string(), "--machine", "ac-trunnion"}, dir);
      CHECK(five.status == 0);
      CHECK(five.out.find(" 0 lint finding") != std::string::npos);
      continue;
    }
    const auto findings = cli::lint_text(slurp(file), file.string(), {});
    CHECK(findings.empty());
  }
  fs::remove_all(dir);
}

TEST_CASE("lint: a stray G20 in a millimetre program, H of another tool, decimal-point input") {
  std::vector<std::string> lines = {"G21 G90", "T1 M6", "G43 H1 Z10."};
  for (int k = 0; k < 60; ++k) lines.push_back("G1 X" + std::to_string(10 + k) + ".5 Y20.25");
  lines.push_back("G20");  // line 64
  for (int k = 0; k < 60; ++k) lines.push_back("G1 X" + std::to_string(10 + k) + ".5 Y20.25");
  lines.push_back("T2 M6");
  lines.push_back("G43 H2 Z10.");
  lines.push_back("T3 M6");
  lines.push_back("G43 H3 Z10.");
  lines.push_back("T4 M6");
  lines.push_back("G43 H1 Z10.");  // line 130: tool 1's length for tool 4
  lines.push_back("G1 X12");       // line 131
  const auto findings = cli::lint_text(join(lines), "p.nc", {});
  REQUIRE(findings.size() == 3);
  CHECK((findings[0].line == 64 && findings[0].code == "units_change"));
  CHECK((findings[1].line == 130 && findings[1].code == "g43_h_mismatch"));
  CHECK((findings[2].line == 131 && findings[2].code == "integer_coordinate"));
  cli::LintSettings calculator;
  calculator.decimal_point_input = true;  // X12 is 12 mm: nothing to say
  CHECK(cli::lint_text(join(lines), "p.nc", calculator).size() == 2);
  // Haas's TCPC G234 H n applies the length as G43 does: after it, Z moves are not g43_missing.
  const std::vector<std::string> haas = {
      "G90 G21", "T1 M6", "G43 H1 Z10.", "T2 M6", "G234 H2 X0. Y0. Z10.", "G1 Z-1.5"};
  CHECK(cli::lint_text(join(haas), "p.nc", {}).empty());
  std::vector<std::string> missing = haas;
  missing[4] = "G0 X0. Y0. Z10.";  // no length applied after T2
  const auto found = cli::lint_text(join(missing), "p.nc", {});
  REQUIRE(found.size() == 1);
  CHECK((found[0].line == 5 && found[0].code == "g43_missing"));
}

// `moves A --diff B`'s JSON lines.
std::vector<json> moves_diff(const fs::path& dir, const std::vector<std::string>& b, int status) {
  write_text(dir / "clean.nc", join(example_excerpt()));
  write_text(dir / "other.nc", join(b));
  CommandResult r =
      run_tridex({"moves", (dir / "clean.nc").string(), "--diff", (dir / "other.nc").string(),
                  "--tools", (kExamples / "mold_3plus2.tools.json").string()},
                 dir);
  CHECK(r.status == status);
  std::vector<json> records;
  for (const std::string& line : split(r.out)) records.push_back(json::parse(line));
  return records;
}

TEST_CASE("moves --diff: a swapped block is one move, a split arc none") {
  const fs::path dir = scratch("moves-diff");
  std::vector<json> same = moves_diff(dir, example_excerpt(), 0);
  REQUIRE(same.size() == 1);
  CHECK(same[0]["summary"]["changes"] == 0);

  std::vector<std::string> b = example_excerpt();
  const std::size_t slot = find_line(b, "(+X TILTED 20 DEG SLOT, 8 MM BALL END)");
  const std::size_t groove = find_line(b, "(+X TILTED 20 DEG CIRCULAR GROOVE, 4 MM BALL END)");
  const std::size_t wave = find_line(b, "(+X TILTED 20 DEG ENGRAVE A WAVE, 2 MM BALL END)");
  std::rotate(b.begin() + static_cast<std::ptrdiff_t>(slot),
              b.begin() + static_cast<std::ptrdiff_t>(groove),
              b.begin() + static_cast<std::ptrdiff_t>(wave));
  std::vector<json> swapped = moves_diff(dir, b, 3);
  REQUIRE(swapped.size() == 2);
  CHECK(swapped[0]["change"] == "moved");
  CHECK(swapped[1]["summary"]["changes"] == 1);

  b = example_excerpt();
  const std::size_t arc = find_line(b, "G2 X22.56 Y6.5 I-4.08 J0. F1800");
  b[arc] = "G2 X26.64 Y2.42 I-4.08 J0. F1800";
  b.insert(b.begin() + static_cast<std::ptrdiff_t>(arc) + 1, "G2 X22.56 Y6.5 I0. J4.08");
  std::vector<json> split_arc = moves_diff(dir, b, 0);
  REQUIRE(split_arc.size() == 1);
  CHECK(split_arc[0]["summary"]["splits"] == 1);
  fs::remove_all(dir);
}

TEST_CASE("line alignment: a moved line is one deletion and one insertion") {
  const cli::LineAlignment a = cli::align_lines("A\nB\nC\nD\nE\n", "A\nC\nD\nB\nE\n");
  CHECK(a.changed_a == std::vector<char>{0, 0, 1, 0, 0, 0});
  CHECK(a.changed_b == std::vector<char>{0, 0, 0, 0, 1, 0});
  CHECK(a.a_to_b[3] == 2);  // C
  CHECK(a.b_to_a[5] == 5);  // E
  // Comments, spaces and sequence numbers do not count.
  const cli::LineAlignment b = cli::align_lines("N10 G1 X1 (cut)\n", "g1x1\n");
  CHECK(b.changed_b == std::vector<char>{0, 0});
}

}  // namespace test_diff
