// Fine cells of a Z-map (ZMapFineCells, zmap.hpp; issue 17): the polyhedron, the grid tree and
// zmap_height agree on the finer solid, and refine_steep_cells (fine_cells.hpp) puts a wall
// parallel to the spindle inside its cell, within a sub-cell of where the moves put it.
#include <doctest/doctest.h>

#include <random>

#include "test_dexel_shapes.hpp"
#include "tridex/grid_tree.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/mill.hpp"
#include "tridex/polyhedron.hpp"
#include "tridex/fine_cells.hpp"

using namespace tridex;
using namespace tridex_test;

namespace {

constexpr int kSteps = ZMapFineCells::kSteps, kSide = ZMapFineCells::kSide;

// A random map in a random frame with about a third of its cells fine; sub-heights are random
// (some beyond the corners' range: ribs and slots between grid points, some cut to empty).
ZMap random_fine_map(std::mt19937& rng, int nx, int ny) {
  std::uniform_real_distribution<double> angle(-60, 60), unit(0, 1);
  ZMapGrid g;
  g.frame = Frame::from_rotation(rotation_z(angle(rng)) * rotation_x(angle(rng)),
                                 Vec3(unit(rng), unit(rng), unit(rng)));
  g.x0 = -2 * unit(rng), g.y0 = -2 * unit(rng), g.cell = 0.3 + unit(rng), g.nx = nx, g.ny = ny;
  ZMap map(g, 0.0f, -0.5f);
  for (float& h : map.heights)
    h = unit(rng) < 0.15 ? map.empty_height : static_cast<float>(3 * unit(rng));
  std::vector<std::uint32_t> cells;
  std::vector<float> sub;
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      if (unit(rng) > 0.35) continue;
      cells.push_back(static_cast<std::uint32_t>(g.index(i, j)));
      for (int p = 0; p < ZMapFineCells::kPoints; ++p)
        sub.push_back(unit(rng) < 0.1 ? -1.0f : static_cast<float>(4 * unit(rng) - 0.5));
    }
  std::shuffle(cells.begin(), cells.end(), rng);  // set_fine_cells takes any order
  map.set_fine_cells(std::move(cells), std::move(sub));
  return map;
}

// The volume under the finer triangulated top, down to the bottom, summed triangle by triangle.
double reference_volume(const ZMap& map) {
  const ZMapGrid& g = map.grid;
  const double bottom = map.empty_height - g.cell;
  double sum = 0;
  auto quad = [&](double h00, double h10, double h01, double h11, double side) {
    return side * side / 2 * ((h00 + h10 + h11) / 3 + (h00 + h11 + h01) / 3 - 2 * bottom);
  };
  auto top = [&](int i, int j) {
    return std::max(double(map.height(i, j)), double(map.empty_height));
  };
  for (int j = 0; j + 1 < g.ny; ++j)
    for (int i = 0; i + 1 < g.nx; ++i) {
      const float* f = map.fine_cell(i, j);
      if (!f) {
        sum += quad(top(i, j), top(i + 1, j), top(i, j + 1), top(i + 1, j + 1), g.cell);
        continue;
      }
      for (int b = 0; b < kSteps; ++b)
        for (int a = 0; a < kSteps; ++a)
          sum += quad(f[a + kSide * b], f[a + 1 + kSide * b], f[a + kSide * (b + 1)],
                      f[a + 1 + kSide * (b + 1)], g.cell / kSteps);
    }
  return sum;
}

