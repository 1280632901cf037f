// The `tridex` command end to end: every exit path, `moves` and `groups` on G68.2 programs, and
// `simulate` against a direct point-membership reference built from the moves.
#include <doctest/doctest.h>

// GCC 12 warns falsely on `"text" + std::string + "text"` (bug 105329) under -Werror=restrict.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ == 12
#pragma GCC diagnostic ignored "-Wrestrict"
#endif

#include <algorithm>
#include <cmath>
#include <functional>
#include <random>

#include <nlohmann/json.hpp>

#include "../kernel/edge_sampling.hpp"
#include "command_harness.hpp"
#include "tool_table.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/mill.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace {

// True if `text` holds `prefix`, then one or more digits, then `suffix` (std::regex is avoided:
// GCC 12 warns falsely inside it under the sanitizers).
bool has_number_between(const std::string& text, const std::string& prefix, const std::string& suffix) {
  for (std::size_t at = text.find(prefix); at != std::string::npos; at = text.find(prefix, at + 1)) {
    std::size_t digits = at + prefix.size(), end = digits;
    while (end < text.size() && std::isdigit(static_cast<unsigned char>(text[end]))) ++end;
    if (end > digits && text.compare(end, suffix.size(), suffix) == 0) return true;
  }
  return false;
}

const std::string kTools = R"({
  "1": {"units": "mm", "shape": "cylindrical", "diameter": 6, "length": 20},
  "2": {"units": "mm", "shape": "ballnose", "diameter": 4, "length": 20},
  "3": {"units": "inch", "shape": "bullnose", "diameter": 0.25, "corner-radius": 0.05, "length": 1}
})";

// G68.2 Euler angles (Z-X-Z) and a feature origin on each face of the 40 x 30 x 20 test stock.
struct Direction {
  const char* name;
  Vec3 origin;
  double a, b, c;
};
const Direction kDirections[] = {
    {"+Z", {20, 15, 20}, 0, 0, 0},       {"+X tilted 20", {40, 15, 12}, 90, 70, 0},
    {"+Y", {20, 30, 10}, 180, 90, 0},    {"-X", {0, 15, 10}, -90, 90, 0},
    {"-Y", {20, 0, 10}, 0, 90, 0},
};
const char* kStock = "box:0,0,0,40,30,20";

// The feature work for one direction, as a CAM post writes it: a flat-end slot with a ramp, a
// ball-end arc groove, a bull-nose plunge.
std::string direction_block(const Direction& d) {
  std::ostringstream p;
  p << "G28 G91 Z0.\nG90\nG69\nT1 M6\nS8000 M3\n"
    << "G68.2 X" << d.origin.x << " Y" << d.origin.y << " Z" << d.origin.z << " I" << d.a << " J" << d.b
    << " K" << d.c << "\nG53.1\n"
    << "G0 X-9 Y-2\nG43 Z8 H1\nG1 Z-2 F500\nG1 X7\nG1 Y3 Z-1\nG0 Z8\n"
    << "T2 M6\nG0 X2 Y-3\nG43 Z8 H2\nG1 Z-1.5\nG2 X8 Y3 I0 J6\nG3 X2 Y-3 I-6 J0\nG0 Z8\n"
    << "T3 M6\nG0 X-6 Y4\nG43 Z8 H3\nG1 Z-2.5\nG1 X-3 Y5\nG0 Z8\n"
    << "G28 G91 Z0.\nG69\n";
  return p.str();
}

std::string program_of(std::initializer_list<const Direction*> directions) {
  std::string text = "%\nG21 G17 G90\n";
  for (const Direction* d : directions) text += direction_block(*d);
  return text + "M30\n%\n";
}

// ---- the reference: is a world point removed by any move? ------------------------------------

struct Reference {
  std::vector<Cutter> cutters;
  std::vector<detail::MoveGeometry> moves;
  std::vector<Frame> frames;
  std::vector<unsigned> direction;  // per move: the index of its spindle direction
  std::vector<Vec3> axes;           // per direction
  // Moves bucketed by a uniform grid over the stock, each in every cell its removal region
  // (everything within the cutter radius of the segment and above it along the axis) can reach.
  Aabb box;
  double cell = 4;
  glm::ivec3 n;
  std::vector<std::vector<std::uint32_t>> buckets;

  Reference(const std::vector<gcode::Move>& program, const cli::ToolTable& table, const Aabb& stock)
      : box(stock) {
    std::map<int, std::size_t> index;
    for (const auto& [number, spec] : table.tools()) {
      index[number] = cutters.size();
      cutters.push_back(spec.cutter);
    }
    frames.reserve(program.size());
    moves.reserve(program.size());
    for (int a = 0; a < 3; ++a) n[a] = std::max(1, static_cast<int>(std::ceil(box.size()[a] / cell)));
    buckets.resize(static_cast<std::size_t>(n.x) * n.y * n.z);
    double reach = glm::length(box.size());
    for (const gcode::Move& m : program) {
      if (m.tool == 0) continue;  // no tool in the spindle
      frames.push_back(Frame::from_axis(m.axis));
      const Frame& f = frames.back();
      auto same = std::find_if(axes.begin(), axes.end(), [&](const Vec3& a) { return glm::length(a - m.axis) < 1e-9; });
      direction.push_back(static_cast<unsigned>(same - axes.begin()));
      if (same == axes.end()) axes.push_back(m.axis);
      const Cutter& cutter = cutters[index.at(m.tool)];
      moves.emplace_back(cutter, Segment{f.to_local(m.start), f.to_local(m.end)});
      Aabb region;
      for (const Vec3& p : {m.start, m.end}) {
        // Clip "far" points to the stock's neighbourhood along the move's own line.
        region.extend(p);
        region.extend(p + reach * f.axis());
      }
      region = region.inflated(cutter.radius());
      glm::ivec3 lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::clamp(static_cast<int>(std::floor((region.min[a] - box.min[a]) / cell)), 0, n[a] - 1);
        hi[a] = std::clamp(static_cast<int>(std::floor((region.max[a] - box.min[a]) / cell)), 0, n[a] - 1);
        if (region.max[a] < box.min[a] || region.min[a] > box.max[a]) lo[a] = 1, hi[a] = 0;
      }
      for (int k = lo.z; k <= hi.z; ++k)
        for (int j = lo.y; j <= hi.y; ++j)
          for (int i = lo.x; i <= hi.x; ++i)
            buckets[static_cast<std::size_t>(i + n.x * (j + n.y * k))].push_back(
                static_cast<std::uint32_t>(moves.size() - 1));
    }
  }

  // 0 outside the stock, 1 kept, otherwise 2 << d for each direction d whose moves remove p.
  unsigned label(const Vec3& p) const {
    if (!in_stock(p)) return 0;
    glm::ivec3 c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp(static_cast<int>(std::floor((p[a] - box.min[a]) / cell)), 0, n[a] - 1);
    unsigned l = 0;
    for (std::uint32_t m : buckets[static_cast<std::size_t>(c.x + n.x * (c.y + n.y * c.z))]) {
      const unsigned bit = 2u << direction[m];
      if (l & bit) continue;
      Vec3 q = frames[m].to_local(p);
      if (q.z >= moves[m].lowest_above(q.x, q.y)) l |= bit;
    }
    return l == 0 ? 1 : l;
  }
  bool removed(const Vec3& p) const {
    glm::ivec3 c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp(static_cast<int>(std::floor((p[a] - box.min[a]) / cell)), 0, n[a] - 1);
    for (std::uint32_t m : buckets[static_cast<std::size_t>(c.x + n.x * (c.y + n.y * c.z))]) {
      Vec3 q = frames[m].to_local(p);
      if (q.z >= moves[m].lowest_above(q.x, q.y)) return true;
    }
    return false;
  }
  // The stock: the box itself unless a test gives another solid inside it.
  std::function<bool(const Vec3&)> solid;
  bool in_stock(const Vec3& p) const { return box.contains(p) && (!solid || solid(p)); }
  bool kept(const Vec3& p) const { return in_stock(p) && !removed(p); }
};

