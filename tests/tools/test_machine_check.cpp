// The machine and the fixture (issue 33): the continuous check against plates and spikes planted
// between the poses a fixed-step sampler tests, a closed-form first contact of a turning table,
// travel passed inside a TCP move, and planted crashes end to end through `tridex check`.
#include <doctest/doctest.h>

#include <cmath>
#include <map>
#include <random>
#include <set>

#include <nlohmann/json.hpp>

#include "checks/machine_check.hpp"
#include "outputs/html_report.hpp"
#include "command_harness.hpp"

namespace test_machine_check {

using namespace tridex;
using namespace tridex::cli;
using namespace tridex::test;
using nlohmann::json;

std::shared_ptr<const TriangleTree> tree_of(const Mesh& m) {
  return std::make_shared<const TriangleTree>(m);
}

MachineBody body(const std::string& name, Link link, const Mesh& mesh) {
  MachineBody b;
  b.name = name, b.group = "test", b.link = link, b.tree = tree_of(mesh);
  return b;
}

TEST_CASE("machine check: thin plates and spikes between a fixed sampler's poses, zero misses") {
  std::mt19937 rng(33);
  std::uniform_real_distribution<double> u(0, 1);
  gcode::CollisionSettings settings;  // contact only
  MachineCheck check(std::nullopt, {true, true, true}, settings);
  // The tool: a cylinder of radius 3 from the tip up 50 mm, on a rapid from X-500 to X500 at Z5.
  check.add(body("tool", {LinkKind::tool, 0}, make_frustum_mesh(3, 3, 0, 50)));
  MachineMove move;
  move.from.x = Vec3(-500, 0, 5), move.to.x = Vec3(500, 0, 5);
  // A sampler testing 100 poses 10 mm apart covers X within 3 mm of each; obstacles go in the gaps.
  const int planted = 60;
  for (int k = 0; k < planted; ++k) {
    const double x = -500 + 10 * std::floor(u(rng) * 100) + 3.5 + 2.7 * u(rng);
    const double y = 2.8 * (2 * u(rng) - 1);
    const Mesh m =
        k % 2 == 0
            // a plate 0.3 mm thick across the path, its top anywhere above Z2
            ? make_box_mesh(Vec3(x, -20, -10), Vec3(x + 0.3, 20, 2 + 50 * u(rng)))
            // a spike 0.2 mm square rising into the tool's path within its radius
            : make_box_mesh(Vec3(x, y - 0.1, -10), Vec3(x + 0.2, y + 0.1, 5.01 + 40 * u(rng)));
    check.add(body("obstacle " + std::to_string(k), {LinkKind::work, 0}, m));
  }
  // The fixed-step sampler misses every one of them ...
  for (std::size_t b = 1; b < check.bodies().size(); ++b)
    for (int i = 0; i <= 100; ++i) {
      const MachineState s = check.state_at(move, i / 100.0);
      const MachineBody& tool = check.bodies()[0];
      const MachineBody& obstacle = check.bodies()[b];
      REQUIRE(tree_distance(*tool.tree, check.frame_of(tool, s, move), *obstacle.tree,
                            check.frame_of(obstacle, s, move))
                  .distance > 0);
    }
  // ... and the check finds each.
  MachineFindings found;
  check.check(move, found);
  CHECK(found.collisions.size() == std::size_t(planted));
  CHECK(found.queries < 100000);
}

TEST_CASE("machine check: a box on a turning C table meets a fixed box at the closed-form angle") {
  gcode::Kinematics kin;
  kin.type = gcode::MachineType::table_table;
  gcode::RotaryAxis c;
  c.letter = 'C', c.direction = Vec3(0, 0, 1), c.pivot = Vec3(0);
  kin.axes = {c};
  MachineCheck check(kin, {true, true, true}, gcode::CollisionSettings{});
  // On C: x 10..50, y -5..5. Fixed (on the spindle, X at 0): the face y = 20.
  check.add(body("arm", {LinkKind::table, 1}, make_box_mesh(Vec3(10, -5, 0), Vec3(50, 5, 10))));
  check.add(body("wall", {LinkKind::spindle, 0}, make_box_mesh(Vec3(0, 20, 0), Vec3(100, 30, 10))));
  MachineMove move;
  move.to.rotary[2] = 90;
  MachineFindings found;
  check.check(move, found);
  REQUIRE(found.collisions.size() == 1);
  // The corner (50, 5) reaches y = 20: 50 sin θ + 5 cos θ = 20.
  const double phi = std::atan2(5.0, 50.0), radius = std::hypot(50.0, 5.0);
  const double expected = glm::degrees(std::asin(20 / radius) - phi);
  CHECK(std::abs(found.collisions[0].state.rotary[2] - expected) < 0.01);
  // Turning the other way it never meets the wall.
  MachineFindings away;
  move.to.rotary[2] = -60;
  check.check(move, away);
  CHECK(away.collisions.empty());
}

TEST_CASE("machine check: travel passed inside a TCP move whose ends are within") {
  gcode::Kinematics kin;
  gcode::RotaryAxis c;
  c.letter = 'C', c.direction = Vec3(0, 0, 1), c.pivot = Vec3(0);
  kin.axes = {c};
  kin.travel[1] = std::array<double, 2>{-50, 50};
  MachineCheck check(kin, {true, true, true}, gcode::CollisionSettings{});
  MachineMove move;
  move.tip_linear = true;
  move.tip_from = move.tip_to = Vec3(80, 0, 0);
  move.to.rotary[2] = 180;
  move.from.x = check.state_at(move, 0).x;
  move.to.x = check.state_at(move, 1).x;
  REQUIRE(std::abs(move.from.x.y) < 1e-9);
  REQUIRE(std::abs(move.to.x.y) < 1e-9);
  MachineFindings found;
  check.check(move, found);
  REQUIRE(found.travel.size() == 1);
  CHECK(found.travel[0].axis == 'Y');
  CHECK(found.travel[0].value == doctest::Approx(80).epsilon(1e-6));
  CHECK(found.travel[0].t == doctest::Approx(0.5).epsilon(1e-4));
}

// ---- end to end: a vise, a clamp, a 0.3 mm plate and a spindle nose ---------------------------

void write_ascii_stl(const fs::path& path, const std::vector<Mesh>& parts) {
  const Mesh m = merge_meshes(parts);
  std::string text = "solid part\n";
  for (const glm::uvec3& t : m.triangles) {
    text += " facet normal 0 0 0\n  outer loop\n";
    for (unsigned i : {t.x, t.y, t.z}) {
      const glm::vec3 p = m.positions[i];
      text += "   vertex " + std::to_string(p.x) + " " + std::to_string(p.y) + " " +
              std::to_string(p.z) + "\n";
    }
    text += "  endloop\n endfacet\n";
  }
  write_text(path, text + "endsolid part\n");
}

struct Setup {
  fs::path dir;
  std::vector<std::string> fixture_args;
};

// The fixtures (a vise, a clamp up to clamp_top, a 0.3 mm plate), a spindle nose and one tool.
Setup make_setup(
    const std::string& name, double clamp_top = 35,
    const std::string& tool =
        R"({"shape": "cylindrical", "diameter": 6, "length": 20, "tool-length": 50})") {
  Setup s{scratch(name), {}};
  write_ascii_stl(s.dir / "vise.stl", {make_box_mesh(Vec3(0, -20, -30), Vec3(100, 0, 0)),
                                       make_box_mesh(Vec3(0, 60, -30), Vec3(100, 80, 0))});
  write_ascii_stl(s.dir / "clamp.stl",
                  {make_box_mesh(Vec3(110, 20, -30), Vec3(130, 40, clamp_top))});
  write_ascii_stl(s.dir / "plate.stl", {make_box_mesh(Vec3(150, -10, -30), Vec3(150.3, 70, 20))});
  fs::create_directories(s.dir / "parts");
  write_ascii_stl(s.dir / "parts" / "nose.stl", {make_frustum_mesh(40, 40, 0, 80)});
  write_text(
      s.dir / "machine.json",
      R"({"components": [{"name": "spindle nose", "on": "spindle", "mesh": "parts/nose.stl"}],
                 "collision": {"clearance": 0.5, "near_miss": 2}})");
  write_text(s.dir / "tools.json", R"({"1": )" + tool + "}");
  for (const char* f : {"vise.stl", "clamp.stl", "plate.stl"})
    s.fixture_args.insert(s.fixture_args.end(), {"--fixture", (s.dir / f).string()});
  return s;
}

