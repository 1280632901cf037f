// Shank and holder collisions (issue 14): the swept parts' depths and near-miss distances against
// a brute-force reference (the swept solid sampled densely along the move) on random moves in
// tilted frames, and the planted faults end to end through `tridex check`.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <tuple>
#include <utility>

#include <nlohmann/json.hpp>

#include "checks/collision_check.hpp"
#include "command_harness.hpp"
#include "tridex/zmap.hpp"

using namespace tridex;
using namespace tridex::cli;
using namespace tridex::test;
using nlohmann::json;

namespace test_collisions {

// ---- the brute-force reference
// -------------------------------------------------------------------

// Height above the section's bottom of its lowest point at distance rho from the axis (+inf
// beyond it), from the section's shape alone.
double section_low(const BodySection& s, double rho) {
  if (rho <= s.bottom_radius) return 0;
  if (s.top_radius > s.bottom_radius && rho <= s.top_radius)
    return (rho - s.bottom_radius) * s.length / (s.top_radius - s.bottom_radius);
  return std::numeric_limits<double>::infinity();
}

double point_segment_2d(Vec2 p, Vec2 a, Vec2 b) {
  Vec2 ab = b - a;
  double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}

// Distance in a meridian plane from the material column at distance rho from the axis (all
// z ≤ top) to the section's cross-section, a trapezoid with its bottom at z = bottom.
double column_distance(const BodySection& s, double bottom, double rho, double top) {
  if (top >= bottom + section_low(s, rho)) return 0;
  const Vec2 corners[4] = {Vec2(-s.bottom_radius, bottom), Vec2(s.bottom_radius, bottom),
                           Vec2(s.top_radius, bottom + s.length),
                           Vec2(-s.top_radius, bottom + s.length)};
  const Vec2 end(rho, top);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 4; ++k) {
    best = std::min(best, point_segment_2d(end, corners[k], corners[(k + 1) % 4]));
    // A corner to the column: straight across if it lies below the column's top.
    const Vec2 c = corners[k];
    best = std::min(best, c.y <= top ? std::abs(c.x - rho) : glm::length(c - end));
  }
  return best;
}

struct Reference {
  double depth_low = -std::numeric_limits<double>::infinity();   // sampled: never above the truth
  double depth_high = -std::numeric_limits<double>::infinity();  // widened by a step: never below
  double distance = std::numeric_limits<double>::infinity();     // sampled
  double step = 0;                                               // the tip's travel per sample
};

Reference brute_force(const ZMap& map, const BodyPart& part, const Segment& tip) {
  constexpr int kSamples = 1200;
  Reference ref;
  const Vec3 v = tip.b - tip.a;
  const double e = std::hypot(v.x, v.y) / kSamples, rise = std::abs(v.z) / kSamples;
  ref.step = glm::length(v) / kSamples;
  const BodySection& s = part.shape;
  // Grid points farther than this from the tip's path are out of reach of the part and its growth.
  const double reach = std::max(s.bottom_radius, s.top_radius) + 3;
  const ZMapGrid& g = map.grid;
  const int i0 = std::max(0, int((std::min(tip.a.x, tip.b.x) - reach - g.x0) / g.cell));
  const int i1 = std::min(g.nx - 1, int((std::max(tip.a.x, tip.b.x) + reach - g.x0) / g.cell) + 1);
  const int j0 = std::max(0, int((std::min(tip.a.y, tip.b.y) - reach - g.y0) / g.cell));
  const int j1 = std::min(g.ny - 1, int((std::max(tip.a.y, tip.b.y) + reach - g.y0) / g.cell) + 1);
  for (int k = 0; k <= kSamples; ++k) {
    const Vec3 c = tip.a + (double(k) / kSamples) * v;
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        if (map.is_empty(i, j)) continue;
        const double h = map.height(i, j);
        const double rho = std::hypot(map.grid.x(i) - c.x, map.grid.y(j) - c.y);
        ref.depth_low = std::max(ref.depth_low, h - (c.z + part.bottom + section_low(s, rho)));
        ref.depth_high = std::max(ref.depth_high, h - (c.z - rise + part.bottom +
                                                       section_low(s, std::max(0.0, rho - e))));
        ref.distance = std::min(ref.distance, column_distance(s, c.z + part.bottom, rho, h));
      }
  }
  return ref;
}

