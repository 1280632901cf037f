// --stock parsing and the automatic stock.
#include <doctest/doctest.h>

#include <random>

#include "errors.hpp"
#include "inputs/stock.hpp"
#include "pipeline/memory.hpp"

using namespace tridex;
using namespace tridex::cli;

TEST_CASE("--stock box, auto and file forms") {
  StockSpec box = parse_stock("box:-1,2.5,-3e1,4,5,0");
  CHECK(box.kind == StockSpec::Kind::box);
  CHECK(box.box.min == Vec3(-1, 2.5, -30));
  CHECK(box.box.max == Vec3(4, 5, 0));
  StockSpec automatic = parse_stock("auto");
  CHECK(automatic.kind == StockSpec::Kind::automatic);
  CHECK(!automatic.margin_mm);
  CHECK(*parse_stock("auto:2.5").margin_mm == 2.5);
  CHECK(parse_stock(TRIDEX_SOURCE_DIR "/tests/tools/CMakeLists.txt").kind == StockSpec::Kind::mesh);
  for (const char* bad : {"box:1,2,3", "box:0,0,0,1,1,x", "box:0,0,0,1,1,0", "box:1,0,0,0,1,1",
                          "box:0,0,0,1,1,nan", "auto:-1", "auto:abc", "no-such-file.stl", ""})
    CHECK_THROWS_AS(parse_stock(bad), InputError);
}

TEST_CASE("the automatic stock contains every cutting point with its margin") {
  std::mt19937 random(3);
  std::uniform_real_distribution<double> coordinate(-50, 50);
  for (int trial = 0; trial < 100; ++trial) {
    Aabb cuts;
    for (int k = 0; k < 5; ++k)
      cuts.extend(Vec3(coordinate(random), coordinate(random), coordinate(random)));
    StockSpec spec;
    spec.margin_mm = trial % 3 == 0 ? 0.0 : 1.5;
    Aabb stock = automatic_stock(cuts, spec);
    CHECK(stock.min.x == doctest::Approx(cuts.min.x - *spec.margin_mm));
    CHECK(stock.max.y == doctest::Approx(cuts.max.y + *spec.margin_mm));
    CHECK(stock.max.z >= cuts.max.z);
    CHECK(stock.max.z - stock.min.z >= 2);
    StockSpec percent;
    Aabb p = automatic_stock(cuts, percent);
    CHECK(p.min.x <= cuts.min.x);
    CHECK(p.max.x >= cuts.max.x);
    CHECK(p.max.z == doctest::Approx(cuts.min.z < 0 ? std::max(cuts.max.z, 0.0) : cuts.max.z));
  }
  CHECK_THROWS_AS(automatic_stock(Aabb{}, StockSpec{}), InputError);
}

TEST_CASE("--max-memory units and the memory estimate") {
  CHECK(parse_memory("512") == 512ull << 20);
  CHECK(parse_memory("2G") == 2ull << 30);
  CHECK(parse_memory("1.5GiB") == 3ull << 29);
  CHECK(parse_memory("64k") == 64ull << 10);
  for (const char* bad : {"", "G", "-1G", "3T", "1e30G"})
    CHECK_THROWS_AS(parse_memory(bad), InputError);
  // The estimate grows with every resolution it depends on.
  MemoryEstimate small = estimate_memory(5e7, 5e7,
                                         {.zmap_points = 1e6, .largest_map = 5e5, .rays = 3e4}),
                 big = estimate_memory(5e7, 5e7,
                                       {.zmap_points = 4e6, .largest_map = 2e6, .rays = 12e4});
  CHECK(big.zmaps == doctest::Approx(4 * small.zmaps));
  CHECK(big.dexels == doctest::Approx(4 * small.dexels));
  CHECK(big.mesh == doctest::Approx(4 * small.mesh));
  CHECK(big.held == small.held);
  CHECK(big.total() > small.total());
  // Keeping or dumping the maps costs more.
  CHECK(estimate_memory(0, 0, {.zmap_points = 1e6, .largest_map = 5e5, .keep_maps = true}).zmaps >
        small.zmaps);
  CHECK(estimate_memory(0, 0, {.zmap_points = 1e6, .largest_map = 5e5, .dump_maps = true}).total() >
        estimate_memory(0, 0, {.zmap_points = 1e6, .largest_map = 5e5}).total());
  CHECK(physical_memory_bytes() > (64ull << 20));
}
