#include <doctest/doctest.h>

#include <random>

#include "helpers.hpp"
#include "tridex/backends/backends.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/intersect_milled.hpp"

using namespace tridex;
using namespace backend_tests;
namespace be = tridex::backends;

TEST_CASE("backend names round-trip and unknown names list the valid ones") {
  for (be::ZMapBackend b : {be::ZMapBackend::cpu, be::ZMapBackend::gl})
    CHECK(be::parse_zmap_backend(be::to_string(b)) == b);
  for (be::DexelBackend b :
       {be::DexelBackend::tree, be::DexelBackend::embree, be::DexelBackend::scan})
    CHECK(be::parse_dexel_backend(be::to_string(b)) == b);
  CHECK_THROWS_WITH_AS(be::parse_zmap_backend("vulkan"),
                       "unknown Z-map backend 'vulkan' (valid: cpu, gl)", Error);
  CHECK_THROWS_WITH_AS(be::parse_dexel_backend("Tree"),
                       "unknown dexel backend 'Tree' (valid: tree, embree, scan)", Error);
  CHECK(be::available(be::default_zmap_backend));
  CHECK(be::available(be::default_dexel_backend));
}

TEST_CASE("every dexel backend computes the same machining result through machine_with") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb stock{Vec3(0, 0, 0), Vec3(3, 2, 1.5)};
  std::vector<ZMap> maps;
  for (int m = 0; m < 4; ++m)
    maps.push_back(random_milled_map(rng, stock, random_frame(rng, m > 0), 0.07, 10));
  DexelLattice l = DexelLattice::covering(stock, 0.06);
  l.origin += Vec3(0.011, 0.007, 0.013);
  TripleDexel w0 = TripleDexel::box(l, stock);
  TripleDexel tree = be::machine_with(be::DexelBackend::tree, w0, maps, 2);
  CHECK(compare_rays(tree, intersect_milled(w0, maps, 1), 0).mismatches == 0);
  for (be::DexelBackend b : {be::DexelBackend::embree, be::DexelBackend::scan}) {
    TripleDexel other = be::machine_with(b, w0, maps, 2);
    RayComparison c = compare_rays(tree, other, 2e-4);
    INFO(be::to_string(b), ": mismatches ", c.mismatches, " of ", c.rays, ", worst ", c.worst);
    CHECK(c.mismatches * 10000 <= c.rays);
    CHECK(volume(other) == doctest::Approx(volume(tree)).epsilon(1e-4));
  }
}

TEST_CASE("mill_with cpu is the kernel's mill") {
  std::mt19937 rng(12);
  const Aabb stock{Vec3(0, 0, 0), Vec3(3, 2, 1.5)};
  ZMap a = random_milled_map(rng, stock, Frame{}, 0.05, 0);
  ZMap b = a;
  std::vector<Cutter> cutters{Cutter::ball(0.3)};
  std::vector<CutMove> moves{{Segment{Vec3(0.5, 0.5, 1.2), Vec3(2.5, 1.5, 1.0)}, 0}};
  be::mill_with(be::ZMapBackend::cpu, a, cutters, moves, 2);
  mill(b, cutters, moves, {.threads = 1});
  CHECK(a.heights == b.heights);
}