using tridex::test::MeshInside;

struct Simulated {
  json report;
  Mesh mesh;
};

Simulated simulate(const fs::path& dir, const fs::path& program, const fs::path& tools,
                   const std::string& stock, int dexel_res, double zmap_cell) {
  fs::path stl = dir / "result.stl", report = dir / "report.json";
  CommandResult r = run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", stock,
                                "--dexel-res", std::to_string(dexel_res), "--zmap-cell",
                                std::to_string(zmap_cell), "-o", stl.string(), "--report",
                                report.string(), "--quiet"},
                               dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.out.empty());  // --quiet
  Simulated s;
  s.report = json::parse(slurp(report));
  s.mesh = read_binary_stl(stl);
  return s;
}

// The result against the reference: watertight, the same volume within what the dexel spacing
// h allows on the cut surfaces, and the same membership at points at least 2h from any change
// of the reference classification.
void check_against_reference(const Simulated& s, const Reference& ref, std::uint32_t seed) {
  const json& result = s.report["result"];
  CHECK(result["watertight"].get<bool>());
  Mesh welded = weld_vertices(s.mesh);
  CHECK(check_mesh(welded).closed());
  double volume = result["volume_mm3"].get<double>();
  CHECK(s.mesh.signed_volume() == doctest::Approx(volume).epsilon(1e-4));
  const double h = s.report["dexel"]["cell_mm"].get<double>();

  // Volume on a jittered regular grid of spacing g; the cut-surface area from the number of
  // neighbouring samples that differ (each face of the surface is crossed by ≤ √3·A/g² pairs,
  // ≥ A/g²: the estimate over-counts by at most √3).
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb& box = ref.box;
  const double g = 0.5;
  glm::ivec3 n = glm::ivec3(glm::floor(box.size() / g));
  Vec3 jitter(unit(random) * g, unit(random) * g, unit(random) * g);
  std::vector<char> kept(static_cast<std::size_t>(n.x) * n.y * n.z);
  auto at = [&](int i, int j, int k) -> char& { return kept[static_cast<std::size_t>(i + n.x * (j + n.y * k))]; };
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) at(i, j, k) = ref.kept(box.min + jitter + g * Vec3(i, j, k));
  std::vector<char> in_stock(kept.size());
  auto stock_at = [&](int i, int j, int k) -> char& { return in_stock[static_cast<std::size_t>(i + n.x * (j + n.y * k))]; };
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) stock_at(i, j, k) = ref.in_stock(box.min + jitter + g * Vec3(i, j, k));
  // Pairs of neighbouring samples that differ: on any surface of the result, and on the surfaces
  // the program cut (both samples in the stock).
  std::size_t kept_count = 0, stock_count = 0, differing = 0, differing_cut = 0;
  auto pair = [&](int i, int j, int k, int i2, int j2, int k2) {
    if (at(i, j, k) == at(i2, j2, k2)) return;
    ++differing;
    if (stock_at(i, j, k) && stock_at(i2, j2, k2)) ++differing_cut;
  };
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) {
        kept_count += at(i, j, k) ? 1 : 0;
        stock_count += stock_at(i, j, k) ? 1 : 0;
        if (i + 1 < n.x) pair(i, j, k, i + 1, j, k);
        if (j + 1 < n.y) pair(i, j, k, i, j + 1, k);
        if (k + 1 < n.z) pair(i, j, k, i, j, k + 1);
      }
  Vec3 size = box.size();
  double stock_volume = size.x * size.y * size.z;
  // Samples cover n·g along each side; scale the kept fraction to the whole box.
  double reference_volume = stock_volume * static_cast<double>(kept_count) / static_cast<double>(kept.size());
  double reference_stock = stock_volume * static_cast<double>(stock_count) / static_cast<double>(kept.size());
  // The surface lies within h of the true one (exact dexel crossings), so the volume is within
  // h/2 · area on average; the sampled reference adds about g³·√(samples on the surface)/2.
  double cut_area = static_cast<double>(differing) * g * g;
  double sampling = 0.5 * g * g * g * std::sqrt(static_cast<double>(differing));
  double tolerance = 0.5 * h * cut_area + 4 * sampling;
  INFO("reference volume " << reference_volume << ", result " << volume << ", tolerance " << tolerance
                           << " (cut area about " << cut_area << " mm^2, h " << h << ")");
  CHECK(std::abs(volume - reference_volume) <= tolerance);
  // The program cuts something well above what the cut surfaces alone would let pass.
  double cut_tolerance = 0.5 * h * static_cast<double>(differing_cut) * g * g +
                         2 * g * g * g * std::sqrt(static_cast<double>(differing_cut));
  CHECK(reference_stock - reference_volume > 3 * cut_tolerance);

  // Point membership wherever the reference classification does not change within h.
  MeshInside inside(s.mesh, 1.0);
  int compared = 0, wrong = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    Vec3 p = box.min + Vec3(unit(random), unit(random), unit(random)) * box.size();
    bool reference = ref.kept(p), clear = true;
    for (int a = 0; a < 3 && clear; ++a)
      for (double sign : {-1.0, 1.0}) {
        Vec3 q = p;
        q[a] += sign * h;
        if (ref.kept(q) != reference) clear = false;
      }
    if (!clear) continue;
    ++compared;
    if (inside.inside(p) != reference) {
      ++wrong;
      if (wrong <= 5) MESSAGE("mismatch at " << p.x << ", " << p.y << ", " << p.z << ": reference kept " << reference);
    }
  }
  CHECK(compared > 1000);
  CHECK(wrong == 0);
}

}  // namespace

