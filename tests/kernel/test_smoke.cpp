#include <doctest/doctest.h>

#include "tridex/mill.hpp"

using namespace tridex;

TEST_CASE("a ball plunge leaves its tip height at the centre") {
  ZMap map = ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(10, 10, 5)}, 0.5);
  std::vector<Cutter> cutters{Cutter::ball(2.0)};
  std::vector<CutMove> moves{{Segment{Vec3(5, 5, 10), Vec3(5, 5, 3)}, 0}};
  mill(map, cutters, moves);
  CHECK(map.height(10, 10) == doctest::Approx(3.0));
  CHECK(map.height(0, 0) == doctest::Approx(5.0));
}
