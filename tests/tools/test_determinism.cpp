// The same run on 1, 2 and 8 threads gives a byte-identical STL and the same report figures
// (issue 16), on the bundled five-direction example: the kernel splits work into a fixed number
// of slabs and joins them in order, so the thread count must not show in the result.
#include <doctest/doctest.h>

#include <nlohmann/json.hpp>

#include "command_harness.hpp"

using namespace tridex;
using namespace tridex::test;

TEST_CASE("simulate and check: --threads 1, 2 and 8 give the same bytes and figures") {
  fs::path dir = scratch("threads");
  const fs::path example =
      fs::path(TRIDEX_SOURCE_DIR) / "gcode" / "examples" / "mold_3plus2.camotics";
  std::string first_stl;
  nlohmann::json first_report, first_check;
  for (const char* threads : {"1", "2", "8"}) {
    CAPTURE(threads);
    const std::string stl = (dir / (std::string("t") + threads + ".stl")).string();
    const std::string report = (dir / (std::string("t") + threads + ".json")).string();
    CommandResult r = run_tridex({"simulate", example.string(), "--dexel-res", "64", "--threads",
                                  threads, "-q", "-o", stl, "--report", report},
                                 dir);
    REQUIRE(r.status == 0);
    nlohmann::json figures = nlohmann::json::parse(slurp(report));
    REQUIRE(figures["groups"].size() == 5);
    figures.erase("timings_s");  // the only figures that may differ
    figures.erase("peak_rss_mib");
    figures.erase("memory_estimate_mib");  // counts the peak so far, measured
    // check compares with a design: the machined result itself, so every finding is rounding.
    const std::string check_report = (dir / (std::string("c") + threads + ".json")).string();
    CommandResult c =
        run_tridex({"check", example.string(), "--design", stl, "--dexel-res", "64",
                    "--lattice-only", "--threads", threads, "-q", "--report", check_report},
                   dir);
    REQUIRE((c.status == 0 || c.status == 3));
    nlohmann::json check = nlohmann::json::parse(slurp(check_report));
    check.erase("timings_s");
    check.erase("peak_rss_mib");
    check.erase("memory_estimate_mib");
    check.erase("design");  // names the design file, which differs by name
    if (first_stl.empty()) {
      first_stl = slurp(stl);
      first_report = figures;
      first_check = check;
      REQUIRE(first_stl.size() > 84);
      continue;
    }
    CHECK(slurp(stl) == first_stl);
    CHECK(figures == first_report);
    CHECK(check == first_check);
  }
  fs::remove_all(dir);
}

// With more than one thread the command makes each direction's initial Z-map beside the milling
// of the one before and writes the STL beside the surface's check (issue 37); an STL stock takes
// the mesh's path to those maps (ZMap::from_mesh). The stock here is the example's own result at
// a coarser lattice: a closed mesh with pockets, so that every direction's map starts uneven.
TEST_CASE("simulate: an STL stock on 1, 2 and 8 threads gives the same bytes and figures") {
  fs::path dir = scratch("threads-stl-stock");
  const fs::path example =
      fs::path(TRIDEX_SOURCE_DIR) / "gcode" / "examples" / "mold_3plus2.camotics";
  const std::string stock = (dir / "stock.stl").string();
  REQUIRE(run_tridex({"simulate", example.string(), "--dexel-res", "40", "-q", "-o", stock}, dir)
              .status == 0);
  std::string first_stl;
  nlohmann::json first_report;
  for (const char* threads : {"1", "2", "8"}) {
    CAPTURE(threads);
    const std::string stl = (dir / (std::string("t") + threads + ".stl")).string();
    const std::string report = (dir / (std::string("t") + threads + ".json")).string();
    CommandResult r = run_tridex({"simulate", example.string(), "--stock", stock, "--dexel-res",
                                  "56", "--threads", threads, "-q", "-o", stl, "--report", report},
                                 dir);
    INFO(r.err);
    REQUIRE(r.status == 0);
    nlohmann::json figures = nlohmann::json::parse(slurp(report));
    REQUIRE(figures["stock"]["kind"] == "stl");
    REQUIRE(figures["groups"].size() == 5);
    REQUIRE(figures["result"]["removed_mm3"].get<double>() > 0);
    figures.erase("timings_s");
    figures.erase("peak_rss_mib");
    figures.erase("memory_estimate_mib");
    if (first_stl.empty()) {
      first_stl = slurp(stl);
      first_report = figures;
      REQUIRE(first_stl.size() > 84);
      continue;
    }
    CHECK(slurp(stl) == first_stl);
    CHECK(figures == first_report);
  }
  fs::remove_all(dir);
}
