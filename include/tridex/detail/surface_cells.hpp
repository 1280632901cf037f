// tridex — the triangles of one lattice cell in surface extraction: marching cubes (Lorensen &
// Cline, SIGGRAPH 1987) with crossings at dexel end points, and Extended Marching Cubes' feature
// points (Kobbelt, Botsch, Schwanecke & Seidel, SIGGRAPH 2001) fanned where the crossings'
// normals spread; the Extractor's member functions for vertices on lattice edges, their
// normals, and the cell's loops and caps (surface_extractor.hpp describes the method).
// Part of surface.hpp, after surface_extractor.hpp; not for inclusion on its own.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <glm/glm.hpp>
#include <limits>
#include <span>
#include <unordered_set>
#include <utility>
#include <vector>

#include "tridex/detail/surface_extractor.hpp"

namespace tridex::detail::surface {

inline std::uint32_t Extractor::edge_vertex(SlabState& st, int a, glm::ivec3 node,
                                            bool start_inside) const {
  std::size_t slot = column(node.x, node.y);
  std::uint32_t* id;
  std::vector<std::uint32_t>* used;
  ColumnSlots& c = st.s.slots[slot];
  if (a == 2) {
    id = &c.ze, used = &st.s.ze_used;
  } else {
    std::size_t p = static_cast<std::size_t>(node.z & 1);
    id = a == 0 ? &c.xe[p] : &c.ye[p];
    used = a == 0 ? &st.s.xe_used[p] : &st.s.ye_used[p];
  }
  if (*id != kNone) return *id;
  const int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
  std::span<const DexelInterval> ray = d_.grids[a].ray(node[u], node[v]);
  double x0 = coord(a, node[a]), x1 = coord(a, node[a] + 1), x = 0;
  bool found = false;
  if (start_inside) {  // leaving the solid: the first exit after the inside node
    auto it = std::upper_bound(
        ray.begin(), ray.end(), x0,
        [](double value, const DexelInterval& s) { return value < double(s.exit); });
    if (it != ray.end() && double(it->exit) <= x1) x = it->exit, found = true;
  } else {  // entering: the last enter before the inside node
    auto it = std::upper_bound(
        ray.begin(), ray.end(), x1,
        [](double value, const DexelInterval& s) { return value < double(s.enter); });
    if (it != ray.begin() && double((it - 1)->enter) >= x0) x = (it - 1)->enter, found = true;
  }
  if (!found) x = ray_contains(ray, x0) == start_inside ? x1 : x0;  // at the node the ray disputes
  double t = std::clamp((x - x0) / h_, delta_, 1 - delta_);
  Vec3 p(coord(0, node.x), coord(1, node.y), coord(2, node.z));
  p[a] = x0 + t * h_;
  glm::vec3 normal(0.0f);
  if (sharp_) normal = crossing_normal(a, node[u], node[v], x, !start_inside);
  *id = add_vertex(st.out, p, normal);
  used->push_back(static_cast<std::uint32_t>(slot));
  return *id;
}

inline glm::vec3 Extractor::crossing_normal(int a, int iu, int iv, double x, bool enter) const {
  const DexelGrid& g = d_.grids[a];
  // The end point of the same kind nearest to `near` on ray (ju, jv), if within two spacings.
  auto end_point_near = [&](int ju, int jv, double near, double& out) {
    if (ju < 0 || jv < 0 || ju >= g.nu || jv >= g.nv) return false;
    std::span<const DexelInterval> ray = g.ray(ju, jv);
    auto end_point = [&](const DexelInterval& s) { return double(enter ? s.enter : s.exit); };
    auto it = std::lower_bound(
        ray.begin(), ray.end(), near,
        [&](const DexelInterval& s, double value) { return end_point(s) < value; });
    double best = std::numeric_limits<double>::infinity();
    if (it != ray.end()) best = end_point(*it);
    if (it != ray.begin() && std::abs(end_point(*(it - 1)) - near) < std::abs(best - near))
      best = end_point(*(it - 1));
    if (!(std::abs(best - near) <= 2 * h_)) return false;
    out = best;
    return true;
  };
  // f_u by finite differences: central where both sides agree; otherwise (an edge or a ridge
  // between the rays) the one-sided difference whose continuation one more ray out is the
  // straighter (ENO), so a crossing's normal is that of its own face.
  auto slope = [&](int du, int dv, double& out) {
    double x1[2], d1[2];
    bool have[2] = {false, false};
    for (int side = 0; side < 2; ++side) {
      int su = side ? 1 : -1;
      if (end_point_near(iu + su * du, iv + su * dv, x, x1[side]))
        have[side] = true, d1[side] = su * (x1[side] - x) / h_;
    }
    if (have[0] && have[1]) {
      if (std::abs(d1[0] - d1[1]) <= 0.1) {
        out = 0.5 * (d1[0] + d1[1]);
        return true;
      }
      double bend[2];
      for (int side = 0; side < 2; ++side) {
        int su = side ? 1 : -1;
        double x2;
        bend[side] = end_point_near(iu + 2 * su * du, iv + 2 * su * dv, x1[side], x2)
                         ? std::abs(su * (x2 - x1[side]) / h_ - d1[side])
                         : std::numeric_limits<double>::infinity();
      }
      int pick = bend[0] < bend[1]                    ? 0
                 : bend[1] < bend[0]                  ? 1
                 : std::abs(d1[0]) <= std::abs(d1[1]) ? 0
                                                      : 1;
      out = d1[pick];
      return true;
    }
    if (have[0] || have[1]) {
      out = have[0] ? d1[0] : d1[1];
      return true;
    }
    return false;
  };
  double fu = 0, fv = 0;
  if (!slope(1, 0, fu) || !slope(0, 1, fv)) return glm::vec3(0.0f);
  Vec3 n(0);
  n[a] = 1, n[TripleDexel::u_axis(a)] = -fu, n[TripleDexel::v_axis(a)] = -fv;
  n = glm::normalize(n);
  return glm::vec3(enter ? -n : n);
}

inline std::uint32_t Extractor::node_vertex(SlabState& st, glm::ivec3 node) const {
  std::size_t p = static_cast<std::size_t>(node.z & 1), slot = column(node.x, node.y);
  std::uint32_t& id = st.s.slots[slot].node[p];
  if (id == kNone) {
    id = add_vertex(st.out, Vec3(coord(0, node.x), coord(1, node.y), coord(2, node.z)),
                    glm::vec3(0.0f));
    st.s.node_used[p].push_back(static_cast<std::uint32_t>(slot));
  }
  return id;
}

inline std::uint32_t Extractor::cube_edge_vertex(SlabState& st, int i, int j, unsigned mask,
                                                 int e) const {
  const CubeTables& t = kCubeTables;
  int a = e / 4, bu = e & 1, bv = (e >> 1) & 1;
  glm::ivec3 node(i, j, st.k);
  node[TripleDexel::u_axis(a)] += bu;
  node[TripleDexel::v_axis(a)] += bv;
  return edge_vertex(st, a, node, (mask >> t.edge_corners[static_cast<std::size_t>(e)][0]) & 1u);
}

inline bool Extractor::fan_is_valid(const Vec3& apex, std::span<const Vec3> p,
                                    const glm::vec3* normals, const Vec3& n) const {
  for (std::size_t i = 0; i < p.size(); ++i) {
    std::size_t j = (i + 1) % p.size();
    Vec3 c = glm::cross(p[i] - apex, p[j] - apex);
    Vec3 ref = n;
    if (normals && normals[i] != glm::vec3(0.0f) && normals[j] != glm::vec3(0.0f)) {
      Vec3 sum = Vec3(normals[i]) + Vec3(normals[j]);
      if (glm::dot(sum, sum) > 1e-6) ref = sum;
    }
    if (!well_shaped(apex, p[i], p[j]) || !(glm::dot(c, ref) > 0)) return false;
  }
  return true;
}

inline void Extractor::emit_loop(SlabState& st, int i, int j, const std::uint8_t* edges, int size,
                                 int fan_start, unsigned mask) const {
  std::array<std::uint32_t, 12>
      id;  // filled up to `size`; left uninitialised on purpose (hot path)
  std::array<Vec3, 12> p;
  std::array<glm::vec3, 12> normal;
  for (int q = 0; q < size; ++q) {
    std::size_t sq = static_cast<std::size_t>(q);
    id[sq] = cube_edge_vertex(st, i, j, mask, edges[q]);
    p[sq] = Vec3(st.out.positions[id[sq]]);
    if (sharp_) normal[sq] = st.out.normals[id[sq]];
  }
  const std::size_t n = static_cast<std::size_t>(size);
  Vec3 centroid(0), newell(0);
  for (std::size_t q = 0; q < n; ++q) centroid += p[q], newell += glm::cross(p[q], p[(q + 1) % n]);
  centroid /= double(size);
  std::span<const Vec3> ring(p.data(), n);
  auto fan_around = [&](const Vec3& apex, bool feature) {
    std::uint32_t c = add_vertex(st.out, apex, glm::vec3(0.0f));
    for (std::size_t q = 0; q < n; ++q) {
      if (feature)
        st.out.feature_triangles.push_back(static_cast<std::uint32_t>(st.out.triangles.size()));
      emit(st.out, c, id[q], id[(q + 1) % n]);
    }
  };
  if (sharp_) {
    Vec3 apex;
    if (feature_point(st, id.data(), ring, centroid, i, j, apex) &&
        fan_is_valid(apex, ring, normal.data(), newell)) {
      fan_around(apex, true);
      return;
    }
  }
  if (size == 3) {
    emit(st.out, id[0], id[1], id[2]);
  } else if (fan_start != 255) {
    std::size_t r = static_cast<std::size_t>(fan_start);
    for (std::size_t q = 1; q + 1 < n; ++q)
      emit(st.out, id[r], id[(r + q) % n], id[(r + q + 1) % n]);
  } else {
    // A centre point; nudged off the loop's mean plane in the rare case that it falls in line
    // with two neighbouring loop vertices.
    Vec3 lift = glm::length(newell) > 0 ? 0.05 * h_ * glm::normalize(newell) : Vec3(0);
    Vec3 apex = centroid;
    for (const Vec3& offset : {Vec3(0), lift, -lift}) {
      apex = centroid + offset;
      bool ok = true;
      for (std::size_t q = 0; q < n && ok; ++q) ok = well_shaped(apex, p[q], p[(q + 1) % n]);
      if (ok) break;
    }
    fan_around(apex, false);
  }
}

inline void Extractor::emit_cell(SlabState& st, int i, int j, unsigned mask) const {
  const CubeCase& cc = kCubeTables.cases[mask];
  int first = 0;
  for (int l = 0; l < cc.loop_count; ++l) {
    int size = cc.loop_size[static_cast<std::size_t>(l)];
    emit_loop(st, i, j, cc.edges.data() + first, size, cc.fan_start[static_cast<std::size_t>(l)],
              mask);
    first += size;
  }
}

inline void Extractor::emit_cap(SlabState& st, int i, int j, unsigned mask, int f) const {
  const CubeTables& t = kCubeTables;
  unsigned face_mask = 0;
  for (int q = 0; q < 4; ++q)
    face_mask |=
        ((mask >> t.face_corners[static_cast<std::size_t>(f)][static_cast<std::size_t>(q)]) & 1u)
        << q;
  const FaceCap& cap = t.caps[static_cast<std::size_t>(f)][face_mask];
  int first = 0;
  for (int g = 0; g < cap.polygon_count; ++g) {
    int size = cap.polygon_size[static_cast<std::size_t>(g)];
    std::array<std::uint32_t, 6> id{};
    for (int q = 0; q < size; ++q) {
      int item = cap.items[static_cast<std::size_t>(first + q)];
      if (item < 4) {
        int c = t.face_corners[static_cast<std::size_t>(f)][static_cast<std::size_t>(item)];
        id[static_cast<std::size_t>(q)] =
            node_vertex(st, glm::ivec3(i + (c & 1), j + ((c >> 1) & 1), st.k + (c >> 2)));
      } else {
        id[static_cast<std::size_t>(q)] = cube_edge_vertex(
            st, i, j, mask,
            t.face_edges[static_cast<std::size_t>(f)][static_cast<std::size_t>(item - 4)]);
      }
    }
    for (int q = 1; q + 1 < size; ++q)
      emit(st.out, id[0], id[static_cast<std::size_t>(q)], id[static_cast<std::size_t>(q + 1)]);
    first += size;
  }
}

}  // namespace tridex::detail::surface
