// Reliability, round 3 (issue 36): the audit's rows through the built command. Inputs are never
// overwritten, whatever path names them (the machine file, a subprogram found while the program
// runs); numbers are checked after unit conversion; JSON outputs are JSON; text that is not UTF-8
// or holds control characters is transcoded or escaped; recursion and option values are bounded.
#include <doctest/doctest.h>

#include <unistd.h>

#include <map>
#include <set>
#include <sstream>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"

using namespace tridex::test;

namespace test_reliability {

const std::string kProgram =
    "G21 G90\nT1 M6\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10 Y5\nG0 Z5\nM30\n";
const std::string kCalling =
    "G21 G90\nT1 M6\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nM98 P9810\nG0 Z5\nM30\n";
const std::string kSubprogram = "O9810\nG1 X3 Y3\nM99\n";
const std::string kTools =
    R"({"1": {"units": "mm", "shape": "ballnose", "diameter": 4, "length": 20}})";

std::set<std::string> listing(const fs::path& dir) {
  std::set<std::string> names;
  for (const auto& entry : fs::directory_iterator(dir))
    names.insert(entry.path().filename().string());
  return names;
}

// A run that must be refused as bad input, naming `expected`, and leave the folder as it was.
void refused(const fs::path& dir, const std::vector<std::string>& args,
             const std::vector<std::string>& expected) {
  std::map<std::string, std::string> before;
  for (const std::string& name : listing(dir)) before[name] = slurp(dir / name);
  CommandResult r = run_tridex(args, dir);
  INFO(r.err);
  CHECK(r.status == 2);
  for (const std::string& text : expected) CHECK(r.err.find(text) != std::string::npos);
  std::map<std::string, std::string> after;
  for (const std::string& name : listing(dir)) after[name] = slurp(dir / name);
  CHECK(after == before);  // nothing written, nothing replaced
}

std::string at(const fs::path& dir, const std::string& name) { return (dir / name).string(); }

fs::path setup(const std::string& name) {
  fs::path dir = scratch("rel-" + name);
  write_text(dir / "p.nc", kProgram);
  write_text(dir / "main.nc", kCalling);
  write_text(dir / "O9810.nc", kSubprogram);
  write_text(dir / "t.json", kTools);
  write_text(dir / "m.json", "{}");
  return dir;
}

// Every line of `text` parses as strict JSON (nlohmann rejects NaN, infinity and bad UTF-8).
bool json_lines(const std::string& text) {
  std::istringstream in(text);
  std::string line;
  int lines = 0;
  while (std::getline(in, line)) {
    if (!nlohmann::json::accept(line)) return false;
    ++lines;
  }
  return lines > 0;
}

TEST_CASE("row 1: an output naming the machine file, the tool table or the program is refused") {
  fs::path d = setup("row1");
  refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "m.json"), "-o", at(d, "m.json")},
          {"would overwrite an input", "m.json"});
  refused(d,
          {"simulate", at(d, "p.nc"), "--tools", at(d, "t.json"), "--machine", at(d, "m.json"),
           "--report", at(d, "m.json")},
          {"--report", "would overwrite an input"});
  refused(d,
          {"simulate", at(d, "p.nc"), "--tools", at(d, "t.json"), "--machine", at(d, "m.json"),
           "--html", at(d, "m.json")},
          {"--html", "would overwrite an input"});
  refused(d, {"groups", at(d, "p.nc"), "--tools", at(d, "t.json"), "-o", at(d, "t.json")},
          {"would overwrite an input"});
  // By identity: a hard link to the machine file is the machine file.
  fs::create_hard_link(d / "m.json", d / "link.json");
  refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "m.json"), "-o", at(d, "link.json")},
          {"would overwrite an input"});
  fs::remove_all(d);
}