TEST_CASE("swept shank and holder depths and near misses match the sampled swept solid") {
  std::mt19937 random(14);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int collisions = 0, near = 0, clear = 0, widening = 0;
  for (int trial = 0; trial < 60; ++trial) {
    // A tilted direction's map: a random height field with some points cut through.
    Vec3 axis = glm::normalize(Vec3(unit(random) - 0.5, unit(random) - 0.5, 1.0));
    ZMapGrid grid{Frame::from_axis(axis), -1.0, -1.0, 0.5, 40, 40};
    ZMap map(grid, 0.0f, -20.0f);
    for (float& h : map.heights)
      h = unit(random) < 0.1 ? -20.0f : static_cast<float>(10 * unit(random));
    BodyPart part;
    part.name = "holder section 1";
    part.bottom = 5 * unit(random);
    const double r0 = 1 + 3 * unit(random);
    const int kind = trial % 3;  // cylinder, widening frustum, narrowing frustum
    part.shape = BodySection{r0,
                             kind == 0   ? r0
                             : kind == 1 ? r0 + 0.5 + 2.5 * unit(random)
                                         : r0 * (0.5 + 0.5 * unit(random)),
                             2 + 6 * unit(random)};
    widening += kind == 1;
    // Moves in the work frame, given to the map in its frame (as the pipeline does).
    Vec3 a_local(3 + 13 * unit(random), 3 + 13 * unit(random), 6 + 8 * unit(random) - part.bottom);
    Vec3 b_local = a_local + Vec3(8 * (unit(random) - 0.5), 8 * (unit(random) - 0.5),
                                  4 * (unit(random) - 0.5));
    if (trial % 5 == 0) b_local = Vec3(a_local.x, a_local.y, b_local.z);  // a plunge
    const Segment tip{grid.frame.to_local(grid.frame.to_world(a_local)),
                      grid.frame.to_local(grid.frame.to_world(b_local))};
    const double clearance = 0.5 + 1.5 * unit(random);
    std::vector<ToolBody> bodies{ToolBody{{part}, 0}};
    BodyCheck check(map, bodies, clearance);
    BodyFindings found;
    gcode::Move move;
    move.line = trial + 1;
    move.tool = 1;
    check.check(
        map, move, CutMove{tip, 0}, axis, grid.frame, 0, true, [] {}, found);
    const Reference ref = brute_force(map, part, tip);
    INFO("trial ", trial, " kind ", kind, " depth in [", ref.depth_low, ", ", ref.depth_high,
         "], distance ", ref.distance);
    if (!found.collisions.empty()) {
      ++collisions;
      const double depth = found.collisions[0].depth_mm;
      CHECK(depth >= ref.depth_low - 1e-4);
      CHECK(depth <= ref.depth_high + 1e-4);
      CHECK(found.near_misses.empty());
      // The reported point is a grid point with material, in the work frame.
      Vec3 local = grid.frame.to_local(found.collisions[0].where);
      CHECK(std::abs(local.x - grid.x0 - grid.cell * std::round((local.x - grid.x0) / grid.cell)) <
            1e-6);
    } else {
      CHECK(ref.depth_low <= kCollisionTolerance + 1e-4);
      const double slack = ref.step + 0.005 * clearance + 2e-3;
      if (!found.near_misses.empty()) {
        ++near;
        CHECK(std::abs(found.near_misses[0].depth_mm - ref.distance) <= slack);
      } else {
        ++clear;
        CHECK(ref.distance >= clearance - slack);
      }
    }
  }
  MESSAGE(collisions, " collisions, ", near, " near misses, ", clear, " clear");
  // The random cases reach every outcome and every shape.
  CHECK(collisions > 5);
  CHECK(near > 3);
  CHECK(clear > 3);
  CHECK(widening > 5);
}

// ---- planted faults, end to end
// ------------------------------------------------------------------

// T2 (no parts described) clears the stock 0..60 × 0..40 × 0..30 to z = 20 except a boss
// beyond the round end of its first pass (x ≥ 30 + √(12² − (y − 8)²), y < 18). T1's holder (Ø30, 25
// mm out) passes by the boss on line 16 with its face at z1 + 25; T3's Ø8 shank, 3 mm above the tip
// of its Ø4 flutes, crosses the pocket's floor on line 21 at z3 + 3.
std::string fault_program(double z1, double z3) {
  std::ostringstream p;
  p << "%\nG21 G17 G90\nT2 M6\nS8000 M3\nG0 X-15 Y8 Z40\nG1 Z20 F500\nG1 X30\nG0 Z40\nG0 X-15 "
       "Y30\nG1 Z20\n"
    << "G1 X75\nG0 Z40\nT1 M6\nG0 X30 Y45 Z40\nG1 Z" << z1
    << " F300\nG1 Y-20\nG0 Z40\nT3 M6\nG0 X-10 Y30 Z40\nG1 Z" << z3 << "\nG1 X70\nG0 Z40\nM30\n%\n";
  return p.str();
}

const char* kFaultTools = R"({
  "1": {"shape": "cylindrical", "diameter": 6, "stick-out": 25,
        "holder": [{"bottom-diameter": 30, "top-diameter": 30, "length": 20}]},
  "2": {"shape": "cylindrical", "diameter": 24},
  "3": {"shape": "cylindrical", "diameter": 4, "flute-length": 3, "shank-diameter": 8}})";