json run_check(const Setup& s, const std::string& program, CommandResult& result) {
  write_text(s.dir / "p.nc", "G21 G90 G17\nT1 M6\nG43 H1\n" + program + "M30\n");
  fs::remove(s.dir / "report.json");
  const std::string stock = "box:0,0,-30,100,60,0";
  CommandResult made = run_tridex(
      {"simulate", (s.dir / "p.nc").string(), "--tools", (s.dir / "tools.json").string(), "--stock",
       stock, "--dexel-cell", "1", "-o", (s.dir / "design.stl").string(), "-q"},
      s.dir);
  REQUIRE(made.status == 0);
  std::vector<std::string> args{"check",        (s.dir / "p.nc").string(),
                                "--design",     (s.dir / "design.stl").string(),
                                "--tools",      (s.dir / "tools.json").string(),
                                "--machine",    (s.dir / "machine.json").string(),
                                "--stock",      stock,
                                "--dexel-cell", "1",
                                "--tolerance",  "1",
                                "--report",     (s.dir / "report.json").string()};
  args.insert(args.end(), s.fixture_args.begin(), s.fixture_args.end());
  result = run_tridex(args, s.dir);
  return fs::exists(s.dir / "report.json") ? json::parse(slurp(s.dir / "report.json")) : json();
}

