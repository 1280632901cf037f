// `tridex simulate --zmap-backend / --dexel-backend`: every backend gives the same solid as the
// defaults (the dexel backends up to float rounding of dexel end points, gl within its cutter
// tessellation tolerance), the report names them, and a bad name is bad input.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"

using namespace tridex::test;
using nlohmann::json;

TEST_CASE("simulate: every Z-map and dexel backend gives the same solid") {
  fs::path dir = scratch("backends");
  const std::string example =
      std::string(TRIDEX_SOURCE_DIR) + "/gcode/examples/mold_3plus2.camotics";
  auto volume_with = [&](const std::string& zmap, const std::string& dexel) {
    fs::path report = dir / (zmap + "-" + dexel + ".json");
    CommandResult r = run_tridex(
        {"simulate", example, "--dexel-res", "96", "--zmap-cell", "0.4", "--zmap-backend", zmap,
         "--dexel-backend", dexel, "--report", report.string(), "--quiet"},
        dir);
    REQUIRE(r.status == 0);
    json j = json::parse(slurp(report));
    CHECK(j["backends"]["zmap"] == zmap);
    CHECK(j["backends"]["dexel"] == dexel);
    CHECK(j["result"]["watertight"] == true);
    return j["result"]["dexel_volume_mm3"].get<double>();
  };
  const double reference = volume_with("cpu", "tree");
  CHECK(volume_with("cpu", "scan") == doctest::Approx(reference).epsilon(1e-5));
  CHECK(volume_with("cpu", "embree") == doctest::Approx(reference).epsilon(1e-5));
  // gl's drawn cutter lies inside the true one (by at most a quarter Z-map cell), so it leaves
  // at least as much material, and not much more.
  double gl = volume_with("gl", "scan");
  CHECK(gl >= reference * (1 - 1e-5));
  CHECK(gl <= reference * 1.01);

  CommandResult bad = run_tridex({"simulate", example, "--dexel-backend", "voxels"}, dir);
  CHECK(bad.status == 2);
  CHECK(bad.err.find("voxels") != std::string::npos);
  fs::remove_all(dir);
}