// Where the ray o + t·d enters or leaves the polyhedron: the brute-force crossings with each
// triangle, signed by its facing and summed where they coincide. A fine cell's step to a plain
// neighbour is a fan whose triangles overlap, with opposite facings, where the sub-points cross
// the straight edge (polyhedron.hpp): there they cancel.
std::vector<double> winding_crossings(const Mesh& m, const Vec3& o, const Vec3& d) {
  std::vector<std::pair<double, int>> hits;
  for (const glm::uvec3& t : m.triangles) {
    const Vec3 a(m.positions[t.x]), b(m.positions[t.y]), c(m.positions[t.z]);
    const Vec3 e1 = b - a, e2 = c - a,
               p = glm::cross(d, e2);  // Möller–Trumbore, as brute_force_hits
    const double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-300) continue;
    const Vec3 s = o - a, q = glm::cross(s, e1);
    const double bu = glm::dot(s, p) / det, bv = glm::dot(d, q) / det;
    if (bu < 0 || bu > 1 || bv < 0 || bu + bv > 1) continue;
    hits.emplace_back(glm::dot(e2, q) / det, glm::dot(glm::cross(e1, e2), d) < 0 ? 1 : -1);
  }
  std::sort(hits.begin(), hits.end());
  std::vector<double> out;
  int winding = 0;
  for (std::size_t k = 0; k < hits.size();) {
    const double t = hits[k].first;
    const int before = winding;
    // Overlapping faces cancel only up to the mesh's float positions: merge within 1e-6.
    for (; k < hits.size() && hits[k].first - t < 1e-6; ++k) winding += hits[k].second;
    if ((before > 0) != (winding > 0)) out.push_back(t);
  }
  return out;
}

}  // namespace

TEST_CASE(
    "fine cells: corners are the map's points, shared edges agree, the polyhedron is closed with "
    "the finer volume") {
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 12; ++trial) {
    const int nx = std::uniform_int_distribution<int>(2, 20)(rng),
              ny = std::uniform_int_distribution<int>(2, 20)(rng);
    const ZMap map = random_fine_map(rng, nx, ny);
    const ZMapGrid& g = map.grid;
    for (int j = 0; j + 1 < ny; ++j)
      for (int i = 0; i + 1 < nx; ++i) {
        const float* f = map.fine_cell(i, j);
        if (!f) continue;
        CHECK(f[0] == std::max(map.height(i, j), map.empty_height));
        CHECK(f[kSteps + kSide * kSteps] == std::max(map.height(i + 1, j + 1), map.empty_height));
        if (const float* right = i + 2 < nx ? map.fine_cell(i + 1, j) : nullptr)
          for (int b = 0; b < kSide; ++b) CHECK(right[kSide * b] == f[kSteps + kSide * b]);
        // zmap_height interpolates the sub-grid: at a sub-point, its height.
        const int a = std::uniform_int_distribution<int>(0, kSteps)(rng),
                  b = std::uniform_int_distribution<int>(0, kSteps)(rng);
        const double x = g.x(i) + a * g.cell / kSteps, y = g.y(j) + b * g.cell / kSteps;
        if (a > 0 && a < kSteps && b > 0 && b < kSteps)
          CHECK(zmap_height(map, x, y) == doctest::Approx(f[a + kSide * b]));
      }
    const Mesh mesh = polyhedrize(map);
    const MeshCheck c = check_mesh(mesh);
    CHECK(c.closed());
    CHECK(mesh.signed_volume() == doctest::Approx(reference_volume(map)).epsilon(1e-5));
  }
}

TEST_CASE("fine cells: grid tree hits equal brute-force hits on the polyhedron for random rays") {
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> unit(0, 1);
  int compared = 0, through_fine = 0;
  for (int trial = 0; trial < 10; ++trial) {
    const ZMap map = random_fine_map(rng, std::uniform_int_distribution<int>(2, 16)(rng),
                                     std::uniform_int_distribution<int>(2, 16)(rng));
    const Frame& frame = map.grid.frame;
    const GridTree tree(map);
    const Mesh mesh = polyhedrize(map);
    const Aabb box = mesh.bounds();
    for (int k = 0; k < 150; ++k) {
      const Vec3 target = box.min + Vec3(unit(rng), unit(rng), unit(rng)) * box.size();
      Vec3 d = glm::normalize(Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5));
      if (k % 3 == 0) d = frame.axis() * (k % 2 ? 1.0 : -1.0);  // along the spindle
      const Vec3 o = target - 100.0 * d;
      if (distance_to_edges(mesh, o, d) < 1e-4) continue;  // not in general position
      const std::vector<double> expected = winding_crossings(mesh, o, d);
      const std::vector<RayHit> got = tree.hits(frame.to_local(o), frame.direction_to_local(d));
      REQUIRE(got.size() == expected.size());
      for (std::size_t h = 0; h < got.size(); ++h)
        CHECK(got[h].t == doctest::Approx(expected[h]).epsilon(1e-6));
      const Vec3 local = frame.to_local(target);
      const ZMapGrid& g = map.grid;
      const int i = static_cast<int>(std::floor((local.x - g.x0) / g.cell)),
                j = static_cast<int>(std::floor((local.y - g.y0) / g.cell));
      through_fine += i >= 0 && j >= 0 && i + 1 < g.nx && j + 1 < g.ny && map.fine_cell(i, j);
      ++compared;
    }
  }
  CHECK(compared > 1000);
  CHECK(through_fine > 150);
}

