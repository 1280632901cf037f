#include <doctest/doctest.h>

#include <random>

#include "test_dexel_shapes.hpp"
#include "tridex/intersect_milled.hpp"
#include "tridex/mill.hpp"
#include "tridex/zmap.hpp"

using namespace tridex;

namespace {

// Top of the box above a frame-local point, by marching along the frame's axis.
double brute_top(const Frame& f, const Aabb& box, double x, double y, double lo, double hi) {
  double top = -INFINITY;
  const int n = 20000;
  for (int k = 0; k <= n; ++k) {
    double z = lo + (hi - lo) * k / n;
    if (box.contains(f.to_world(Vec3(x, y, z)))) top = z;
  }
  return top;
}

}  // namespace

TEST_CASE("frames: canonical frame of an axis, G68.2-style rotations and inverses") {
  std::mt19937 rng(3);
  std::normal_distribution<double> n(0, 1);
  for (int k = 0; k < 100; ++k) {
    Vec3 axis(n(rng), n(rng), n(rng)), origin(n(rng), n(rng), n(rng));
    Frame f = Frame::from_axis(axis, origin);
    CHECK(glm::length(f.axis() - glm::normalize(axis)) < 1e-12);
    CHECK(glm::length(f.to_local(origin + glm::normalize(axis)) - Vec3(0, 0, 1)) < 1e-12);
    Vec3 p(n(rng), n(rng), n(rng));
    CHECK(glm::length(f.to_world(f.to_local(p)) - p) < 1e-12);
    CHECK(glm::length(f.inverse().to_world(p) - f.to_local(p)) < 1e-12);
    CHECK(glm::determinant(f.rotation) == doctest::Approx(1.0));
  }
  // The Fanuc G68.2 checks of the design notes: R = Rz(a)·Rx(b)·Rz(c), tool axis R·(0,0,1).
  auto g68_2_axis = [](double a, double b, double c) {
    return Frame::from_rotation(rotation_z(a) * rotation_x(b) * rotation_z(c)).axis();
  };
  CHECK(glm::length(g68_2_axis(90, 90, 0) - Vec3(1, 0, 0)) < 1e-12);
  CHECK(glm::length(g68_2_axis(-90, 90, 0) - Vec3(-1, 0, 0)) < 1e-12);
  CHECK(glm::length(g68_2_axis(0, 90, 0) - Vec3(0, -1, 0)) < 1e-12);
  CHECK(glm::length(g68_2_axis(180, 90, 0) - Vec3(0, 1, 0)) < 1e-12);
  CHECK_THROWS_AS(Frame::from_axis(Vec3(0)), Error);
  CHECK_THROWS_AS(Frame::from_axis(Vec3(NAN, 0, 1)), Error);
  CHECK_THROWS_AS(Frame::from_rotation(Mat3(2.0)), Error);
  CHECK_THROWS_AS(Frame::from_rotation(Mat3(Vec3(-1, 0, 0), Vec3(0, 1, 0), Vec3(0, 0, 1))), Error);
}

TEST_CASE("Z-map from a box: exact tops in tilted frames, empty outside the projection") {
  const Aabb box{Vec3(-3, 1, 2), Vec3(7, 5, 4)};
  std::mt19937 rng(11);
  std::normal_distribution<double> n(0, 1);
  for (int k = 0; k < 6; ++k) {
    Vec3 axis = k == 0 ? Vec3(0, 0, 1) : Vec3(n(rng), n(rng), n(rng));
    Frame f = Frame::from_axis(axis);
    ZMap map = ZMap::from_box(f, box, 0.5);
    Aabb local = local_bounds(f, box);
    CHECK(map.empty_height < local.min.z);
    int empty = 0, full = 0;
    for (int j = 0; j < map.grid.ny; j += 3)
      for (int i = 0; i < map.grid.nx; i += 3) {
        double x = map.grid.x(i), y = map.grid.y(j);
        double sampled = brute_top(f, box, x, y, local.min.z, local.max.z);
        if (map.is_empty(i, j)) {
          CHECK(std::isinf(sampled));  // sampling can miss a sliver, never invent one
          ++empty;
          continue;
        }
        // The height lies on the box's top: inside it, and just above is outside.
        double h = map.height(i, j);
        CHECK(box.inflated(1e-5).contains(f.to_world(Vec3(x, y, h))));
        CHECK(!box.contains(f.to_world(Vec3(x, y, h + 1e-4))));
        if (!std::isinf(sampled)) CHECK(h >= sampled - 1e-6);
        ++full;
      }
    CHECK(full > 0);
    if (k > 0) CHECK(empty > 0);
  }
}