TEST_CASE("row 2: an output naming a subprogram the program calls is refused, nothing written") {
  fs::path d = setup("row2");
  refused(d, {"moves", at(d, "main.nc"), "-o", at(d, "O9810.nc")},
          {"would overwrite an input", "O9810.nc"});
  refused(d, {"groups", at(d, "main.nc"), "-o", at(d, "O9810.nc")}, {"would overwrite an input"});
  refused(d,
          {"simulate", at(d, "main.nc"), "--tools", at(d, "t.json"), "--report", at(d, "r.json"),
           "--html", at(d, "O9810.nc")},
          {"--html", "would overwrite an input"});
  // Found by its O number whatever its name, and in a --subprograms folder.
  fs::create_directories(d / "subs");
  fs::rename(d / "O9810.nc", d / "subs" / "holes.nc");
  refused(d / "subs",
          {"moves", at(d, "main.nc"), "--subprograms", at(d, "subs"), "-o", at(d, "subs/holes.nc")},
          {"would overwrite an input", "holes.nc"});
  // Without the clash the same run works: the refusal is the output's, not the program's.
  CommandResult ok = run_tridex(
      {"moves", at(d, "main.nc"), "--subprograms", at(d, "subs"), "-o", at(d, "moves.jsonl")}, d);
  CHECK(ok.status == 0);
  CHECK(json_lines(slurp(d / "moves.jsonl")));
  fs::remove_all(d);
}

TEST_CASE("row 3: a machine file nested 20,000 deep is refused, not a crash") {
  fs::path d = setup("row3");
  std::string deep = "{\"kinematics\":";
  for (int k = 0; k < 20000; ++k) deep += "{\"profile\":";
  deep += "\"x\"";
  deep += std::string(20000, '}') + "}";
  write_text(d / "deep.json", deep);
  refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "deep.json")}, {"deep.json", "nested"});
  fs::remove_all(d);
}

TEST_CASE("rows 4 and 11: tool numbers are checked after the conversion from inches") {
  fs::path d = setup("row4");
  write_text(d / "inch.json", R"({"linear_units": "inch"})");
  write_text(d / "big.tbl", "T1 P1 D0.25 Z1e308 ;big\n");
  refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "inch.json"), "--tools", at(d, "big.tbl")},
          {"big.tbl", "\"Z\"", "after unit conversion"});
  write_text(
      d / "len.json",
      R"({"1": {"units": "inch", "shape": "ballnose", "diameter": 0.2, "tool-length": 1e307}})");
  refused(d, {"moves", at(d, "p.nc"), "--tools", at(d, "len.json")}, {"len.json", "tool-length"});
  write_text(d / "holder.json",
             R"({"1": {"units": "inch", "shape": "ballnose", "diameter": 0.2, "stick-out": 1,
                 "holder": [{"bottom-diameter": 1, "top-diameter": 1, "length": 1e307}]}})");
  refused(d, {"simulate", at(d, "p.nc"), "--tools", at(d, "holder.json")},
          {"holder.json", "tool 1", "holder section 1"});
  write_text(d / "fusion.json", R"({"data": [
    {"type": "flat end mill", "unit": "inches", "description": "big holder",
     "geometry": {"DC": 0.25, "LCF": 0.75, "LB": 1.25, "OAL": 2.5, "SFDM": 0.25, "RE": 0},
     "holder": {"segments": [{"height": 1e307, "lower-diameter": 1, "upper-diameter": 1}]},
     "post-process": {"number": 1}}]})");
  refused(d, {"simulate", at(d, "p.nc"), "--tools", at(d, "fusion.json")},
          {"fusion.json", "tool 1", "holder section 1"});
  // A .tbl with CR-only line ends (classic Mac) reads as two tools, not one line.
  write_text(d / "cr.tbl", "T1 P1 D4 Z20\rT2 P2 D3 Z2\r");
  CommandResult cr = run_tridex({"simulate", at(d, "p.nc"), "--tools", at(d, "cr.tbl"), "-q"}, d);
  CHECK(cr.status == 0);
  fs::remove_all(d);
}