TEST_CASE(
    "refine steep cells: a pocket's walls lie within a sub-cell of where the moves put them") {
  // A flat end sinks a round pocket and a ball end a slot into a box (the ball's shank above its
  // centre makes a wall too), in a frame turned about z so that no wall follows the grid. On
  // random points of the fine cells, the solid z ≤ H is classified at a level through the walls
  // against the moves. Without fine cells the ramp misplaces a wall by up to a cell; with them,
  // by up to a sub-cell.
  std::mt19937 rng(47);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(0), Vec3(8, 6, 3)};
  const Frame frame = Frame::from_rotation(rotation_z(17));
  const double cell = 0.11;
  ZMap map = ZMap::from_box(frame, stock, cell);
  const ZMap initial = map;
  const Aabb local = local_bounds(frame, stock);
  const std::vector<Cutter> cutters{Cutter::flat(0.5), Cutter::ball(0.4)};
  const double floor = local.max.z - 1.5, level = floor + 0.75;
  const Vec3 c(0.5 * (local.min.x + local.max.x) - 1, 0.5 * (local.min.y + local.max.y), floor);
  std::vector<CutMove> moves;
  for (int k = 0; k < 24; ++k) {  // a circle of radius 1.2 round c
    const double a0 = 2 * M_PI * k / 24, a1 = 2 * M_PI * (k + 1) / 24;
    moves.push_back({Segment{c + 1.2 * Vec3(std::cos(a0), std::sin(a0), 0),
                             c + 1.2 * Vec3(std::cos(a1), std::sin(a1), 0)},
                     0});
  }
  moves.push_back({Segment{Vec3(c.x + 2.5, c.y - 2, floor), Vec3(c.x + 3.1, c.y + 2, floor)}, 1});
  mill(map, cutters, moves, {.threads = 1});
  raise_uncut(map, initial);
  ZMap fine = map;
  refine_steep_cells(fine, cutters, moves, {.threads = 2});
  CHECK(!fine.fine.empty());
  CHECK(fine.fine.cells.size() < map.heights.size() / 10);  // only the walls' cells

  // The reference: below `level` where some swept cutter reaches below it.
  auto below = [&](double x, double y) {
    for (const CutMove& m : moves)
      if (detail::MoveGeometry(cutters[m.cutter], m.tip).lowest(x, y).z < level) return true;
    return false;
  };
  auto to_wall = [&](double x,
                     double y) {  // along 16 directions, in steps of a hundredth of a cell
    const bool side = below(x, y);
    double best = 2 * cell;
    for (int dir = 0; dir < 16; ++dir)
      for (double r = 0.01 * cell; r < best; r += 0.01 * cell)
        if (below(x + r * std::cos(dir * M_PI / 8), y + r * std::sin(dir * M_PI / 8)) != side) {
          best = r;
          break;
        }
    return best;
  };
  int samples = 0, wrong_plain = 0, wrong_fine = 0;
  double worst_plain = 0, worst_fine = 0;
  const ZMapGrid& g = map.grid;
  for (std::size_t k = 0; k < fine.fine.cells.size(); ++k) {
    const int i = static_cast<int>(fine.fine.cells[k] % static_cast<std::uint32_t>(g.nx));
    const int j = static_cast<int>(fine.fine.cells[k] / static_cast<std::uint32_t>(g.nx));
    for (int s = 0; s < 8; ++s) {
      const double x = g.x(i) + unit(rng) * cell, y = g.y(j) + unit(rng) * cell;
      const bool truth = below(x, y);
      ++samples;
      if ((zmap_height(map, x, y) < level) != truth)
        ++wrong_plain, worst_plain = std::max(worst_plain, to_wall(x, y));
      if ((zmap_height(fine, x, y) < level) != truth)
        ++wrong_fine, worst_fine = std::max(worst_fine, to_wall(x, y));
    }
  }
  const double sub = cell / kSteps;
  MESSAGE("wall cells: " << samples << " points, plain map wrong at " << wrong_plain << " (up to "
                         << worst_plain / cell << " cells from the wall), fine cells wrong at "
                         << wrong_fine << " (up to " << worst_fine / cell << ")");
  CHECK(samples > 500);
  CHECK(worst_fine <= sub * 1.02);
  CHECK(worst_plain > 2 * sub);  // the plain map's ramp is off farther: the test can tell
  CHECK(wrong_fine * 3 < wrong_plain);
}