TEST_CASE("Z-map from a closed mesh equals the Z-map from the same box") {
  const Aabb box{Vec3(0, 0, 0), Vec3(10, 6, 3)};
  for (Vec3 axis : {Vec3(0, 0, 1), Vec3(1, 2, 3), Vec3(-1, 0.3, 0.2)}) {
    Frame f = Frame::from_axis(axis);
    ZMap a = ZMap::from_box(f, box, 0.25),
         b = ZMap::from_mesh(f, tridex_test::box_mesh(box.min, box.max), 0.25);
    REQUIRE(a.grid.nx == b.grid.nx);
    REQUIRE(a.grid.ny == b.grid.ny);
    int differ = 0;
    for (std::size_t p = 0; p < a.heights.size(); ++p)
      if (std::abs(a.heights[p] - b.heights[p]) > 1e-4) ++differ;
    // Only points exactly on the projected outline may disagree (inside for one, outside for
    // the other within rounding).
    CHECK(differ <= a.grid.nx + a.grid.ny);
  }
}

TEST_CASE("bad Z-map parameters are rejected") {
  const Aabb box{Vec3(0), Vec3(1)};
  CHECK_THROWS_WITH_AS(ZMap::from_box(Frame{}, box, 0), doctest::Contains("cell size"), Error);
  CHECK_THROWS_AS(ZMap::from_box(Frame{}, box, -1), Error);
  CHECK_THROWS_AS(ZMap::from_box(Frame{}, box, NAN), Error);
  CHECK_THROWS_AS(ZMap::from_box(Frame{}, Aabb{}, 0.1), Error);
  CHECK_THROWS_AS(ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(INFINITY)}, 0.1), Error);
  CHECK_THROWS_WITH_AS(ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(1e6)}, 1e-3),
                       doctest::Contains("too large"), Error);
  CHECK_THROWS_WITH_AS(ZMap::from_box(Frame{}, box, 1e-3, ZMapLimits{1000}),
                       doctest::Contains("over the limit"), Error);
  ZMapGrid g;
  g.nx = 0, g.ny = 5;
  CHECK_THROWS_WITH_AS(ZMap(g, 0, -1), doctest::Contains("empty"), Error);
  CHECK_THROWS_AS(ZMap::from_mesh(Frame{}, Mesh{}, 0.1), Error);
}

TEST_CASE(
    "raise_uncut: no fin of stock left between the last grid row and a face that falls between "
    "rows") {
  // A facing cut over the whole top, 1 mm down. Cell 0.3 puts the faces x = 10 and y = 8 between
  // grid rows: the strip beyond the last row inside interpolates towards the first row outside.
  // Raised above the stock, that row left a fin of uncut stock up to the old top in the strip.
  const Aabb stock{Vec3(0, 0, 0), Vec3(10, 8, 5)};
  const DexelLattice lattice = DexelLattice::covering_resolution(stock, 50);
  const ZMap initial = ZMap::from_box(Frame{}, stock, 0.3);
  ZMap milled = initial;
  std::vector<Cutter> cutters{Cutter::flat(2)};
  std::vector<CutMove> facing;
  for (double y = -2; y <= 10; y += 1.5)
    facing.push_back({Segment{Vec3(-3, y, 4), Vec3(13, y, 4)}, 0});
  mill(milled, cutters, facing);
  raise_uncut(milled, initial);
  std::vector<ZMap> maps{milled};
  const TripleDexel result = intersect_milled(stock, lattice, maps);
  int checked = 0, above_cut = 0;
  for (int a = 0; a < 2; ++a) {  // the rays along x and along y: those that cross the faces
    const DexelGrid& g = result.grids[a];
    for (int iv = 0; iv < g.nv; ++iv)
      for (int iu = 0; iu < g.nu; ++iu) {
        const double z = a == 0 ? lattice.node(0, iu, iv).z : lattice.node(iv, 0, iu).z;
        if (z <= 4 + 1e-6 || z >= 5) continue;
        ++checked;
        above_cut += !g.ray(iu, iv).empty();
      }
  }
  CHECK(checked > 100);
  CHECK(above_cut == 0);
}

