// The fast paths after Step 1 against their plain forms: the scan's inline 128-bit conversion
// against the compiler's, Steps 2–3 fused on threads against the scan's Booleans, check_mesh on
// threads against a map of edges, and write_stl on threads against one thread and the records
// by hand.
#include <doctest/doctest.h>

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>
#include <map>
#include <random>
#include <sstream>
#include <utility>

#include "tridex/mill.hpp"
#include "tridex/scan_dexelize.hpp"
#include "tridex/stl.hpp"

using namespace tridex;

namespace test_tail_paths {

__extension__ using Wide = __int128;
__extension__ using UnsignedWide = unsigned __int128;

bool same_double(double a, double b) {
  return std::bit_cast<std::uint64_t>(a) == std::bit_cast<std::uint64_t>(b);
}

TEST_CASE("wide_to_double rounds as the compiler's conversion, bit for bit") {
  std::vector<Wide> values = {0, 1, -1};
  const Wide lowest = static_cast<Wide>(UnsignedWide{1} << 127);
  values.insert(values.end(), {lowest, lowest + 1, ~lowest, ~lowest - 1});
  for (int k = 0; k < 127; ++k)
    for (int d = -3; d <= 3; ++d) {
      const Wide p = static_cast<Wide>(UnsignedWide{1} << k);
      values.push_back(p + d), values.push_back(-p + d);
    }
  // Ties and near-ties: 54 or more significant bits, the bit below the 53rd set, with and
  // without bits below it, the 53rd bit odd and even.
  for (int k = 53; k < 126; ++k)
    for (int e = 0; e + k < 127; e += 7)
      for (UnsignedWide low : {UnsignedWide{1}, UnsignedWide{3}}) {
        const auto tie = static_cast<Wide>(((UnsignedWide{1} << k) | (low << (k - 53))) << e);
        for (Wide v : {tie, tie + 1, tie - 1}) values.push_back(v), values.push_back(-v);
      }
  std::mt19937_64 rng(37);
  for (int k = 0; k < 200000; ++k) {
    const auto x = static_cast<Wide>((UnsignedWide{rng()} << 64) | rng());
    values.push_back(x >> (rng() % 128));
  }
  std::size_t wrong = 0;
  for (Wide x : values)
    if (!same_double(detail::wide_to_double(x), static_cast<double>(x))) ++wrong;
  CHECK(values.size() > 200000);
  CHECK(wrong == 0);
}

// A box's Z-map in `frame` milled by a few random moves, some through the stock.
ZMap milled_map(std::mt19937& rng, const Aabb& stock, const Frame& frame, double cell) {
  std::uniform_real_distribution<double> unit(0, 1);
  ZMap map = ZMap::from_box(frame, stock, cell);
  const Aabb local = local_bounds(frame, stock);
  const std::vector<Cutter> cutters{Cutter::ball(0.8), Cutter::flat(0.5)};
  std::vector<CutMove> moves;
  for (int k = 0; k < 6; ++k) {
    auto tip = [&] {
      return Vec3(local.min.x + unit(rng) * local.size().x,
                  local.min.y + unit(rng) * local.size().y,
                  local.max.z - (k == 5 ? 1.2 : 0.6) * unit(rng) * local.size().z);
    };
    moves.push_back({Segment{tip(), tip()}, static_cast<std::uint32_t>(k % 2)});
  }
  mill(map, cutters, moves);
  return map;
}

// Rays whose intervals differ in number or by more than `epsilon` at an end.
std::size_t mismatched_rays(const TripleDexel& a, const TripleDexel& b, double epsilon) {
  std::size_t mismatches = 0;
  for (int k = 0; k < 3; ++k)
    for (std::size_t r = 0; r < a.grids[k].ray_count(); ++r) {
      auto x = a.grids[k].ray(r), y = b.grids[k].ray(r);
      bool same = x.size() == y.size();
      for (std::size_t i = 0; same && i < x.size(); ++i)
        same = std::abs(double(x[i].enter) - y[i].enter) <= epsilon &&
               std::abs(double(x[i].exit) - y[i].exit) <= epsilon;
      mismatches += !same;
    }
  return mismatches;
}

bool same_grids(const TripleDexel& a, const TripleDexel& b) {
  for (int k = 0; k < 3; ++k) {
    if (a.grids[k].offsets != b.grids[k].offsets) return false;
    const auto &x = a.grids[k].intervals, &y = b.grids[k].intervals;
    if (x.size() != y.size()) return false;
    for (std::size_t i = 0; i < x.size(); ++i)
      if (x[i].enter != y[i].enter || x[i].exit != y[i].exit) return false;
  }
  return true;
}

TEST_CASE("scan machine: fused on 1, 2 and 8 threads equals the scanned maps' Booleans") {
  // Over 4096 rays a family, so that the crossings are filed into several chunks of rays and
  // the grids concatenated from several parts; a tilted map and a quarter-turned one, whose
  // walls and steps project to long thin triangles (the narrowed lines).
  std::mt19937 rng(4096);
  const Aabb stock{Vec3(0, 0, 0), Vec3(9, 7, 4)};
  std::vector<ZMap> maps;
  maps.push_back(milled_map(rng, stock, Frame{}, 0.05));
  maps.push_back(milled_map(rng, stock, Frame::from_axis(Vec3(0.94, 0.1, 0.34)), 0.06));
  maps.push_back(milled_map(rng, stock, Frame::from_axis(Vec3(0, -1, 0)), 0.05));
  const DexelLattice lattice = DexelLattice::covering(stock, 0.06);
  REQUIRE(lattice.n.x * lattice.n.z > 2 * 4096);
  const TripleDexel w0 = TripleDexel::box(lattice, stock);
  TripleDexel booleans = w0;
  for (const ZMap& map : maps) booleans = intersect(booleans, scan_dexelize(map, lattice, 1));
  const TripleDexel one = scan_intersect_milled(w0, maps, 1);
  validate(one);
  CHECK(same_grids(one, booleans));
  CHECK(same_grids(scan_intersect_milled(w0, maps, 2), one));
  CHECK(same_grids(scan_intersect_milled(w0, maps, 8), one));
  // The tilted map's walls are the narrowed lines' case: ray by ray as the grid tree finds it.
  const TripleDexel tilted = scan_dexelize(maps[1], lattice, 8);
  CHECK(same_grids(tilted, scan_dexelize(maps[1], lattice, 1)));
  CHECK(mismatched_rays(tilted, dexelize(maps[1], lattice, {.threads = 2}), 1e-4) == 0);
  // Something was cut, and the grid tree's machine agrees on the solid.
  CHECK(volume(one) < 0.95 * volume(w0));
  CHECK(volume(one) == doctest::Approx(volume(intersect_milled(w0, maps, 2))).epsilon(1e-4));
}

// check_mesh's counts from a map of undirected edges.
MeshCheck reference_check(const Mesh& mesh) {
  std::map<std::pair<std::uint32_t, std::uint32_t>, std::pair<int, int>> uses;  // all, forward
  for (const glm::uvec3& t : mesh.triangles)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a == b) continue;
      auto& u = uses[{std::min(a, b), std::max(a, b)}];
      ++u.first, u.second += a < b;
    }
  MeshCheck c;
  for (const auto& [edge, u] : uses) {
    if (u.first == 1)
      ++c.boundary_edges;
    else if (u.first > 2)
      ++c.non_manifold_edges;
    else if (u.second != 1)
      ++c.misoriented_edges;
  }
  for (const glm::uvec3& t : mesh.triangles)
    if (detail::is_degenerate(mesh, t)) ++c.degenerate_triangles;
  return c;
}