TEST_CASE(
    "refine steep cells: every inner sub-point is the brute-force lowest point over all moves") {
  // Random short and long moves of mixed cutters, level, sloped and vertical, over a map of many
  // 16-row bands (the moves are sorted into bands and skipped by their lowest tip and by their
  // distance to a cell and the profile's height there): each fine cell's sub-points other than its
  // corners (which are the map's own points) must be min(ceiling, min over every move of
  // MoveGeometry::lowest), raised to the empty height, exactly.
  std::mt19937 rng(1717);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(0), Vec3(12, 9, 4)};
  const Frame frame = Frame::from_rotation(rotation_z(23) * rotation_x(9));
  ZMap map = ZMap::from_box(frame, stock, 0.09);
  const ZMap initial = map;
  const Aabb local = local_bounds(frame, stock);
  const std::vector<Cutter> cutters{Cutter::ball(0.5), Cutter::flat(0.4),
                                    Cutter::bull_nose(0.6, 0.2), Cutter::cone(0.5, 30),
                                    Cutter::tapered_ball(0.7, 0.3, 10)};
  std::vector<CutMove> moves;
  auto point = [&] {
    return Vec3(local.min.x - 1 + (local.max.x - local.min.x + 2) * unit(rng),
                local.min.y - 1 + (local.max.y - local.min.y + 2) * unit(rng),
                local.max.z - 2.5 * unit(rng));
  };
  for (int k = 0; k < 400; ++k) {
    const Vec3 a = point();
    Vec3 b = k % 3 == 0
                 ? point()
                 : a + Vec3(1.5 * unit(rng) - 0.75, 1.5 * unit(rng) - 0.75, 0.4 * unit(rng) - 0.2);
    if (k % 7 == 0) b = Vec3(a.x, a.y, b.z);  // vertical
    if (k % 5 == 0) b.z = a.z;                // level
    moves.push_back({Segment{a, b}, static_cast<std::uint32_t>(k % cutters.size())});
  }
  mill(map, cutters, moves, {.threads = 1});
  raise_uncut(map, initial);
  float ceiling = map.empty_height;
  for (float h : map.heights) ceiling = std::max(ceiling, h);
  refine_steep_cells(map, cutters, moves, {.threads = 2});
  REQUIRE(map.fine.cells.size() > 500);
  REQUIRE(map.grid.ny > 4 * 16);

  std::vector<detail::MoveGeometry> geometry;
  for (const CutMove& m : moves) geometry.emplace_back(cutters[m.cutter], m.tip);
  const ZMapGrid& g = map.grid;
  const double step = g.cell / kSteps;
  std::size_t compared = 0, wrong = 0;
  for (std::size_t k = 0; k < map.fine.cells.size(); ++k) {
    const int i = static_cast<int>(map.fine.cells[k] % static_cast<std::uint32_t>(g.nx));
    const int j = static_cast<int>(map.fine.cells[k] / static_cast<std::uint32_t>(g.nx));
    for (int b = 0; b < kSide; ++b)
      for (int a = 0; a < kSide; ++a) {
        if ((a == 0 || a == kSteps) && (b == 0 || b == kSteps)) continue;
        const double x = g.x0 + (kSteps * i + a) * step, y = g.y0 + (kSteps * j + b) * step;
        double lowest = ceiling;
        for (const detail::MoveGeometry& m : geometry) lowest = std::min(lowest, m.lowest(x, y).z);
        const float expected = std::max(static_cast<float>(lowest), map.empty_height);
        wrong += map.fine.heights[k * ZMapFineCells::kPoints +
                                  static_cast<std::size_t>(a + kSide * b)] != expected;
        ++compared;
      }
  }
  CHECK(compared > 10000);
  CHECK(wrong == 0);
}

