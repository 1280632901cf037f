#include <doctest/doctest.h>

#include <random>

#include "test_dexel_shapes.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/polyhedron.hpp"

using namespace tridex;

namespace {

// A random Z-map in a random tilted frame: heights in [0, 3], some points cut to empty.
ZMap random_zmap(std::mt19937& rng, int nx, int ny) {
  std::uniform_real_distribution<double> angle(-60, 60), unit(0, 1);
  Frame frame = Frame::from_rotation(rotation_z(angle(rng)) * rotation_x(angle(rng)),
                                     Vec3(unit(rng), unit(rng), unit(rng)));
  ZMapGrid g;
  g.frame = frame, g.x0 = -2 * unit(rng), g.y0 = -2 * unit(rng), g.cell = 0.2 + unit(rng),
  g.nx = nx, g.ny = ny;
  ZMap map(g, 0.0f, -0.5f);
  for (float& h : map.heights)
    h = unit(rng) < 0.15 ? map.empty_height : static_cast<float>(3 * unit(rng));
  return map;
}

// The volume of the solid under the Z-map's triangulated top, down to its bottom.
double reference_volume(const ZMap& map) {
  const ZMapGrid& g = map.grid;
  double bottom = map.empty_height - g.cell, sum = 0;
  auto top = [&](int i, int j) {
    return std::max(double(map.height(i, j)), double(map.empty_height)) - bottom;
  };
  for (int j = 0; j + 1 < g.ny; ++j)
    for (int i = 0; i + 1 < g.nx; ++i)
      sum += (top(i, j) + top(i + 1, j) + top(i + 1, j + 1)) / 3 +
             (top(i, j) + top(i + 1, j + 1) + top(i, j + 1)) / 3;
  return sum * g.cell * g.cell / 2;
}

}  // namespace

TEST_CASE("polyhedrize: closed, outward, two triangles per cell, volume of the height field") {
  std::mt19937 rng(17);
  for (int trial = 0; trial < 20; ++trial) {
    int nx = std::uniform_int_distribution<int>(2, 30)(rng),
        ny = std::uniform_int_distribution<int>(2, 30)(rng);
    ZMap map = random_zmap(rng, nx, ny);
    Mesh mesh = polyhedrize(map);
    MeshCheck c = check_mesh(mesh);
    CHECK(c.closed());
    CHECK(c.degenerate_triangles == 0);
    std::size_t border = 2 * static_cast<std::size_t>(nx + ny) - 4;
    CHECK(mesh.triangles.size() ==
          2 * static_cast<std::size_t>(nx - 1) * static_cast<std::size_t>(ny - 1) + 3 * border);
    CHECK(mesh.signed_volume() == doctest::Approx(reference_volume(map)).epsilon(1e-5));
    // Top vertices are the grid points, in world coordinates.
    for (int k = 0; k < 20; ++k) {
      int i = std::uniform_int_distribution<int>(0, nx - 1)(rng),
          j = std::uniform_int_distribution<int>(0, ny - 1)(rng);
      Vec3 expected = map.grid.frame.to_world(
          Vec3(map.grid.x(i), map.grid.y(j), std::max(map.height(i, j), map.empty_height)));
      Vec3 got(mesh.positions[map.grid.index(i, j)]);
      CHECK(glm::length(got - expected) < 1e-5);
      CHECK(zmap_height(map, map.grid.x(i), map.grid.y(j)) ==
            doctest::Approx(std::max(map.height(i, j), map.empty_height)));
    }
  }
}

TEST_CASE("polyhedrize: a fully cut map still encloses a slab one cell thick") {
  ZMapGrid g;
  g.cell = 0.5, g.nx = 4, g.ny = 3;
  ZMap map(g, -1.0f, -1.0f);
  Mesh mesh = polyhedrize(map);
  CHECK(check_mesh(mesh).closed());
  CHECK(mesh.signed_volume() == doctest::Approx(1.5 * 1.0 * 0.5));
}

TEST_CASE("polyhedrize: a map without cells is an error") {
  ZMapGrid g;
  g.nx = 1, g.ny = 5;
  ZMap map(g, 0.0f, -1.0f);
  CHECK_THROWS_WITH_AS(polyhedrize(map), doctest::Contains("1 x 5"), Error);
}
