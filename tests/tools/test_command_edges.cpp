// `tridex simulate` where two spindle directions' cuts meet (issue 17): points sampled within one
// dexel spacing of those edges, classified against the moves, on the bundled example, on random
// pairs of a scalloped top and a tilted side, and on a five-direction part (docs/design.md,
// "Known errors", has the figures).
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "command_reference.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

// The issue's figure (#17), a measurement run by hand because it takes minutes:
//   ./build/tests/tools/test_tools -tc="*edge figure*" --no-skip
// The bundled five-direction example at 0.1 mm dexels (--dexel-res 1000; the Z-map cell is the
// command's default, h/2), 40,000 points within h of the edges where two directions' cuts meet,
// classified against the moves. Target: at most 2 in 10,000 wrong beyond h/2, none beyond 1.5 h.
// TRIDEX_EDGE_RES overrides the resolution. Figures: docs/design.md, "Known errors".
TEST_CASE("the example's edge figure at 0.1 mm dexels (a measurement, run by hand)" *
          doctest::skip()) {
  fs::path dir = scratch("edge-figure");
  const std::string examples = TRIDEX_SOURCE_DIR "/gcode/examples/";
  const char* res = std::getenv("TRIDEX_EDGE_RES");
  fs::path stl = dir / "example.stl", report = dir / "example.json";
  CommandResult r =
      run_tridex({"simulate", examples + "mold_3plus2.camotics", "--dexel-res", res ? res : "1000",
                  "-o", stl.string(), "--report", report.string(), "--quiet"},
                 dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  Simulated s{json::parse(slurp(report)), read_binary_stl(stl)};
  Reference ref(gcode::read_moves(examples + "mold_3plus2.nc"),
                cli::ToolTable::read(examples + "mold_3plus2.tools.json"),
                Aabb{Vec3(0, 0, 0), Vec3(100, 80, 50)});
  std::mt19937 rng(17);
  const double h = s.report["dexel"]["cell_mm"].get<double>();
  test::EdgeErrors edges = test::measure_edges(
      ref.box, [&](const Vec3& p) { return ref.label(p); }, s.mesh, h, 40000, rng);
  MESSAGE("the example's edges at h = " << h << " mm: " << edges.samples << " points, "
                                        << edges.wrong << " wrong, " << edges.beyond_half
                                        << " beyond h/2, " << edges.beyond_one_and_half
                                        << " beyond 1.5h, worst " << edges.worst << " h");
  for (const auto& [p, d] : edges.beyond_half_at)
    MESSAGE("beyond h/2: (" << p.x << ", " << p.y << ", " << p.z << ") label " << ref.label(p)
                            << ", " << d << " h");
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
  double azimuth,
      b;      // G68.2 I and J: the spindle points to the side, 90 - b degrees above horizontal
  bool ball;  // a ball-end raster (scalloped), else a flat-end facing (planar)
  bool slot;  // then a slot 1.5 mm deep across it with the same tool
};
const char* kPartTools =
    R"({"1": {"units": "mm", "shape": "cylindrical", "diameter": 6, "length": 30},
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
    p << "G28 G91 Z0.\nG90\nG69\nT" << tool << " M6\nS9000 M3\nG68.2 X" << origin.x << " Y"
      << origin.y << " Z" << origin.z << " I" << side.azimuth << " J" << side.b
      << " K0\nG53.1\nG0 X-26 Y0\nG43 Z10 H" << tool << "\nG1 Z0 F600\n";
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
test::EdgeErrors tilted_part_edges(const std::string& name, const std::vector<TiltedSide>& sides,
                                   const std::string& dexel_res, int count, std::uint32_t seed) {
  fs::path dir = scratch(name);
  fs::path program = dir / "part.nc", tools = dir / "tools.json", stl = dir / "part.stl",
           report = dir / "part.json";
  write_text(program, tilted_part(sides));
  write_text(tools, kPartTools);
  CommandResult r = run_tridex(
      {"simulate", program.string(), "--tools", tools.string(), "--stock", kPartStock,
       "--dexel-res", dexel_res, "-o", stl.string(), "--report", report.string(), "--quiet"},
      dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  Simulated s{json::parse(slurp(report)), read_binary_stl(stl)};
  CHECK(s.report["result"]["watertight"].get<bool>());
  CHECK(s.report["groups"].size() == sides.size() + 1);
  Reference ref(gcode::read_moves(program.string()), cli::ToolTable::read(tools.string()),
                Aabb{Vec3(0), Vec3(40, 40, 25)});
  std::mt19937 rng(seed);
  const double h = s.report["dexel"]["cell_mm"].get<double>();
  test::EdgeErrors edges = test::measure_edges(
      ref.box, [&](const Vec3& p) { return ref.label(p); }, s.mesh, h, count, rng);
  MESSAGE(name << " at h = " << h << " mm: " << edges.samples << " points, " << edges.wrong
               << " wrong, " << edges.beyond_half << " beyond h/2, " << edges.beyond_one_and_half
               << " beyond 1.5h, worst " << edges.worst << " h");
  for (const auto& [p, d] : edges.beyond_half_at)
    MESSAGE("beyond h/2: (" << p.x << ", " << p.y << ", " << p.z << ") label " << ref.label(p)
                            << ", " << d << " h");
  CHECK(edges.samples == count);
  fs::remove_all(dir);
  return edges;
}

const std::vector<TiltedSide> kFiveDirections{
    {90, 60, false, true}, {180, 70, true, false}, {-90, 55, false, false}, {0, 65, true, false}};

}  // namespace

TEST_CASE(
    "simulate: random pairs of a scalloped top and a tilted planar or scalloped side agree with "
    "the moves at their edges") {
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
    test::EdgeErrors edges =
        tilted_part_edges("edge-pair", {side}, "100", 1000, 100 + static_cast<std::uint32_t>(pair));
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
TEST_CASE("the five-direction edge figure at 0.1 mm dexels (a measurement, run by hand)" *
          doctest::skip()) {
  const char* res = std::getenv("TRIDEX_EDGE_RES");
  test::EdgeErrors edges =
      tilted_part_edges("edge-five-figure", kFiveDirections, res ? res : "400", 40000, 17);
  CHECK(edges.beyond_one_and_half == 0);
  CHECK(edges.beyond_half * 10000 <= 2 * edges.samples);
}