TEST_CASE("--version, --help and option errors") {
  fs::path dir = scratch("options");
  CommandResult version = run_tridex({"--version"}, dir);
  CHECK(version.status == 0);
  CHECK(version.out.rfind("tridex ", 0) == 0);
  CHECK(run_tridex({"--help"}, dir).status == 0);
  for (const char* command : {"simulate", "moves", "groups"}) {
    CommandResult help = run_tridex({command, "--help"}, dir);
    CHECK(help.status == 0);
    CHECK(help.out.find("PROGRAM") != std::string::npos);
  }
  CHECK(run_tridex({"simulate", "--help"}, dir).out.find("--dexel-res") != std::string::npos);
  fs::path program = dir / "p.nc";
  write_text(program, "G0 X0\n");
  CHECK(run_tridex({}, dir).status == 2);
  CHECK(run_tridex({"frobnicate"}, dir).status == 2);
  CHECK(run_tridex({"simulate"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--no-such-option"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--dexel-res", "100", "--dexel-cell", "1"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--zmap-cell", "-1"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--quiet", "--progress"}, dir).status == 2);
  CHECK(run_tridex({"simulate", program.string(), "--max-memory", "lots"}, dir).status == 2);
  CommandResult missing = run_tridex({"moves", (dir / "absent.nc").string()}, dir);
  CHECK(missing.status == 2);
  CHECK(missing.err.find("absent.nc") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("a bad program exits 2 with file:line:col, and leaves no output behind") {
  fs::path dir = scratch("bad-program");
  fs::path program = dir / "bad.nc", tools = dir / "tools.json", stl = dir / "out.stl";
  write_text(tools, kTools);
  write_text(program, "G21 G90\nT1 M6\nG0 X1 Y2 Z30\nG1 X5 F100 G987\nM30\n");
  write_text(stl, "the previous result");
  for (const char* command : {"simulate", "moves", "groups"}) {
    std::vector<std::string> args{command, program.string()};
    if (std::string(command) == "simulate") args.insert(args.end(), {"--tools", tools.string()});
    args.insert(args.end(), {"-o", stl.string()});
    CommandResult r = run_tridex(args, dir);
    CHECK(r.status == 2);
    INFO(r.err);
    CHECK(has_number_between(r.err, "bad.nc:4:", ": "));
    CHECK(slurp(stl) == "the previous result");
  }
  // Nothing but the three files: no temporary file left.
  CHECK(std::distance(fs::directory_iterator(dir), fs::directory_iterator()) == 3);
  fs::remove_all(dir);
}

TEST_CASE("bad tool tables, missing tools and bad stocks exit 2 naming the problem") {
  fs::path dir = scratch("bad-input");
  fs::path program = dir / "p.nc", tools = dir / "tools.json";
  write_text(program, "G21 G90\nT1 M6\nG0 X1 Y2 Z30\nG1 Z5 F100\nT5 M6\nG0 X3 Y3 Z30\nG1 Z4\nM30\n");
  auto simulate_with = [&](const std::string& table, const std::string& stock) {
    write_text(tools, table);
    return run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", stock,
                       "--dexel-res", "32", "-o", (dir / "out.stl").string()},
                      dir);
  };
  CommandResult not_json = simulate_with("{\"1\": {", "auto");
  CHECK(not_json.status == 2);
  CHECK(not_json.err.find("tools.json") != std::string::npos);
  CommandResult bad_shape = simulate_with(R"({"1": {"shape": "drill", "diameter": 3}})", "auto");
  CHECK(bad_shape.status == 2);
  CHECK(bad_shape.err.find("tool 1: unknown shape") != std::string::npos);
  CommandResult missing_tool = simulate_with(R"({"1": {"shape": "ballnose", "diameter": 3}})", "auto");
  CHECK(missing_tool.status == 2);
  INFO(missing_tool.err);
  CHECK(missing_tool.err.find("p.nc:5") != std::string::npos);
  CHECK(missing_tool.err.find("tool 5") != std::string::npos);
  CHECK(run_tridex({"simulate", program.string(), "--dexel-res", "32"}, dir).status == 2);  // no table

  const std::string good = R"({"1": {"shape": "ballnose", "diameter": 3}, "5": {"shape": "cylindrical", "diameter": 2}})";
  for (const char* stock : {"box:0,0,0,10,10", "box:0,0,0,10,10,a", "box:0,0,5,10,10,5", "cube:1", "auto:-2"})
    CHECK(simulate_with(good, stock).status == 2);
  fs::path broken = dir / "broken.stl";
  write_text(broken, "solid broken\n  facet normal 0 0 1\n    outer loop\n      vertex 0 0 0\n");
  CommandResult bad_stl = simulate_with(good, broken.string());
  CHECK(bad_stl.status == 2);
  CHECK(bad_stl.err.find("broken.stl") != std::string::npos);
  CHECK(!fs::exists(dir / "out.stl"));
  fs::remove_all(dir);
}

// A hobby mill's Fusion 360 output (tests/data/gcode/public): `T1` and no M6, Z zero touched off
// on the tip. Without the machine that loads tools on T the first feed is refused, saying how to
// describe such a machine; with it the program mills a watertight solid.
TEST_CASE("simulate: a public hobby program that loads its tool with T alone") {
  fs::path dir = scratch("public-hobby");
  const fs::path program = fs::path(TRIDEX_TEST_DATA) / "gcode" / "public" / "led_floor" / "1101_bore_tests.nc";
  write_text(dir / "tools.json", R"({"1": {"shape": "cylindrical", "diameter": 2}})");
  write_text(dir / "hobby.json", R"({"tool_loads_on_t": true})");
  std::vector<std::string> args{"simulate", program.string(), "--tools", (dir / "tools.json").string(),
                                "--stock", "box:-5,-5,-13,35,95,0", "--dexel-res", "128", "-o",
                                (dir / "out.stl").string()};
  CommandResult refused = run_tridex(args, dir);
  CHECK(refused.status == 2);
  CHECK(refused.err.find("1101_bore_tests.nc:17") != std::string::npos);
  CHECK(refused.err.find("\"tool_loads_on_t\": true") != std::string::npos);
  CHECK(!fs::exists(dir / "out.stl"));
  args.insert(args.end(), {"--machine", (dir / "hobby.json").string()});
  CommandResult r = run_tridex(args, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.out.find("watertight") != std::string::npos);
  CHECK(fs::exists(dir / "out.stl"));
  fs::remove_all(dir);
}

// A feed with no tool loaded is named by the file that holds it: a project's file (CAMotics'
// heart example, whose heart.ngc loads its tool with T alone, was refused as
// "heart.camotics:15"), or the subprogram a program called (it was named by the main program).
TEST_CASE("simulate: a feed move with no tool loaded is named by the file that holds it") {
  fs::path dir = scratch("toolless-file");
  write_text(dir / "tools.json", R"({"1": {"shape": "cylindrical", "diameter": 2}})");
  write_text(dir / "first.nc", "G21 G90\nT1 M6\nG0 X0 Y0 Z5\nG1 Z-1 F100\nG1 X10\nM30\n");
  write_text(dir / "second.nc", "G21 G90\nG0 X0 Y0 Z5\nG0 X5\nG1 Z-1 F100\nM30\n");
  // The project's first file feeds at its line 4 before any tool is loaded.
  write_text(dir / "bare.camotics", R"({"files": ["second.nc", "first.nc"], "tools": {"1": {"shape": "cylindrical", "diameter": 2}}})");
  CommandResult project = run_tridex({"simulate", (dir / "bare.camotics").string(), "-o", (dir / "out.stl").string()}, dir);
  CHECK(project.status == 2);
  CHECK(project.err.find("second.nc:4:") != std::string::npos);
  CHECK(project.err.find("bare.camotics:4") == std::string::npos);
  // A subprogram (O1000.nc, found in the program's folder) that feeds before any tool change.
  write_text(dir / "O1000.nc", "O1000\nG0 X0 Y0 Z5\nG1 Z-1 F100\nM99\n");
  write_text(dir / "main.nc", "G21 G90\nM98 P1000\nT1 M6\nM30\n");
  CommandResult called = run_tridex({"simulate", (dir / "main.nc").string(), "--tools", (dir / "tools.json").string(),
                                     "-o", (dir / "out.stl").string()}, dir);
  CHECK(called.status == 2);
  CHECK(called.err.find("O1000.nc:3:") != std::string::npos);
  CHECK(!fs::exists(dir / "out.stl"));
  fs::remove_all(dir);
}