std::set<int> collision_lines(const json& report) {
  std::set<int> lines;
  for (const json& c : report["machine"]["collisions"]) lines.insert(c["line"].get<int>());
  return lines;
}

TEST_CASE("check --fixture and a spindle nose: each planted crash at its line, none when clean") {
  const Setup s = make_setup("machine-crashes");
  CommandResult r;
  // Line 4 onward are the program's; line 6 crosses the clamp at Z5.
  json report = run_check(s, "G0 X100 Y30 Z40\nG0 Z5\nG0 X140\nG0 Z40\n", r);
  INFO(r.out, r.err);
  CHECK(r.status == 3);
  CHECK(collision_lines(report) == std::set<int>{6});
  CHECK(report["machine"]["collisions"][0]["b"] == "tool 1 flutes");
  CHECK(r.out.find("p.nc:6: collision: clamp.stl and tool 1 flutes") != std::string::npos);
  // The spindle nose (radius 40, 50 mm above the tip) comes down onto the clamp's top (Z35)
  // while the tool goes 20 deep into a pocket at X95 (line 6); the retract is not a new crash.
  report = run_check(s, "G0 X95 Y30 Z40\nG1 Z-10 F300\nG1 Z-20\nG0 Z40\n", r);
  CHECK(collision_lines(report) == std::set<int>{6});
  CHECK(report["machine"]["collisions"][0]["a"] == "clamp.stl");
  CHECK(report["machine"]["collisions"][0]["b"] == "spindle nose");
  // A 1000 mm rapid at Z5 across the plate, 0.3 mm thick (and the clamp): line 6 both times.
  report = run_check(s, "G0 X-400 Y50 Z40\nG0 Z5\nG0 X600\nG0 Z40\n", r);
  CHECK(collision_lines(report) == std::set<int>{6});
  bool plate = false;
  for (const json& c : report["machine"]["collisions"]) plate |= c["a"] == "plate.stl";
  CHECK(plate);
  // Clean: pockets inside the vise at safe heights, the rapids above everything.
  report = run_check(s, "G0 X50 Y30 Z40\nG1 Z-10 F300\nG1 X60\nG1 Y35\nG0 Z40\nG0 X200\n", r);
  CHECK(r.status == 0);
  CHECK(report["machine"]["collisions"].empty());
  CHECK(report["machine"]["near_misses"].empty());
  CHECK(r.out.find("collision:") == std::string::npos);
}

// The issue's bar: a vise, a clamp and a 0.3 mm plate as fixtures, a spindle nose on the spindle,
// a long tool (60 mm from tip to gauge point) for a 25 mm deep pocket. Each planted crash is
// found at its line only; the clean program cuts the deep pocket with the nose passing 4.6 mm
// from the clamp, below its top, and gives nothing (not even a near miss at 2 mm).
Setup make_bar_setup(const std::string& name) {
  return make_setup(name, 45,
                    R"({"shape": "cylindrical", "diameter": 6, "length": 35, "tool-length": 60})");
}

std::set<std::pair<std::string, std::string>> collision_pairs(const json& report) {
  std::set<std::pair<std::string, std::string>> pairs;
  for (const json& c : report["machine"]["collisions"])
    pairs.insert({c["a"].get<std::string>(), c["b"].get<std::string>()});
  return pairs;
}

