#include <doctest/doctest.h>

#include <random>

#include "test_dexel_shapes.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/mill.hpp"
#include "tridex/polyhedron.hpp"

using namespace tridex;

namespace {

// A box stock's Z-map in a tilted frame, milled by a few random ball and flat moves.
ZMap milled_map(std::mt19937& rng, const Aabb& stock, const Frame& frame, double cell) {
  ZMap map = ZMap::from_box(frame, stock, cell);
  std::uniform_real_distribution<double> unit(0, 1);
  Aabb local = local_bounds(frame, stock);
  std::vector<Cutter> cutters{Cutter::ball(0.8), Cutter::flat(0.6)};
  std::vector<CutMove> moves;
  for (int k = 0; k < 6; ++k) {
    auto point = [&] {
      return Vec3(local.min.x + unit(rng) * (local.max.x - local.min.x),
                  local.min.y + unit(rng) * (local.max.y - local.min.y),
                  local.max.z - 0.2 - 1.2 * unit(rng));
    };
    moves.push_back({Segment{point(), point()}, static_cast<std::uint32_t>(k % 2)});
  }
  mill(map, cutters, moves);
  return map;
}

}  // namespace

TEST_CASE("dexelize Z-map through the grid tree equals dexelizing its polyhedron") {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> unit(0, 1), angle(-50, 50);
  Aabb stock{Vec3(0, 0, 0), Vec3(4, 3, 2)};
  std::size_t rays_compared = 0, mismatches = 0;
  for (int trial = 0; trial < 10; ++trial) {
    Frame frame = Frame::from_rotation(rotation_z(angle(rng)) * rotation_x(angle(rng)));
    ZMap map = milled_map(rng, stock, frame, 0.1 + 0.1 * unit(rng));
    Mesh mesh = polyhedrize(map);
    DexelLattice l = DexelLattice::covering(stock.inflated(0.5), 0.07 + 0.1 * unit(rng));
    l.origin += Vec3(unit(rng), unit(rng), unit(rng)) * (0.1 * l.spacing);
    TripleDexel via_tree = dexelize(map, l, {.threads = 1 + static_cast<unsigned>(trial % 2)});
    TripleDexel via_mesh = dexelize(mesh, l);
    validate(via_tree);
    CHECK(volume(via_tree) == doctest::Approx(volume(via_mesh)).epsilon(1e-5));
    for (int a = 0; a < 3; ++a)
      for (std::size_t r = 0; r < via_tree.grids[a].ray_count(); ++r) {
        auto x = via_tree.grids[a].ray(r), y = via_mesh.grids[a].ray(r);
        ++rays_compared;
        bool same = x.size() == y.size();
        for (std::size_t k = 0; same && k < x.size(); ++k)
          same = std::abs(x[k].enter - y[k].enter) < 1e-4 && std::abs(x[k].exit - y[k].exit) < 1e-4;
        mismatches += same ? 0 : 1;
      }
  }
  // The mesh path rounds vertices to float; a ray may differ only where it grazes the surface.
  CHECK(rays_compared > 50000);
  CHECK(mismatches * 10000 <= rays_compared);
}

TEST_CASE(
    "dexelize Z-map of an unmilled box stock: stock ∩ M = stock, up to the Z-map's silhouette "
    "band") {
  // The polyhedron interpolates linearly between the last point inside the stock's projection
  // and the first empty one, so along the silhouette it shaves a wedge at most one Z-map cell
  // wide off the stock (the paper's step error on walls parallel to the spindle). Deeper than
  // that, and everywhere for an untilted frame, the stock is whole.
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> unit(0, 1), angle(-80, 80);
  for (int trial = 0; trial < 8; ++trial) {
    Aabb stock{Vec3(-1, 0, 2), Vec3(2 + unit(rng), 1.5 + unit(rng), 3 + unit(rng))};
    if (trial == 0) stock.max = Vec3(2.5, 1.75, 3.6);  // whole cells: grid points on every wall
    Frame frame = trial == 0
                      ? Frame{}
                      : Frame::from_rotation(rotation_z(angle(rng)) * rotation_y(angle(rng)));
    const double cell = 0.05;
    ZMap map = ZMap::from_box(frame, stock, cell);
    DexelLattice l = DexelLattice::covering(stock, 0.1);
    l.origin += Vec3(0.013, 0.007, 0.011);
    TripleDexel box = TripleDexel::box(l, stock);
    TripleDexel part = intersect(box, dexelize(map, l));
    Vec3 size = stock.size();
    double area = 2 * (size.x * size.y + size.y * size.z + size.z * size.x);
    double lost = volume(box) - volume(part);
    CHECK(lost >= -1e-9);
    CHECK(lost <= (trial == 0 ? 1e-6 : 0.5 * cell * area));
    for (int k = 0; k < 2000; ++k) {
      Vec3 p = stock.min + Vec3(unit(rng), unit(rng), unit(rng)) * size;
      Vec3 gap = glm::min(p - stock.min, stock.max - p);
      if (std::min({gap.x, gap.y, gap.z}) < 2 * cell + l.spacing) continue;
      CHECK(contains(part, p));
    }
  }
}

TEST_CASE("dexelize Z-map: every spindle ray holds exactly the milled column") {
  // Identity frame: the z-ray at (x, y) inside the stock must be [0, H(x, y)] clipped to the
  // stock, H the polyhedron's top.
  std::mt19937 rng(13);
  Aabb stock{Vec3(0), Vec3(5, 4, 2)};
  ZMap map = milled_map(rng, stock, Frame{}, 0.05);
  DexelLattice l = DexelLattice::covering(stock, 0.04);
  l.origin += Vec3(0.011, 0.017, 0.005);
  TripleDexel part = intersect(TripleDexel::box(l, stock), dexelize(map, l));
  const DexelGrid& g = part.grids[2];
  int checked = 0, cut = 0;
  for (int iv = 0; iv < g.nv; ++iv)
    for (int iu = 0; iu < g.nu; ++iu) {
      double x = l.origin.x + l.spacing * iu, y = l.origin.y + l.spacing * iv;
      if (x <= 0 || x >= 5 || y <= 0 || y >= 4) {
        CHECK(g.ray(iu, iv).empty());
        continue;
      }
      double top = std::min(2.0, zmap_height(map, x, y));
      auto ray = g.ray(iu, iv);
      if (top <= 1e-6) {
        CHECK(ray.empty());
        continue;
      }
      REQUIRE(ray.size() == 1);
      CHECK(ray[0].enter == 0.0f);
      CHECK(ray[0].exit == doctest::Approx(top).epsilon(1e-6));
      ++checked, cut += top < 2 - 1e-6;
    }
  CHECK(checked > 10000);
  CHECK(cut > 500);
}
