// The --html page's writer (tools/cli/outputs/html_report.*): base64 against RFC 4648's vectors,
// the display mesh against its budget and the triangles it must keep, the thinned toolpath against
// the moves (every stop reachable in program order, every move within the tolerance of the segment
// that stands for it), the program order across groups and files, the page's data against the
// report, and pages that say when there is nothing to show. The page in a browser: tests/html
// (CTest's html_report_browser).
#include <doctest/doctest.h>

#include <array>
#include <cmath>
#include <set>

#include <nlohmann/json.hpp>

#include "checks/deviation.hpp"
#include "command_harness.hpp"
#include "outputs/compressed_text.hpp"
#include "outputs/html_report.hpp"
#include "tridex/gcode/interpreter.hpp"

using namespace tridex;
using namespace tridex::cli;
using namespace tridex::test;
using nlohmann::json;

namespace {

// The JSON inside the page's tridex-data block.
json page_data(const std::string& html) {
  const std::string open = "<script type=\"application/json\" id=\"tridex-data\">";
  const std::size_t start = html.find(open);
  REQUIRE(start != std::string::npos);
  const std::size_t end = html.find("</script>", start);
  REQUIRE(end != std::string::npos);
  return json::parse(html.substr(start + open.size(), end - start - open.size()));
}

// Base64 decoded (RFC 4648, written here rather than taken from the writer under test).
std::string html_unbase64(const std::string& text) {
  const std::string digits = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  std::uint32_t bits = 0;
  int count = 0;
  for (char c : text) {
    if (c == '=') break;
    bits = bits << 6 | static_cast<std::uint32_t>(digits.find(c));
    if ((count += 6) >= 8) out += static_cast<char>((bits >> (count -= 8)) & 0xff);
  }
  return out;
}

// A page file's compressed chunks of lines, inflated and joined: its text as the slider sees it.
std::string html_chunked_text(const json& file) {
  std::string text;
  for (const json& chunk : file["chunks"])
    text += inflate_raw(html_unbase64(chunk.get<std::string>()));
  return text;
}

// A heightfield of n × n cells (2 n² triangles), gently curved so that simplifying costs error.
Mesh heightfield(int n) {
  Mesh m;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) {
      const double x = 100.0 * i / n, y = 100.0 * j / n;
      m.positions.emplace_back(x, y, 5 * std::sin(x / 15) * std::cos(y / 20));
    }
  auto at = [&](int i, int j) { return static_cast<unsigned>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      m.triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      m.triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  return m;
}

gcode::Move move(int line, gcode::MoveKind kind, Vec3 start, Vec3 end, int tool = 1) {
  gcode::Move m;
  m.line = line;
  m.kind = kind;
  m.start = start;
  m.end = end;
  m.tool = tool;
  m.feed = kind == gcode::MoveKind::rapid ? 0 : 600;
  return m;
}

double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  const Vec3 ab = b - a;
  const double t =
      glm::dot(ab, ab) > 0 ? std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0) : 0.0;
  return glm::length(p - (a + t * ab));
}

}  // namespace

TEST_CASE("base64 as RFC 4648 §10") {
  auto encode = [](const std::string& s) {
    return base64({reinterpret_cast<const std::uint8_t*>(s.data()), s.size()});
  };
  CHECK(encode("") == "");
  CHECK(encode("f") == "Zg==");
  CHECK(encode("fo") == "Zm8=");
  CHECK(encode("foo") == "Zm9v");
  CHECK(encode("foob") == "Zm9vYg==");
  CHECK(encode("fooba") == "Zm9vYmE=");
  CHECK(encode("foobar") == "Zm9vYmFy");
  const std::vector<std::uint8_t> high = {0xff, 0xfe, 0x00};
  CHECK(base64(high) == "//4A");
}