TEST_CASE(
    "steep cells: the row bands on any thread count list every steep cell, ascending, as a scan of "
    "all cells") {
  std::mt19937 rng(31);
  std::uniform_real_distribution<double> unit(0, 1);
  for (int trial = 0; trial < 4; ++trial) {
    // Random heights, flat patches and empty points over more rows than a band, so that bands
    // with no steep cell and cells on the bands' borders occur.
    ZMapGrid g;
    g.cell = 0.1, g.nx = 37 + 11 * trial, g.ny = 2 * detail::kMapBandRows + 17 * trial;
    ZMap map(g, 0.0f, -0.5f);
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i)
        if (j % 50 < 30)
          map.heights[g.index(i, j)] =
              unit(rng) < 0.1 ? -1.0f : static_cast<float>(0.4 * unit(rng));
    std::vector<std::uint32_t> want;
    for (int j = 0; j + 1 < g.ny; ++j)
      for (int i = 0; i + 1 < g.nx; ++i)
        if (is_steep_cell(map, i, j, 1.5))
          want.push_back(static_cast<std::uint32_t>(g.index(i, j)));
    REQUIRE(want.size() > 100);
    for (unsigned threads : {1u, 2u, 3u}) CHECK(steep_cells(map, 1.5, threads) == want);
  }
}

namespace test_fine_cells {

// A pocket roughed in layers, top down, by a raster of short flat-end moves, then its walls
// finished by a ball end sloping down round it: the walls are cut again layer after layer, and
// their cells next to uncut stock keep sub-points at the ceiling.
std::vector<CutMove> raster_pocket(const Aabb& local) {
  std::vector<CutMove> moves;
  // Steps off the grid's: a sub-point exactly a radius from a move is a tie that the moves'
  // boxes and MoveGeometry::lowest settle differently.
  const double x0 = local.min.x + 1.4137, x1 = local.max.x - 1.3871;
  const double y0 = local.min.y + 1.1173, y1 = local.max.y - 1.0919;
  for (int layer = 1; layer <= 4; ++layer) {
    const double z = local.max.z - 0.3 * layer;
    for (double y = y0; y <= y1 + 1e-9; y += 0.2917)
      for (double x = x0; x < x1 - 1e-9; x += 0.2113)
        moves.push_back({Segment{Vec3(x, y, z), Vec3(std::min(x + 0.2113, x1), y, z)}, 0});
  }
  const Vec3 corners[] = {Vec3(x0, y0, 0), Vec3(x1, y0, 0), Vec3(x1, y1, 0), Vec3(x0, y1, 0)};
  double z = local.max.z - 0.2;
  for (int lap = 0; lap < 3; ++lap)
    for (int side = 0; side < 4; ++side)
      for (int k = 0; k < 8; ++k) {
        const Vec3 a = corners[side], b = corners[(side + 1) % 4];
        const Vec3 p = a + (b - a) * (k / 8.0), q = a + (b - a) * ((k + 1) / 8.0);
        moves.push_back({Segment{Vec3(p.x, p.y, z), Vec3(q.x, q.y, z - 0.01)}, 1});
        z -= 0.01;
      }
  return moves;
}

}  // namespace test_fine_cells

