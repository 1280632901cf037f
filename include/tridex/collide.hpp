// tridex — a triangle tree (bounding volume hierarchy) with exact distance queries, for the
// machine check (tools/cli/checks/machine_check.hpp): the distance between two meshes each placed
// by a rigid Frame, from a point and from a segment, and whether a point lies inside a closed mesh.
//
// Why not a library: Debian's libfcl-dev (FCL 0.7) does exact mesh–mesh distances, but it pulls
// Eigen, libccd and octomap into every consumer of this header-only kernel, and Embree (already a
// backend) answers ray queries only, not distances. What the check needs is narrow: the
// distance between two placed trees with an early exit (below a threshold: "in contact"; above a
// cap: "far enough"), which is some 200 lines over detail/triangle_distance.hpp's exact
// primitives (Ericson, "Real-Time Collision Detection", 2005, ch. 5 and 6).
//
// The tree: axis-aligned boxes in the mesh's own frame, split at the median centroid along the
// longest side, up to 4 triangles a leaf. Between two trees in different frames, the other tree's
// box is carried into this one's frame as the box around the turned box (centre turned, half
// sizes through |R|), a lower bound of the distance between what the two boxes hold.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <map>
#include <utility>
#include <vector>

#include "tridex/detail/triangle_distance.hpp"
#include "tridex/geometry.hpp"
#include "tridex/mesh.hpp"

namespace tridex {

class TriangleTree {
 public:
  struct Node {
    Aabb box;
    std::uint32_t first = 0, count = 0;  // leaf: triangles [first, first + count); else count = 0
    std::uint32_t left = 0, right = 0;   // inner: children
  };

  TriangleTree() = default;
  explicit TriangleTree(const Mesh& mesh) {
    triangles_.reserve(mesh.triangles.size());
    for (const glm::uvec3& t : mesh.triangles)
      triangles_.push_back(
          {Vec3(mesh.positions[t.x]), Vec3(mesh.positions[t.y]), Vec3(mesh.positions[t.z])});
    build();
  }
  explicit TriangleTree(std::vector<detail::Triangle3> triangles)
      : triangles_(std::move(triangles)) {
    build();
  }

  bool empty() const { return triangles_.empty(); }
  std::size_t size() const { return triangles_.size(); }
  const Aabb& bounds() const { return nodes_.front().box; }
  const std::vector<Node>& nodes() const { return nodes_; }
  const std::vector<detail::Triangle3>& triangles() const { return triangles_; }

  // The largest distance of a vertex from `centre` (for bounds on how far a turning body moves).
  double radius_about(const Vec3& centre) const {
    double r = 0;
    for (const detail::Triangle3& t : triangles_)
      r = std::max(
          {r, glm::length(t.a - centre), glm::length(t.b - centre), glm::length(t.c - centre)});
    return r;
  }

  // A vertex of each connected piece of the surface (triangles sharing a corner point join).
  std::vector<Vec3> piece_vertices() const {
    std::vector<std::uint32_t> parent(triangles_.size());
    for (std::uint32_t k = 0; k < parent.size(); ++k) parent[k] = k;
    auto root = [&](std::uint32_t k) {
      while (parent[k] != k) k = parent[k] = parent[parent[k]];
      return k;
    };
    std::map<std::array<double, 3>, std::uint32_t> owner;
    for (std::uint32_t k = 0; k < triangles_.size(); ++k)
      for (const Vec3& p : {triangles_[k].a, triangles_[k].b, triangles_[k].c}) {
        auto [it, fresh] = owner.try_emplace({p.x, p.y, p.z}, k);
        if (!fresh) parent[root(k)] = root(it->second);
      }
    std::vector<Vec3> out;
    for (std::uint32_t k = 0; k < triangles_.size(); ++k)
      if (root(k) == k) out.push_back(triangles_[k].a);
    return out;
  }

  // Distance from point p (this tree's frame) to the surface.
  double distance(const Vec3& p) const {
    double best2 = std::numeric_limits<double>::infinity();
    visit([&](const Aabb& b) { return box_distance2(b, p) < best2; },
          [&](const detail::Triangle3& t) {
            best2 = std::min(best2, detail::point_triangle_distance2(p, t));
          });
    return std::sqrt(best2);
  }

  // Distance from segment [p, q] (this tree's frame) to the surface.
  double distance(const Vec3& p, const Vec3& q) const {
    double best2 = std::numeric_limits<double>::infinity();
    visit([&](const Aabb& b) { return segment_box_lower2(b, p, q) < best2; },
          [&](const detail::Triangle3& t) {
            double d2 = detail::segment_crosses_triangle(p, q, t)
                            ? 0.0
                            : std::min({detail::point_triangle_distance2(p, t),
                                        detail::point_triangle_distance2(q, t),
                                        detail::segment_distance2(p, q, t.a, t.b),
                                        detail::segment_distance2(p, q, t.b, t.c),
                                        detail::segment_distance2(p, q, t.c, t.a)});
            best2 = std::min(best2, d2);
          });
    return std::sqrt(best2);
  }

