#include <doctest/doctest.h>

#include <random>

#include "helpers.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/intersect_milled.hpp"
#include "tridex/polyhedron.hpp"
#include "tridex/scan_dexelize.hpp"

using namespace tridex;
using namespace backend_tests;

TEST_CASE("scan dexelize equals the grid tree ray by ray on random Z-maps and frames") {
  std::mt19937 rng(101);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(0, 0, 0), Vec3(4, 3, 2)};
  RayComparison total;
  for (int trial = 0; trial < 12; ++trial) {
    Frame frame = random_frame(rng, trial % 4 != 0);
    ZMap map = random_milled_map(rng, stock, frame, 0.06 + 0.1 * unit(rng));
    DexelLattice l = DexelLattice::covering(stock.inflated(0.4), 0.05 + 0.1 * unit(rng));
    l.origin += Vec3(unit(rng), unit(rng), unit(rng)) * (0.5 * l.spacing);
    const unsigned threads = 1 + static_cast<unsigned>(trial % 2);
    TripleDexel tree = dexelize(map, l, {.threads = threads});
    TripleDexel scan = scan_dexelize(map, l, threads);
    validate(scan);
    CHECK(volume(scan) == doctest::Approx(volume(tree)).epsilon(1e-5));
    RayComparison c = compare_rays(tree, scan, 1e-4);
    total.rays += c.rays, total.mismatches += c.mismatches, total.intervals += c.intervals;
    total.worst = std::max(total.worst, c.worst);
  }
  INFO("rays ", total.rays, " intervals ", total.intervals, " mismatches ", total.mismatches,
       " worst ", total.worst);
  CHECK(total.rays > 50000);
  CHECK(total.intervals > 20000);
  CHECK(total.mismatches == 0);
  CHECK(total.worst < 1e-4);
}

TEST_CASE(
    "scan dexelize on a lattice aligned with the Z-map grid equals dexelizing the polyhedron "
    "mesh") {
  // Every ray passes through grid points and cell edges: the tie-breaking (symbolic
  // perturbation) decides them the way the mesh dexelizer does.
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(0, 0, 0), Vec3(3, 2, 1.5)};
  for (int trial = 0; trial < 4; ++trial) {
    const double cell = 0.125;
    ZMap map = random_milled_map(rng, stock, Frame{}, cell, 8);
    DexelLattice l;
    l.spacing = trial % 2 ? 0.125 : 0.25;
    l.origin = Vec3(-0.5, -0.5, -0.75);
    l.n = glm::ivec3(33, 25, 21);
    TripleDexel scan = scan_dexelize(map, l);
    TripleDexel mesh = dexelize(polyhedrize(map), l);
    RayComparison c = compare_rays(mesh, scan, 1e-5);
    INFO("trial ", trial, " mismatches ", c.mismatches, " of ", c.rays);
    CHECK(c.mismatches == 0);
    CHECK(c.intervals > 250);
  }
}

TEST_CASE("scan dexelize equals the grid tree and the polyhedron mesh on maps with fine cells") {
  // Fine cells (ZMapFineCells) bring sub-grid triangles and vertical steps to plain neighbours;
  // the three must still describe one solid, also on a lattice aligned with the sub-grid, where
  // rays run through sub-points and along the steps.
  std::mt19937 rng(211);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(0, 0, 0), Vec3(3, 2, 1.5)};
  std::size_t fine_cells = 0;
  for (int trial = 0; trial < 8; ++trial) {
    const bool aligned = trial % 2 == 0;
    const Frame frame = aligned ? Frame{} : random_frame(rng, true);
    const double cell = aligned ? 0.125 : 0.06 + 0.1 * unit(rng);
    const ZMap map = random_milled_map(rng, stock, frame, cell, 12, true);
    fine_cells += map.fine.cells.size();
    DexelLattice l =
        DexelLattice::covering(stock.inflated(0.4), aligned ? cell / 4 : 0.05 + 0.1 * unit(rng));
    if (aligned) l.origin = Vec3(-0.5, -0.5, -0.75);
    const TripleDexel scan = scan_dexelize(map, l);
    validate(scan);
    const TripleDexel tree = dexelize(map, l);
    const TripleDexel mesh = dexelize(polyhedrize(map), l);
    RayComparison with_tree = compare_rays(tree, scan, 1e-4),
                  with_mesh = compare_rays(mesh, scan, 1e-4);
    INFO("trial ", trial, ": ", with_tree.mismatches, " and ", with_mesh.mismatches,
         " mismatches of ", with_tree.rays, " rays against the tree and the mesh");
    // On the aligned lattice the tree decides exact ties its own way, and the mesh's float
    // positions are exact; tilted, they are not (an overlapping step can leave a sliver).
    if (aligned)
      CHECK(with_mesh.mismatches == 0);
    else
      CHECK(with_tree.mismatches == 0);
    CHECK(volume(scan) == doctest::Approx(volume(tree)).epsilon(1e-4));
  }
  CHECK(fine_cells > 500);
}