TEST_CASE("the display mesh meets its budget and keeps every out-of-tolerance triangle as it was") {
  const Mesh mesh = heightfield(120);  // 28,800 triangles
  // A gouge in a disc around (30, 60) and excess around (70, 30).
  std::vector<double> deviation(mesh.positions.size(), 0.0);
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    const glm::vec3& p = mesh.positions[v];
    if (std::hypot(p.x - 30, p.y - 60) < 6) deviation[v] = -0.5;
    if (std::hypot(p.x - 70, p.y - 30) < 4) deviation[v] = 0.3;
  }
  const std::size_t budget = 3000;
  DisplayMesh shown = simplify_for_display(mesh, deviation, 0.1, 0.1, budget);
  REQUIRE(shown.indices.size() % 3 == 0);
  CHECK(shown.indices.size() / 3 <= budget);
  CHECK(shown.indices.size() / 3 > budget / 2);  // not simplified further than needed
  REQUIRE(shown.deviation.size() == shown.positions.size());
  // Every shown vertex is an input vertex with its deviation.
  std::map<std::array<float, 3>, double> input;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    input[{mesh.positions[v].x, mesh.positions[v].y, mesh.positions[v].z}] = deviation[v];
  for (std::size_t v = 0; v < shown.positions.size(); ++v) {
    auto found = input.find({shown.positions[v].x, shown.positions[v].y, shown.positions[v].z});
    REQUIRE(found != input.end());
    CHECK(static_cast<float>(found->second) == shown.deviation[v]);
  }
  // Every triangle touching an out-of-tolerance vertex is still there.
  std::set<std::array<std::uint32_t, 3>> triangles;
  std::map<std::array<float, 3>, std::uint32_t> index_of;
  for (std::size_t v = 0; v < shown.positions.size(); ++v)
    index_of[{shown.positions[v].x, shown.positions[v].y, shown.positions[v].z}] =
        static_cast<std::uint32_t>(v);
  for (std::size_t k = 0; k < shown.indices.size(); k += 3)
    triangles.insert({shown.indices[k], shown.indices[k + 1], shown.indices[k + 2]});
  std::size_t flagged = 0;
  for (const glm::uvec3& t : mesh.triangles) {
    if (deviation[t.x] == 0 && deviation[t.y] == 0 && deviation[t.z] == 0) continue;
    ++flagged;
    std::array<std::uint32_t, 3> mapped{};
    for (int k = 0; k < 3; ++k) {
      const glm::vec3& p = mesh.positions[t[k]];
      REQUIRE(index_of.count({p.x, p.y, p.z}));
      mapped[static_cast<std::size_t>(k)] = index_of[{p.x, p.y, p.z}];
    }
    CHECK(triangles.count(mapped) == 1);
  }
  CHECK(flagged > 100);
  // Without deviations the same budget holds; a mesh within it is merged where flat (all but the
  // open border, which stays: 160 vertices there need about as many triangles).
  CHECK(simplify_for_display(mesh, {}, 0, 0, budget).indices.size() / 3 <= budget);
  Mesh flat = heightfield(40);
  for (glm::vec3& p : flat.positions) p.z = 0;
  const std::size_t flat_shown = simplify_for_display(flat, {}, 0, 0, 1'000'000).indices.size() / 3;
  CHECK(flat_shown < 3200 / 10);
  // The same grid curved keeps more (the first error bound holds the curvature).
  CHECK(simplify_for_display(heightfield(40), {}, 0, 0, 1'000'000).indices.size() / 3 >
        flat_shown + 100);
}

TEST_CASE("the display mesh keeps sharp edges: every input vertex near the simplified surface") {
  // Terraces: flat steps joined by steep one-cell walls, so every wall meets its terraces at a
  // crease. Simplified within the budget, the flat parts merge and the creases stay where they
  // are: every input vertex lies within the first error bound (5e-4 of the extent) of the shown
  // surface, up to the quadric's approximation of it (a factor of 2 here).
  Mesh terraces = heightfield(60);
  for (glm::vec3& p : terraces.positions) p.z = 5 * std::floor(p.x / 25.01f) + (p.y > 70 ? 3 : 0);
  const DisplayMesh shown = simplify_for_display(terraces, {}, 0, 0, 1'000'000);
  CHECK(shown.indices.size() / 3 < terraces.triangles.size() / 10);
  Mesh simplified;
  simplified.positions = shown.positions;
  for (std::size_t k = 0; k < shown.indices.size(); k += 3)
    simplified.triangles.emplace_back(shown.indices[k], shown.indices[k + 1], shown.indices[k + 2]);
  const DistanceTree tree(simplified);
  const double extent = glm::length(terraces.bounds().size());
  double farthest = 0;
  for (const glm::vec3& p : terraces.positions)
    farthest = std::max(farthest, tree.nearest(Vec3(p)).distance);
  CHECK(farthest <= 2 * 5e-4 * extent);
}