  // Whether p lies inside the closed surface: the parity of the crossings of a ray from p (a
  // direction no axis-aligned face or edge lies along).
  bool contains(const Vec3& p) const {
    const Vec3 far = p + Vec3(0.5773, 0.5774, 0.5772) * (4 * glm::length(bounds().size()) + 1);
    if (!bounds().contains(p)) return false;
    int crossings = 0;
    visit([&](const Aabb& b) { return segment_box_lower2(b, p, far) == 0; },
          [&](const detail::Triangle3& t) {
            crossings += detail::segment_crosses_triangle(p, far, t);
          });
    return crossings % 2 == 1;
  }

  // Calls leaf(t) for every triangle in a box for which enter(box) holds.
  template <class Enter, class Leaf>
  void visit(const Enter& enter, const Leaf& leaf) const {
    if (nodes_.empty()) return;
    std::uint32_t stack[64];
    int top = 0;
    stack[top++] = 0;
    while (top > 0) {
      const Node& n = nodes_[stack[--top]];
      if (!enter(n.box)) continue;
      if (n.count > 0) {
        for (std::uint32_t k = n.first; k < n.first + n.count; ++k) leaf(triangles_[k]);
      } else {
        stack[top++] = n.right;
        stack[top++] = n.left;
      }
    }
  }

  static double box_distance2(const Aabb& b, const Vec3& p) {
    const Vec3 d = glm::max(glm::max(b.min - p, p - b.max), Vec3(0));
    return glm::dot(d, d);
  }

  // A lower bound of the squared distance from segment [p, q] to box b: 0 when the segment meets
  // it (slab test), else the distance from the box around the segment.
  static double segment_box_lower2(const Aabb& b, const Vec3& p, const Vec3& q) {
    double t0 = 0, t1 = 1;
    const Vec3 d = q - p;
    bool meets = true;
    for (int k = 0; k < 3 && meets; ++k) {
      if (std::abs(d[k]) < 1e-300) {
        meets = p[k] >= b.min[k] && p[k] <= b.max[k];
        continue;
      }
      double a = (b.min[k] - p[k]) / d[k], c = (b.max[k] - p[k]) / d[k];
      if (a > c) std::swap(a, c);
      t0 = std::max(t0, a), t1 = std::min(t1, c);
      meets = t0 <= t1;
    }
    if (meets) return 0;
    return box_box_distance2(b, Aabb::of(p, q));
  }

  static double box_box_distance2(const Aabb& a, const Aabb& b) {
    const Vec3 d = glm::max(glm::max(a.min - b.max, b.min - a.max), Vec3(0));
    return glm::dot(d, d);
  }

 private:
  void build() {
    if (triangles_.empty()) return;
    std::vector<Vec3> centres(triangles_.size());
    for (std::size_t k = 0; k < triangles_.size(); ++k)
      centres[k] = (triangles_[k].a + triangles_[k].b + triangles_[k].c) / 3.0;
    std::vector<std::uint32_t> order(triangles_.size());
    for (std::uint32_t k = 0; k < order.size(); ++k) order[k] = k;
    nodes_.reserve(2 * triangles_.size() / 3 + 2);
    nodes_.push_back({});
    // Iterative: (node, first, count) still to split.
    std::vector<std::array<std::uint32_t, 3>> work{
        {0, 0, static_cast<std::uint32_t>(order.size())}};
    while (!work.empty()) {
      const auto [node, first, count] = work.back();
      work.pop_back();
      Aabb box, centre_box;
      for (std::uint32_t k = first; k < first + count; ++k) {
        const detail::Triangle3& t = triangles_[order[k]];
        box.extend(t.a), box.extend(t.b), box.extend(t.c);
        centre_box.extend(centres[order[k]]);
      }
      nodes_[node].box = box;
      const Vec3 size = centre_box.size();
      if (count <= 4) {  // (equal centres still split in half: leaves hold at most 4)
        nodes_[node].first = first, nodes_[node].count = count;
        continue;
      }
      const int axis = size.x >= size.y && size.x >= size.z ? 0 : size.y >= size.z ? 1 : 2;
      const std::uint32_t half = count / 2;
      std::nth_element(
          order.begin() + first, order.begin() + first + half, order.begin() + first + count,
          [&](std::uint32_t a, std::uint32_t b) { return centres[a][axis] < centres[b][axis]; });
      const auto left = static_cast<std::uint32_t>(nodes_.size());
      nodes_.push_back({});
      nodes_.push_back({});
      nodes_[node].left = left, nodes_[node].right = left + 1;
      work.push_back({left, first, half});
      work.push_back({left + 1, first + half, count - half});
    }
    std::vector<detail::Triangle3> sorted(triangles_.size());
    for (std::size_t k = 0; k < order.size(); ++k) sorted[k] = triangles_[order[k]];
    triangles_ = std::move(sorted);
  }

