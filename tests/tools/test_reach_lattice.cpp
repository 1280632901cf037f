// A box stock far larger than the toolpath (issue 36, row 15; tools/cli/pipeline/reach.hpp): the
// lattice covers only the part of the stock the moves reach, the cut is measured there as on a
// normal stock, and the STL is the whole stock with the cut, watertight.
#include <doctest/doctest.h>

#include <cmath>
#include <nlohmann/json.hpp>
#include <numbers>

#include "command_harness.hpp"
#include "tridex/mesh_check.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace test_reach_lattice {

// A 10 mm flat end plunged 2 mm deep, then moved 10 mm along X: a slot with round ends.
constexpr const char* kPocket =
    "G21 G90 G17\nT1 M6\nS8000 M3\nG0 X0 Y0 Z5\nG1 Z-2 F300\nG1 X10\nG0 Z5\nM30\n";
constexpr double kPocketVolume = (10.0 * 10.0 + std::numbers::pi * 25.0) * 2.0;

json simulate(const fs::path& dir, const std::string& stock, const fs::path& stl) {
  CommandResult r = run_tridex(
      {"simulate", (dir / "pocket.nc").string(), "--tools", (dir / "tools.json").string(),
       "--stock", stock, "-o", stl.string(), "--report", (dir / "report.json").string()},
      dir);
  REQUIRE(r.status == 0);
  return json::parse(slurp(dir / "report.json"));
}

TEST_CASE("simulate: a 10 mm pocket in a 10 m plate is measured on a lattice over its reach") {
  fs::path dir = scratch("reach-lattice");
  write_text(dir / "tools.json", R"({"1": {"shape": "cylindrical", "diameter": 10}})");
  write_text(dir / "pocket.nc", kPocket);
  const json report = simulate(dir, "box:-5000,-5000,-10,5000,5000,0", dir / "plate.stl");
  const double removed = report["result"]["removed_mm3"].get<double>();
  CHECK(removed == doctest::Approx(kPocketVolume).epsilon(0.01));
  // The lattice is fine over the reach (20 mm / 320), not 10 m / 320.
  CHECK(report["dexel"]["cell_mm"].get<double>() < 0.1);
  bool said = false;
  for (const json& w : report["warnings"])
    said = said || w.get<std::string>().find(
                       "covers only the part of the stock the moves "
                       "reach") != std::string::npos;
  CHECK(said);
  CHECK(report["result"]["watertight"].get<bool>());
  // The STL: the whole plate, closed, its volume the plate's less the analytic pocket's.
  const Mesh mesh = weld_vertices(read_binary_stl(dir / "plate.stl"));
  CHECK(check_mesh(mesh).closed());
  const Aabb bounds = mesh.bounds();
  CHECK(bounds.min.x == -5000);
  CHECK(bounds.max.y == 5000);
  CHECK(bounds.min.z == -10);
  CHECK(std::abs(mesh.signed_volume() - (1e9 - kPocketVolume)) < 0.01 * kPocketVolume);

  // A stock about the size of the toolpath keeps its lattice over the whole stock.
  const json normal = simulate(dir, "box:-10,-10,-10,20,10,0", dir / "block.stl");
  for (const json& w : normal["warnings"])
    CHECK(w.get<std::string>().find("covers only") == std::string::npos);
  CHECK(normal["result"]["removed_mm3"].get<double>() ==
        doctest::Approx(kPocketVolume).epsilon(0.01));
  fs::remove_all(dir);
}

}  // namespace test_reach_lattice
