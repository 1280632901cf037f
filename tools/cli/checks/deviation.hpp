// tridex check — the signed distance from points to a closed triangle mesh, and the regions of a
// mesh whose vertices lie beyond a tolerance.
//
// Nearest points: a binary AABB tree over the triangles (median split on the longest axis of the
// centroids' box, leaves of a few triangles), searched nearest child first with the box distance
// as the bound; the closest point on a triangle is Ericson's (Real-Time Collision Detection,
// 2005, §5.1.5), which also tells whether it falls inside the face, on an edge or at a vertex.
// The sign: inside the face, the side of the face's plane; on an edge or a vertex, where the
// plane test is ambiguous, the caller's inside test (a point-membership query on a dexelized
// solid, reliable beyond about one dexel spacing from the surface — closer than that the distance
// is below any sensible tolerance anyway).
#pragma once

#include <cstdint>
#include <functional>
#include <vector>

#include "tridex/geometry.hpp"
#include "tridex/mesh.hpp"

namespace tridex::cli {

class DistanceTree {
 public:
  // Throws tridex::Error when the mesh has no triangles.
  explicit DistanceTree(const Mesh& mesh);

  struct Nearest {
    double distance = 0;
    Vec3 point{0};
    std::uint32_t triangle = 0;
    bool on_face = false;  // the nearest point is inside the triangle (not on an edge or vertex)
    double side = 0;       // on_face: dot(p − point, the triangle's outward normal)
  };
  Nearest nearest(const Vec3& p) const;

  // Positive outside, negative inside; `inside` decides where the face plane cannot.
  double signed_distance(const Vec3& p, const std::function<bool(const Vec3&)>& inside) const;

 private:
  struct Node {
    Aabb box;
    std::uint32_t first = 0, count = 0;  // leaf: triangles order_[first, first + count)
    std::uint32_t left = 0, right = 0;   // inner: children (count == 0)
  };
  struct Item {
    Vec3 centroid;
    std::uint32_t triangle;
  };
  std::uint32_t build(std::uint32_t first, std::uint32_t count, std::vector<Item>& items);

  const Mesh* mesh_;
  std::vector<std::uint32_t> order_;
  std::vector<Node> nodes_;
};

// One connected set of out-of-tolerance vertices (connected through the mesh's edges).
struct DeviationRegion {
  std::vector<std::uint32_t> vertices;
  double depth = 0;  // the largest |deviation| in it
  std::uint32_t deepest = 0;
  Vec3 centroid{0};
  Aabb box;
  double area = 0;  // each triangle's area shared equally among its three vertices
};

// The connected components of the vertices with `selected[v]`, largest depth first.
std::vector<DeviationRegion> deviation_regions(const Mesh& mesh,
                                               const std::vector<double>& deviation,
                                               const std::vector<char>& selected);

// Points on the design's surface about `step` apart: its vertices, and in each triangle split into
// n² similar ones (n = ⌈longest edge / step⌉) their centroids; the step grows until at most
// `max_samples` remain. A design whose vertices and triangles alone exceed that (n = 1 gives
// each triangle one sample) is sampled by stride instead: every k-th of its vertices and then
// triangle centroids, k = ⌈(vertices + triangles) / `max_samples`⌉. Either way at most
// `max_samples` points, at a cost linear in the design's size.
std::vector<Vec3> design_samples(const Mesh& design, double step, std::size_t max_samples);

}  // namespace tridex::cli