TEST_CASE("raise_uncut: an uncut direction keeps the whole stock; cuts stay cut") {
  const Aabb stock{Vec3(0, 0, 0), Vec3(10, 8, 5)};
  const DexelLattice lattice = DexelLattice::covering_resolution(stock, 40);
  const double stock_volume = volume(TripleDexel::box(lattice, stock));
  for (Vec3 axis : {Vec3(0, 0, 1), Vec3(1, 0, 0.364), Vec3(-1, 0.2, 0.3), Vec3(0.3, -1, 0.1)}) {
    Frame f = Frame::from_axis(axis);
    const ZMap initial = ZMap::from_box(f, stock, 0.2);
    // The stock's own top, interpolated cell by cell, shaves a tilted stock where nothing is cut...
    std::vector<ZMap> maps{initial};
    double shaved = volume(intersect_milled(stock, lattice, maps));
    if (axis.z != 1) CHECK(shaved < stock_volume * (1 - 1e-4));
    // ...raised, it keeps it all.
    raise_uncut(maps[0], initial);
    CHECK(volume(intersect_milled(stock, lattice, maps)) ==
          doctest::Approx(stock_volume).epsilon(1e-9));
    // A plunge through the middle stays: cut points keep their heights, cut-through stays low.
    ZMap milled = initial;
    Vec3 centre = f.to_local(stock.center());
    std::vector<Cutter> cutters{Cutter::flat(1.5)};
    std::vector<CutMove> plunge{{Segment{centre + Vec3(0, 0, 20), centre - Vec3(0, 0, 20)}, 0}};
    mill(milled, cutters, plunge);
    ZMap raised = milled;
    raise_uncut(raised, initial);
    int kept = 0;
    for (std::size_t p = 0; p < milled.heights.size(); ++p)
      if (milled.heights[p] != initial.heights[p]) kept += raised.heights[p] == milled.heights[p];
    CHECK(kept > 100);
    std::vector<ZMap> cut{raised};
    CHECK(volume(intersect_milled(stock, lattice, cut)) <
          stock_volume - 0.5 * 3.14 * 1.5 * 1.5 * 5);
  }
  ZMap other = ZMap::from_box(Frame{}, stock, 0.5);
  ZMap mismatched = ZMap::from_box(Frame{}, stock, 0.25);
  CHECK_THROWS_AS(raise_uncut(other, mismatched), Error);
}

namespace {

// The old whole-map ZMap::from_box: every point's line against the box, one thread.
ZMap from_box_reference(const Frame& frame, const Aabb& stock, double cell) {
  const Aabb local = local_bounds(frame, stock);
  const ZMapGrid g = ZMapGrid::covering(frame, local.inflated(detail::empty_margin(cell)), cell);
  const auto empty = static_cast<float>(local.min.z - detail::empty_margin(cell));
  ZMap map(g, empty, empty);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) {
      double s0, s1;
      if (detail::line_box_interval(frame.to_world(Vec3(g.x(i), g.y(j), 0)), frame.axis(), stock,
                                    s0, s1))
        map.heights[g.index(i, j)] = static_cast<float>(s1);
    }
  return map;
}

// The old raise_uncut, point by point over the whole map on one thread, reading `initial`.
void raise_uncut_reference(ZMap& milled, const ZMap& initial) {
  const ZMapGrid& a = milled.grid;
  float top = milled.empty_height;
  for (float h : initial.heights) top = std::max(top, h);
  const float above = static_cast<float>(top + detail::empty_margin(a.cell));
  auto inside = [&](int i, int j) {
    return i >= 0 && j >= 0 && i < a.nx && j < a.ny && initial.height(i, j) > initial.empty_height;
  };
  auto cut = [&](int i, int j) {
    return inside(i, j) && milled.height(i, j) != initial.height(i, j);
  };
  std::vector<std::pair<std::size_t, float>> continued;
  for (int j = 0; j < a.ny; ++j)
    for (int i = 0; i < a.nx; ++i) {
      if (inside(i, j)) continue;
      float best = -std::numeric_limits<float>::infinity();
      for (int dj = -1; dj <= 1; ++dj)
        for (int di = -1; di <= 1; ++di) {
          if ((di == 0 && dj == 0) || !cut(i + di, j + dj)) continue;
          const float near = milled.height(i + di, j + dj);
          const float far =
              cut(i + 2 * di, j + 2 * dj) ? milled.height(i + 2 * di, j + 2 * dj) : near;
          best = std::max(best, 2 * near - far);
        }
      if (best > -std::numeric_limits<float>::infinity())
        continued.emplace_back(a.index(i, j), std::clamp(best, milled.empty_height, above));
    }
  for (std::size_t p = 0; p < milled.heights.size(); ++p)
    if (milled.heights[p] == initial.heights[p]) milled.heights[p] = above;
  for (const auto& [p, h] : continued) milled.heights[p] = h;
}

}  // namespace

