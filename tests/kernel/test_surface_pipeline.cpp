// Surface extraction at the end of the kernel pipeline: a box stock milled in tilted directions
// (mill.hpp), combined by intersect_milled() into W0 ∩ M1 ∩ … ∩ MN (intersect_milled.hpp), then
// extract_surface.
// The dexels come from Z-map polyhedra through the grid tree, with their stair steps and the
// rounding of three independently cast ray families.
#include <doctest/doctest.h>

#include <algorithm>
#include <limits>
#include <random>

#include "tridex/dexel_ops.hpp"
#include "tridex/intersect_milled.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/mill.hpp"
#include "tridex/surface.hpp"

using namespace tridex;

TEST_CASE("extract_surface on a machined stock: closed, inside the stock, the stock itself exact") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  const std::vector<Cutter> cutters{Cutter::ball(1.0), Cutter::flat(0.7),
                                    Cutter::bull_nose(0.9, 0.3)};
  for (int trial = 0; trial < 3; ++trial) {
    Aabb stock{Vec3(-3, -2, 0), Vec3(3 + unit(rng), 2 + unit(rng), 3 + unit(rng))};
    std::vector<ZMap> maps;
    for (int direction = 0; direction < 2 + trial; ++direction) {
      Vec3 axis = glm::normalize(Vec3(unit(rng) - 0.5, unit(rng) - 0.5, 0.5 + unit(rng)));
      Frame frame = Frame::from_axis(axis);
      Aabb local = local_bounds(frame, stock);
      std::vector<CutMove> moves;
      auto tip = [&] {
        return Vec3(local.min.x + unit(rng) * (local.max.x - local.min.x),
                    local.min.y + unit(rng) * (local.max.y - local.min.y),
                    local.max.z - (0.1 + 0.3 * unit(rng)) * (local.max.z - local.min.z));
      };
      for (int k = 0; k < 6; ++k)
        moves.push_back({Segment{tip(), tip()}, static_cast<std::uint32_t>(k % 3)});
      maps.push_back(ZMap::from_box(frame, stock, 0.05));
      mill(maps.back(), cutters, moves);
    }
    const double h = 0.1;
    const DexelLattice lattice = DexelLattice::covering(stock, h);
    const Vec3 e = stock.size();
    const double stock_volume = e.x * e.y * e.z, area = 2 * (e.x * e.y + e.y * e.z + e.z * e.x);
    // The unmilled stock comes back exactly (its faces lie between nodes, sharp features on).
    Mesh raw = extract_surface(intersect_milled(stock, lattice, std::span<const ZMap>()));
    CHECK(raw.signed_volume() == doctest::Approx(stock_volume).epsilon(1e-5));
    TripleDexel solid = intersect_milled(stock, lattice, maps);
    for (bool sharp : {false, true}) {
      CAPTURE(sharp);
      Mesh m = extract_surface(solid, {.sharp_features = sharp});
      MeshCheck check = check_mesh(m);
      CHECK(check.closed());
      CHECK(check.degenerate_triangles == 0);
      // Material was removed, and the mesh stays inside the stock (feature points may stand
      // out by at most kFeatureOvershoot spacings).
      CHECK(m.signed_volume() < stock_volume - 0.5);
      CHECK(m.signed_volume() > 0.3 * stock_volume);
      Aabb b = m.bounds();
      for (int a = 0; a < 3; ++a) {
        CHECK(b.min[a] >= stock.min[a] - 0.06 * h);
        CHECK(b.max[a] <= stock.max[a] + 0.06 * h);
      }
      // The dexel volume estimate (dexel_ops.hpp) is within about area × h / 2 of the truth.
      CHECK(std::abs(m.signed_volume() - volume(solid)) <= 0.5 * area * h);
    }
  }
}

TEST_CASE(
    "a machined box keeps its top edges on every side, when it is a whole number of spacings "
    "wide") {
  // 10 × 8 × 5 at spacing 0.25: every face would lie on a row of rays, where the half-open
  // intervals keep the rows on the min faces and drop those on the max faces, and the top edge
  // along the max faces came out up to 1.3 spacings low. The lattice puts the rows nearest the
  // faces just inside them.
  const Aabb stock{Vec3(0, 0, 0), Vec3(10, 8, 5)};
  const DexelLattice lattice = DexelLattice::covering(stock, 0.25);
  for (int a = 0; a < 3; ++a) {
    const double first = std::ceil((stock.min[a] - lattice.origin[a]) / lattice.spacing);
    const double last = std::floor((stock.max[a] - lattice.origin[a]) / lattice.spacing);
    CHECK(lattice.origin[a] + first * lattice.spacing > stock.min[a]);
    CHECK(lattice.origin[a] + last * lattice.spacing < stock.max[a]);
    CHECK(last - first == doctest::Approx((stock.max[a] - stock.min[a]) / 0.25));
  }
  // A flat end on moves rising along x and y leaves the plane z = 3.6 + 0.1·x + 0.07·y.
  auto plane = [](double x, double y) { return 3.6 + 0.1 * x + 0.07 * y; };
  ZMap map = ZMap::from_box(Frame{}, stock, 0.1);
  const ZMap initial = map;
  const std::vector<Cutter> cutters{Cutter::flat(2)};
  std::vector<CutMove> moves;
  for (double y = -2; y <= 10; y += 1.5)
    moves.push_back({Segment{Vec3(-3, y, plane(-1, y)), Vec3(13, y, plane(15, y))}, 0});
  mill(map, cutters, moves);
  raise_uncut(map, initial);
  std::vector<ZMap> maps{map};
  const Mesh mesh = extract_surface(intersect_milled(stock, lattice, maps));
  // Every vertex on a side face is below the top, and the top edge is there: within each
  // stretch of a spacing along the face, the highest vertex is within 3/4 of a spacing of the
  // top (measured: 0.17 on the min faces, 0.57 on the max faces; 1.3 before).
  for (int axis = 0; axis < 2; ++axis)
    for (double face : {stock.min[axis], stock.max[axis]}) {
      const int along = 1 - axis;
      std::vector<double> worst(static_cast<std::size_t>(stock.max[along] / lattice.spacing),
                                std::numeric_limits<double>::infinity());
      for (const auto& p : mesh.positions) {
        if (std::abs(p[axis] - face) > 1e-4) continue;
        const double below = plane(p.x, p.y) - p.z;
        CHECK(below > -1e-3);
        double& w = worst[static_cast<std::size_t>(
            std::clamp(p[along] / lattice.spacing, 0.0, double(worst.size() - 1)))];
        w = std::min(w, below);
      }
      double dip = 0;
      for (double w : worst) dip = std::max(dip, w);
      CAPTURE(axis);
      CAPTURE(face);
      CHECK(dip < 0.75 * lattice.spacing);
    }
}
