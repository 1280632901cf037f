#include <doctest/doctest.h>

#include <random>

#include "tridex/dexel_ops.hpp"

using namespace tridex;

namespace {

// A random solid in dexel form: 0–3 intervals per ray with endpoints on a coarse set of values,
// so that equal and touching endpoints across operands are common.
TripleDexel random_dexel(const DexelLattice& l, std::mt19937& rng) {
  TripleDexel d = TripleDexel::empty(l);
  for (int a = 0; a < 3; ++a) {
    DexelGrid& g = d.grids[a];
    g.intervals.clear();
    for (std::size_t r = 0; r < g.ray_count(); ++r) {
      int count = std::uniform_int_distribution<int>(0, 3)(rng);
      std::vector<int> ends;
      for (int k = 0; k < 2 * count; ++k)
        ends.push_back(std::uniform_int_distribution<int>(0, 20)(rng));
      std::sort(ends.begin(), ends.end());
      for (std::size_t k = 0; k + 1 < ends.size(); k += 2)
        if (ends[k] < ends[k + 1] &&
            (g.intervals.size() == g.offsets[r] || float(ends[k]) * 0.5f > g.intervals.back().exit))
          g.intervals.push_back({float(ends[k]) * 0.5f, float(ends[k + 1]) * 0.5f});
      g.offsets[r + 1] = static_cast<std::uint32_t>(g.intervals.size());
    }
  }
  return d;
}

bool in_ray(std::span<const DexelInterval> ray, double x) {
  for (const DexelInterval& s : ray)
    if (s.enter <= x && x < s.exit) return true;
  return false;
}

bool same(const TripleDexel& a, const TripleDexel& b) {
  if (!(a.lattice() == b.lattice())) return false;
  for (int k = 0; k < 3; ++k) {
    if (a.grids[k].offsets != b.grids[k].offsets) return false;
    if (a.grids[k].intervals.size() != b.grids[k].intervals.size()) return false;
    for (std::size_t i = 0; i < a.grids[k].intervals.size(); ++i)
      if (a.grids[k].intervals[i].enter != b.grids[k].intervals[i].enter ||
          a.grids[k].intervals[i].exit != b.grids[k].intervals[i].exit)
        return false;
  }
  return true;
}

const DexelLattice kLattice{Vec3(0.25, -1, 0.5), 0.5, glm::ivec3(7, 5, 6)};

}  // namespace

TEST_CASE("dexel Booleans equal point-wise Booleans along every ray") {
  std::mt19937 rng(42);
  for (int trial = 0; trial < 20; ++trial) {
    TripleDexel a = random_dexel(kLattice, rng), b = random_dexel(kLattice, rng);
    validate(a);
    TripleDexel i = intersect(a, b), u = unite(a, b), s = subtract(a, b);
    validate(i), validate(u), validate(s);
    for (int axis = 0; axis < 3; ++axis)
      for (std::size_t r = 0; r < a.grids[axis].ray_count(); ++r)
        for (double x = -0.2; x < 11; x += 0.125) {  // samples on and between endpoints
          bool in_a = in_ray(a.grids[axis].ray(r), x), in_b = in_ray(b.grids[axis].ray(r), x);
          CHECK(in_ray(i.grids[axis].ray(r), x) == (in_a && in_b));
          CHECK(in_ray(u.grids[axis].ray(r), x) == (in_a || in_b));
          CHECK(in_ray(s.grids[axis].ray(r), x) == (in_a && !in_b));
        }
  }
}

TEST_CASE("dexel Boolean identities on random solids") {
  std::mt19937 rng(9);
  for (int trial = 0; trial < 20; ++trial) {
    TripleDexel a = random_dexel(kLattice, rng), b = random_dexel(kLattice, rng);
    CHECK(same(intersect(a, a), a));
    CHECK(same(unite(a, a), unite(a, TripleDexel::empty(kLattice))));
    CHECK(interval_count(subtract(a, a)) == 0);
    CHECK(volume(subtract(a, a)) == 0);
    CHECK(volume(unite(a, b)) + volume(intersect(a, b)) ==
          doctest::Approx(volume(a) + volume(b)).epsilon(1e-12));
    CHECK(volume(subtract(a, b)) + volume(intersect(a, b)) ==
          doctest::Approx(volume(a)).epsilon(1e-12));
    CHECK(same(intersect(a, b), intersect(b, a)));
    CHECK(same(unite(a, b), unite(b, a)));
    CHECK(same(subtract(a, subtract(a, b)), intersect(a, b)));
    CHECK(same(intersect(a, b, 1), intersect(a, b, 3)));  // independent of the thread count
  }
}