// A wavy height field of side × side vertices, numbered at random, with every kind of defect.
Mesh defective_sheet(std::mt19937& rng, int side) {
  Mesh mesh;
  std::vector<std::uint32_t> number(static_cast<std::size_t>(side * side));
  for (std::uint32_t k = 0; k < number.size(); ++k) number[k] = k;
  std::shuffle(number.begin(), number.end(), rng);
  mesh.positions.resize(number.size());
  for (int j = 0; j < side; ++j)
    for (int i = 0; i < side; ++i)
      mesh.positions[number[static_cast<std::size_t>(i + side * j)]] =
          glm::vec3(float(i), float(j), std::sin(0.1f * float(i)) * std::cos(0.07f * float(j)));
  auto at = [&](int i, int j) { return number[static_cast<std::size_t>(i + side * j)]; };
  std::uniform_int_distribution<int> pick(0, 199);
  for (int j = 0; j + 1 < side; ++j)
    for (int i = 0; i + 1 < side; ++i) {
      glm::uvec3 t1(at(i, j), at(i + 1, j), at(i + 1, j + 1)),
          t2(at(i, j), at(i + 1, j + 1), at(i, j + 1));
      switch (pick(rng)) {
        case 0:
          continue;  // a hole
        case 1:
          std::swap(t1.y, t1.z);
          break;  // flipped
        case 2:
          mesh.triangles.push_back(t1);
          break;  // doubled
        case 3:
          t2.z = t2.x;
          break;  // a repeated vertex
        default:
          break;
      }
      mesh.triangles.push_back(t1), mesh.triangles.push_back(t2);
    }
  return mesh;
}