TEST_CASE("the issue's bar: vise, clamp, plate and spindle nose; planted crashes at their lines") {
  const Setup s = make_bar_setup("machine-bar");
  CommandResult r;
  using Pairs = std::set<std::pair<std::string, std::string>>;
  // A rapid through the clamp at Z10 (line 6); the nose passes 25 mm above the clamp's top.
  json report = run_check(s, "G0 X50 Y30 Z50\nG0 Z10\nG0 X140\nG0 Z50\n", r);
  INFO(r.out, r.err);
  CHECK(r.status == 3);
  CHECK(collision_lines(report) == std::set<int>{6});
  CHECK(collision_pairs(report) == Pairs{{"clamp.stl", "tool 1 flutes"}});
  // The nose (radius 40, 60 mm above the tip) onto the clamp's top (Z45) as the tool plunges
  // 25 mm deep at X85 beside it (line 5); the retract (line 6) backs off the same contact.
  report = run_check(s, "G0 X85 Y30 Z50\nG1 Z-25 F300\nG0 Z50\n", r);
  CHECK(r.status == 3);
  CHECK(collision_lines(report) == std::set<int>{5});
  CHECK(collision_pairs(report) == Pairs{{"clamp.stl", "spindle nose"}});
  // The tip reaches Z-14.5 when the nose's bottom (Z45.5) comes within the clearance.
  CHECK(report["machine"]["collisions"][0]["axes"]["Z"].get<double>() ==
        doctest::Approx(-14.5).epsilon(1e-3));
  // A 260 mm rapid at Z5 across the 0.3 mm plate (line 6), clear of the clamp beside it.
  report = run_check(s, "G0 X140 Y50 Z50\nG0 Z5\nG0 X400\nG0 Z50\n", r);
  CHECK(r.status == 3);
  CHECK(collision_lines(report) == std::set<int>{6});
  CHECK(collision_pairs(report) == Pairs{{"plate.stl", "tool 1 flutes"}});
  // Clean: the deep pocket at X55..65, the nose 4.6 mm from the clamp and 15 mm below its top;
  // the rapids above everything.
  report = run_check(s,
                     "G0 X65 Y30 Z50\nG1 Z-25 F300\nG1 X55\nG1 Y35\nG1 X65\nG1 Y30\nG0 Z50\n"
                     "G0 X200\n",
                     r);
  CHECK(r.status == 0);
  CHECK(report["machine"]["collisions"].empty());
  CHECK(report["machine"]["near_misses"].empty());
  CHECK(r.out.find("collision:") == std::string::npos);
  // The program's first move comes from "far along the tool axis": where it lands is checked.
  report = run_check(s, "G0 X120 Y30 Z10\nG0 Z50\n", r);
  CHECK(collision_lines(report) == std::set<int>{4});
  // The same pocket 6 mm nearer the clamp (X71) puts the nose in it: the bar is not vacuous.
  report = run_check(s, "G0 X71 Y30 Z50\nG1 Z-25 F300\nG0 Z50\n", r);
  CHECK(collision_lines(report) == std::set<int>{5});
}

// ---- the spindle's parts and the in-process stock; what could not be checked; the page ----------

// A bore plunged 38 mm deep, then again to 45 mm, by a tool whose gauge point is 40 mm above its
// tip: the nose (radius 40) clears the stock's top by 2 mm on the first plunge and goes 5 mm below
// it on the second (line 7), into the bore the first cut. No fixtures: the stock alone. (Parts
// are tested against the stock as it stands before their move is milled, as holders are:
// collision_check.hpp.)
json run_bore(const Setup& s, double diameter, CommandResult& result,
              const std::string& html = "") {
  write_text(s.dir / "tools.json", R"({"1": {"shape": "cylindrical", "diameter": )" +
                                       std::to_string(diameter) +
                                       R"(, "length": 35, "tool-length": 40}})");
  write_text(
      s.dir / "p.nc",
      "G21 G90 G17\nT1 M6\nG43 H1\nG0 X50 Y50 Z20\nG1 Z-38 F300\nG0 Z20\nG1 Z-45\nG0 Z20\nM30\n");
  fs::remove(s.dir / "report.json");
  const std::string stock = "box:0,0,-60,100,100,0";
  const std::vector<std::string> common{
      "--tools", (s.dir / "tools.json").string(), "--stock", stock, "--dexel-cell", "1", "-q"};
  std::vector<std::string> make{"simulate", (s.dir / "p.nc").string(), "-o",
                                (s.dir / "design.stl").string()};
  make.insert(make.end(), common.begin(), common.end());
  REQUIRE(run_tridex(make, s.dir).status == 0);
  std::vector<std::string> args{"check",       (s.dir / "p.nc").string(),
                                "--design",    (s.dir / "design.stl").string(),
                                "--machine",   (s.dir / "machine.json").string(),
                                "--tolerance", "1",
                                "--report",    (s.dir / "report.json").string()};
  args.insert(args.end(), common.begin(), common.end() - 1);
  if (!html.empty()) args.insert(args.end(), {"--html", (s.dir / html).string()});
  result = run_tridex(args, s.dir);
  return fs::exists(s.dir / "report.json") ? json::parse(slurp(s.dir / "report.json")) : json();
}

