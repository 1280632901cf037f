// Issue 30 end to end: a horizontal machining centre's program with a shop's machine file (its
// variables, M-codes and macro folder), and a LinuxCNC tool table with a zero-diameter tool.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"
#include "inputs/tool_table.hpp"

using namespace tridex;
using namespace tridex::test;
using namespace tridex::cli;
using nlohmann::json;

namespace test_posts_cli {

std::vector<json> move_lines(const std::string& out) {
  std::vector<json> moves;
  std::istringstream in(out);
  for (std::string line; std::getline(in, line);)
    if (!line.empty()) moves.push_back(json::parse(line));
  return moves;
}

TEST_CASE("moves: an HMC program runs with the shop's variables, M-codes and macro folder") {
  fs::path dir = scratch("posts-hmc");
  fs::create_directories(dir / "macros");
  // The fixture's persistent variable gives G54's B; the macro library holds O140001.
  write_text(dir / "hmc.json", R"({"base": "hmc-b-table", "start": [0, 0, 500],
    "variables": {"#901004": 0.25, "#901001": 10},
    "m_codes": [10, 11, 60, 71, 8, 9], "subprograms": ["macros"]})");
  write_text(dir / "macros" / "O140001.nc",
             "O140001 (FACE)\nG0 X#24 Y#4 Z[#26 + 5]\nG1 Z#26 F#9\nG0 Z[#26 + 50]\nM99\n");
  write_text(dir / "part.nc",
             "%\nO7001 (HMC PART)\nG21 G90 G17\nM60\nM71\nT13 M6\n"
             "G10 L2 P1 X#901001 Y0 Z0 B#901004\nM11\nG0 G54 B90.\nM10\n"
             "G54 G65 P140001 X180.95 I155. Z49.984 F500. M0.07\nM11\nG0 B0.\nM10\nM30\n%\n");
  CommandResult r = run_tridex(
      {"moves", (dir / "part.nc").string(), "--machine", (dir / "hmc.json").string()}, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.err.find("M60") == std::string::npos);  // declared: no warning
  std::vector<json> moves = move_lines(r.out);
  REQUIRE(!moves.empty());
  bool face = false;
  for (const json& m : moves)
    face |= m["kind"] == "feed" && std::abs(m["machine"][0].get<double>() - 190.95) < 1e-9 &&
            std::abs(m["machine"][2].get<double>() - 49.984) < 1e-9 &&
            std::abs(m["rotary"]["B"].get<double>() - 90) < 1e-9;
  // The macro's cut in G54 (X offset #901001 = 10), at B90 of the part (B90.25 on the machine).
  CHECK(face);
}

// LinuxCNC reads a tool without a diameter (`D0`) as a tool that cuts nothing: G41 with it
// offsets by 0, as rs274 does with the same table.
TEST_CASE("moves: a LinuxCNC table's D0 tool is in the table, G41 with it offsets by 0") {
  ToolTable table = ToolTable::from_tbl("T1 P1 D0.25 Z0\nT2 P2 Z0 D0 ;probe\nT3 P3 Z1\n", "t.tbl");
  CHECK(table.find(2) == nullptr);  // no cutter
  CHECK(table.zero_diameter() == std::set<int>{2, 3});
  fs::path dir = scratch("posts-d0");
  write_text(dir / "t.tbl", "T2 P2 Z0 D0 ;a probe, or a tool not measured yet\n");
  write_text(dir / "p.ngc",
             "G20 G90 G17\nT2 M6\nG0 X0 Y0 Z0.1\nG41 D002\nG1 X1 Y0 F10\nY1\nG40\nG0 X0 Y0\nM2\n");
  CommandResult r = run_tridex({"moves", (dir / "p.ngc").string(), "--machine", "linuxcnc",
                                "--tools", (dir / "t.tbl").string()},
                               dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  std::vector<json> moves = move_lines(r.out);
  REQUIRE(moves.size() >= 3);
  CHECK(moves[1]["end"][0].get<double>() == doctest::Approx(25.4));  // no offset
  CHECK(moves[2]["end"][1].get<double>() == doctest::Approx(25.4));
}

}  // namespace test_posts_cli