TEST_CASE("check_mesh on 1, 2 and 8 threads counts as a map of edges does") {
  // Over 65,536 triangles and 4,096 vertices: several chunks of triangles and ranges of vertices.
  std::mt19937 rng(65536);
  const Mesh mesh = defective_sheet(rng, 260);
  REQUIRE(mesh.triangles.size() > 2 * 65536);
  const MeshCheck expected = reference_check(mesh);
  CHECK(expected.boundary_edges > 1000);
  CHECK(expected.non_manifold_edges > 100);
  CHECK(expected.misoriented_edges > 100);
  CHECK(expected.degenerate_triangles > 100);
  for (unsigned threads : {1u, 2u, 8u}) {
    const MeshCheck c = check_mesh(mesh, threads);
    INFO("threads ", threads);
    CHECK(c.boundary_edges == expected.boundary_edges);
    CHECK(c.non_manifold_edges == expected.non_manifold_edges);
    CHECK(c.misoriented_edges == expected.misoriented_edges);
    CHECK(c.degenerate_triangles == expected.degenerate_triangles);
  }
  CHECK(check_mesh(Mesh{}, 2).closed());
}

TEST_CASE("write_stl on 2, 3 and 8 threads writes one thread's bytes; the records by hand") {
  // Seven batches of 32,768 triangles: several groups on 2 and 3 threads, one on 8.
  std::mt19937 rng(50);
  const Mesh mesh = defective_sheet(rng, 330);
  REQUIRE(mesh.triangles.size() > 6 * 32768);
  REQUIRE(mesh.triangles.size() < 7 * 32768);
  std::ostringstream one;
  write_stl(one, mesh, 1);
  const std::string bytes = one.str();
  REQUIRE(bytes.size() == 84 + 50 * mesh.triangles.size());
  for (unsigned threads : {2u, 3u, 8u}) {
    std::ostringstream out;
    write_stl(out, mesh, threads);
    INFO("threads ", threads);
    CHECK(out.str() == bytes);
  }
  // Three records by hand: the normal from the vertex order, then the corners, then two zeros.
  for (std::size_t k : {std::size_t{0}, std::size_t{32768}, mesh.triangles.size() - 1}) {
    const glm::uvec3& t = mesh.triangles[k];
    const glm::vec3 &a = mesh.positions[t.x], &b = mesh.positions[t.y], &c = mesh.positions[t.z];
    const Vec3 n = glm::cross(Vec3(b) - Vec3(a), Vec3(c) - Vec3(a));
    const double length = glm::length(n);
    const glm::vec3 values[4] = {glm::vec3(length > 0 ? n / length : Vec3(0)), a, b, c};
    float stored[12];
    std::memcpy(stored, bytes.data() + 84 + 50 * k, sizeof stored);  // little-endian host
    bool same = bytes[84 + 50 * k + 48] == 0 && bytes[84 + 50 * k + 49] == 0;
    for (int v = 0; v < 4; ++v)
      for (int e = 0; e < 3; ++e) same = same && stored[3 * v + e] == values[v][e];
    CHECK(same);
  }
}

}  // namespace test_tail_paths