TEST_CASE("row 5: Latin-1 comments and non-UTF-8 file names make valid JSON") {
  fs::path d = setup("row5");
  write_text(d / "lat.nc",
             "G21 G90\n(Fr\xe4ser \xd8"
             "6)\nT1 M6\nS1000 M3\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10 Y5\nG0 Z5\nM30\n");
  CommandResult html = run_tridex(
      {"simulate", at(d, "lat.nc"), "--tools", at(d, "t.json"), "--html", at(d, "l.html"), "-q"},
      d);
  INFO(html.err);
  CHECK(html.status == 0);
  CHECK(slurp(d / "l.html")
            .find("Fr\xc3\xa4ser \xc3\x98"
                  "6") != std::string::npos);  // transcoded to UTF-8
  const std::string odd = "n\xff.nc";
  fs::copy_file(d / "p.nc", d / odd);
  CommandResult report = run_tridex(
      {"simulate", at(d, odd), "--tools", at(d, "t.json"), "--report", at(d, "r.json"), "-q"}, d);
  CHECK(report.status == 0);
  nlohmann::json parsed = nlohmann::json::parse(slurp(d / "r.json"));  // throws on bad UTF-8
  CHECK(parsed["program"].get<std::string>().find("n\xc3\xbf.nc") != std::string::npos);
  CommandResult groups = run_tridex({"groups", at(d, odd), "-o", at(d, "g.json")}, d);
  CHECK(groups.status == 0);
  CHECK(nlohmann::json::accept(slurp(d / "g.json")));
  fs::remove_all(d);
}

TEST_CASE("row 6: forbidden_m_codes covers the M-codes tridex acts on") {
  fs::path d = setup("row6");
  write_text(d / "f.json", R"({"forbidden_m_codes": [0, 3, 6, 30]})");
  refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "f.json")},
          {"p.nc:2", "M6 is not allowed on this machine"});
  write_text(d / "f99.json", R"({"forbidden_m_codes": [99]})");
  refused(d, {"moves", at(d, "main.nc"), "--machine", at(d, "f99.json")}, {"M99 is not allowed"});
  write_text(d / "f30.json", R"({"forbidden_m_codes": [30]})");
  refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "f30.json")}, {"p.nc:8", "M30"});
  fs::remove_all(d);
}

TEST_CASE("row 7: a variable given twice under two spellings is refused") {
  fs::path d = setup("row7");
  for (const char* variables :
       {R"({"#5": 1, "#05": 2})", R"({"#<_a>": 1, "#<_A>": 2})", R"({"# 5": 1})"}) {
    write_text(d / "v.json", std::string("{\"variables\": ") + variables + "}");
    refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "v.json")}, {"v.json", "variables"});
  }
  fs::remove_all(d);
}

TEST_CASE("row 8: machine-file numbers beyond range name the machine file") {
  fs::path d = setup("row8");
  write_text(d / "g28.nc", "G21 G90\nG28\nM30\n");
  write_text(d / "h.json", R"({"home": [1e308, 1e308, 1e308]})");
  refused(d, {"groups", at(d, "g28.nc"), "--machine", at(d, "h.json")}, {"h.json", "\"home\""});
  write_text(d / "v.json", R"({"variables": {"#5221": 1e308}})");
  refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "v.json")}, {"v.json", "#5221"});
  write_text(d / "k.json", R"({"kinematics": {"type": "table-table", "axes": [{"letter": "A",
             "on": "table", "direction": [1, 0, 0], "pivot": [0, 0, 1e300]}]}})");
  refused(d, {"moves", at(d, "p.nc"), "--machine", at(d, "k.json")}, {"k.json", "pivot"});
  fs::remove_all(d);
}

TEST_CASE("row 10: empty option values are bad input") {
  fs::path d = setup("row10");
  refused(d, {"simulate", at(d, "p.nc"), "--tools", at(d, "t.json"), "--html", ""},
          {"--html", "empty"});
  refused(d, {"moves", at(d, "p.nc"), "--machine", ""}, {"--machine", "empty"});
  refused(d, {"moves", at(d, "p.nc"), "--subprograms", ""}, {"--subprograms", "empty"});
  refused(d, {"moves", ""}, {"empty"});
  fs::remove_all(d);
}

