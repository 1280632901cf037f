// Closed test meshes with shared vertices, counter-clockwise from outside: box, UV sphere,
// capped cylinder, torus. Shared by the mesh-check, dexel, STL and machine tests.
#pragma once

#include <cmath>
#include <cstdint>
#include <numbers>
#include <algorithm>
#include <random>
#include <vector>

#include "tridex/mesh.hpp"
#include <glm/glm.hpp>

namespace tridex_test {

using tridex::Mesh;
using tridex::Vec3;

inline std::uint32_t add_vertex(Mesh& m, const Vec3& p) {
  m.positions.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y),
                           static_cast<float>(p.z));
  return static_cast<std::uint32_t>(m.positions.size() - 1);
}

// Quad a-b-c-d counter-clockwise from outside, as two triangles.
inline void add_quad(Mesh& m, std::uint32_t a, std::uint32_t b, std::uint32_t c, std::uint32_t d) {
  m.triangles.emplace_back(a, b, c);
  m.triangles.emplace_back(a, c, d);
}

inline Mesh box_mesh(const Vec3& lo, const Vec3& hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    add_vertex(m, Vec3((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z));
  add_quad(m, 0, 2, 3, 1);  // z = lo
  add_quad(m, 4, 5, 7, 6);  // z = hi
  add_quad(m, 0, 1, 5, 4);  // y = lo
  add_quad(m, 2, 6, 7, 3);  // y = hi
  add_quad(m, 0, 4, 6, 2);  // x = lo
  add_quad(m, 1, 3, 7, 5);  // x = hi
  return m;
}

inline Mesh sphere_mesh(const Vec3& c, double r, int slices = 48, int stacks = 24) {
  Mesh m;
  std::uint32_t south = add_vertex(m, c - Vec3(0, 0, r));
  for (int s = 1; s < stacks; ++s) {
    double phi = std::numbers::pi * s / stacks - std::numbers::pi / 2;
    for (int k = 0; k < slices; ++k) {
      double theta = 2 * std::numbers::pi * k / slices;
      add_vertex(m, c + r * Vec3(std::cos(phi) * std::cos(theta), std::cos(phi) * std::sin(theta),
                                 std::sin(phi)));
    }
  }
  std::uint32_t north = add_vertex(m, c + Vec3(0, 0, r));
  auto at = [&](int s, int k) {
    return static_cast<std::uint32_t>(1 + (s - 1) * slices + (k % slices));
  };
  for (int k = 0; k < slices; ++k) {
    m.triangles.emplace_back(south, at(1, k + 1), at(1, k));
    m.triangles.emplace_back(north, at(stacks - 1, k), at(stacks - 1, k + 1));
    for (int s = 1; s + 1 < stacks; ++s)
      add_quad(m, at(s, k), at(s, k + 1), at(s + 1, k + 1), at(s + 1, k));
  }
  return m;
}

// Volume of the inscribed polyhedron is what a mesh test should compare against; these give the
// analytic solid, and the tests allow for the facetting.
inline Mesh cylinder_mesh(const Vec3& base, double r, double h, int slices = 64) {
  Mesh m;
  std::uint32_t bottom = add_vertex(m, base), top = add_vertex(m, base + Vec3(0, 0, h));
  for (int k = 0; k < slices; ++k) {
    double theta = 2 * std::numbers::pi * k / slices;
    Vec3 d(r * std::cos(theta), r * std::sin(theta), 0);
    add_vertex(m, base + d);
    add_vertex(m, base + d + Vec3(0, 0, h));
  }
  auto lo = [&](int k) { return static_cast<std::uint32_t>(2 + 2 * (k % slices)); };
  auto hi = [&](int k) { return static_cast<std::uint32_t>(3 + 2 * (k % slices)); };
  for (int k = 0; k < slices; ++k) {
    m.triangles.emplace_back(bottom, lo(k + 1), lo(k));
    m.triangles.emplace_back(top, hi(k), hi(k + 1));
    add_quad(m, lo(k), lo(k + 1), hi(k + 1), hi(k));
  }
  return m;
}

inline Mesh torus_mesh(const Vec3& c, double major, double minor, int nu = 64, int nv = 32) {
  Mesh m;
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j) {
      double u = 2 * std::numbers::pi * i / nu, v = 2 * std::numbers::pi * j / nv;
      double rr = major + minor * std::cos(v);
      add_vertex(m, c + Vec3(rr * std::cos(u), rr * std::sin(u), minor * std::sin(v)));
    }
  auto at = [&](int i, int j) { return static_cast<std::uint32_t>((i % nu) * nv + (j % nv)); };
  for (int i = 0; i < nu; ++i)
    for (int j = 0; j < nv; ++j)
      add_quad(m, at(i, j), at(i + 1, j), at(i + 1, j + 1), at(i, j + 1));
  return m;
}

// Volumes of the meshes above as polyhedra (exact for the facetted solids, up to float rounding).
inline double cylinder_mesh_volume(double r, double h, int slices = 64) {
  return 0.5 * slices * r * r * std::sin(2 * std::numbers::pi / slices) * h;
}

}  // namespace tridex_test

namespace tridex_test {

// Every crossing of the ray o + t·d with the mesh's triangles (Möller–Trumbore in double),
// sorted: the brute-force reference for ray queries on meshes in general position.
inline std::vector<double> brute_force_hits(const Mesh& m, const Vec3& o, const Vec3& d) {
  std::vector<double> hits;
  for (const glm::uvec3& t : m.triangles) {
    Vec3 a(m.positions[t.x]), b(m.positions[t.y]), c(m.positions[t.z]);
    Vec3 e1 = b - a, e2 = c - a, p = glm::cross(d, e2);
    double det = glm::dot(e1, p);
    if (std::abs(det) < 1e-300) continue;
    Vec3 s = o - a;
    double bu = glm::dot(s, p) / det;
    if (bu < 0 || bu > 1) continue;
    Vec3 q = glm::cross(s, e1);
    double bv = glm::dot(d, q) / det;
    if (bv < 0 || bu + bv > 1) continue;
    hits.push_back(glm::dot(e2, q) / det);
  }
  std::sort(hits.begin(), hits.end());
  return hits;
}

// The distance from the ray o + t·d to the nearest mesh edge: rays farther than a small
// tolerance from every edge are in general position for the brute-force reference.
inline double distance_to_edges(const Mesh& m, const Vec3& o, const Vec3& d) {
  double best = 1e300;
  for (const glm::uvec3& t : m.triangles)
    for (int e = 0; e < 3; ++e) {
      Vec3 a(m.positions[t[e]]), b(m.positions[t[(e + 1) % 3]]);
      // Distance between a line and a segment: sample the segment's closest point analytically.
      Vec3 ab = b - a, w = a - o;
      Vec3 n = glm::cross(ab, d);
      double nn = glm::dot(n, n);
      double dist;
      if (nn < 1e-30) {
        Vec3 perp = w - glm::dot(w, d) * d;
        dist = glm::length(perp);
      } else {
        // Closest point parameters between line a + s·ab and o + t·d.
        double s_par = glm::dot(glm::cross(d, w), n) / nn;
        s_par = std::clamp(s_par, 0.0, 1.0);
        Vec3 p = a + s_par * ab - o;
        dist = glm::length(p - glm::dot(p, d) * d);
      }
      best = std::min(best, dist);
    }
  return best;
}

}  // namespace tridex_test