// CAMotics ships TPL programs (JavaScript that writes G-code) beside its G-code examples, and
// its projects name them as they name G-code files.
TEST_CASE("a CAMotics TPL program, given or named by a project, is refused as not G-code") {
  fs::path dir = scratch("tpl");
  write_text(dir / "gear.tpl", "var teeth = 12;\nfunction gear() {}\n");
  write_text(dir / "gear.camotics", R"({"files": ["gear.tpl"], "tools": {"1": {"shape": "cylindrical", "diameter": 2}}})");
  for (const char* program : {"gear.tpl", "gear.camotics"}) {
    CAPTURE(program);
    CommandResult r = run_tridex({"moves", (dir / program).string()}, dir);
    CHECK(r.status == 2);
    CHECK(r.err.find("gear.tpl: a CAMotics TPL program") != std::string::npos);
  }
  fs::remove_all(dir);
}

TEST_CASE("unwritable outputs and inputs named as outputs are refused before any work") {
  fs::path dir = scratch("outputs");
  fs::path program = dir / "p.nc", tools = dir / "tools.json";
  write_text(program, program_of({&kDirections[0]}));
  write_text(tools, kTools);
  std::string before = slurp(program);
  std::vector<std::string> base{"simulate", program.string(), "--tools", tools.string(), "--stock", kStock,
                                "--dexel-res", "32"};
  auto with = [&](std::vector<std::string> extra) {
    std::vector<std::string> args = base;
    args.insert(args.end(), extra.begin(), extra.end());
    return run_tridex(args, dir);
  };
  CommandResult no_dir = with({"-o", (dir / "missing" / "out.stl").string()});
  CHECK(no_dir.status == 2);
  CHECK(no_dir.err.find("does not exist") != std::string::npos);
  CHECK(with({"--png", dir.string()}).status == 2);
  CommandResult over_input = with({"-o", program.string()});
  CHECK(over_input.status == 2);
  CHECK(over_input.err.find("would overwrite the input") != std::string::npos);
  CHECK(with({"--report", tools.string()}).status == 2);
  CHECK(slurp(program) == before);
  CHECK(run_tridex({"moves", program.string(), "-o", program.string()}, dir).status == 2);
  CHECK(slurp(program) == before);
  if (::geteuid() != 0) {
    fs::create_directories(dir / "locked");
    fs::permissions(dir / "locked", fs::perms::owner_read | fs::perms::owner_exec);
    CHECK(with({"-o", (dir / "locked" / "out.stl").string()}).status == 2);
    fs::permissions(dir / "locked", fs::perms::owner_all);
  }
  fs::remove_all(dir);
}

TEST_CASE("a resolution over --max-memory is refused up front with the figure") {
  fs::path dir = scratch("memory");
  fs::path program = dir / "p.nc", tools = dir / "tools.json", stl = dir / "out.stl";
  write_text(program, program_of({&kDirections[0], &kDirections[1]}));
  write_text(tools, kTools);
  CommandResult r = run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", kStock,
                                "--dexel-res", "4000", "--max-memory", "512M", "-o", stl.string()},
                               dir);
  CHECK(r.status == 2);
  INFO(r.err);
  CHECK(has_number_between(r.err, "needs an estimated ", " MiB"));
  CHECK(r.err.find("--max-memory 512 MiB") != std::string::npos);
  CHECK(!fs::exists(stl));
  // The same run fits with the default resolution.
  CHECK(run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", kStock,
                    "--dexel-res", "48", "--zmap-cell", "0.2", "--max-memory", "512M", "-o", stl.string(), "--quiet"},
                   dir)
            .status == 0);
  CHECK(fs::file_size(stl) > 84);
  fs::remove_all(dir);
}

namespace {

// G68.2's rotation written out independently: R = Rz(a)·Rx(b)·Rz(c), row-major here.
std::array<std::array<double, 3>, 3> euler_zxz(double a, double b, double c) {
  auto rz = [](double t) {
    double r = t * M_PI / 180;
    return std::array<std::array<double, 3>, 3>{{{std::cos(r), -std::sin(r), 0}, {std::sin(r), std::cos(r), 0}, {0, 0, 1}}};
  };
  auto rx = [](double t) {
    double r = t * M_PI / 180;
    return std::array<std::array<double, 3>, 3>{{{1, 0, 0}, {0, std::cos(r), -std::sin(r)}, {0, std::sin(r), std::cos(r)}}};
  };
  auto mul = [](const auto& p, const auto& q) {
    std::array<std::array<double, 3>, 3> m{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) m[i][j] += p[i][k] * q[k][j];
    return m;
  };
  return mul(mul(rz(a), rx(b)), rz(c));
}

Vec3 rotate_by(const std::array<std::array<double, 3>, 3>& m, const Vec3& p) {
  return Vec3(m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z, m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z,
              m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z);
}

Vec3 vec(const json& j) { return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>()); }

}  // namespace