TEST_CASE("row 12: control characters of a tool description never reach the terminal") {
  fs::path d = setup("row12");
  write_text(d / "fusion.json", R"({"data": [
    {"type": "flat end mill", "unit": "millimeters",
     "description": "\u001b]0;pwned\u0007\u001b[2J",
     "geometry": {"DC": 6, "LCF": 18, "LB": 70, "OAL": 60, "SFDM": 6, "RE": 0},
     "post-process": {"number": 1}}]})");
  CommandResult r = run_tridex({"simulate", at(d, "p.nc"), "--tools", at(d, "fusion.json")}, d);
  INFO(r.err);
  CHECK(r.status == 2);
  CHECK(r.err.find('\x1b') == std::string::npos);
  CHECK(r.err.find('\x07') == std::string::npos);
  CHECK(r.err.find("\\x1b]0;pwned") != std::string::npos);  // shown, escaped
  fs::remove_all(d);
}

TEST_CASE("row 13: sizes beyond range are bad input, not a failed run") {
  fs::path d = setup("row13");
  const std::vector<std::string> base = {"simulate", at(d, "p.nc"), "--tools", at(d, "t.json")};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return args;
  };
  refused(d, with({"--zmap-cell", "1e300"}), {"--zmap-cell"});
  refused(d, with({"--stock", "box:-1e200,-1e200,-1e200,1e200,1e200,1e200"}), {"--stock"});
  refused(d, with({"--stock", "auto:1e308"}), {"--stock"});
  write_text(d / "p.camotics", R"({"files": ["p.nc"], "tools": )" + kTools +
                                   R"(, "workpiece": {"automatic": true, "margin": 1e308}})");
  refused(d, {"simulate", at(d, "p.camotics")}, {"p.camotics", "margin"});
  fs::remove_all(d);
}

TEST_CASE("row 14: an output name too long is refused before the work") {
  fs::path d = setup("row14");
  const std::string long_name(250, 'a');
  refused(d,
          {"simulate", at(d, "p.nc"), "--tools", at(d, "t.json"), "-o", at(d, "r.stl"), "--report",
           at(d, long_name)},
          {"--report", "too long"});
  refused(d, {"moves", at(d, "p.nc"), "-o", at(d, long_name)}, {"-o", "too long"});
  fs::remove_all(d);
}

TEST_CASE("moves writes strict JSON Lines") {
  fs::path d = setup("lines");
  CommandResult r = run_tridex({"moves", at(d, "main.nc")}, d);
  CHECK(r.status == 0);
  CHECK(json_lines(r.out));
  fs::remove_all(d);
}

TEST_CASE("row 9: --max-moves bounds a loop of huge arcs, for moves too") {
  fs::path d = setup("row9");
  write_text(d / "loop.nc",
             "G21 G90 G17\nT1 M6\nG0 X0 Y0 Z0\n#1=0\nWHILE[#1LT1000000]DO1\nG2 X0 Y0 I1000000 J0 "
             "F100\n#1=#1+1\nEND1\nM30\n");
  refused(d, {"moves", at(d, "loop.nc"), "--max-moves", "300000", "-o", at(d, "m.jsonl")},
          {"loop.nc:6", "--max-moves 300000"});
  refused(d, {"groups", at(d, "loop.nc"), "--max-moves", "300000"}, {"--max-moves"});
  fs::remove_all(d);
}

// The cut measured on a lattice over the moves' reach: tests/tools/test_reach_lattice.cpp.
TEST_CASE("row 15: a stock around the whole toolpath: the cut measured, never negative") {
  fs::path d = setup("row15");
  CommandResult r = run_tridex({"simulate", at(d, "p.nc"), "--tools", at(d, "t.json"), "--stock",
                                "box:-5000,-5000,-10,5000,5000,0", "--report", at(d, "r.json")},
                               d);
  INFO(r.err);
  REQUIRE(r.status == 0);
  nlohmann::json report = nlohmann::json::parse(slurp(d / "r.json"));
  CHECK(report["result"]["removed_mm3"].get<double>() > 0);
  // The moves do reach this stock: "no move reaches the stock" would be false.
  CHECK(r.err.find("no move reaches") == std::string::npos);
  CHECK(r.err.find("the lattice covers only the part of the stock the moves reach") !=
        std::string::npos);
  fs::remove_all(d);
}

}  // namespace test_reliability