TEST_CASE("scan machine equals the kernel's machine (W0 ∩ M1 ∩ … ∩ MN)") {
  std::mt19937 rng(55);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(-1, 0, 0), Vec3(2, 2.5, 1.8)};
  for (int trial = 0; trial < 4; ++trial) {
    std::vector<ZMap> maps;
    for (int m = 0; m < 3; ++m)
      maps.push_back(random_milled_map(rng, stock, random_frame(rng, m > 0), 0.08, 8));
    DexelLattice l = DexelLattice::covering(stock, 0.07 + 0.03 * unit(rng));
    l.origin += Vec3(unit(rng), unit(rng), unit(rng)) * (0.3 * l.spacing);
    TripleDexel w0 = TripleDexel::box(l, stock);
    TripleDexel reference = intersect_milled(w0, maps, 2);
    TripleDexel scan = scan_intersect_milled(w0, maps, 2);
    validate(scan);
    RayComparison c = compare_rays(reference, scan, 1e-4);
    INFO("trial ", trial, " mismatches ", c.mismatches, " worst ", c.worst);
    CHECK(c.mismatches == 0);
    CHECK(volume(scan) < volume(w0));
    // The result is independent of the order of the maps.
    std::vector<ZMap> reversed(maps.rbegin(), maps.rend());
    CHECK(compare_rays(scan, scan_intersect_milled(w0, reversed, 1), 0).mismatches == 0);
  }
}

TEST_CASE("scan dexelize rejects bad input with clear errors") {
  ZMap tiny(ZMapGrid{Frame{}, 0, 0, 1, 1, 5}, 1, 0);
  DexelLattice l{Vec3(0), 1, glm::ivec3(4)};
  CHECK_THROWS_WITH_AS(scan_dexelize(tiny, l), doctest::Contains("no cell"), Error);
  ZMap map = ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(2)}, 0.5);
  CHECK_THROWS_WITH_AS(scan_dexelize(map, DexelLattice{Vec3(0), 0, glm::ivec3(4)}),
                       doctest::Contains("spacing"), Error);
  DexelLattice far{Vec3(0), 1e-15, glm::ivec3(4)};
  CHECK_THROWS_WITH_AS(scan_dexelize(map, far), doctest::Contains("too far"), Error);
}

TEST_CASE(
    "scan dexelize visiting only the rows and columns that reach a ray equals the grid tree on "
    "frames along the lattice") {
  // A frame whose x or y runs along a lattice axis puts the rays of two families a ray spacing
  // apart across the grid's rows or columns, and the scanner skips the rows and columns in
  // between (ZMapScanner::reaches_rays): on a lattice several cells apart, most of them. Turned
  // about the lattice's axes (quarter turns, and a tilt about y as the paper-scale workload's
  // fifth direction), with fine cells, against the grid tree ray by ray.
  std::mt19937 rng(919);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(0, 0, 0), Vec3(3, 2.5, 2)};
  const Frame frames[] = {
      Frame{}, Frame::from_rotation(rotation_x(90)), Frame::from_rotation(rotation_y(-90)),
      Frame::from_rotation(rotation_y(70)), Frame::from_rotation(rotation_x(180) * rotation_z(90))};
  RayComparison total;
  std::size_t fine_cells = 0;
  for (int trial = 0; trial < 10; ++trial) {
    const Frame& frame = frames[trial % 5];
    const double cell = 0.03 + 0.02 * unit(rng);
    const ZMap map = random_milled_map(rng, stock, frame, cell, 10, trial % 2 == 0);
    fine_cells += map.fine.cells.size();
    DexelLattice l = DexelLattice::covering(stock.inflated(0.2), (3 + 4 * unit(rng)) * cell);
    l.origin += Vec3(unit(rng), unit(rng), unit(rng)) * (0.5 * l.spacing);
    const unsigned threads = 1 + static_cast<unsigned>(trial % 2);
    const TripleDexel scan = scan_dexelize(map, l, threads);
    validate(scan);
    const RayComparison c = compare_rays(dexelize(map, l, {.threads = threads}), scan, 1e-4);
    total.rays += c.rays, total.mismatches += c.mismatches, total.intervals += c.intervals;
  }
  INFO("rays ", total.rays, " intervals ", total.intervals, " mismatches ", total.mismatches);
  CHECK(total.intervals > 5000);
  CHECK(total.mismatches == 0);
  CHECK(fine_cells > 200);
}
