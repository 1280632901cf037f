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
#include <memory>
#include <unordered_map>
#include <vector>

#include <glm/glm.hpp>

#include "tridex/error.hpp"
#include "tridex/mesh.hpp"
#include "tridex/parallel.hpp"

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

namespace detail {

// Classifies the edges of one vertex v: [lo, hi) holds (max(a, b) << 1) | (a < b) for each of
// its directed edges a→b with min(a, b) = v, and is sorted here.
inline void classify_vertex_edges(std::uint64_t* lo, std::uint64_t* hi, MeshCheck& result) {
  std::sort(lo, hi);
  for (std::uint64_t* i = lo; i != hi;) {
    std::uint64_t* j = i;
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

// Calls visit(a, b) for each directed edge a→b of triangles [first, last) whose ends differ (a
// collapsed edge joins nothing).
template <class Visit>
void for_each_mesh_edge(const Mesh& mesh, std::size_t first, std::size_t last, Visit&& visit) {
  for (std::size_t k = first; k < last; ++k) {
    const glm::uvec3& t = mesh.triangles[k];
    const std::uint32_t v[3] = {t.x, t.y, t.z};
    for (int e = 0; e < 3; ++e) {
      const std::uint32_t a = v[e], b = v[(e + 1) % 3];
      if (a != b) visit(a, b);
    }
  }
}

}  // namespace detail

// Counts the edge defects of `mesh` on `threads` threads (1 unless asked; 0: every hardware
// thread; the counts do not depend on it). Throws tridex::Error if a triangle names a missing
// vertex.
//
// Each directed edge a→b is filed under its lower vertex min(a, b): vertices are cut into
// ranges, the triangles into chunks; each chunk counts its edges per range and then places them
// (a counting sort over the ranges, chunks on the threads), and each range files its edges by
// vertex (a counting sort over the range's vertices, small enough to stay in cache) and
// classifies each vertex's few edges, ranges on the threads. Sorting all 3·T edges at once took
// most of the check on a surface of millions of triangles, and one pass over them all ran on one
// thread.
inline MeshCheck check_mesh(const Mesh& mesh, unsigned threads = 1) {
  detail::require_valid_indices(mesh, "check_mesh");
  const std::size_t n = mesh.positions.size(), triangles = mesh.triangles.size();
  constexpr std::size_t kTriangleChunk = std::size_t{1} << 16;
  const std::size_t chunks = (triangles + kTriangleChunk - 1) / kTriangleChunk;
  // Ranges of 2^range_bits vertices, at most about 256 of them.
  int range_bits = 12;
  while ((n >> range_bits) > 256) ++range_bits;
  const std::size_t ranges = (n >> range_bits) + 1;
  auto range_of = [&](std::uint32_t a, std::uint32_t b) { return std::min(a, b) >> range_bits; };
  // at[c · ranges + g]: where chunk c's edges of range g go (first their counts).
  std::vector<std::size_t> at(chunks * ranges + 1, 0);
  std::vector<std::size_t> degenerate(chunks, 0);
  detail::for_each_chunk(chunks, threads, [&](std::size_t c) {
    const std::size_t first = c * kTriangleChunk,
                      last = std::min(triangles, first + kTriangleChunk);
    std::size_t* count = at.data() + c * ranges;
    detail::for_each_mesh_edge(mesh, first, last,
                               [&](std::uint32_t a, std::uint32_t b) { ++count[range_of(a, b)]; });
    for (std::size_t k = first; k < last; ++k)
      if (detail::is_degenerate(mesh, mesh.triangles[k])) ++degenerate[c];
  });
  // Range-major order: range g's edges are contiguous, chunk by chunk.
  std::vector<std::size_t> range_start(ranges + 1, 0);
  {
    std::size_t sum = 0;
    for (std::size_t g = 0; g < ranges; ++g) {
      range_start[g] = sum;
      for (std::size_t c = 0; c < chunks; ++c) {
        const std::size_t count = at[c * ranges + g];
        at[c * ranges + g] = sum;
        sum += count;
      }
    }
    range_start[ranges] = sum;
  }
  // Directed edges (a << 32) | b. Left uninitialised (new[] of a trivial type), so that each
  // page is first touched, and zeroed by the kernel, by the worker that fills it: a vector's
  // value-initialisation zeroed all 24 bytes a triangle on the calling thread alone, 0.2-0.4 s on
  // model-D's surface of 8 M triangles (bench/README.md, issue 37).
  const std::unique_ptr<std::uint64_t[]> edges(new std::uint64_t[range_start[ranges]]);
  detail::for_each_chunk(chunks, threads, [&](std::size_t c) {
    const std::size_t first = c * kTriangleChunk,
                      last = std::min(triangles, first + kTriangleChunk);
    std::size_t* fill = at.data() + c * ranges;
    detail::for_each_mesh_edge(mesh, first, last, [&](std::uint32_t a, std::uint32_t b) {
      edges[fill[range_of(a, b)]++] = (std::uint64_t{a} << 32) | b;
    });
  });
  std::vector<MeshCheck> part(ranges);
  detail::for_each_chunk(ranges, threads, [&](std::size_t g) {
    const std::size_t v0 = g << range_bits, v1 = std::min(n, (g + 1) << range_bits);
    if (v0 >= v1) return;
    const std::uint64_t* lo = edges.get() + range_start[g];
    const std::uint64_t* hi = edges.get() + range_start[g + 1];
    thread_local std::vector<std::size_t> first;
    thread_local std::vector<std::uint64_t> keys;
    first.assign(v1 - v0 + 1, 0);
    for (const std::uint64_t* e = lo; e != hi; ++e) {
      const auto a = static_cast<std::uint32_t>(*e >> 32), b = static_cast<std::uint32_t>(*e);
      ++first[std::min(a, b) - v0 + 1];
    }
    for (std::size_t v = 0; v < v1 - v0; ++v) first[v + 1] += first[v];
    keys.resize(first[v1 - v0]);
    for (const std::uint64_t* e = lo; e != hi; ++e) {
      const auto a = static_cast<std::uint32_t>(*e >> 32), b = static_cast<std::uint32_t>(*e);
      keys[first[std::min(a, b) - v0]++] = (std::uint64_t{std::max(a, b)} << 1) | (a < b ? 1u : 0u);
    }
    // `first` now holds each vertex's end.
    for (std::size_t v = 0; v < v1 - v0; ++v)
      detail::classify_vertex_edges(keys.data() + (v ? first[v - 1] : 0), keys.data() + first[v],
                                    part[g]);
  });
  MeshCheck result;
  for (const MeshCheck& p : part) {
    result.boundary_edges += p.boundary_edges;
    result.non_manifold_edges += p.non_manifold_edges;
    result.misoriented_edges += p.misoriented_edges;
  }
  for (std::size_t d : degenerate) result.degenerate_triangles += d;
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
