#include <doctest/doctest.h>

#include <random>

#include "test_dexel_shapes.hpp"
#include "tridex/intersect_milled.hpp"
#include "tridex/mill.hpp"

using namespace tridex;

namespace test_intersect_milled {

struct Direction {
  Frame frame;
  std::vector<CutMove> moves;  // tool tip in the frame
};

// Random moves in each tilted direction over a box stock: tips from above the stock down to
// 40 % of its depth, so cuts cross and overlap between directions.
std::vector<Direction> random_program(std::mt19937& rng, const Aabb& stock, int direction_count) {
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Direction> program;
  for (int i = 0; i < direction_count; ++i) {
    Vec3 axis = glm::normalize(Vec3(unit(rng) - 0.5, unit(rng) - 0.5, 0.6 + unit(rng)));
    if (i == 1) axis = glm::normalize(Vec3(1, 0.2 * unit(rng), 0.1));  // nearly horizontal spindle
    Direction d{Frame::from_axis(axis), {}};
    Aabb local = local_bounds(d.frame, stock);
    for (int k = 0; k < 8; ++k) {
      auto tip = [&] {
        return Vec3(local.min.x + unit(rng) * (local.max.x - local.min.x),
                    local.min.y + unit(rng) * (local.max.y - local.min.y),
                    local.max.z - (0.1 + 0.4 * unit(rng)) * (local.max.z - local.min.z));
      };
      d.moves.push_back({Segment{tip(), tip()}, static_cast<std::uint32_t>(k % 3)});
    }
    program.push_back(d);
  }
  return program;
}

// The reference: p is removed iff, in some direction, some move's swept cutter reaches down to
// p's local height over p's local (x, y).
bool removed(const std::vector<Direction>& program, const std::vector<Cutter>& cutters,
             const Vec3& p) {
  for (const Direction& d : program) {
    Vec3 q = d.frame.to_local(p);
    for (const CutMove& m : d.moves)
      if (q.z >= detail::MoveGeometry(cutters[m.cutter], m.tip).lowest_above(q.x, q.y)) return true;
  }
  return false;
}

TEST_CASE(
    "intersect_milled: a box milled in several tilted directions matches the point-membership "
    "reference") {
  std::mt19937 rng(101);
  std::uniform_real_distribution<double> unit(0, 1);
  const std::vector<Cutter> cutters{Cutter::ball(1.0), Cutter::flat(0.7),
                                    Cutter::bull_nose(0.9, 0.3)};
  for (int trial = 0; trial < 4; ++trial) {
    Aabb stock{Vec3(-3, -2, 0), Vec3(3 + unit(rng), 2 + unit(rng), 3 + unit(rng))};
    std::vector<Direction> program = random_program(rng, stock, 2 + trial % 2);
    const double cell = 0.04, spacing = 0.08;
    std::vector<ZMap> maps;
    for (const Direction& d : program) {
      maps.push_back(ZMap::from_box(d.frame, stock, cell));
      mill(maps.back(), cutters, d.moves);
    }
    DexelLattice lattice = DexelLattice::covering(stock, spacing);
    TripleDexel result = intersect_milled(stock, lattice, maps);
    validate(result);
    // Away from every surface (the stock's faces and the cut) by the Z-map and dexel error
    // bands, the classification must agree.
    const double margin = 2 * spacing + 2 * cell;
    const Vec3 offsets[] = {Vec3(1, 0, 0),
                            Vec3(-1, 0, 0),
                            Vec3(0, 1, 0),
                            Vec3(0, -1, 0),
                            Vec3(0, 0, 1),
                            Vec3(0, 0, -1),
                            Vec3(1, 1, 1) / std::sqrt(3.0),
                            Vec3(-1, -1, -1) / std::sqrt(3.0),
                            Vec3(1, -1, 1) / std::sqrt(3.0),
                            Vec3(-1, 1, -1) / std::sqrt(3.0)};
    int compared = 0, cut = 0;
    for (int k = 0; k < 6000; ++k) {
      Vec3 p = stock.min + Vec3(unit(rng), unit(rng), unit(rng)) * stock.size();
      Vec3 gap = glm::min(p - stock.min, stock.max - p);
      if (std::min({gap.x, gap.y, gap.z}) < margin) continue;
      bool expected = removed(program, cutters, p), stable = true;
      for (const Vec3& o : offsets)
        stable = stable && removed(program, cutters, p + margin * o) == expected;
      if (!stable) continue;
      CHECK(contains(result, p) == !expected);
      ++compared, cut += expected;
    }
    CHECK(compared > 1500);
    CHECK(cut > 100);
    // Removing material only: the result lies within the stock, and its volume is below it.
    CHECK(volume(intersect(result, TripleDexel::box(lattice, stock))) ==
          doctest::Approx(volume(result)));
    CHECK(volume(result) < volume(TripleDexel::box(lattice, stock)));
  }
}

TEST_CASE(
    "intersect_milled: independent of the order of directions and of the thread count; equals the "
    "Booleans") {
  std::mt19937 rng(7);
  const std::vector<Cutter> cutters{Cutter::ball(1.0), Cutter::flat(0.7), Cutter::ball(0.5)};
  Aabb stock{Vec3(0), Vec3(5, 4, 3)};
  std::vector<Direction> program = random_program(rng, stock, 3);
  std::vector<ZMap> maps;
  for (const Direction& d : program) {
    maps.push_back(ZMap::from_box(d.frame, stock, 0.05));
    mill(maps.back(), cutters, d.moves);
  }
  DexelLattice lattice = DexelLattice::covering(stock, 0.1);
  TripleDexel a = intersect_milled(stock, lattice, maps, 1);
  std::vector<ZMap> reversed(maps.rbegin(), maps.rend());
  TripleDexel b = intersect_milled(stock, lattice, reversed, 3);
  for (int k = 0; k < 3; ++k) {
    CHECK(a.grids[k].offsets == b.grids[k].offsets);
    bool same = a.grids[k].intervals.size() == b.grids[k].intervals.size();
    for (std::size_t i = 0; same && i < a.grids[k].intervals.size(); ++i)
      same = a.grids[k].intervals[i].enter == b.grids[k].intervals[i].enter &&
             a.grids[k].intervals[i].exit == b.grids[k].intervals[i].exit;
    CHECK(same);
  }
  TripleDexel booleans = TripleDexel::box(lattice, stock);
  for (const ZMap& m : maps) booleans = intersect(booleans, dexelize(m, lattice));
  CHECK(volume(a) == doctest::Approx(volume(booleans)).epsilon(1e-6));
  // From a stock mesh: the same solid.
  TripleDexel from_mesh =
      intersect_milled(tridex_test::box_mesh(stock.min, stock.max), lattice, maps);
  CHECK(volume(from_mesh) == doctest::Approx(volume(a)).epsilon(1e-3));
  // No map: the stock itself.
  CHECK(volume(intersect_milled(stock, lattice, {})) ==
        doctest::Approx(volume(TripleDexel::box(lattice, stock))));
}

}  // namespace test_intersect_milled