struct CheckRun {
  CommandResult result;
  json report;  // null where check wrote none
};

// Simulates the program into its own design, then checks the program against that design on
// the stock 0..60 × 0..40 × 0..30: only the tools' non-cutting parts can fail the check.
CheckRun simulate_then_check(const fs::path& dir, const std::string& program,
                             const std::string& tools, const std::vector<std::string>& more = {}) {
  write_text(dir / "tools.json", tools);
  write_text(dir / "p.nc", program);
  fs::remove(dir / "report.json");
  CommandResult made = run_tridex(
      {"simulate", (dir / "p.nc").string(), "--tools", (dir / "tools.json").string(), "--stock",
       "box:0,0,0,60,40,30", "--dexel-cell", "0.5", "-o", (dir / "design.stl").string(), "-q"},
      dir);
  REQUIRE(made.status == 0);
  std::vector<std::string> args{"check",        (dir / "p.nc").string(),
                                "--design",     (dir / "design.stl").string(),
                                "--tools",      (dir / "tools.json").string(),
                                "--stock",      "box:0,0,0,60,40,30",
                                "--dexel-cell", "0.5",
                                "--tolerance",  "0.6",
                                "--report",     (dir / "report.json").string()};
  args.insert(args.end(), more.begin(), more.end());
  CheckRun run{run_tridex(args, dir), json()};
  if (fs::exists(dir / "report.json")) run.report = json::parse(slurp(dir / "report.json"));
  return run;
}

CheckRun run_faults(const fs::path& dir, double z1, double z3,
                    const std::vector<std::string>& more = {}) {
  return simulate_then_check(dir, fault_program(z1, z3), kFaultTools, more);
}