TEST_CASE("moves: JSON Lines in the work frame under random G68.2 planes") {
  fs::path dir = scratch("moves");
  std::mt19937 random(5);
  std::uniform_real_distribution<double> angle(-180, 180), tilt(0, 120), offset(-50, 50), local(-10, 10);
  for (int trial = 0; trial < 8; ++trial) {
    double a = angle(random), b = tilt(random), c = angle(random);
    Vec3 origin(offset(random), offset(random), offset(random));
    std::vector<Vec3> points;
    std::ostringstream text;
    text.precision(10);
    text << "G21 G90 G17\nT2 M6\nS5000 M3\nG68.2 X" << origin.x << " Y" << origin.y << " Z" << origin.z
         << " I" << a << " J" << b << " K" << c << "\nG53.1\n";
    for (int k = 0; k < 6; ++k) {
      Vec3 p(local(random), local(random), local(random));
      points.push_back(p);
      text << "G1 X" << p.x << " Y" << p.y << " Z" << p.z << " F700\n";
    }
    // A half circle of radius 5 about the last point, in the feature XY plane.
    Vec3 centre = points.back() + Vec3(5, 0, 0), last = points.back() + Vec3(10, 0, 0);
    text << "G3 X" << last.x << " Y" << last.y << " I5 J0\nG69\nM30\n";
    fs::path program = dir / ("p" + std::to_string(trial) + ".ngc");
    write_text(program, text.str());
    CommandResult r = run_tridex({"moves", program.string(), "--arc-tolerance", "0.01"}, dir);
    INFO(r.err);
    REQUIRE(r.status == 0);
    auto R = euler_zxz(a, b, c);
    Vec3 axis(std::sin(a * M_PI / 180) * std::sin(b * M_PI / 180), -std::cos(a * M_PI / 180) * std::sin(b * M_PI / 180),
              std::cos(b * M_PI / 180));
    std::istringstream lines(r.out);
    std::string line;
    std::vector<json> records;
    while (std::getline(lines, line)) records.push_back(json::parse(line));
    // The feed moves, in order; the first comes straight down the tool axis from far away.
    std::vector<json> feeds, arcs;
    for (const json& m : records) {
      for (const char* key : {"line", "kind", "tool", "start", "end", "axis", "feed"}) REQUIRE(m.contains(key));
      if (m["kind"] == "feed") feeds.push_back(m);
      if (m["kind"] == "arc") arcs.push_back(m);
    }
    REQUIRE(feeds.size() == points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      Vec3 expected = origin + rotate_by(R, points[k]);
      Vec3 end = vec(feeds[k]["end"]);
      CHECK(glm::length(end - expected) < 1e-6);
      CHECK(glm::length(vec(feeds[k]["axis"]) - axis) < 1e-9);
      CHECK(feeds[k]["tool"] == 2);
      CHECK(feeds[k]["feed"].get<double>() == doctest::Approx(700));
      CHECK(feeds[k]["line"] == 6 + static_cast<int>(k));
    }
    Vec3 approach = vec(feeds[0]["start"]) - vec(feeds[0]["end"]);
    CHECK(glm::length(approach) > 1000);
    CHECK(glm::dot(glm::normalize(approach), axis) == doctest::Approx(1));
    // Arc pieces: chained, on the circle about the rotated centre, ending at the rotated end.
    REQUIRE(arcs.size() >= 8);
    Vec3 world_centre = origin + rotate_by(R, centre);
    for (std::size_t k = 0; k < arcs.size(); ++k) {
      CHECK(glm::length(vec(arcs[k]["end"]) - world_centre) == doctest::Approx(5).epsilon(1e-6));
      if (k > 0) CHECK(glm::length(vec(arcs[k]["start"]) - vec(arcs[k - 1]["end"])) < 1e-9);
      CHECK(arcs[k]["line"] == 12);
    }
    CHECK(glm::length(vec(arcs.back()["end"]) - (origin + rotate_by(R, last))) < 1e-6);
  }
  fs::remove_all(dir);
}