TEST_CASE(
    "from_box and raise_uncut in row bands on any thread count match the old whole-map passes") {
  // Random tilted directions and random cuts, some leaving the stock's footprint; maps of more
  // than 64 rows, so that the bands' borders (and the rows each band reads beyond them) count.
  std::mt19937 rng(29);
  std::uniform_real_distribution<double> u(0, 1);
  const Aabb stock{Vec3(0, 0, 0), Vec3(12, 9, 8)};
  const std::vector<Cutter> cutters{Cutter::ball(0.6), Cutter::flat(0.9),
                                    Cutter::bull_nose(1.0, 0.3)};
  for (int trial = 0; trial < 8; ++trial) {
    CAPTURE(trial);
    const Vec3 axis = trial == 0
                          ? Vec3(0, 0, 1)
                          : glm::normalize(Vec3(2 * u(rng) - 1, 2 * u(rng) - 1, 0.2 + u(rng)));
    const Frame f = Frame::from_axis(axis);
    const double cell = 0.03 + 0.03 * u(rng);
    const ZMap initial = from_box_reference(f, stock, cell);
    for (unsigned threads : {1u, 2u, 3u})
      CHECK(ZMap::from_box(f, stock, cell, {}, threads).heights == initial.heights);
    REQUIRE(initial.grid.ny > 2 * detail::kMapBandRows);
    const Aabb local = local_bounds(f, stock);
    auto at = [&](double depth) {
      return Vec3(local.min.x - 1 + (local.size().x + 2) * u(rng),
                  local.min.y - 1 + (local.size().y + 2) * u(rng), local.max.z - depth);
    };
    std::vector<CutMove> moves;
    for (int k = 0; k < 12; ++k)
      moves.push_back({Segment{at(3 * u(rng)), at(3 * u(rng))},
                       static_cast<std::uint32_t>(k % cutters.size())});
    ZMap milled = initial;
    mill(milled, cutters, moves, {.threads = 1});
    ZMap want = milled;
    raise_uncut_reference(want, initial);
    for (unsigned threads : {1u, 2u, 3u}) {
      CAPTURE(threads);
      ZMap from_map = milled, from_box = milled;
      raise_uncut(from_map, initial, threads);
      raise_uncut(from_box, stock, threads);
      CHECK(from_map.heights == want.heights);
      CHECK(from_box.heights == want.heights);
    }
  }
  // The box's grid must be the map's.
  ZMap other = ZMap::from_box(Frame{}, stock, 0.5);
  CHECK_THROWS_AS(raise_uncut(other, Aabb{Vec3(0), Vec3(12, 10, 8)}), Error);
}