TEST_CASE("check: the spindle nose against the in-process stock, not the raw stock") {
  const Setup s = make_setup("machine-nose-stock");
  CommandResult r;
  // A Ø60 bore: its walls stand within the nose's 40 mm radius, 5 mm above its bottom.
  json report = run_bore(s, 60, r);
  INFO(r.out, r.err);
  CHECK(r.status == 3);
  // The second plunge (line 7) and the retract from there (line 8), as a holder's are reported.
  REQUIRE(report["collisions"].size() == 2);
  for (const json& c : report["collisions"]) {
    CHECK(c["part"] == "spindle nose");
    CHECK(c["depth_mm"].get<double>() == doctest::Approx(5).epsilon(0.05));
  }
  CHECK(report["collisions"][0]["line"] == 7);
  CHECK(report["collisions"][1]["line"] == 8);
  CHECK(r.out.find("p.nc:7: tool 1's spindle nose is 5.000 mm into the stock") !=
        std::string::npos);
  CHECK(report["machine"]["collisions"].empty());  // no fixture: the stock is the only obstacle
  // A Ø100 bore: the first plunge cut away all the material the nose reaches on the second (the
  // raw stock would hold it): nothing.
  report = run_bore(s, 100, r);
  CHECK(r.status == 0);
  CHECK(report["collisions"].empty());
  CHECK(report["near_misses"]["moves"].empty());
}

TEST_CASE("check: spindle parts a tool cannot place are said where the verdict is read") {
  const Setup s = make_setup("machine-unplaced", 35,
                             R"({"shape": "cylindrical", "diameter": 6, "length": 20})");
  CommandResult r;
  const json report = run_check(s, "G0 X50 Y30 Z40\nG1 Z-10 F300\nG0 Z40\n", r);
  INFO(r.out, r.err);
  CHECK(r.status == 0);  // nothing found: the verdict passes, and says what it does not cover
  CHECK(report["machine"]["spindle_parts_unplaced_tools"] == json::array({1}));
  REQUIRE(report["not_checked"].size() == 1);
  const std::string text = report["not_checked"][0];
  CHECK(text.find("spindle's parts not tested with T1") != std::string::npos);
  bool warned = false;
  for (const json& w : report["warnings"]) warned |= w == text;
  CHECK(warned);
  const std::size_t verdict = r.out.find("  verdict: pass");
  REQUIRE(verdict != std::string::npos);
  const std::string line = r.out.substr(verdict, r.out.find('\n', verdict) - verdict);
  CHECK(line.find("NOT CHECKED: " + text) != std::string::npos);
  CHECK(r.err.find("warning: " + text) != std::string::npos);
  // With a tool length the nose is placed: nothing said.
  const Setup placed = make_setup("machine-placed");
  const json clean = run_check(placed, "G0 X50 Y30 Z40\nG1 Z-10 F300\nG0 Z40\n", r);
  CHECK(!clean.contains("not_checked"));
  CHECK(r.out.find("NOT CHECKED") == std::string::npos);
}

// The JSON inside a page's tridex-data block.
json machine_page_data(const fs::path& html) {
  const std::string text = slurp(html);
  const std::string open = "<script type=\"application/json\" id=\"tridex-data\">";
  const std::size_t start = text.find(open);
  REQUIRE(start != std::string::npos);
  return json::parse(
      text.substr(start + open.size(), text.find("</script>", start) - start - open.size()));
}