TEST_CASE("--block-delete: on (the default) skips the blocks that start with '/', off runs them") {
  fs::path dir = scratch("block_delete");
  fs::path program = dir / "p.nc";
  write_text(program, "G21 G90\nG0 X0 Y0 Z5\n/G0 X10\nG0 Y20\nM30\n");
  // The end of the last move, for the command's extra options.
  auto last_end = [&](std::vector<std::string> args) {
    args.insert(args.begin(), {"moves", program.string()});
    CommandResult r = run_tridex(args, dir);
    INFO(r.err);
    REQUIRE(r.status == 0);
    std::istringstream lines(r.out);
    std::string line, last;
    while (std::getline(lines, line)) last = line;
    return vec(json::parse(last)["end"]);
  };
  CHECK(glm::length(last_end({}) - Vec3(0, 20, 5)) < 1e-12);
  CHECK(glm::length(last_end({"--block-delete", "on"}) - Vec3(0, 20, 5)) < 1e-12);
  CHECK(glm::length(last_end({"--block-delete", "off"}) - Vec3(10, 20, 5)) < 1e-12);
  CommandResult bad = run_tridex({"moves", program.string(), "--block-delete", "yes"}, dir);
  CHECK(bad.status == 2);
  CHECK(bad.err.find("--block-delete") != std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("groups: one group per spindle direction with its moves and tools") {
  fs::path dir = scratch("groups");
  fs::path program = dir / "five.nc", out = dir / "groups.json";
  write_text(program, program_of({&kDirections[0], &kDirections[1], &kDirections[2], &kDirections[3],
                                  &kDirections[4], &kDirections[2]}));
  CommandResult r = run_tridex({"groups", program.string(), "-o", out.string()}, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  json doc = json::parse(slurp(out));
  REQUIRE(doc["groups"].size() == 5);  // +Y appears twice in the program but is one direction
  CommandResult moves = run_tridex({"moves", program.string()}, dir);
  long long lines = std::count(moves.out.begin(), moves.out.end(), '\n');
  CHECK(doc["segments"].get<long long>() == lines);
  long long total = 0;
  for (std::size_t g = 0; g < 5; ++g) {
    const Direction& d = kDirections[g];
    const json& group = doc["groups"][g];
    double a = d.a * M_PI / 180, b = d.b * M_PI / 180;
    Vec3 axis(std::sin(a) * std::sin(b), -std::cos(a) * std::sin(b), std::cos(b));
    CHECK(glm::length(vec(group["axis"]) - axis) < 1e-9);
    CHECK(glm::length(vec(group["frame"]["z"]) - axis) < 1e-9);
    CHECK(group["tools"] == json::array({1, 2, 3}));
    total += group["moves"].get<long long>();
    long long by_kind = 0;
    for (const auto& [kind, count] : group["by_kind"].items()) by_kind += count.get<long long>();
    CHECK(by_kind == group["moves"].get<long long>());
    CHECK(group["by_kind"]["arc"].get<long long>() > 0);
  }
  CHECK(total == lines);
  CHECK(doc["groups"][2]["moves"].get<long long>() > doc["groups"][3]["moves"].get<long long>());
  fs::remove_all(dir);
}

TEST_CASE("simulate: each direction alone matches the point-membership reference") {
  fs::path dir = scratch("directions");
  fs::path tools = dir / "tools.json";
  write_text(tools, kTools);
  cli::ToolTable table = cli::ToolTable::read(tools);
  const Aabb stock{Vec3(0, 0, 0), Vec3(40, 30, 20)};
  std::uint32_t seed = 100;
  for (const Direction& d : kDirections) {
    INFO("direction " << d.name);
    fs::path program = dir / "one.nc";
    write_text(program, program_of({&d}));
    Simulated s = simulate(dir, program, tools, kStock, 128, 0.08);
    REQUIRE(s.report["groups"].size() == 1);
    Reference ref(gcode::read_moves(program.string()), table, stock);
    check_against_reference(s, ref, seed++);
  }
  fs::remove_all(dir);
}

TEST_CASE("simulate: all five directions together, and the report's schema") {
  fs::path dir = scratch("five");
  fs::path tools = dir / "tools.json", program = dir / "five.nc";
  write_text(tools, kTools);
  write_text(program, program_of({&kDirections[0], &kDirections[1], &kDirections[2], &kDirections[3], &kDirections[4]}));
  Simulated s = simulate(dir, program, tools, kStock, 128, 0.08);
  const json& report = s.report;
  for (const char* key : {"program", "segments", "groups", "dexel", "timings_s", "peak_rss_mib", "result", "warnings"})
    CHECK(report.contains(key));
  for (const char* key : {"parse", "zmap", "dexelize", "intersect", "mesh", "total"})
    CHECK(report["timings_s"][key].get<double>() >= 0);
  for (const char* key : {"volume_mm3", "removed_mm3", "triangles", "watertight"}) CHECK(report["result"].contains(key));
  CHECK(report["result"]["volume_mm3"].get<double>() + report["result"]["removed_mm3"].get<double>() ==
        doctest::Approx(40 * 30 * 20));
  CHECK(report["result"]["triangles"].get<std::size_t>() == s.mesh.triangles.size());
  CHECK(report["groups"].size() == 5);
  CHECK(report["rapid_cuts"].empty());  // every rapid of the program stays clear of the stock
  long long moves = 0;
  for (const json& g : report["groups"]) {
    moves += g["moves"].get<long long>();
    CHECK(g["zmap"][0].get<int>() > 100);
    CHECK(g["cell_mm"].get<double>() == doctest::Approx(0.08));
  }
  CHECK(moves == report["segments"].get<long long>());
  CHECK(report["dexel"]["res"][0].get<int>() >= 128);
  cli::ToolTable table = cli::ToolTable::read(tools);
  Reference ref(gcode::read_moves(program.string()), table, Aabb{Vec3(0, 0, 0), Vec3(40, 30, 20)});
  check_against_reference(s, ref, 7);
  fs::remove_all(dir);
}

TEST_CASE("simulate: an STL stock (a hexagonal prism) and the automatic stock") {
  fs::path dir = scratch("stl-stock");
  fs::path tools = dir / "tools.json", program = dir / "two.nc", prism = dir / "prism.stl";
  write_text(tools, kTools);
  write_text(program, program_of({&kDirections[0], &kDirections[4]}));
  // A hexagonal prism around the box's centre axis (x, y within 15 mm of (20, 15)), z 0..20,
  // as ASCII STL, outward facing.
  const Vec3 centre(20, 15, 0);
  const double radius = 15;
  std::vector<Vec3> ring;
  for (int k = 0; k < 6; ++k) {
    double a = M_PI / 3 * k;
    ring.push_back(centre + Vec3(radius * std::cos(a), radius * std::sin(a), 0));
  }
  std::ostringstream stl;
  stl.precision(17);
  auto facet = [&](Vec3 a, Vec3 b, Vec3 c) {
    stl << "facet normal 0 0 0\n outer loop\n";
    for (const Vec3& p : {a, b, c}) stl << "  vertex " << p.x << ' ' << p.y << ' ' << p.z << '\n';
    stl << " endloop\nendfacet\n";
  };
  stl << "solid prism\n";
  const Vec3 up(0, 0, 20);
  for (int k = 0; k < 6; ++k) {
    Vec3 a = ring[static_cast<std::size_t>(k)], b = ring[static_cast<std::size_t>((k + 1) % 6)];
    facet(a, b, b + up);
    facet(a, b + up, a + up);
    facet(centre, b, a);
    facet(centre + up, a + up, b + up);
  }
  stl << "endsolid prism\n";
  write_text(prism, stl.str());
  Simulated s = simulate(dir, program, tools, prism.string(), 128, 0.08);
  cli::ToolTable table = cli::ToolTable::read(tools);
  Reference ref(gcode::read_moves(program.string()), table, Aabb{Vec3(5, 15 - radius * std::sqrt(3) / 2, 0), Vec3(35, 15 + radius * std::sqrt(3) / 2, 20)});
  ref.solid = [&](const Vec3& p) {
    Vec2 q(p.x - centre.x, p.y - centre.y);
    // Inside all six half-planes of the hexagon's sides (apothem r·√3/2).
    for (int k = 0; k < 6; ++k) {
      double a = M_PI / 3 * k + M_PI / 6;
      if (q.x * std::cos(a) + q.y * std::sin(a) > radius * std::sqrt(3) / 2) return false;
    }
    return true;
  };
  check_against_reference(s, ref, 23);
  double prism_volume = 1.5 * std::sqrt(3) * radius * radius * 20;
  CHECK(s.report["result"]["removed_mm3"].get<double>() + s.report["result"]["volume_mm3"].get<double>() ==
        doctest::Approx(prism_volume).epsilon(1e-6));
  CHECK(s.report["stock"]["kind"] == "stl");

  // auto:1: the box around the tool tips of the cutting moves (approaches from far excluded),
  // one millimetre larger on every side.
  fs::path report = dir / "auto.json";
  CommandResult r = run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", "auto:1",
                                "--dexel-res", "48", "--report", report.string(), "--quiet"},
                               dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  Aabb cuts;
  for (const gcode::Move& m : gcode::read_moves(program.string()))
    if (m.kind != gcode::MoveKind::rapid) {
      if (glm::length(m.start) < 1000) cuts.extend(m.start);
      cuts.extend(m.end);
    }
  json stock = json::parse(slurp(report))["stock"];
  CHECK(stock["kind"] == "auto");
  CHECK(glm::length(vec(stock["min"]) - (cuts.min - Vec3(1))) < 1e-9);
  CHECK(glm::length(vec(stock["max"]) - (cuts.max + Vec3(1))) < 1e-9);
  fs::remove_all(dir);
}

TEST_CASE("simulate: the bundled example, from its CAMotics project, matches the reference") {
  fs::path dir = scratch("example");
  const std::string examples = TRIDEX_SOURCE_DIR "/gcode/examples/";
  fs::path stl = dir / "example.stl", png = dir / "example.png", report = dir / "example.json", maps = dir / "maps";
  CommandResult r = run_tridex({"simulate", examples + "mold_3plus2.camotics", "--dexel-res", "200", "--zmap-cell",
                                "0.2", "-o", stl.string(), "--png", png.string(), "--report", report.string(),
                                "--dump-zmaps", maps.string()},
                               dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.out.find("watertight") != std::string::npos);  // the one-line summary
  Simulated s{json::parse(slurp(report)), read_binary_stl(stl)};
  CHECK(s.report["groups"].size() == 5);
  CHECK(slurp(png).substr(1, 3) == "PNG");
  std::size_t dumped = 0;
  for (const auto& entry : fs::directory_iterator(maps)) dumped += entry.path().extension() == ".stl" || entry.path().extension() == ".png";
  CHECK(dumped == 10);
  cli::ToolTable table = cli::ToolTable::read(examples + "mold_3plus2.tools.json");
  Reference ref(gcode::read_moves(examples + "mold_3plus2.nc"), table, Aabb{Vec3(0, 0, 0), Vec3(100, 80, 50)});
  check_against_reference(s, ref, 11);
  // Along the edges where two directions' cuts meet (the +X bevel's top edge, the side
  // features' rims). At this resolution (h 0.5 mm, Z-map cell 0.4 h) with fine cells at the
  // walls (fine_cells.hpp): none of 3000 points wrong beyond h/2 (the worst 0.19 h); without
  // them the walls' rims are off by up to a Z-map cell (docs/design.md, "Known errors"). The
  // target, 2 in 10,000, is below what 3000 points resolve.
  std::mt19937 rng(13);
  const double h = s.report["dexel"]["cell_mm"].get<double>();
  test::EdgeErrors edges = test::measure_edges(ref.box, [&](const Vec3& p) { return ref.label(p); }, s.mesh, h, 3000, rng);
  MESSAGE("the example's edges: " << edges.samples << " points, " << edges.wrong << " wrong, " << edges.beyond_half
                                  << " beyond h/2, " << edges.beyond_one_and_half << " beyond 1.5h, worst " << edges.worst << " h");
  CHECK(edges.samples == 3000);
  CHECK(edges.beyond_one_and_half == 0);
  CHECK(edges.beyond_half * 10000 <= 4 * edges.samples);
  CHECK(edges.worst < 0.55);
  fs::remove_all(dir);
}

// The issue's figure (#17), a measurement run by hand because it takes minutes:
//   ./build/tests/tools/test_tools -tc="*edge figure*" --no-skip
// The bundled five-direction example at 0.1 mm dexels (--dexel-res 1000; the Z-map cell is the
// command's default, h/2), 40,000 points within h of the edges where two directions' cuts meet,
// classified against the moves. Target: at most 2 in 10,000 wrong beyond h/2, none beyond 1.5 h.
// TRIDEX_EDGE_RES overrides the resolution. Figures: docs/design.md, "Known errors".
TEST_CASE("the example's edge figure at 0.1 mm dexels (a measurement, run by hand)" * doctest::skip()) {
  fs::path dir = scratch("edge-figure");
  const std::string examples = TRIDEX_SOURCE_DIR "/gcode/examples/";
  const char* res = std::getenv("TRIDEX_EDGE_RES");
  fs::path stl = dir / "example.stl", report = dir / "example.json";
  CommandResult r = run_tridex({"simulate", examples + "mold_3plus2.camotics", "--dexel-res", res ? res : "1000", "-o",
                                stl.string(), "--report", report.string(), "--quiet"},
                               dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  Simulated s{json::parse(slurp(report)), read_binary_stl(stl)};
  Reference ref(gcode::read_moves(examples + "mold_3plus2.nc"), cli::ToolTable::read(examples + "mold_3plus2.tools.json"),
                Aabb{Vec3(0, 0, 0), Vec3(100, 80, 50)});
  std::mt19937 rng(17);
  const double h = s.report["dexel"]["cell_mm"].get<double>();
  test::EdgeErrors edges = test::measure_edges(ref.box, [&](const Vec3& p) { return ref.label(p); }, s.mesh, h, 40000, rng);
  MESSAGE("the example's edges at h = " << h << " mm: " << edges.samples << " points, " << edges.wrong << " wrong, "
                                        << edges.beyond_half << " beyond h/2, " << edges.beyond_one_and_half
                                        << " beyond 1.5h, worst " << edges.worst << " h");
  for (const auto& [p, d] : edges.beyond_half_at)
    MESSAGE("beyond h/2: (" << p.x << ", " << p.y << ", " << p.z << ") label " << ref.label(p) << ", " << d << " h");
  CHECK(edges.beyond_one_and_half == 0);
  CHECK(edges.beyond_half * 10000 <= 2 * edges.samples);
  fs::remove_all(dir);
}

// ---- edges of a five-direction part (issue 17) ------------------------------------------------

namespace {

// A part in the manner of the paper's five-direction model (Inui, Chen and Umezu 2022, §6): a
// 40 x 40 x 25 mm block whose top a 4 mm ball end finishes along X (scallops 0.09 mm high), and
// whose sides spindles tilted 15-40 degrees above horizontal cut, either faced flat by a 6 mm
// flat end or finished by the ball end (scallops 0.14 mm high), and may be slotted across.
// Every tilted cut runs past the top and the neighbouring sides, so that planar and scalloped
// cuts of two directions meet along the top's edges and at the corners.
struct TiltedSide {
  double azimuth, b;  // G68.2 I and J: the spindle points to the side, 90 - b degrees above horizontal
  bool ball;          // a ball-end raster (scalloped), else a flat-end facing (planar)
  bool slot;          // then a slot 1.5 mm deep across it with the same tool
};
const char* kPartTools = R"({"1": {"units": "mm", "shape": "cylindrical", "diameter": 6, "length": 30},
                            "2": {"units": "mm", "shape": "ballnose", "diameter": 4, "length": 30}})";
const char* kPartStock = "box:0,0,0,40,40,25";

std::string tilted_part(const std::vector<TiltedSide>& sides) {
  std::ostringstream p;
  auto top = [](double x, double y) { return 20 + 1.5 * std::sin(x / 5) * std::cos(y / 6); };
  p << "%\nG21 G17 G90\nT2 M6\nS12000 M3\nG0 X-3 Y-3\nG43 Z30 H2\nG1 Z" << top(-3, -3) << " F800\n";
  bool forward = true;
  for (int row = 0; row <= 38; ++row) {
    const double y = -3 + 1.2 * row;
    if (row > 0) p << "G1 Y" << y << " Z" << top(forward ? -3 : 43, y) << "\n";
    for (int k = 1; k <= 46; ++k) {
      const double x = forward ? -3 + k : 43 - k;
      p << "G1 X" << x << " Z" << top(x, y) << "\n";
    }
    forward = !forward;
  }
  p << "G0 Z30\n";
  for (const TiltedSide& side : sides) {
    // The feature origin: the middle of the side, 12 mm up; u runs along the side, v up the cut.
    const double a = side.azimuth * M_PI / 180;
    const Vec3 out(std::sin(a), -std::cos(a), 0), origin = Vec3(20, 20, 12) + 20.0 * out;
    const int tool = side.ball ? 2 : 1;
    p << "G28 G91 Z0.\nG90\nG69\nT" << tool << " M6\nS9000 M3\nG68.2 X" << origin.x << " Y" << origin.y << " Z"
      << origin.z << " I" << side.azimuth << " J" << side.b << " K0\nG53.1\nG0 X-26 Y0\nG43 Z10 H" << tool
      << "\nG1 Z0 F600\n";
    const double step = side.ball ? 1.5 : 4;
    forward = true;
    for (double v = 0; v <= 20; v += step) {
      if (v > 0) p << "G1 Y" << v << "\n";
      p << "G1 X" << (forward ? 26 : -26) << "\n";
      forward = !forward;
    }
    p << "G0 Z10\n";
    if (side.slot) p << "G0 X-26 Y6\nG1 Z-1.5\nG1 X26\nG0 Z10\n";
    p << "G28 G91 Z0.\nG90\nG69\n";
  }
  return p.str() + "M30\n%\n";
}

// The part simulated at `dexel_res` (the command's other defaults), `count` points near its
// edges classified against the moves.
test::EdgeErrors tilted_part_edges(const std::string& name, const std::vector<TiltedSide>& sides, const std::string& dexel_res,
                                   int count, std::uint32_t seed) {
  fs::path dir = scratch(name);
  fs::path program = dir / "part.nc", tools = dir / "tools.json", stl = dir / "part.stl", report = dir / "part.json";
  write_text(program, tilted_part(sides));
  write_text(tools, kPartTools);
  CommandResult r = run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", kPartStock,
                                "--dexel-res", dexel_res, "-o", stl.string(), "--report", report.string(), "--quiet"},
                               dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  Simulated s{json::parse(slurp(report)), read_binary_stl(stl)};
  CHECK(s.report["result"]["watertight"].get<bool>());
  CHECK(s.report["groups"].size() == sides.size() + 1);
  Reference ref(gcode::read_moves(program.string()), cli::ToolTable::read(tools.string()), Aabb{Vec3(0), Vec3(40, 40, 25)});
  std::mt19937 rng(seed);
  const double h = s.report["dexel"]["cell_mm"].get<double>();
  test::EdgeErrors edges = test::measure_edges(ref.box, [&](const Vec3& p) { return ref.label(p); }, s.mesh, h, count, rng);
  MESSAGE(name << " at h = " << h << " mm: " << edges.samples << " points, " << edges.wrong << " wrong, "
               << edges.beyond_half << " beyond h/2, " << edges.beyond_one_and_half << " beyond 1.5h, worst "
               << edges.worst << " h");
  for (const auto& [p, d] : edges.beyond_half_at)
    MESSAGE("beyond h/2: (" << p.x << ", " << p.y << ", " << p.z << ") label " << ref.label(p) << ", " << d << " h");
  CHECK(edges.samples == count);
  fs::remove_all(dir);
  return edges;
}

const std::vector<TiltedSide> kFiveDirections{
    {90, 60, false, true}, {180, 70, true, false}, {-90, 55, false, false}, {0, 65, true, false}};

}  // namespace