TEST_CASE(
    "the thinned toolpath keeps every stop reachable in program order, every move within its "
    "tolerance") {
  using gcode::MoveKind;
  std::vector<gcode::MoveGroup> groups(2);
  groups[1].axis = Vec3(1, 0, 0);
  // Program order: group 0's rapid in and a straight feed in 50 pieces (file 0, lines 1-51), then
  // a subprogram file (file 1, lines 1-5, numbers the main file uses too) in group 1, then group 0
  // again: a circle in 200 chords and a rapid out home (file 0, lines 60-260), then the
  // subprogram's lines 2-3 called again.
  int line = 1;
  groups[0].moves.push_back(move(line++, MoveKind::rapid, Vec3(0, 0, 20), Vec3(0, 0, 1)));
  for (int k = 0; k < 50; ++k)
    groups[0].moves.push_back(move(line++, MoveKind::feed, Vec3(k, 0, 1), Vec3(k + 1, 0, 1)));
  auto sub = [&](int first, int last) {
    for (int k = first; k <= last; ++k) {
      gcode::Move m = move(k, MoveKind::feed, Vec3(-1, k, 0), Vec3(-1, k + 1, 0));
      m.file = 1;
      groups[1].moves.push_back(m);
    }
  };
  sub(1, 5);
  line = 60;
  Vec3 previous(50, 0, 1);
  for (int k = 1; k <= 200; ++k) {
    const double a = 2 * M_PI * k / 200;
    Vec3 next(40 + 10 * std::cos(a), 10 * std::sin(a), 1);
    groups[0].moves.push_back(move(line++, MoveKind::feed, previous, next, 2));
    previous = next;
  }
  const int home_line = line++;
  groups[0].moves.push_back(
      move(home_line, MoveKind::rapid, previous, Vec3(0, 0, gcode::MachineConfig::kDefaultFar)));
  sub(2, 3);
  const std::vector<GroupRun> order = {{0, 51}, {1, 5}, {0, 201}, {1, 2}};

  // The reference: the moves in program order and the stop of each.
  std::vector<std::pair<gcode::Move, std::size_t>> program;  // copies (MoveList reads by value)
  std::vector<std::pair<int, int>> stops;                    // (file, line)
  std::vector<std::size_t> next(2, 0);
  for (const GroupRun& run : order)
    for (std::uint64_t k = 0; k < run.moves; ++k) {
      const gcode::Move m = groups[run.group].moves[next[run.group]++];
      if (stops.empty() || stops.back() != std::pair{m.file, m.line})
        stops.emplace_back(m.file, m.line);
      program.emplace_back(m, run.group);
    }

  const double tolerance = 0.05;
  DisplayPath path = thin_toolpath(groups, order, tolerance);
  CHECK(path.moves == 259);
  REQUIRE(path.stop_count == stops.size());
  std::vector<std::pair<int, int>> decoded;
  for (std::size_t r = 0; r + 2 < path.stop_runs.size(); r += 3)
    for (std::uint32_t k = 0; k < path.stop_runs[r + 2]; ++k)
      decoded.emplace_back(static_cast<int>(path.stop_runs[r]),
                           static_cast<int>(path.stop_runs[r + 1] + k));
  CHECK(decoded == stops);
  CHECK(path.stop_runs.size() ==
        3 * 4);  // file 0 from line 1, file 1 from 1, file 0 from 60, file 1 from 2
  REQUIRE(path.ends.size() == 2 * path.stops.size());
  CHECK(path.stops.size() < 60);  // the straight feed is one segment, the circle a few dozen
  CHECK(std::is_sorted(path.stops.begin(), path.stops.end()));
  // Every drawn move lies within the tolerance of the segment carrying its stop (the first whose
  // stop is not before it), which has its tool and direction; the move home is not drawn.
  std::size_t stop = 0;
  for (std::size_t k = 0; k < program.size(); ++k) {
    const auto& [m, g] = program[k];
    while (stops[stop] != std::pair{m.file, m.line}) ++stop;
    if (m.line == home_line) continue;
    const auto s = static_cast<std::size_t>(
        std::lower_bound(path.stops.begin(), path.stops.end(), static_cast<std::uint32_t>(stop)) -
        path.stops.begin());
    REQUIRE(s < path.stops.size());
    const Vec3 a(path.ends[2 * s]), b(path.ends[2 * s + 1]);
    CHECK(segment_distance(m.start, a, b) <= tolerance + 1e-5);
    CHECK(segment_distance(m.end, a, b) <= tolerance + 1e-5);
    CHECK(path.tools[s] == m.tool);
    CHECK((path.flags[s] & 127) == g);
    CHECK(((path.flags[s] & 128) != 0) == (m.kind == MoveKind::rapid));
  }
  CHECK(path.stops.back() == stops.size() - 1);
  for (const glm::vec3& p : path.ends) CHECK(glm::length(p) < 100);
  // With no tolerance only exactly collinear moves merge: the circle's chords all stay.
  CHECK(thin_toolpath(groups, order, 0).stops.size() >= 200);
  // Without an order, each group in turn; an order that does not match the groups is a defect.
  CHECK(thin_toolpath(groups, {}, tolerance).stop_runs[0] == 0);
  const std::vector<GroupRun> wrong = {{0, 300}};
  CHECK_THROWS_AS(thin_toolpath(groups, wrong, tolerance), std::logic_error);
}