TEST_CASE("check --html: the machine finding's pair drawn at its pose, the fixtures always") {
  const Setup s = make_bar_setup("machine-page");
  CommandResult r;
  // The nose onto the clamp's top (the bar's second crash): the tip at Z-14.5 then.
  const std::vector<std::string> html{"--html", (s.dir / "page.html").string()};
  Setup with_page = s;
  with_page.fixture_args.insert(with_page.fixture_args.end(), html.begin(), html.end());
  const json report = run_check(with_page, "G0 X85 Y30 Z50\nG1 Z-25 F300\nG0 Z50\n", r);
  INFO(r.out, r.err);
  REQUIRE(report["machine"]["collisions"].size() == 1);
  const json data = machine_page_data(s.dir / "page.html");
  REQUIRE(data.contains("machine"));
  const json& m = data["machine"];
  std::map<std::string, json> bodies;
  for (const json& b : m["bodies"]) bodies[b["name"].get<std::string>()] = b;
  // The fixtures and the pair drawn; the tool's parts (in no finding) left out.
  for (const char* name : {"vise.stl", "clamp.stl", "plate.stl", "spindle nose"})
    CHECK(bodies[name]["triangles_shown"].get<int>() > 0);
  CHECK(bodies["tool 1 flutes"]["triangles_shown"] == 0);
  CHECK(bodies["clamp.stl"]["group"] == "fixture");
  REQUIRE(m["collisions"].size() == 1);
  const json& pose = m["collisions"][0];
  REQUIRE(pose.size() == 2);
  const auto& names = m["bodies"];
  CHECK(names[pose[0]["body"].get<int>()]["name"] == "clamp.stl");
  CHECK(names[pose[1]["body"].get<int>()]["name"] == "spindle nose");
  // The clamp is in the work frame (the identity); the nose's gauge point 60 mm above the tip.
  const std::vector<double> identity{1, 0, 0, 0, 0, 1, 0, 0, 0, 0, 1, 0};
  for (std::size_t k = 0; k < 12; ++k)
    CHECK(pose[0]["matrix"][k].get<double>() == doctest::Approx(identity[k]));
  const json& nose = pose[1]["matrix"];
  CHECK(nose[3].get<double>() == doctest::Approx(85));
  CHECK(nose[7].get<double>() == doctest::Approx(30));
  CHECK(nose[11].get<double>() == doctest::Approx(-14.5 + 60).epsilon(1e-3));
  CHECK(nose[10].get<double>() == doctest::Approx(1));
}

TEST_CASE("the page's machine bodies: a 100 k triangle part within the budget") {
  // A wavy sheet of 2 × 224² triangles on the spindle, and a small fixture.
  Mesh big;
  const int n = 224;
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i)
      big.positions.emplace_back(i, j, 3 * std::sin(0.3 * i) * std::cos(0.2 * j));
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      const unsigned a = static_cast<unsigned>(j * (n + 1) + i), b = a + 1, c = a + n + 1,
                     d = c + 1;
      big.triangles.push_back({a, b, d});
      big.triangles.push_back({a, d, c});
    }
  REQUIRE(big.triangles.size() > 100000);
  const Mesh vise = make_box_mesh(Vec3(0), Vec3(10));
  HtmlMachine machine;
  machine.names = {"head", "vise.stl", "bed"};
  machine.groups = {"component", "fixture", "component"};
  machine.meshes = {&big, &vise, &big};
  machine.collisions.push_back({HtmlMachinePose{0, Frame{}}, HtmlMachinePose{1, Frame{}}});
  HtmlPage page;
  page.report = json::object();
  page.machine = &machine;
  HtmlLimits limits;
  const json data = html_page_data(page, limits);
  const json& bodies = data["machine"]["bodies"];
  const std::size_t shown = bodies[0]["triangles_shown"].get<std::size_t>();
  CHECK(shown > 0);
  CHECK(shown <= limits.max_machine_triangles);
  CHECK(bodies[0]["triangles"] == big.triangles.size());
  CHECK(bodies[1]["triangles_shown"] == 12);  // under its floor: whole
  CHECK(bodies[2]["triangles_shown"] == 0);   // in no finding and no fixture: not drawn
  CHECK(data["machine"].dump().size() < std::size_t{2} << 20);
}

// ---- the bundled example on the bundled trunnion ---------------------------------------------

// The example's tool table with gauge lengths (tool tip to spindle nose) of real holders; without
// them the spindle's parts are not placed (machine_run.hpp).
json example_tools(double t3_t4_length) {
  const std::string examples = std::string(TRIDEX_SOURCE_DIR) + "/gcode/examples/";
  json tools = json::parse(slurp(examples + "mold_3plus2.tools.json"));
  tools["1"]["tool-length"] = 110, tools["2"]["tool-length"] = 110;
  tools["3"]["tool-length"] = t3_t4_length, tools["4"]["tool-length"] = t3_t4_length;
  return tools;
}