TEST_CASE(
    "check: a holder passing a boss and a shank on a pocket's floor are found at their lines") {
  fs::path dir = scratch("collisions");
  CheckRun run = run_faults(dir, 4, 16.5);
  INFO(run.result.out, run.result.err);
  CHECK(run.result.status == 3);
  const json& c = run.report["collisions"];
  REQUIRE(c.size() == 2);
  // The holder's face at z = 29, the boss's top at 30.
  CHECK(c[0]["line"] == 16);
  CHECK(c[0]["tool"] == 1);
  CHECK(c[0]["part"] == "holder section 1");
  CHECK(c[0]["depth_mm"].get<double>() == doctest::Approx(1.0).epsilon(0.001));
  CHECK(c[0]["point"][2].get<double>() == doctest::Approx(30));
  // On the boss: outside the round end of T2's first pass (centre (30, 8), radius 12).
  CHECK(std::hypot(c[0]["point"][0].get<double>() - 30, c[0]["point"][1].get<double>() - 8) >=
        12 - 0.1);
  CHECK(c[0]["point"][1].get<double>() < 20);
  CHECK(c[0]["axis"] == json::array({0.0, 0.0, 1.0}));
  // The shank's bottom at z = 19.5, the floor at 20.
  CHECK(c[1]["line"] == 21);
  CHECK(c[1]["tool"] == 3);
  CHECK(c[1]["part"] == "shank");
  CHECK(c[1]["depth_mm"].get<double>() == doctest::Approx(0.5).epsilon(0.001));
  CHECK(c[1]["point"][2].get<double>() == doctest::Approx(20));
  // The holder must come out 1 mm further (and the tolerance).
  REQUIRE(run.report["stick_out"].size() == 1);
  CHECK(run.report["stick_out"][0]["tool"] == 1);
  CHECK(run.report["stick_out"][0]["needed_mm"].get<double>() ==
        doctest::Approx(26.0).epsilon(0.001));
  CHECK(run.result.out.find("p.nc:16: tool 1's holder section 1 is 1.000 mm into the stock") !=
        std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE(
    "check: a program whose holder and shank clear by a known margin passes, the margins as near "
    "misses") {
  fs::path dir = scratch("near-misses");
  CheckRun run = run_faults(dir, 6, 17.5, {"--clearance", "2"});
  INFO(run.result.out, run.result.err);
  CHECK(run.result.status == 0);
  CHECK(run.report["collisions"].empty());
  CHECK(run.report["stick_out"].empty());
  const json& near = run.report["near_misses"];
  CHECK(near["clearance_mm"] == 2.0);
  REQUIRE(near["moves"].size() == 2);
  // Within one Z-map cell (here diagonal / 1000 ≈ 0.08 mm) of the margins planted.
  CHECK(near["moves"][0]["line"] == 16);
  CHECK(near["moves"][0]["part"] == "holder section 1");
  CHECK(std::abs(near["moves"][0]["distance_mm"].get<double>() - 1.0) <= 0.08);
  CHECK(near["moves"][1]["line"] == 21);
  CHECK(near["moves"][1]["part"] == "shank");
  CHECK(std::abs(near["moves"][1]["distance_mm"].get<double>() - 0.5) <= 0.08);
  // Below the margins: nothing.
  run = run_faults(dir, 6, 17.5, {"--clearance", "0.4"});
  CHECK(run.result.status == 0);
  CHECK(run.report["near_misses"]["moves"].empty());
  fs::remove_all(dir);
}

TEST_CASE(
    "check: a hole by the stock's edge buries the holder along +Z and clears it tilted away") {
  fs::path dir = scratch("tilted-clear");
  const std::string tools = R"({"1": {"shape": "cylindrical", "diameter": 6, "stick-out": 20,
      "holder": [{"bottom-diameter": 30, "top-diameter": 30, "length": 20}]}})";
  auto run = [&](const std::string& program) {
    CheckRun r = simulate_then_check(dir, program, tools, {"--clearance", "3"});
    INFO(r.result.out, r.result.err);
    return std::make_pair(r.result.status, r.report);
  };
  // A hole 25 mm deep, 4 mm from the front face: the holder's face at z = 25 under the top at 30.
  auto [status, report] =
      run("%\nG21 G17 G90\nT1 M6\nS8000 M3\nG0 X30 Y4 Z40\nG1 Z5 F300\nG0 Z40\nM30\n%\n");
  CHECK(status == 3);
  REQUIRE(!report["collisions"].empty());
  CHECK(report["collisions"][0]["line"] == 6);
  CHECK(report["collisions"][0]["depth_mm"].get<double>() == doctest::Approx(5.0).epsilon(0.001));
  // The stick-out the program needs, for this tool along this direction: 20 mm + 5 mm.
  REQUIRE(report["stick_out"].size() == 1);
  CHECK(report["stick_out"][0]["tool"] == 1);
  CHECK(report["stick_out"][0]["axis"] == json::array({0.0, 0.0, 1.0}));
  CHECK(report["stick_out"][0]["stick_out_mm"] == 20.0);
  CHECK(report["stick_out"][0]["needed_mm"].get<double>() == doctest::Approx(25.0).epsilon(0.001));
  // The same entry, 15 mm along a spindle tilted 45° out through the front face: the holder's face
  // (centre entry + 5 mm back along the axis, radius 15) passes the top front edge at 2.172 mm
  // (its distance along the axis; the edge lies within the face's radius).
  std::tie(status, report) =
      run("%\nG21 G17 G90\nT1 M6\nS8000 M3\nG68.2 X30 Y4 Z30 I0 J45 K0\nG53.1\nG0 X0 Y0 Z10\nG1 "
          "Z-15 F300\nG0 Z10\n"
          "G69\nM30\n%\n");
  CHECK(status == 0);
  CHECK(report["collisions"].empty());
  CHECK(report["stick_out"].empty());
  REQUIRE(!report["near_misses"]["moves"].empty());
  const json& near = report["near_misses"]["moves"][0];
  CHECK(near["line"] == 8);
  CHECK(near["axis"][1].get<double>() == doctest::Approx(-std::sqrt(0.5)));
  CHECK(std::abs(near["distance_mm"].get<double>() - 2.172) <=
        0.08);  // one Z-map cell (diagonal / 1000)
  fs::remove_all(dir);
}

TEST_CASE("check: a shank working down its own slot meets only what the earlier passes left") {
  // Three passes down a slot, one batch (no rapid in the material between them): the shank above
  // the 10 mm flutes of the last pass stands where the first two passes cut. Checked against the
  // map before those passes are milled it would hit 5 mm of material; the check must see them.
  fs::path dir = scratch("own-slot");
  CheckRun run = simulate_then_check(
      dir,
      "%\nG21 G17 G90\nT1 M6\nS8000 M3\nG0 X10 Y20 Z35\nG1 Z25 F300\nG1 X50\nG1 Z20\n"
      "G1 X10\nG1 Z15\nG1 X50\nG0 Z40\nM30\n%\n",
      R"({"1": {"shape": "cylindrical", "diameter": 6, "flute-length": 10,
      "shank-diameter": 5.8, "stick-out": 30, "holder": [{"bottom-diameter": 30, "top-diameter": 30, "length": 20}]}})");
  INFO(run.result.out, run.result.err);
  CHECK(run.result.status == 0);
  const json& report = run.report;
  CHECK(report["collisions"].empty());
  // The shank passes the slot's walls 0.1 mm away on the last pass.
  bool walls = false;
  for (const json& m : report["near_misses"]["moves"])
    if (m["line"] == 11 && m["part"] == "shank")
      walls = std::abs(m["distance_mm"].get<double>() - 0.1) <= 0.08;
  CHECK(walls);
  fs::remove_all(dir);
}

}  // namespace test_collisions
