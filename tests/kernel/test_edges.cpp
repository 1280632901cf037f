// Accuracy along the edges where two spindle directions' cuts meet (issue 17), sampled there
// (edge_sampling.hpp) because uniform samples, as in test_machine.cpp, almost never land on
// them. Errors beyond h/2 and beyond 1.5 h are counted; the target is at most 2 in 10,000
// beyond h/2 and none beyond 1.5 h.
//
// Both cases meet it with the command's defaults: a Z-map cell of h/2 and fine cells at the
// walls (fine_cells.hpp). Where one direction's pocket wall (parallel to its spindle) meets
// the other's surface, the plain Z-map polyhedron ramps across the wall's cell and is off by up
// to a cell at the rim (docs/design.md, "Known errors"); the second case shows that fine cells
// remove those errors.
#include <doctest/doctest.h>

#include <bit>
#include <random>
#include <string>
#include <utility>

#include "tridex/intersect_milled.hpp"
#include "tridex/mill.hpp"
#include "tridex/surface.hpp"
#include "tridex/zmap.hpp"
#include "tridex/fine_cells.hpp"
#include "edge_sampling.hpp"

using namespace tridex;
using tridex::test::EdgeErrors;

namespace {

struct Direction {
  Frame frame;
  std::vector<CutMove> moves;  // tool tip in the frame
};

// Point membership by the moves: p is removed by direction i iff one of its moves' swept
// cutters reaches down to p's local height over p's local (x, y). The moves of each direction
// are bucketed on a grid of its local x-y plane, so a query looks at a few of them.
class EdgeReference {
 public:
  EdgeReference(const Aabb& stock, const std::vector<Direction>& program,
                const std::vector<Cutter>& cutters)
      : stock_(stock), program_(program) {
    for (const Direction& d : program) {
      Bucketed b;
      b.box = local_bounds(d.frame, stock).inflated(0.5);
      b.nx = static_cast<int>(std::ceil(b.box.size().x / kBucket)) + 1;
      b.ny = static_cast<int>(std::ceil(b.box.size().y / kBucket)) + 1;
      b.cells.resize(static_cast<std::size_t>(b.nx * b.ny));
      for (const CutMove& m : d.moves) {
        b.moves.emplace_back(cutters[m.cutter], m.tip);
        const double r = cutters[m.cutter].radius();
        const auto index = static_cast<std::uint32_t>(b.moves.size() - 1);
        for (int j = b.bin_y(std::min(m.tip.a.y, m.tip.b.y) - r);
             j <= b.bin_y(std::max(m.tip.a.y, m.tip.b.y) + r); ++j)
          for (int i = b.bin_x(std::min(m.tip.a.x, m.tip.b.x) - r);
               i <= b.bin_x(std::max(m.tip.a.x, m.tip.b.x) + r); ++i)
            b.cells[static_cast<std::size_t>(i + b.nx * j)].push_back(index);
      }
      buckets_.push_back(std::move(b));
    }
  }

  // 0 outside the stock, 1 kept, otherwise 2 << i for each direction i that removes p.
  unsigned label(const Vec3& p) const {
    if (!stock_.contains(p)) return 0;
    unsigned l = 0;
    for (std::size_t i = 0; i < program_.size(); ++i) {
      const Vec3 q = program_[i].frame.to_local(p);
      const Bucketed& b = buckets_[i];
      for (std::uint32_t m : b.cells[static_cast<std::size_t>(b.bin_x(q.x) + b.nx * b.bin_y(q.y))])
        if (q.z >= b.moves[m].lowest(q.x, q.y).z) {
          l |= 2u << i;
          break;
        }
    }
    return l == 0 ? 1 : l;
  }
  bool kept(const Vec3& p) const { return label(p) == 1; }