TEST_CASE(
    "refine steep cells: a raster pocket's sub-points are the brute-force lowest points, in one "
    "call or two, on any thread count") {
  // Each fine cell runs down its wall tile's moves lowest bound first and stops at the first
  // move above it (lower_fine_cells): the heights are the minimum over every move, whatever
  // the order, so lowering by the first moves and then by the rest from those heights (as an
  // embedder does when moves come later) gives the same heights as one call.
  const Aabb stock{Vec3(0), Vec3(6, 4.5, 3)};
  const Frame frame = Frame::from_rotation(rotation_z(11));
  ZMap map = ZMap::from_box(frame, stock, 0.1);
  const ZMap initial = map;
  const std::vector<Cutter> cutters{Cutter::flat(0.6), Cutter::ball(0.3)};
  const std::vector<CutMove> moves = test_fine_cells::raster_pocket(local_bounds(frame, stock));
  mill(map, cutters, moves, {.threads = 1});
  raise_uncut(map, initial);
  const std::vector<std::uint32_t> cells = steep_cells(map, 1.5);
  REQUIRE(cells.size() > 150);
  const ZMapGrid& g = map.grid;
  std::vector<std::size_t> row_begin(static_cast<std::size_t>(g.ny), cells.size());
  for (std::size_t k = cells.size(); k-- > 0;)
    row_begin[cells[k] / static_cast<std::uint32_t>(g.nx)] = k;
  for (std::size_t row = row_begin.size() - 1; row-- > 0;)
    row_begin[row] = std::min(row_begin[row], row_begin[row + 1]);
  const float ceiling = *std::max_element(map.heights.begin(), map.heights.end());
  const std::size_t points = cells.size() * ZMapFineCells::kPoints;
  auto lowered = [&](std::span<const CutMove> first, std::span<const CutMove> rest,
                     unsigned threads) {
    std::vector<float> sub(points, ceiling);
    detail::lower_fine_cells(g, cutters, first, cells, row_begin, ceiling, threads, sub);
    detail::lower_fine_cells(g, cutters, rest, cells, row_begin, ceiling, threads, sub);
    return sub;
  };
  const std::span<const CutMove> all(moves);
  const std::vector<float> once = lowered(all, {}, 2);
  CHECK(lowered(all, {}, 1) == once);
  CHECK(lowered(all.first(moves.size() / 3), all.subspan(moves.size() / 3), 2) == once);

  std::vector<detail::MoveGeometry> geometry;
  for (const CutMove& m : moves) geometry.emplace_back(cutters[m.cutter], m.tip);
  const double step = g.cell / kSteps;
  std::size_t wrong = 0, at_ceiling = 0, lowered_points = 0;
  for (std::size_t k = 0; k < cells.size(); ++k) {
    const int i = static_cast<int>(cells[k] % static_cast<std::uint32_t>(g.nx));
    const int j = static_cast<int>(cells[k] / static_cast<std::uint32_t>(g.nx));
    for (int b = 0; b < kSide; ++b)
      for (int a = 0; a < kSide; ++a) {
        const double x = g.x0 + (kSteps * i + a) * step, y = g.y0 + (kSteps * j + b) * step;
        double lowest = ceiling;
        for (const detail::MoveGeometry& m : geometry) lowest = std::min(lowest, m.lowest(x, y).z);
        const float got =
            once[k * ZMapFineCells::kPoints + static_cast<std::size_t>(a + kSide * b)];
        wrong += got != static_cast<float>(lowest);
        at_ceiling += got == ceiling;
        lowered_points += got < ceiling;
      }
  }
  CHECK(wrong == 0);
  CHECK(at_ceiling > 100);  // cells next to uncut stock
  CHECK(lowered_points > 1000);
}
