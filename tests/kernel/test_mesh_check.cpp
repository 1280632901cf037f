#include <doctest/doctest.h>

#include <algorithm>
#include <map>
#include <random>
#include <set>

#include "test_dexel_shapes.hpp"
#include "tridex/mesh_check.hpp"

using namespace tridex;
using namespace tridex_test;

namespace {

// The same solid with vertices renumbered and each triangle's corners rotated: nothing about
// closedness may depend on the numbering.
Mesh shuffled(const Mesh& m, std::mt19937& rng) {
  std::vector<std::uint32_t> perm(m.positions.size());
  for (std::uint32_t i = 0; i < perm.size(); ++i) perm[i] = i;
  std::shuffle(perm.begin(), perm.end(), rng);
  Mesh out;
  out.positions.resize(m.positions.size());
  for (std::size_t i = 0; i < perm.size(); ++i) out.positions[perm[i]] = m.positions[i];
  for (const glm::uvec3& t : m.triangles) {
    glm::uvec3 r(perm[t.x], perm[t.y], perm[t.z]);
    for (int k = std::uniform_int_distribution<int>(0, 2)(rng); k > 0; --k)
      r = glm::uvec3(r.y, r.z, r.x);
    out.triangles.push_back(r);
  }
  std::shuffle(out.triangles.begin(), out.triangles.end(), rng);
  return out;
}

// Unshared corners, as STL stores them.
Mesh triangle_soup(const Mesh& m) {
  Mesh out;
  for (const glm::uvec3& t : m.triangles) {
    auto base = static_cast<std::uint32_t>(out.positions.size());
    out.positions.push_back(m.positions[t.x]);
    out.positions.push_back(m.positions[t.y]);
    out.positions.push_back(m.positions[t.z]);
    out.triangles.emplace_back(base, base + 1, base + 2);
  }
  return out;
}

std::vector<Mesh> closed_shapes() {
  return {box_mesh(Vec3(-1, 0, 2), Vec3(3, 1.5, 4)), sphere_mesh(Vec3(1, 2, 3), 2.5, 17, 9),
          cylinder_mesh(Vec3(0), 1, 3, 23), torus_mesh(Vec3(0, 0, 1), 3, 1, 19, 11)};
}

}  // namespace

TEST_CASE("check_mesh: the test solids are closed, non-degenerate and outward") {
  std::mt19937 rng(7);
  for (const Mesh& m : closed_shapes()) {
    MeshCheck c = check_mesh(shuffled(m, rng));
    CHECK(c.closed());
    CHECK(c.boundary_edges == 0);
    CHECK(c.non_manifold_edges == 0);
    CHECK(c.misoriented_edges == 0);
    CHECK(c.degenerate_triangles == 0);
    CHECK(m.signed_volume() > 0);
  }
  CHECK(check_mesh(Mesh{}).closed());
}

TEST_CASE("check_mesh: removing triangles opens exactly their unshared edges") {
  std::mt19937 rng(11);
  for (const Mesh& solid : closed_shapes()) {
    for (int trial = 0; trial < 10; ++trial) {
      Mesh m = shuffled(solid, rng);
      // Remove a random subset; an edge becomes boundary iff exactly one of its two triangles went.
      std::vector<bool> removed(m.triangles.size());
      for (std::size_t k = 0; k < removed.size(); ++k)
        removed[k] = std::uniform_int_distribution<int>(0, 9)(rng) == 0;
      std::map<std::pair<std::uint32_t, std::uint32_t>, int> kept_uses;
      Mesh opened;
      opened.positions = m.positions;
      for (std::size_t k = 0; k < m.triangles.size(); ++k) {
        const glm::uvec3& t = m.triangles[k];
        for (int e = 0; e < 3; ++e) {
          std::uint32_t a = t[e], b = t[(e + 1) % 3];
          kept_uses[{std::min(a, b), std::max(a, b)}] += removed[k] ? 0 : 1;
        }
        if (!removed[k]) opened.triangles.push_back(t);
      }
      std::size_t expected = 0;
      for (auto& [edge, uses] : kept_uses) expected += uses == 1 ? 1 : 0;
      MeshCheck c = check_mesh(opened);
      CHECK(c.boundary_edges == expected);
      CHECK(c.non_manifold_edges == 0);
      CHECK(c.misoriented_edges == 0);
      CHECK(c.closed() == (expected == 0));
    }
  }
}

TEST_CASE("check_mesh: flipped triangles make their edges misoriented") {
  std::mt19937 rng(5);
  for (const Mesh& solid : closed_shapes()) {
    Mesh m = shuffled(solid, rng);
    // Flip an independent set of triangles (no two share an edge): each flips 3 edges.
    std::set<std::pair<std::uint32_t, std::uint32_t>> touched;
    std::size_t flipped = 0;
    for (glm::uvec3& t : m.triangles) {
      if (std::uniform_int_distribution<int>(0, 4)(rng) != 0) continue;
      bool free = true;
      for (int e = 0; e < 3; ++e)
        free = free &&
               !touched.count({std::min(t[e], t[(e + 1) % 3]), std::max(t[e], t[(e + 1) % 3])});
      if (!free) continue;
      for (int e = 0; e < 3; ++e)
        touched.insert({std::min(t[e], t[(e + 1) % 3]), std::max(t[e], t[(e + 1) % 3])});
      std::swap(t.y, t.z);
      ++flipped;
    }
    REQUIRE(flipped > 0);
    MeshCheck c = check_mesh(m);
    CHECK(c.misoriented_edges == 3 * flipped);
    CHECK(c.boundary_edges == 0);
    CHECK(!c.closed());
  }
}

