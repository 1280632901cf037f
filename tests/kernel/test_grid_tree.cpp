#include <doctest/doctest.h>

#include <random>

#include "test_dexel_shapes.hpp"
#include "tridex/grid_tree.hpp"

using namespace tridex;
using namespace tridex_test;

namespace {

ZMap random_map(std::mt19937& rng, int nx, int ny, const Frame& frame) {
  std::uniform_real_distribution<double> unit(0, 1);
  ZMapGrid g;
  g.frame = frame, g.x0 = -1 + unit(rng), g.y0 = -1 + unit(rng), g.cell = 0.3 + unit(rng),
  g.nx = nx, g.ny = ny;
  ZMap map(g, 0.0f, -0.5f);
  // Smooth hills plus noise plus some cut-through points.
  double fx = 0.2 + unit(rng), fy = 0.2 + unit(rng);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) {
      double h = 1.5 + std::sin(fx * i) * std::cos(fy * j) + 0.3 * unit(rng);
      map.heights[g.index(i, j)] = unit(rng) < 0.05 ? map.empty_height : static_cast<float>(h);
    }
  return map;
}

}  // namespace

TEST_CASE("grid tree: node bounds enclose their heights, leaves have at most 4 x 4 cells") {
  std::mt19937 rng(2);
  ZMap map = random_map(rng, 37, 21, Frame{});
  GridTree tree(map);
  const auto& nodes = tree.nodes();
  float lo = 1e30f, hi = -1e30f;
  for (float h : map.heights)
    lo = std::min(lo, std::max(h, map.empty_height)), hi = std::max(hi, h);
  CHECK(nodes[0].lo == lo);
  CHECK(nodes[0].hi == hi);
  std::size_t leaves = 0;
  for (const auto& n : nodes) {
    if (n.left == 0) {
      ++leaves;
      continue;
    }
    CHECK(nodes[n.left].lo >= n.lo);
    CHECK(nodes[n.left + 1].hi <= n.hi);
    CHECK(std::min(nodes[n.left].lo, nodes[n.left + 1].lo) == n.lo);
  }
  // 36 × 20 cells in aligned blocks of 4 × 4: 9 × 5 leaves, a binary tree of them.
  CHECK(leaves == 45);
  CHECK(nodes.size() == 2 * leaves - 1);
}

TEST_CASE("grid tree: every node's height range and plane bound hold at all its points") {
  std::mt19937 rng(6);
  std::uniform_real_distribution<double> angle(-60, 60);
  for (int trial = 0; trial < 6; ++trial) {
    Frame frame = Frame::from_rotation(rotation_z(angle(rng)) * rotation_x(angle(rng)));
    ZMap map = trial % 2 ? random_map(rng, 41, 29, frame)
                         : ZMap::from_box(frame, Aabb{Vec3(0), Vec3(7, 5, 3)}, 0.13);
    GridTree tree(map);
    const auto& nodes = tree.nodes();
    std::vector<GridTree::NodeCells> cells = tree.node_cells();
    for (std::uint32_t k = 0; k < nodes.size(); ++k) {
      const GridTree::NodeCells& c = cells[k];
      CHECK(c.i1 > c.i0);
      CHECK(c.j1 > c.j0);
      if (nodes[k].left == 0) {  // aligned 4 × 4 blocks, cut short only at the grid's far side
        CHECK(c.i1 - c.i0 <= 4);
        CHECK(c.j1 - c.j0 <= 4);
        CHECK(c.i0 % 4 == 0);
        CHECK(c.j0 % 4 == 0);
        CHECK((c.i1 - c.i0 == 4 || c.i1 == map.grid.nx - 1));
        CHECK((c.j1 - c.j0 == 4 || c.j1 == map.grid.ny - 1));
      } else {  // the children tile the node
        const GridTree::NodeCells &a = cells[nodes[k].left], &b = cells[nodes[k].left + 1];
        CHECK((a.i1 - a.i0) * (a.j1 - a.j0) + (b.i1 - b.i0) * (b.j1 - b.j0) ==
              (c.i1 - c.i0) * (c.j1 - c.j0));
      }
      float lo = 1e30f, hi = -1e30f;
      for (int j = c.j0; j <= c.j1; ++j)
        for (int i = c.i0; i <= c.i1; ++i) {
          double h = std::max(map.height(i, j), map.empty_height);
          lo = std::min(lo, static_cast<float>(h)), hi = std::max(hi, static_cast<float>(h));
          CHECK(std::abs(h - tree.plane_at(k, c, map.grid.x(i), map.grid.y(j))) <=
                nodes[k].deviation);
        }
      CHECK(nodes[k].lo == lo);
      CHECK(nodes[k].hi == hi);
    }
    // An uncut tilted box is flat over wide regions: many nodes fit their plane to float noise.
    if (trial % 2 == 0) {
      std::size_t flat = 0;
      for (const auto& n : nodes) flat += n.deviation < 1e-4f;
      CHECK(flat * 3 > nodes.size());
    }
  }
}