 private:
  static constexpr double kBucket = 0.5;
  struct Bucketed {
    Aabb box;
    int nx = 0, ny = 0;
    std::vector<detail::MoveGeometry> moves;
    std::vector<std::vector<std::uint32_t>> cells;
    int bin_x(double x) const {
      return std::clamp(static_cast<int>(std::floor((x - box.min.x) / kBucket)), 0, nx - 1);
    }
    int bin_y(double y) const {
      return std::clamp(static_cast<int>(std::floor((y - box.min.y) / kBucket)), 0, ny - 1);
    }
  };
  Aabb stock_;
  const std::vector<Direction>& program_;
  std::vector<Bucketed> buckets_;
};

// A random pair: direction A, near +z, finishes a tilted, rippled surface with a ball end in
// raster passes (scallops); direction B, tilted 50–80° from +z, faces a plane with a flat end
// and, when `pocket`, sinks a pocket 0.8 deep into part of it (walls parallel to B's spindle
// that meet A's surface).
std::vector<Direction> random_pair(std::mt19937& rng, const Aabb& stock, bool pocket) {
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<Direction> program;
  {
    Direction d{
        Frame::from_axis(glm::normalize(Vec3(0.5 * (unit(rng) - 0.5), 0.5 * (unit(rng) - 0.5), 1))),
        {}};
    const Aabb local = local_bounds(d.frame, stock);
    const double z0 = local.max.z - 0.8 - 0.5 * unit(rng), sx = 0.15 * (unit(rng) - 0.5),
                 sy = 0.15 * (unit(rng) - 0.5);
    const double step = 0.5 + 0.4 * unit(rng);  // × the ball's radius, 1
    auto z = [&](double x, double y) {
      return z0 + sx * (x - local.min.x) + sy * (y - local.min.y) + 0.2 * std::sin(x);
    };
    for (double y = local.min.y - 1; y <= local.max.y + 1; y += step)
      for (double x = local.min.x - 1; x < local.max.x + 1; x += 0.7)
        d.moves.push_back({Segment{Vec3(x, y, z(x, y)), Vec3(x + 0.7, y, z(x + 0.7, y))}, 0});
    program.push_back(d);
  }
  {
    const double tilt = (50 + 30 * unit(rng)) * M_PI / 180, azimuth = 2 * M_PI * unit(rng);
    Direction d{Frame::from_axis(Vec3(std::sin(tilt) * std::cos(azimuth),
                                      std::sin(tilt) * std::sin(azimuth), std::cos(tilt))),
                {}};
    const Aabb local = local_bounds(d.frame, stock);
    const double c = local.max.z - (0.25 + 0.2 * unit(rng)) * (local.max.z - local.min.z);
    for (double y = local.min.y - 1; y <= local.max.y + 1; y += 1.5)
      d.moves.push_back({Segment{Vec3(local.min.x - 1, y, c), Vec3(local.max.x + 1, y, c)}, 1});
    if (pocket) {
      const double y0 = local.min.y + (0.3 + 0.2 * unit(rng)) * (local.max.y - local.min.y);
      for (double y = y0; y <= y0 + 1.5; y += 0.75)
        d.moves.push_back(
            {Segment{Vec3(local.min.x - 1, y, c - 0.8), Vec3(local.max.x + 1, y, c - 0.8)}, 1});
    }
    program.push_back(d);
  }
  return program;
}

EdgeErrors machine_and_measure(std::mt19937& rng, bool pocket, double h, double cell, int samples,
                               bool fine = true) {
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(0), Vec3(6 + unit(rng), 5 + unit(rng), 4 + unit(rng))};
  const std::vector<Cutter> cutters{Cutter::ball(1.0), Cutter::flat(1.0)};
  const std::vector<Direction> program = random_pair(rng, stock, pocket);
  std::vector<ZMap> maps;
  for (const Direction& d : program) {
    maps.push_back(ZMap::from_box(d.frame, stock, cell));
    const ZMap initial = maps.back();
    mill(maps.back(), cutters, d.moves);
    raise_uncut(maps.back(), initial);
    if (fine) refine_steep_cells(maps.back(), cutters, d.moves, {.threads = 2});
  }
  const Mesh mesh =
      extract_surface(intersect_milled(stock, DexelLattice::covering(stock, h), maps));
  const EdgeReference ref(stock, program, cutters);
  return test::measure_edges(
      stock, [&](const Vec3& p) { return ref.label(p); }, mesh, h, samples, rng);
}

void add(EdgeErrors& total, const EdgeErrors& e) {
  total.samples += e.samples, total.wrong += e.wrong, total.beyond_half += e.beyond_half;
  total.beyond_one_and_half += e.beyond_one_and_half, total.worst = std::max(total.worst, e.worst);
}

}  // namespace

TEST_CASE(
    "edges where two directions meet: tilted planar and scalloped ball-end cuts, Z-map cell h/2") {
  // Measured: 4500 edge points, 0 wrong beyond h/2, worst 0.37 h.
  std::mt19937 rng(17);
  const double h = 0.1;
  EdgeErrors total;
  for (int trial = 0; trial < 3; ++trial)
    add(total, machine_and_measure(rng, false, h, 0.5 * h, 1500));
  MESSAGE("planar + scalloped, cell h/2: " << total.samples << " edge points, " << total.wrong
                                           << " wrong, " << total.beyond_half << " beyond h/2, "
                                           << total.beyond_one_and_half << " beyond 1.5h, worst "
                                           << total.worst << " h");
  CHECK(total.samples == 4500);
  CHECK(total.beyond_one_and_half == 0);
  CHECK(total.beyond_half * 10000 <= 2 * total.samples);  // the target: 2 in 10,000
  CHECK(total.worst < 0.75);
}

TEST_CASE(
    "edges where two directions meet: a pocket wall of one direction meeting the other's "
    "scallops") {
  // The same pairs with and without fine cells at the walls (fine_cells.hpp). Without them the
  // wall's rims are off by up to a Z-map cell (here h/2), which puts edge points wrong beyond
  // h/2; with them, by up to a sub-cell.
  const double h = 0.1;
  EdgeErrors fine, plain;
  for (std::uint32_t seed : {29u, 31u, 37u}) {
    std::mt19937 a(seed), b(seed);
    add(fine, machine_and_measure(a, true, h, 0.5 * h, 1500, true));
    add(plain, machine_and_measure(b, true, h, 0.5 * h, 1500, false));
  }
  for (const auto& [name, e] :
       {std::pair{std::string("fine cells"), fine}, std::pair{std::string("plain cells"), plain}})
    MESSAGE("pocket wall + scalloped, cell h/2, "
            << name << ": " << e.samples << " edge points, " << e.wrong << " wrong, "
            << e.beyond_half << " beyond h/2, " << e.beyond_one_and_half << " beyond 1.5h, worst "
            << e.worst << " h");
  CHECK(fine.samples == 4500);
  CHECK(plain.samples == 4500);
  CHECK(fine.beyond_one_and_half == 0);
  CHECK(fine.beyond_half * 10000 <=
        2 * fine.samples);  // the target; measured: 0 in 4500, worst 0.43 h
  CHECK(fine.worst < 0.5);
  CHECK(plain.beyond_half * 10000 > 2 * plain.samples);  // measured: 7 in 4500, worst 0.62 h
}