TEST_CASE(
    "the page holds the report, the listed source lines, and says when there is nothing to show") {
  fs::path dir = scratch("html-writer");
  // Two files with the same line numbers: a finding's lines come from its own file only.
  const fs::path program = dir / "p.nc", subprogram = dir / "O1001.nc";
  std::string text;
  for (int k = 1; k <= 20; ++k)
    text += "G1 X" + std::to_string(k) + " ( line " + std::to_string(k) + " </script> )\n";
  write_text(program, text);
  write_text(subprogram, text);
  HtmlPage page;
  page.title = "a <title> & more";
  page.report = {
      {"rapid_cuts",
       json::array({{{"file", program.string()}, {"line", 10}, {"where", {1, 2, 3}}}})},
      {"gouges",
       json::array({{{"lines", {2, 18}}, {"files", {subprogram.string(), subprogram.string()}}}})},
      {"note", "</script><b>"}};
  page.files = {program.string(), subprogram.string()};
  HtmlLimits limits;
  limits.max_source_bytes = 0;  // only the lines around findings
  write_html_report(dir / "page.html", page, limits);
  const std::string html = slurp(dir / "page.html");
  CHECK(html.find("<title>a &lt;title&gt; &amp; more</title>") != std::string::npos);
  CHECK(html.find("</script><b>") == std::string::npos);  // escaped inside the data
  json data = page_data(html);
  CHECK(data["report"] == page.report);
  auto source_lines = [](std::initializer_list<std::pair<int, int>> ranges) {
    json source = json::object();
    for (const auto& [first, last] : ranges)
      for (int k = first; k <= last; ++k)
        source[std::to_string(k)] =
            "G1 X" + std::to_string(k) + " ( line " + std::to_string(k) + " </script> )";
    return source;
  };
  REQUIRE(data["files"].size() == 2);
  CHECK(data["files"][0]["name"] == program.string());
  CHECK(data["files"][0]["source"] == source_lines({{7, 13}}));
  CHECK(data["files"][1]["name"] == subprogram.string());
  CHECK(data["files"][1]["source"] == source_lines({{1, 5}, {15, 20}}));
  // Each large file's whole text compressed too: the slider shows any line's text (issue 32).
  CHECK(html_chunked_text(data["files"][0]) == text);
  CHECK(html_chunked_text(data["files"][1]) == text);
  CHECK(data["files"][0]["note"] == "the program is large: its text is kept compressed");
  CHECK(data["mesh"]["triangles_shown"] == 0);
  CHECK(data["toolpath"]["segments"] == 0);
  REQUIRE(data["messages"].size() == 2);
  CHECK(data["messages"][0].get<std::string>().rfind("No material is left", 0) == 0);
  CHECK(data["messages"][1].get<std::string>().rfind("The program has no moves", 0) == 0);
  // With the whole (small) program inlined, and a mesh and moves: no messages.
  Mesh mesh = heightfield(4);
  std::vector<gcode::MoveGroup> groups(1);
  groups[0].moves.push_back(move(3, gcode::MoveKind::feed, Vec3(0), Vec3(1, 0, 0)));
  page.mesh = &mesh;
  page.groups = &groups;
  data = html_page_data(page, {});
  CHECK(data["files"][0]["source"].size() == 20);
  CHECK(data["files"][1]["source"].size() == 20);
  CHECK(data["messages"].empty());
  CHECK(data["mesh"]["triangles"] == mesh.triangles.size());
  CHECK(data["toolpath"]["segments"] == 1);
  const std::vector<std::uint32_t> runs = {0, 3, 1};  // file 0, line 3, one stop
  CHECK(data["toolpath"]["stop_runs"] ==
        base64({reinterpret_cast<const std::uint8_t*>(runs.data()), 12}));
  CHECK(data["toolpath"]["stop_count"] == 1);
  CHECK(!data.contains("design"));
  // check's design: its own mesh in the page, within its budget, over its own box.
  const Mesh design = heightfield(60);  // 7,200 triangles
  page.design = &design;
  limits = {};
  limits.max_design_triangles = 1000;
  data = html_page_data(page, limits);
  REQUIRE(data.contains("design"));
  CHECK(data["design"]["triangles"] == design.triangles.size());
  CHECK(data["design"]["triangles_shown"].get<std::size_t>() <= 1000);
  CHECK(data["design"]["triangles_shown"].get<std::size_t>() > 100);
  CHECK(!data["design"].contains("deviation"));
  const Aabb design_box = design.bounds();
  for (int a = 0; a < 3; ++a) {
    CHECK(data["design"]["box"]["min"][a].get<double>() ==
          doctest::Approx(design_box.min[a]).epsilon(1e-6));
    CHECK(data["design"]["box"]["max"][a].get<double>() ==
          doctest::Approx(design_box.max[a]).epsilon(1e-6));
  }
  fs::remove_all(dir);
}