TEST_CASE(
    "raise_uncut for a mesh stock, row by row on any thread count, matches it against the stored "
    "map") {
  // A sphere and a tilted box as stocks, seen along random directions, with random cuts some of
  // which leave the footprint; maps of more than 64 rows, so that triangles cross bands.
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> u(0, 1);
  const std::vector<Cutter> cutters{Cutter::ball(0.6), Cutter::flat(0.9)};
  const Frame tilt = Frame::from_axis(glm::normalize(Vec3(0.3, -0.2, 1)));
  Mesh tilted_box = tridex_test::box_mesh(Vec3(0, 0, 0), Vec3(10, 7, 6));
  for (glm::vec3& p : tilted_box.positions) p = glm::vec3(tilt.to_world(Vec3(p)));
  const std::vector<Mesh> stocks{tridex_test::sphere_mesh(Vec3(5, 4, 3), 4.5), tilted_box};
  for (int trial = 0; trial < 6; ++trial) {
    CAPTURE(trial);
    const Mesh& stock = stocks[static_cast<std::size_t>(trial % 2)];
    const Vec3 axis = trial < 2
                          ? Vec3(0, 0, 1)
                          : glm::normalize(Vec3(2 * u(rng) - 1, 2 * u(rng) - 1, 0.2 + u(rng)));
    const Frame f = Frame::from_axis(axis);
    const double cell = 0.04 + 0.03 * u(rng);
    const ZMap initial = ZMap::from_mesh(f, stock, cell);
    REQUIRE(initial.grid.ny > 2 * detail::kMapBandRows);
    Aabb local;
    for (const glm::vec3& p : stock.positions) local.extend(f.to_local(Vec3(p)));
    auto at = [&](double depth) {
      return Vec3(local.min.x - 1 + (local.size().x + 2) * u(rng),
                  local.min.y - 1 + (local.size().y + 2) * u(rng), local.max.z - depth);
    };
    std::vector<CutMove> moves;
    for (int k = 0; k < 12; ++k)
      moves.push_back({Segment{at(4 * u(rng)), at(4 * u(rng))},
                       static_cast<std::uint32_t>(k % cutters.size())});
    ZMap milled = initial;
    mill(milled, cutters, moves, {.threads = 1});
    ZMap want = milled;
    raise_uncut(want, initial);
    CHECK(want.heights != milled.heights);
    for (unsigned threads : {1u, 2u, 3u}) {
      CAPTURE(threads);
      ZMap from_mesh = milled;
      raise_uncut(from_mesh, stock, threads);
      CHECK(from_mesh.heights == want.heights);
    }
  }
  // The mesh's grid must be the map's.
  ZMap other = ZMap::from_mesh(Frame{}, stocks[0], 0.5);
  CHECK_THROWS_AS(raise_uncut(other, stocks[1]), Error);
}

namespace test_zmap {

// The previous box_top_row: line_box_interval point by point.
std::vector<float> box_row_by_points(const ZMapGrid& g, const Aabb& stock, float empty, int j) {
  std::vector<float> row(static_cast<std::size_t>(g.nx));
  for (int i = 0; i < g.nx; ++i) {
    double s0, s1;
    const Vec3 p = g.frame.to_world(Vec3(g.x(i), g.y(j), 0));
    row[static_cast<std::size_t>(i)] = detail::line_box_interval(p, g.frame.axis(), stock, s0, s1)
                                           ? static_cast<float>(s1)
                                           : empty;
  }
  return row;
}

}  // namespace test_zmap

TEST_CASE("box_top_row, axis by axis over blocks, equals line_box_interval point by point") {
  // from_box and raise_uncut take a box's heights from box_top_row, which runs the interval test
  // over blocks of points so that it vectorises: bit for bit the same heights, on frames along
  // the box's axes (whose zero components skip the division) and turned at random.
  std::mt19937 rng(4242);
  std::uniform_real_distribution<double> unit(0, 1), angle(-180, 180);
  std::size_t compared = 0, inside = 0;
  for (int trial = 0; trial < 12; ++trial) {
    const Aabb stock{Vec3(unit(rng), unit(rng), unit(rng)),
                     Vec3(2 + 3 * unit(rng), 2 + 3 * unit(rng), 1 + 2 * unit(rng))};
    const Frame frame =
        trial % 3 == 0 ? Frame{}
        : trial % 3 == 1
            ? Frame::from_rotation(rotation_y(90 * (trial % 4)))
            : Frame::from_rotation(rotation_z(angle(rng)) * rotation_x(angle(rng) / 3));
    const auto [grid, empty] = detail::box_map_grid(frame, stock, 0.05 + 0.1 * unit(rng));
    std::vector<float> row(static_cast<std::size_t>(grid.nx));
    for (int j = 0; j < grid.ny; ++j) {
      detail::box_top_row(grid, stock, empty, j, row.data());
      const std::vector<float> want = test_zmap::box_row_by_points(grid, stock, empty, j);
      for (std::size_t i = 0; i < row.size(); ++i) {
        compared += 1;
        inside += want[i] != empty;
        REQUIRE(std::bit_cast<std::uint32_t>(row[i]) == std::bit_cast<std::uint32_t>(want[i]));
      }
    }
  }
  CHECK(compared > 10000);
  CHECK(inside > compared / 3);
}