TEST_CASE("check_mesh: a duplicated triangle is non-manifold, a repeated vertex degenerate") {
  Mesh m = box_mesh(Vec3(0), Vec3(1));
  m.triangles.push_back(m.triangles[0]);
  MeshCheck c = check_mesh(m);
  CHECK(c.non_manifold_edges == 3);
  CHECK(!c.closed());

  Mesh d = box_mesh(Vec3(0), Vec3(1));
  d.triangles.emplace_back(0u, 0u, 1u);
  d.positions.emplace_back(0.5f, 0.0f, 0.0f);  // collinear with vertices 0 and 1
  d.triangles.emplace_back(0u, 1u, static_cast<std::uint32_t>(d.positions.size() - 1));
  CHECK(check_mesh(d).degenerate_triangles == 2);
}

TEST_CASE("check_mesh: an index past the vertices is an error") {
  Mesh m = box_mesh(Vec3(0), Vec3(1));
  m.triangles.emplace_back(0u, 1u, 8u);
  CHECK_THROWS_AS(check_mesh(m), Error);
  CHECK_THROWS_AS(weld_vertices(m), Error);
}

TEST_CASE("weld_vertices: a triangle soup welds back to the closed solid") {
  std::mt19937 rng(3);
  for (const Mesh& solid : closed_shapes()) {
    Mesh soup = triangle_soup(shuffled(solid, rng));
    CHECK(check_mesh(soup).boundary_edges == 3 * soup.triangles.size());
    Mesh welded = weld_vertices(soup);
    CHECK(welded.positions.size() == solid.positions.size());
    CHECK(welded.triangles.size() == solid.triangles.size());
    CHECK(check_mesh(welded).closed());
    CHECK(welded.signed_volume() == doctest::Approx(solid.signed_volume()).epsilon(1e-9));
  }
  // +0 and -0 are one position.
  Mesh signs;
  signs.positions = {{0.0f, 1.0f, 2.0f}, {-0.0f, 1.0f, 2.0f}};
  CHECK(weld_vertices(signs).positions.size() == 1);
}

namespace {

// check_mesh's edge counts the plain way: every directed edge with its undirected key, all
// sorted, each key classified by how many uses it has and in which directions.
MeshCheck sorted_edges_reference(const Mesh& m) {
  std::vector<std::pair<std::pair<std::uint32_t, std::uint32_t>, bool>> edges;
  for (const glm::uvec3& t : m.triangles)
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = t[e], b = t[(e + 1) % 3];
      if (a != b) edges.push_back({{std::min(a, b), std::max(a, b)}, a < b});
    }
  std::sort(edges.begin(), edges.end());
  MeshCheck c;
  for (std::size_t i = 0; i < edges.size();) {
    std::size_t j = i, forward = 0;
    for (; j < edges.size() && edges[j].first == edges[i].first; ++j)
      forward += edges[j].second ? 1 : 0;
    if (j - i == 1)
      ++c.boundary_edges;
    else if (j - i > 2)
      ++c.non_manifold_edges;
    else if (forward != 1)
      ++c.misoriented_edges;
    i = j;
  }
  return c;
}

}  // namespace

TEST_CASE(
    "check_mesh: random triangle sets (repeated, collapsed, both ways) counted as by sorting all "
    "edges") {
  std::mt19937 rng(23);
  for (int trial = 0; trial < 200; ++trial) {
    // Few vertices for many triangles: edges used once, twice either way, and three or more times.
    const auto vertices = std::uniform_int_distribution<std::uint32_t>(1, 12)(rng);
    Mesh m;
    for (std::uint32_t v = 0; v < vertices; ++v)
      m.positions.emplace_back(std::uniform_real_distribution<float>(-1, 1)(rng),
                               std::uniform_real_distribution<float>(-1, 1)(rng),
                               std::uniform_real_distribution<float>(-1, 1)(rng));
    std::uniform_int_distribution<std::uint32_t> pick(0, vertices - 1);
    const int triangles = std::uniform_int_distribution<int>(0, 40)(rng);
    for (int k = 0; k < triangles; ++k) m.triangles.emplace_back(pick(rng), pick(rng), pick(rng));
    const MeshCheck got = check_mesh(m), want = sorted_edges_reference(m);
    CHECK(got.boundary_edges == want.boundary_edges);
    CHECK(got.non_manifold_edges == want.non_manifold_edges);
    CHECK(got.misoriented_edges == want.misoriented_edges);
  }
  // A closed solid's check agrees too, and so does the same solid opened and flipped at random.
  for (const Mesh& solid : closed_shapes()) {
    Mesh m = shuffled(solid, rng);
    for (glm::uvec3& t : m.triangles)
      if (std::uniform_int_distribution<int>(0, 6)(rng) == 0) std::swap(t.y, t.z);
    m.triangles.resize(m.triangles.size() - m.triangles.size() / 5);
    const MeshCheck got = check_mesh(m), want = sorted_edges_reference(m);
    CHECK(got.boundary_edges == want.boundary_edges);
    CHECK(got.misoriented_edges == want.misoriented_edges);
    CHECK(got.non_manifold_edges == want.non_manifold_edges);
  }
}