TEST_CASE("dexel Booleans reject operands on different lattices") {
  TripleDexel a = TripleDexel::empty(kLattice);
  DexelLattice other = kLattice;
  other.spacing = 0.25;
  TripleDexel b = TripleDexel::empty(other);
  CHECK_THROWS_AS(intersect(a, b), Error);
  CHECK_THROWS_AS(unite(a, b), Error);
  CHECK_THROWS_AS(subtract(a, b), Error);
  CHECK_THROWS_WITH_AS(intersect(a, b), doctest::Contains("different lattices"), Error);
}

TEST_CASE("lattice covering: outer nodes lie outside the box, spacing as asked") {
  std::mt19937 rng(1);
  std::uniform_real_distribution<double> coord(-50, 50), extent(0.1, 40), spacing(0.05, 3);
  for (int trial = 0; trial < 200; ++trial) {
    Vec3 lo(coord(rng), coord(rng), coord(rng));
    Aabb box{lo, lo + Vec3(extent(rng), extent(rng), extent(rng))};
    double s = spacing(rng);
    DexelLattice l = DexelLattice::covering(box, s);
    CHECK(l.spacing == doctest::Approx(s).epsilon(1e-6));  // a hair less (DexelLattice::covering)
    for (int a = 0; a < 3; ++a) {
      CHECK(l.origin[a] < box.min[a] - 0.5 * s + 1e-9);
      CHECK(l.origin[a] + s * (l.n[a] - 1) > box.max[a] + 0.5 * s - 1e-9);
      CHECK(l.origin[a] > box.min[a] - 1.5 * s - 1e-9);  // and not more than needed
    }
    DexelLattice r = DexelLattice::covering_resolution(box, 100);
    CHECK(r.spacing == doctest::Approx(std::max({box.size().x, box.size().y, box.size().z}) / 100));
  }
  CHECK_THROWS_AS(DexelLattice::covering(Aabb{}, 1.0), Error);
  CHECK_THROWS_AS(DexelLattice::covering(Aabb{Vec3(0), Vec3(1)}, 0.0), Error);
  CHECK_THROWS_AS(DexelLattice::covering_resolution(Aabb{Vec3(0), Vec3(1)}, 0), Error);
  CHECK_THROWS_AS(TripleDexel::empty(DexelLattice{Vec3(0), 1.0, glm::ivec3(0, 4, 4)}), Error);
}

TEST_CASE("box dexel: volume and point membership match the box") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> coord(-5, 5), extent(0.5, 6), unit(0, 1);
  for (int trial = 0; trial < 30; ++trial) {
    Vec3 lo(coord(rng), coord(rng), coord(rng));
    Aabb box{lo, lo + Vec3(extent(rng), extent(rng), extent(rng))};
    Aabb around = box.inflated(1.0);
    double s = 0.05 + 0.2 * unit(rng);
    TripleDexel d = TripleDexel::box(DexelLattice::covering(around, s), box);
    validate(d);
    Vec3 size = box.size();
    double area = 2 * (size.x * size.y + size.y * size.z + size.z * size.x);
    CHECK(std::abs(volume(d) - size.x * size.y * size.z) <= 0.5 * area * s);
    for (int k = 0; k < 300; ++k) {
      Vec3 p = around.min + Vec3(unit(rng), unit(rng), unit(rng)) * around.size();
      Vec3 gap = glm::min(glm::abs(p - box.min), glm::abs(p - box.max));
      if (std::min({gap.x, gap.y, gap.z}) < s) continue;  // near the surface: either answer
      CHECK(contains(d, p) == box.contains(p));
    }
  }
  CHECK(volume(TripleDexel::box(kLattice, Aabb{Vec3(0), Vec3(1, 1, 0)})) == 0);
}

TEST_CASE("validate rejects malformed dexels") {
  TripleDexel d = TripleDexel::box(kLattice, Aabb{Vec3(0), Vec3(2)});
  validate(d);
  TripleDexel bad = d;
  bad.grids[1].intervals[0].exit = bad.grids[1].intervals[0].enter;
  CHECK_THROWS_AS(validate(bad), Error);
  bad = d;
  bad.grids[2].offsets.pop_back();
  CHECK_THROWS_AS(validate(bad), Error);
}