TEST_CASE("grid tree: hits equal brute-force hits on the polyhedron for random rays") {
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> unit(0, 1), angle(-70, 70);
  int compared = 0;
  for (int trial = 0; trial < 12; ++trial) {
    Frame frame = Frame::from_rotation(rotation_z(angle(rng)) * rotation_x(angle(rng)),
                                       Vec3(unit(rng), unit(rng), unit(rng)));
    ZMap map = random_map(rng, std::uniform_int_distribution<int>(2, 40)(rng),
                          std::uniform_int_distribution<int>(2, 40)(rng), frame);
    GridTree tree(map);
    Mesh mesh = polyhedrize(map);
    Aabb box = mesh.bounds();
    for (int k = 0; k < 150; ++k) {
      Vec3 target = box.min + Vec3(unit(rng), unit(rng), unit(rng)) * box.size();
      Vec3 d = glm::normalize(Vec3(unit(rng) - 0.5, unit(rng) - 0.5, unit(rng) - 0.5));
      if (k % 3 == 0) d = frame.axis() * (k % 2 ? 1.0 : -1.0);  // along the spindle
      Vec3 o = target - 100.0 * d;
      if (distance_to_edges(mesh, o, d) < 1e-4) continue;  // not in general position
      std::vector<double> expected = brute_force_hits(mesh, o, d);
      std::vector<RayHit> got = tree.hits(frame.to_local(o), frame.direction_to_local(d));
      if (got.size() != expected.size()) {
        MESSAGE("trial ", trial, " ray ", k);
        for (double e : expected) MESSAGE("expected ", e);
        for (const RayHit& h : got) MESSAGE("got ", h.t);
      }
      REQUIRE(got.size() == expected.size());
      for (std::size_t h = 0; h < got.size(); ++h) {
        CHECK(got[h].t == doctest::Approx(expected[h]).epsilon(1e-6));
        CHECK(got[h].entering == (h % 2 == 0));
      }
      ++compared;
    }
  }
  CHECK(compared > 1000);
}

TEST_CASE("grid tree: rays exactly through grid points and along grid lines") {
  std::mt19937 rng(4);
  ZMap map = random_map(rng, 23, 19, Frame{});
  GridTree tree(map);
  const ZMapGrid& g = map.grid;
  double bottom = tree.bottom();
  // Along the spindle through every grid point: one span from the bottom to the point's top.
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i)
      for (double sign : {1.0, -1.0}) {
        std::vector<RaySpan> spans;
        tree.spans(Vec3(g.x(i), g.y(j), 0), Vec3(0, 0, sign), spans);
        REQUIRE(spans.size() == 1);
        double top = std::max(map.height(i, j), map.empty_height);
        CHECK(std::abs(sign * (sign > 0 ? spans[0].enter : spans[0].exit) - bottom) < 1e-9);
        CHECK(std::abs(sign * (sign > 0 ? spans[0].exit : spans[0].enter) - top) < 1e-9);
      }
  // Horizontal rays along grid lines and diagonals, at the heights of grid points (so they touch
  // vertices exactly): the solid part agrees with dense samples of the top.
  for (int trial = 0; trial < 300; ++trial) {
    int i = std::uniform_int_distribution<int>(0, g.nx - 1)(rng),
        j = std::uniform_int_distribution<int>(0, g.ny - 1)(rng);
    double z = std::max(map.height(i, j), map.empty_height);
    Vec3 o(g.x(i), g.y(j), z);
    Vec3 d = trial % 3 == 0   ? Vec3(1, 0, 0)
             : trial % 3 == 1 ? Vec3(0, 1, 0)
                              : glm::normalize(Vec3(1, 1, 0));
    std::vector<RaySpan> spans;
    tree.spans(o, d, spans);
    for (std::size_t k = 1; k < spans.size(); ++k) CHECK(spans[k].enter > spans[k - 1].exit);
    for (double t = -60; t < 60; t += 0.0137) {
      Vec3 p = o + t * d;
      if (p.x < g.x(0) || p.x > g.x(g.nx - 1) || p.y < g.y(0) || p.y > g.y(g.ny - 1)) continue;
      double gap = zmap_height(map, p.x, p.y) - z;
      if (std::abs(gap) < 1e-6) continue;  // on the surface: either
      bool in = false;
      for (const RaySpan& s : spans) in = in || (s.enter <= t && t <= s.exit);
      CHECK(in == (gap > 0));
    }
  }
}
