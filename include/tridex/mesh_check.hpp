// tridex — watertightness and orientation checks for indexed triangle meshes.
//
// A closed (watertight, consistently oriented, 2-manifold along its edges) mesh uses every
// undirected edge {a, b} exactly twice: once as a→b and once as b→a. The check groups the 3·T
// directed edges by their undirected key and classifies each key by how it is used. Vertices are
// identified by index: a mesh read from STL repeats positions per triangle and must be welded
// first (weld_vertices).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "tridex/error.hpp"
#include "tridex/mesh.hpp"

namespace tridex {

struct MeshCheck {
  std::size_t boundary_edges = 0;        // undirected edges used by one triangle only
  std::size_t non_manifold_edges = 0;    // undirected edges used by three or more triangles
  std::size_t misoriented_edges = 0;     // edges used twice in the same direction
  std::size_t degenerate_triangles = 0;  // repeated vertex, or (near-)zero area

  // Every edge shared by exactly two triangles with opposite orientation. Degenerate triangles
  // are counted separately: they do not open a mesh, but most consumers reject them too.
  bool closed() const {
    return boundary_edges == 0 && non_manifold_edges == 0 && misoriented_edges == 0;
  }
};

namespace detail {

// A triangle is degenerate when its doubled area is below this fraction of its longest edge
// squared: a sliver whose normal is dominated by float rounding of its vertices.
constexpr double kDegenerateRatio = 1e-12;

inline bool is_degenerate(const Mesh& mesh, const glm::uvec3& t) {
  if (t.x == t.y || t.y == t.z || t.z == t.x) return true;
  Vec3 a(mesh.positions[t.x]), b(mesh.positions[t.y]), c(mesh.positions[t.z]);
  double longest =
      std::max({glm::dot(b - a, b - a), glm::dot(c - b, c - b), glm::dot(a - c, a - c)});
  double doubled_area = glm::length(glm::cross(b - a, c - a));
  return !(doubled_area > kDegenerateRatio * longest);
}

inline void require_valid_indices(const Mesh& mesh, const char* who) {
  const std::size_t n = mesh.positions.size();
  for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
    const glm::uvec3& t = mesh.triangles[k];
    if (t.x >= n || t.y >= n || t.z >= n)
      fail(who, ": triangle ", k, " refers to vertex ", std::max({t.x, t.y, t.z}),
           " but the mesh has ", n, " vertices");
  }
}

}  // namespace detail

// Counts the edge defects of `mesh`. Throws tridex::Error if a triangle names a missing vertex.
inline MeshCheck check_mesh(const Mesh& mesh) {
  detail::require_valid_indices(mesh, "check_mesh");
  MeshCheck result;
  // Each directed edge a→b is filed under its lower vertex min(a, b), as (max(a, b) << 1) | (a <
  // b): a counting sort (count, prefix sums, place) in two linear passes, where sorting all 3·T
  // edges took most of the check on a surface of millions of triangles. A vertex has a handful
  // of edges, so each vertex's few entries are then sorted and classified in place.
  const std::size_t n = mesh.positions.size();
  std::vector<std::size_t> first(n + 1, 0);  // vertex v's entries: [first[v], first[v + 1])
  auto for_each_edge = [&](auto&& visit) {
    for (const glm::uvec3& t : mesh.triangles) {
      const std::uint32_t v[3] = {t.x, t.y, t.z};
      for (int e = 0; e < 3; ++e) {
        const std::uint32_t a = v[e], b = v[(e + 1) % 3];
        if (a != b) visit(a, b);  // a collapsed edge joins nothing
      }
    }
  };
  for_each_edge(
      [&](std::uint32_t a, std::uint32_t b) { ++first[std::min(a, b) + std::size_t{1}]; });
  for (std::size_t v = 0; v < n; ++v) first[v + 1] += first[v];
  std::vector<std::uint64_t> entries(first[n]);
  {
    std::vector<std::size_t> at(first.begin(), first.end() - 1);
    for_each_edge([&](std::uint32_t a, std::uint32_t b) {
      entries[at[std::min(a, b)]++] = (std::uint64_t{std::max(a, b)} << 1) | (a < b ? 1u : 0u);
    });
  }
  for (std::size_t v = 0; v < n; ++v) {
    const auto lo = entries.begin() + static_cast<std::ptrdiff_t>(first[v]);
    const auto hi = entries.begin() + static_cast<std::ptrdiff_t>(first[v + 1]);
    std::sort(lo, hi);
    for (auto i = lo; i != hi;) {
      auto j = i;
      std::size_t forward = 0;
      for (; j != hi && (*j >> 1) == (*i >> 1); ++j) forward += *j & 1;
      const auto uses = j - i;
      if (uses == 1)
        ++result.boundary_edges;
      else if (uses > 2)
        ++result.non_manifold_edges;
      else if (forward != 1)
        ++result.misoriented_edges;
      i = j;
    }
  }
  for (const glm::uvec3& t : mesh.triangles)
    if (detail::is_degenerate(mesh, t)) ++result.degenerate_triangles;
  return result;
}

// Merges vertices with bit-identical positions (+0 and −0 taken as equal), keeping the first
// occurrence's order, and remaps the triangles. STL stores each triangle's corners separately;
// a mesh written from shared vertices comes back with its sharing intact.
inline Mesh weld_vertices(const Mesh& mesh) {
  detail::require_valid_indices(mesh, "weld_vertices");
  struct KeyHash {
    std::size_t operator()(const glm::uvec3& k) const {
      std::uint64_t h = k.x * 0x9E3779B97F4A7C15ull;
      h ^= (h >> 29) + k.y * 0xBF58476D1CE4E5B9ull;
      h ^= (h >> 31) + k.z * 0x94D049BB133111EBull;
      return static_cast<std::size_t>(h ^ (h >> 32));
    }
  };
  auto key_of = [](const glm::vec3& p) {
    auto bits = [](float f) { return std::bit_cast<std::uint32_t>(f == 0.0f ? 0.0f : f); };
    return glm::uvec3(bits(p.x), bits(p.y), bits(p.z));
  };
  Mesh out;
  std::unordered_map<glm::uvec3, std::uint32_t, KeyHash> index;
  index.reserve(mesh.positions.size());
  std::vector<std::uint32_t> remap(mesh.positions.size());
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    auto [it, inserted] = index.try_emplace(key_of(mesh.positions[v]),
                                            static_cast<std::uint32_t>(out.positions.size()));
    if (inserted) out.positions.push_back(mesh.positions[v]);
    remap[v] = it->second;
  }
  out.triangles.reserve(mesh.triangles.size());
  for (const glm::uvec3& t : mesh.triangles)
    out.triangles.emplace_back(remap[t.x], remap[t.y], remap[t.z]);
  return out;
}

}  // namespace tridex
