// `removed_mm3` against exact volumes: a flat end clearing a pocket with rounded corners and a
// ball end cutting a slot, 3-axis on a box stock whose faces lie on lattice node planes. The
// removal is measured surface against surface (pipeline.cpp, surface_volume): an uncut face's
// offset from the nodes cancels (before, it made these removals 0.9-1.2 % low at 0.25 mm).
#include <doctest/doctest.h>

#include <cmath>
#include <numbers>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"

namespace test_removed_volume {

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

constexpr double kPi = std::numbers::pi;

double removed(const fs::path& dir, const std::string& program) {
  write_text(dir / "tools.json",
             R"({"1": {"units": "mm", "shape": "cylindrical", "diameter": 6, "length": 40},)"
             R"( "2": {"units": "mm", "shape": "ballnose", "diameter": 6, "length": 40}})");
  write_text(dir / "p.nc", program);
  CommandResult r =
      run_tridex({"simulate", (dir / "p.nc").string(), "--tools", (dir / "tools.json").string(),
                  "--stock", "box:-30,-30,-10,30,30,0", "--dexel-cell", "0.25", "--report",
                  (dir / "r.json").string(), "-q"},
                 dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  const json report = json::parse(slurp(dir / "r.json"));
  CHECK(report["result"]["watertight"] == true);
  // The result's volume is the stock's less the removal.
  CHECK(report["result"]["volume_mm3"].get<double>() +
            report["result"]["removed_mm3"].get<double>() ==
        doctest::Approx(60.0 * 60 * 10).epsilon(1e-12));
  return report["result"]["removed_mm3"].get<double>();
}

TEST_CASE("removed_mm3: a pocket and a ball-end slot within 0.3 % of their exact volumes") {
  fs::path dir = scratch("removed-volume");
  // The tip traces the rectangle [-7, 7] x [-2, 2] 2 mm deep: a 6 mm flat end clears the
  // 20 x 10 mm pocket with corners of radius 3, walls and floor on node planes.
  const double pocket = removed(dir,
                                "G21 G90 G17\nT1 M6\nS8000 M3\nG0 X-7 Y-2 Z10\n"
                                "G1 Z-2 F300\nG1 X7\nG1 Y2\nG1 X-7\nG1 Y-2\nG0 Z10\nM2\n");
  const double pocket_exact = 2 * (20 * 10 - (4 - kPi) * 9);
  INFO("pocket " << pocket << " exact " << pocket_exact);
  CHECK(std::abs(pocket - pocket_exact) < 0.003 * pocket_exact);
  // A 6 mm ball end 3 mm deep along 20 mm: half a cylinder and a hemisphere.
  const double slot = removed(
      dir, "G21 G90 G17\nT2 M6\nS8000 M3\nG0 X-10 Y0 Z10\nG1 Z-3 F300\nG1 X10\nG0 Z10\nM2\n");
  const double slot_exact = 20 * kPi * 9 / 2 + 2.0 / 3 * kPi * 27;
  INFO("slot " << slot << " exact " << slot_exact);
  CHECK(std::abs(slot - slot_exact) < 0.003 * slot_exact);
  fs::remove_all(dir);
}

}  // namespace test_removed_volume