TEST_CASE("simulate: random pairs of a scalloped top and a tilted planar or scalloped side agree with the moves at their edges") {
  // +Z and one tilted side (random azimuth, 15-40 degrees above horizontal, planar or
  // scalloped, slotted or not) at h = 0.4 mm: no point near their edges wrong beyond 1.5 h, at
  // most 2 in 1000 beyond h/2.
  std::mt19937 rng(1717);
  std::uniform_int_distribution<int> quarter(0, 3), coin(0, 1);
  std::uniform_real_distribution<double> b(50, 75);
  for (int pair = 0; pair < 4; ++pair) {
    const TiltedSide side{90.0 * quarter(rng) - 90, b(rng), coin(rng) == 1, coin(rng) == 1};
    CAPTURE(side.azimuth);
    CAPTURE(side.b);
    CAPTURE(side.ball);
    CAPTURE(side.slot);
    test::EdgeErrors edges = tilted_part_edges("edge-pair", {side}, "100", 1000, 100 + static_cast<std::uint32_t>(pair));
    CHECK(edges.beyond_one_and_half == 0);
    CHECK(edges.beyond_half <= 2);
  }
}

TEST_CASE("simulate: a five-direction part agrees with the moves along its edges") {
  test::EdgeErrors edges = tilted_part_edges("edge-five", kFiveDirections, "100", 2000, 5);
  CHECK(edges.beyond_one_and_half == 0);
  CHECK(edges.beyond_half * 1000 <= 2 * edges.samples);
}