// The machine is the subject: a coarse lattice, compared on its samples alone (--lattice-only).
json run_example(const fs::path& dir, const json& tools, CommandResult& result) {
  const std::string examples = std::string(TRIDEX_SOURCE_DIR) + "/gcode/examples/";
  write_text(dir / "tools.json", tools.dump());
  fs::remove(dir / "report.json");
  result =
      run_tridex({"check", examples + "mold_3plus2_bc.nc", "--machine", "bc-trunnion", "--tools",
                  (dir / "tools.json").string(), "--stock", "box:0,0,0,100,80,50", "--design",
                  examples + "mold_3plus2.design.stl", "--dexel-res", "24", "--lattice-only",
                  "--tolerance", "5", "--report", (dir / "report.json").string()},
                 dir);
  return fs::exists(dir / "report.json") ? json::parse(slurp(dir / "report.json")) : json();
}

TEST_CASE("check --machine bc-trunnion: the bundled example with real tool lengths is clean") {
  const fs::path dir = scratch("machine-example");
  CommandResult r;
  // Gauge lengths of 110 and 120 mm: the 90 mm spindle nose clears the 200 mm platter when the
  // part's -X face (on the platter's centre line) is cut at B90, and the cradle everywhere.
  json report = run_example(dir, example_tools(120), r);
  INFO(r.out, r.err);
  REQUIRE(report.contains("machine"));
  const json& m = report["machine"];
  CHECK(m["moves"].get<long long>() > 20000);
  CHECK(m["spindle_parts_unplaced_tools"].empty());
  CHECK(m["collisions_count"] == 0);
  CHECK(m["near_misses_count"] == 0);
  CHECK(r.out.find("collision:") == std::string::npos);
  // The nose is checked: 100 mm tools for T3/T4 put it inside the platter's rim where they cut
  // the faces that lie on the platter's centre lines (the stock's corner is on the C axis): -X
  // (B90 C0, the tip at X1.5) and -Y (B90 C-90); nowhere else.
  report = run_example(dir, example_tools(100), r);
  REQUIRE(report.contains("machine"));
  CHECK(report["machine"]["collisions_count"].get<int>() > 0);
  for (const json& c : report["machine"]["collisions"]) {
    CHECK(c["b"] == "spindle nose");
    CHECK(c["axes"]["B"].get<double>() == doctest::Approx(90));
    const double c_axis = c["axes"]["C"].get<double>();
    CHECK((std::abs(c_axis) < 1e-6 || std::abs(c_axis + 90) < 1e-6));
    CHECK((c["tool"] == 3 || c["tool"] == 4));
  }
}

TEST_CASE("machine file: the collision keys' faults name the key, exit status 2") {
  const Setup s = make_setup("machine-file-faults");
  write_text(s.dir / "p.nc", "G0 X0 Y0 Z10\nM30\n");
  for (
      const auto& [text, expected] : std::vector<std::pair<std::string, std::string>>{
          {R"({"components": [{"name": "x", "on": "B", "mesh": "parts/nose.stl"}]})",
           "\"components\"[0].on"},
          {R"({"components": [{"name": "x", "on": "bed", "mesh": "parts/nose.stl", "colour": 1}]})",
           "colour: unknown key"},
          {R"({"collision": {"clearance": -1}})", "clearance: must be a distance"},
          {R"({"collision": {"ignore": [["a", "b"]]}})", "ignore: no component"},
          {R"({"linear_axes": {"X": "ram"}})", "\"head\" or \"table\""},
          {R"({"components": [{"name": "x", "on": "bed", "mesh": "missing.stl"}]})",
           "missing.stl: no such file"}}) {
    write_text(s.dir / "bad.json", text);
    CommandResult r =
        run_tridex({"check", (s.dir / "p.nc").string(), "--design", (s.dir / "clamp.stl").string(),
                    "--machine", (s.dir / "bad.json").string(), "--stock", "box:0,0,-30,100,60,0",
                    "--dexel-cell", "2"},
                   s.dir);
    INFO(text, r.err);
    CHECK(r.status == 2);
    CHECK(r.err.find(expected) != std::string::npos);
  }
}

}  // namespace test_machine_check
