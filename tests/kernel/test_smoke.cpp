#include <doctest/doctest.h>

#include <cmath>

#include "tridex/mill.hpp"

using namespace tridex;

TEST_CASE("a ball plunge leaves its tip height at the centre") {
  ZMap map = ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(10, 10, 5)}, 0.5);
  std::vector<Cutter> cutters{Cutter::ball(2.0)};
  std::vector<CutMove> moves{{Segment{Vec3(5, 5, 10), Vec3(5, 5, 3)}, 0}};
  mill(map, cutters, moves);
  auto index = [&](double x, double origin) {
    return static_cast<int>(std::lround((x - origin) / map.grid.cell));
  };
  CHECK(map.height(index(5, map.grid.x0), index(5, map.grid.y0)) == doctest::Approx(3.0));
  CHECK(map.height(index(0.5, map.grid.x0), index(0.5, map.grid.y0)) == doctest::Approx(5.0));
  CHECK(map.is_empty(0, 0));  // the grid reaches beyond the stock
}