TEST_CASE(
    "simulate --html: the page's report is the --report file; an unwritable page is refused up "
    "front") {
  fs::path dir = scratch("html-command");
  write_text(dir / "p.nc",
             "%\nG21 G90\nT1 M6\nM3 S1000\nG0 X5 Y5 Z20\nG1 Z5 F100\nG1 X15\nG0 Z20\nM30\n%\n");
  write_text(dir / "tools.json",
             R"({"1": {"units": "mm", "shape": "ballnose", "diameter": 4, "length": 20}})");
  const std::vector<std::string> common = {
      "simulate", (dir / "p.nc").string(), "--tools",     (dir / "tools.json").string(),
      "--stock",  "box:0,0,0,20,10,10",    "--dexel-res", "64",
      "-q"};
  std::vector<std::string> args = common;
  args.insert(args.end(),
              {"--report", (dir / "r.json").string(), "--html", (dir / "r.html").string()});
  CommandResult r = run_tridex(args, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  json data = page_data(slurp(dir / "r.html"));
  json report = json::parse(slurp(dir / "r.json"));
  CHECK(data["report"] == report);
  CHECK(data["toolpath"]["moves"] == report["segments"]);
  CHECK(data["directions"].size() == report["groups"].size());
  CHECK(data["mesh"]["triangles"] == report["result"]["triangles"]);
  CHECK(data["files"][0]["source"]["7"] == "G1 X15");
  args = common;
  args.insert(args.end(), {"--html", (dir / "missing" / "r.html").string()});
  r = run_tridex(args, dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("--html") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE(
    "simulate --html with a subprogram file: each file's text, the stops in program order across "
    "the files") {
  fs::path dir = scratch("html-subprogram");
  write_text(dir / "p.nc",
             "%\nG21 G90\nT1 M6\nM3 S1000\nG0 X5 Y5 Z20\nM98 P1001\nG0 Z20\nM30\n%\n");
  write_text(dir / "O1001.nc", "O1001\nG0 Z12\nG1 Z5 F100\nG1 X15\nM99\n");
  write_text(dir / "tools.json",
             R"({"1": {"units": "mm", "shape": "ballnose", "diameter": 4, "length": 20}})");
  CommandResult r = run_tridex(
      {"simulate", (dir / "p.nc").string(), "--tools", (dir / "tools.json").string(), "--stock",
       "box:0,0,0,20,10,10", "--dexel-res", "64", "-q", "--html", (dir / "r.html").string()},
      dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  json data = page_data(slurp(dir / "r.html"));
  REQUIRE(data["files"].size() == 2);
  CHECK(fs::path(data["files"][0]["name"].get<std::string>()).filename() == "p.nc");
  CHECK(fs::path(data["files"][1]["name"].get<std::string>()).filename() == "O1001.nc");
  CHECK(data["files"][0]["source"]["4"] == "M3 S1000");
  CHECK(data["files"][1]["source"]["4"] == "G1 X15");
  // Line 5 of p.nc, lines 2-4 of O1001.nc, line 7 of p.nc: (file, first line, count) runs.
  const std::vector<std::uint32_t> runs = {0, 5, 1, 1, 2, 3, 0, 7, 1};
  CHECK(data["toolpath"]["stop_runs"] ==
        base64({reinterpret_cast<const std::uint8_t*>(runs.data()), 4 * runs.size()}));
  CHECK(data["toolpath"]["stop_count"] == 5);
  fs::remove_all(dir);
}

TEST_CASE(
    "the findings name their file: a rapid into the stock in a subprogram file, both files with "
    "moves on its line") {
  fs::path dir = scratch("html-finding-file");
  write_text(dir / "p.nc", "%\nG21 G90 T1 M6\nM3 S1000 G0 X5 Y5 Z20\nM98 P1001\nG0 Z20\nM30\n%\n");
  write_text(dir / "O1001.nc", "O1001\nG0 X5 Y5 Z12\nG0 Z5\nG0 Z20\nM99\n");
  write_text(dir / "tools.json",
             R"({"1": {"units": "mm", "shape": "ballnose", "diameter": 4, "length": 20}})");
  CommandResult r =
      run_tridex({"simulate", (dir / "p.nc").string(), "--tools", (dir / "tools.json").string(),
                  "--stock", "box:0,0,0,20,10,10", "--dexel-res", "64", "-q", "--report",
                  (dir / "r.json").string(), "--html", (dir / "r.html").string()},
                 dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  const json report = json::parse(slurp(dir / "r.json"));
  // The plunge (line 3) and the retract from it (line 4): no feed move removes that material.
  REQUIRE(report["rapid_cuts"].size() == 2);
  CHECK(report["rapid_cuts"][1]["line"] == 4);
  CHECK(report["rapid_cuts"][1]["file"] == report["rapid_cuts"][0]["file"]);
  const json& cut = report["rapid_cuts"][0];
  CHECK(cut["line"] == 3);
  CHECK(fs::path(cut["file"].get<std::string>()).filename() == "O1001.nc");
  CHECK(cut["depth_mm"].get<double>() == doctest::Approx(5).epsilon(1e-3));
  for (int a = 0; a < 3; ++a)
    CHECK(cut["where"][a].get<double>() == doctest::Approx(std::array{5.0, 5.0, 5.0}[a]));
  // The page names the same file: the finding's "file" is one of its files' names.
  const json data = page_data(slurp(dir / "r.html"));
  REQUIRE(data["files"].size() == 2);
  CHECK(data["files"][1]["name"] == cut["file"]);
  CHECK(data["files"][0]["source"]["3"] == "M3 S1000 G0 X5 Y5 Z20");
  CHECK(data["files"][1]["source"]["3"] == "G0 Z5");
  fs::remove_all(dir);
}

TEST_CASE("playback: each stock cell is removed at the first stop whose cutter passes below it") {
  // A 10 mm cube of stock; a Ø4 flat end mill plunges at (5, 5) to z = 5 (stop 1: line 2), slots
  // to x = 9 (stop 2: line 3) and retracts (stop 3). The part is the slab below z = 3 (a closed
  // box mesh); what lies between it and the cut is removed at the last stop.
  Stock stock;
  stock.box = Aabb{Vec3(0), Vec3(10)};
  std::vector<gcode::MoveGroup> groups(1);
  groups[0].moves.push_back(move(1, gcode::MoveKind::rapid, {5, 5, 20}, {5, 5, 12}));
  groups[0].moves.push_back(move(2, gcode::MoveKind::feed, {5, 5, 12}, {5, 5, 5}));
  groups[0].moves.push_back(move(3, gcode::MoveKind::feed, {5, 5, 5}, {9, 5, 5}));
  groups[0].moves.push_back(move(4, gcode::MoveKind::rapid, {9, 5, 5}, {9, 5, 12}));
  Mesh part;
  const Aabb slab{Vec3(0), Vec3(10, 10, 3)};
  for (const Vec3& c : slab.corners()) part.positions.emplace_back(c);
  // The corners are numbered x + 2y + 4z: two triangles per face.
  for (const std::array<unsigned, 4>& f : std::array<std::array<unsigned, 4>, 6>{
           {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}}}) {
    part.triangles.emplace_back(f[0], f[1], f[2]);
    part.triangles.emplace_back(f[0], f[2], f[3]);
  }
  const std::vector<Cutter> cutters = {Cutter::flat(2)};
  const std::map<int, std::uint32_t> cutter_of_tool = {{1, 0}};
  HtmlPage page;
  page.mesh = &part;
  page.groups = &groups;
  page.stock = &stock;
  page.cutters = cutters;
  page.cutter_of_tool = &cutter_of_tool;
  const Playback p = playback_cells(page, 0.5);
  REQUIRE(p.n == std::array<int, 3>{20, 20, 20});
  CHECK(p.stop_count == 4);
  CHECK(p.stock_mask.empty());  // a box: every cell is stock
  // Walk the cells as the writer does: part cells are skipped, the others take the next stop.
  std::size_t removed = 0, in_part = 0;
  std::map<std::uint32_t, int> by_stop;
  for (int k = 0, index = 0; k < 20; ++k)
    for (int j = 0; j < 20; ++j)
      for (int i = 0; i < 20; ++i, ++index) {
        const bool is_part = (p.part_mask[index / 8] >> (index % 8)) & 1;
        CHECK(is_part == (k < 6));  // centres below z = 3
        if (is_part) {
          ++in_part;
          continue;
        }
        const std::uint32_t stop = p.removed_at.at(removed++);
        const Vec3 c(0.25 + 0.5 * i, 0.25 + 0.5 * j, 0.25 + 0.5 * k);
        const double plunge = std::hypot(c.x - 5, c.y - 5),
                     slot = std::hypot(c.x - std::clamp(c.x, 5.0, 9.0), c.y - 5);
        const std::uint32_t expected = c.z > 5 && plunge <= 2 ? 1 : c.z > 5 && slot <= 2 ? 2 : 3;
        CHECK(stop == expected);
        ++by_stop[stop];
      }
  CHECK(removed == p.removed_at.size());
  CHECK(in_part == 20 * 20 * 6);
  CHECK(by_stop[1] > 0);
  CHECK(by_stop[2] > 0);
  CHECK(by_stop[1] + by_stop[2] + by_stop[3] == static_cast<int>(removed));
  CHECK(by_stop.count(0) == 0);  // the rapid above the stock removes nothing
}

TEST_CASE("a large program's text: deflated in chunks of lines, kept in order within the budget") {
  std::string text;
  for (int k = 1; k <= 1000; ++k) text += "G1 X" + std::to_string(k % 97) + ".125 Y-3.5 Z0.25\n";
  for (const std::string& tail : {std::string(), std::string("M30")}) {  // with a last line unended
    const std::string whole = text + tail;
    for (unsigned threads : {1u, 3u}) {
      const CompressedText packed = compress_lines(whole, 64, std::size_t{1} << 30, threads);
      CHECK(packed.lines == (tail.empty() ? 1000u : 1001u));
      CHECK(packed.lines_kept == packed.lines);
      CHECK(packed.chunks.size() == (packed.lines + 63) / 64);
      std::string joined;
      for (const std::string& chunk : packed.chunks) {
        const std::string lines = inflate_raw(html_unbase64(chunk));
        CHECK(lines.size() < 64 * 40);
        joined += lines;
      }
      CHECK(joined == whole);
      CHECK(packed.chunks.front().size() * 3 < 64 * 24);  // near-identical lines deflate well
    }
  }
  // A budget for three chunks keeps the first three, and says how many lines they hold.
  const CompressedText full = compress_lines(text, 64, std::size_t{1} << 30);
  const std::size_t three = full.chunks[0].size() + full.chunks[1].size() + full.chunks[2].size();
  const CompressedText cut = compress_lines(text, 64, three);
  CHECK(cut.chunks.size() == 3);
  CHECK(cut.lines_kept == 192);
  CHECK(cut.lines == 1000);
  CHECK(compress_lines("", 64, 1000).chunks.empty());
  CHECK_THROWS(inflate_raw("not deflate data"));
}