  std::vector<detail::Triangle3> triangles_;
  std::vector<Node> nodes_;
};

// The box around box b turned and moved by frame f.
inline Aabb turned_box(const Frame& f, const Aabb& b) {
  const Vec3 c = f.to_world(b.center()), h = 0.5 * b.size();
  Vec3 e(0);
  for (int r = 0; r < 3; ++r)
    for (int k = 0; k < 3; ++k) e[r] += std::abs(f.rotation[k][r]) * h[k];
  return Aabb{c - e, c + e};
}

// A lower bound of the squared distance between triangles u and t: how far t lies wholly on one
// side of u's plane (0 when it touches or crosses it, or u is degenerate).
inline double plane_gap2(const detail::Triangle3& u, const detail::Triangle3& t) {
  const Vec3 n = glm::cross(u.b - u.a, u.c - u.a);
  const double n2 = glm::dot(n, n);
  if (!(n2 > 0)) return 0;
  const double a = glm::dot(n, t.a - u.a), b = glm::dot(n, t.b - u.a), c = glm::dot(n, t.c - u.a);
  const double gap = std::max({std::min({a, b, c}), -std::max({a, b, c}), 0.0});
  return gap * gap / n2;
}

// The distance between tree a placed by frame fa and tree b placed by frb (each frame maps its
// tree's coordinates to a common one), and the closest points in the common frame. The search
// stops early at the first pair closer than `stop_below` (the result is then that pair's
// distance, ≤ stop_below: "in contact") and returns `cap` when nothing lies closer than it.
struct TreeDistance {
  double distance = 0;
  Vec3 on_a{0}, on_b{0};
};

inline TreeDistance tree_distance(const TriangleTree& a, const Frame& fa, const TriangleTree& b,
                                  const Frame& fb, double stop_below = 0,
                                  double cap = std::numeric_limits<double>::infinity()) {
  TreeDistance result{cap, Vec3(0), Vec3(0)};
  if (a.empty() || b.empty()) return result;
  const Frame rel{glm::transpose(fa.rotation) * fb.rotation,
                  glm::transpose(fa.rotation) * (fb.origin - fa.origin)};  // b's frame in a's
  double best2 = cap * cap;
  const double stop2 = stop_below * stop_below;
  std::vector<std::pair<std::uint32_t, std::uint32_t>> stack{{0, 0}};
  const auto& na = a.nodes();
  const auto& nb = b.nodes();
  while (!stack.empty() && !(best2 <= stop2)) {
    const auto [ia, ib] = stack.back();
    stack.pop_back();
    const TriangleTree::Node &x = na[ia], &y = nb[ib];
    if (!(TriangleTree::box_box_distance2(x.box, turned_box(rel, y.box)) < best2)) continue;
    if (x.count > 0 && y.count > 0) {
      detail::Triangle3 moved[4];
      Aabb moved_box[4];
      for (std::uint32_t j = 0; j < y.count; ++j) {
        const detail::Triangle3& s = b.triangles()[y.first + j];
        moved[j] = {rel.to_world(s.a), rel.to_world(s.b), rel.to_world(s.c)};
        moved_box[j] = Aabb::of(glm::min(moved[j].a, moved[j].b), glm::max(moved[j].a, moved[j].b));
        moved_box[j].extend(moved[j].c);
      }
      for (std::uint32_t i = x.first; i < x.first + x.count; ++i) {
        const detail::Triangle3& u = a.triangles()[i];
        Aabb box = Aabb::of(glm::min(u.a, u.b), glm::max(u.a, u.b));
        box.extend(u.c);
        for (std::uint32_t j = 0; j < y.count; ++j) {
          if (!(TriangleTree::box_box_distance2(box, moved_box[j]) < best2)) continue;
          const detail::Triangle3& t = moved[j];
          // Each triangle's plane separates: no point of the other lies nearer to it than the
          // nearest vertex on the far side (prunes parallel faces, whose boxes overlap).
          if (!(plane_gap2(u, t) < best2) || !(plane_gap2(t, u) < best2)) continue;
          const double d2 = detail::triangle_distance2(u, t);
          if (d2 < best2) {
            best2 = d2;
            const Vec3 centre = (t.a + t.b + t.c) / 3.0;
            result.on_a = fa.to_world(detail::closest_on_triangle(centre, u));
            result.on_b = fa.to_world(centre);
          }
        }
      }
      continue;
    }
    // Split the larger node (a leaf cannot be split).
    const bool split_a =
        y.count > 0 || (x.count == 0 && glm::length(x.box.size()) >= glm::length(y.box.size()));
    // The nearer child last, so it is searched first and the bound tightens early.
    std::pair<std::uint32_t, std::uint32_t> first{x.left, ib}, second{x.right, ib};
    if (!split_a) first = {ia, y.left}, second = {ia, y.right};
    auto lower = [&](const std::pair<std::uint32_t, std::uint32_t>& p) {
      return TriangleTree::box_box_distance2(na[p.first].box, turned_box(rel, nb[p.second].box));
    };
    const double l1 = lower(first), l2 = lower(second);
    if (l1 > l2) std::swap(first, second);
    if (std::max(l1, l2) < best2) stack.push_back(second);
    if (std::min(l1, l2) < best2) stack.push_back(first);
  }
  if (best2 < cap * cap) result.distance = std::sqrt(best2);
  return result;
}

// The surface swept by a tree's triangles translated by d: each triangle at its start and its
// end, and each edge's parallelogram. A triangle translated along a segment sweeps the convex
// prism these bound, so the least distance from another mesh to this surface, when neither lies
// inside the other's prism, is the least distance over the whole translation (used by the machine
// check to settle a straight move in two queries, tools/cli/checks/machine_check.hpp).
inline std::vector<detail::Triangle3> swept_triangles(const TriangleTree& tree, const Vec3& d) {
  std::vector<detail::Triangle3> out;
  out.reserve(8 * tree.size());
  for (const detail::Triangle3& t : tree.triangles()) {
    out.push_back(t);
    out.push_back({t.a + d, t.b + d, t.c + d});
    const Vec3 v[3] = {t.a, t.b, t.c};
    for (int k = 0; k < 3; ++k) {
      const Vec3 &p = v[k], &q = v[(k + 1) % 3];
      out.push_back({p, q, q + d});
      out.push_back({p, q + d, p + d});
    }
  }
  return out;
}

// ---- simple closed meshes (the tools' parts and the bundled machines' parts) -------------------

// A box from `lo` to `hi`; a frustum about +Z (radii r0 at z0, r1 at z1) whose polygon of `sides`
// facets lies around the circle (never inside it); several meshes as one.

inline Mesh make_box_mesh(const Vec3& lo, const Vec3& hi) {
  Mesh m;
  for (int i = 0; i < 8; ++i)
    m.positions.emplace_back((i & 1) ? hi.x : lo.x, (i & 2) ? hi.y : lo.y, (i & 4) ? hi.z : lo.z);
  const unsigned f[12][3] = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                             {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
  for (const auto& t : f) m.triangles.emplace_back(t[0], t[1], t[2]);
  return m;
}

inline Mesh make_frustum_mesh(double r0, double r1, double z0, double z1, int sides = 24) {
  Mesh m;
  // The polygon's edges touch the circle at their middles: every point of the round body is in.
  const double grow = 1 / std::cos(3.14159265358979323846 / sides);
  for (int ring = 0; ring < 2; ++ring)
    for (int k = 0; k < sides; ++k) {
      const double a = 2 * 3.14159265358979323846 * k / sides, r = (ring ? r1 : r0) * grow;
      m.positions.emplace_back(r * std::cos(a), r * std::sin(a), ring ? z1 : z0);
    }
  const auto n = static_cast<unsigned>(sides);
  m.positions.emplace_back(0, 0, z0);
  m.positions.emplace_back(0, 0, z1);
  for (unsigned k = 0; k < n; ++k) {
    const unsigned k1 = (k + 1) % n;
    m.triangles.emplace_back(k, k1, n + k1);
    m.triangles.emplace_back(k, n + k1, n + k);
    m.triangles.emplace_back(2 * n, k1, k);
    m.triangles.emplace_back(2 * n + 1, n + k, n + k1);
  }
  return m;
}

inline Mesh merge_meshes(const std::vector<Mesh>& parts) {
  Mesh m;
  for (const Mesh& p : parts) {
    const auto base = static_cast<unsigned>(m.positions.size());
    m.positions.insert(m.positions.end(), p.positions.begin(), p.positions.end());
    for (const glm::uvec3& t : p.triangles) m.triangles.push_back(t + glm::uvec3(base));
  }
  return m;
}

}  // namespace tridex