// The issue's figure (#17) on the five-direction part, run by hand (minutes):
//   ./build/tests/tools/test_tools -tc="*five-direction edge figure*" --no-skip
// At 0.1 mm dexels (--dexel-res 400; TRIDEX_EDGE_RES overrides it), 40,000 points within h of
// the edges. Target: at most 2 in 10,000 wrong beyond h/2, none beyond 1.5 h. Figures:
// docs/design.md, "Known errors".
TEST_CASE("the five-direction edge figure at 0.1 mm dexels (a measurement, run by hand)" * doctest::skip()) {
  const char* res = std::getenv("TRIDEX_EDGE_RES");
  test::EdgeErrors edges = tilted_part_edges("edge-five-figure", kFiveDirections, res ? res : "400", 40000, 17);
  CHECK(edges.beyond_one_and_half == 0);
  CHECK(edges.beyond_half * 10000 <= 2 * edges.samples);
}

TEST_CASE("progress goes to stderr only when asked (stderr is not a terminal here), and projects with several files") {
  fs::path dir = scratch("progress");
  fs::path tools = dir / "tools.json", first = dir / "first.nc", second = dir / "second.nc", project = dir / "job.camotics";
  write_text(tools, kTools);
  write_text(first, program_of({&kDirections[0]}));
  write_text(second, program_of({&kDirections[3]}));
  write_text(project, R"({"files": ["first.nc", "second.nc"], "tools": )" + kTools +
                          R"(, "workpiece": {"automatic": false, "bounds": {"min": [0, 0, 0], "max": [40, 30, 20]}}})");
  std::vector<std::string> args{"simulate", project.string(), "--dexel-res", "40", "--zmap-cell", "0.2"};
  CommandResult plain = run_tridex(args, dir);
  REQUIRE(plain.status == 0);
  CHECK(plain.out.find("job.camotics: ") == 0);
  CHECK(plain.err.find("milling direction") == std::string::npos);
  args.push_back("--progress");
  CommandResult progress = run_tridex(args, dir);
  REQUIRE(progress.status == 0);
  CHECK(progress.err.find("milling direction 2/2") != std::string::npos);
  CHECK(progress.err.find("extracting the surface") != std::string::npos);
  CHECK(progress.out == plain.out.substr(0, plain.out.rfind(';')) + progress.out.substr(progress.out.rfind(';')));

  // `moves` on the project: both files, in order, each record naming its file.
  CommandResult moves = run_tridex({"moves", project.string()}, dir);
  REQUIRE(moves.status == 0);
  std::istringstream lines(moves.out);
  std::string line, last_file;
  std::vector<std::string> files;
  while (std::getline(lines, line)) {
    std::string file = json::parse(line)["file"].get<std::string>();
    if (file != last_file) files.push_back(file), last_file = file;
  }
  REQUIRE(files.size() == 2);
  CHECK(fs::path(files[0]).filename() == "first.nc");
  CHECK(fs::path(files[1]).filename() == "second.nc");
  fs::remove_all(dir);
}

TEST_CASE("rapids that cut material no feed move removes are reported with their line and depth") {
  fs::path dir = scratch("rapids");
  fs::path tools = dir / "tools.json", program = dir / "crash.nc", report = dir / "report.json";
  write_text(tools, kTools);
  // Line 6 plunges at rapid 5 mm into the 20 mm high stock where no feed move goes, and line 7
  // retracts through the same material; line 11 rapids back over the path a feed move (line 10)
  // cut 2 mm deeper, so it meets nothing the feeds leave; lines 12-13 are clear.
  write_text(program,
             "G21 G90\nT1 M6\nS1000 M3\nG0 X10 Y10\nG43 Z30 H1\nG0 Z15\nG0 Z30\nG0 X30 Y20\nG1 Z16 F100\n"
             "G1 X34 Y8\nG0 X30 Y20 Z18\nG0 Z30\nG0 X5 Y25\nM30\n");
  CommandResult r = run_tridex({"simulate", program.string(), "--tools", tools.string(), "--stock", kStock,
                                "--dexel-res", "40", "--report", report.string()},
                               dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.err.find("2 rapid move(s) cut material that no feed move removes (at " + program.string() + ":6, " +
                   program.string() + ":7;") != std::string::npos);
  json found = json::parse(slurp(report))["rapid_cuts"];
  REQUIRE(found.size() == 2);
  for (std::size_t k = 0; k < 2; ++k) {
    CHECK(found[k]["line"] == 6 + static_cast<int>(k));
    CHECK(found[k]["tool"] == 1);
    CHECK(found[k]["depth_mm"].get<double>() == doctest::Approx(5).epsilon(1e-4));
  }
  fs::remove_all(dir);
}
