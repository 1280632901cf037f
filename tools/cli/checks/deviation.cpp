#include "checks/deviation.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numeric>

#include "tridex/error.hpp"

namespace tridex::cli {

namespace {

constexpr std::uint32_t kLeafSize = 4;

double box_distance2(const Aabb& box, const Vec3& p) {
  Vec3 d = glm::max(glm::max(box.min - p, p - box.max), Vec3(0));
  return glm::dot(d, d);
}

// Ericson §5.1.5: the closest point of triangle abc to p; `face` when it lies inside the face.
Vec3 closest_on_triangle(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c, bool& face) {
  face = false;
  Vec3 ab = b - a, ac = c - a, ap = p - a;
  double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return a;
  Vec3 bp = p - b;
  double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return b;
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return a + ab * (d1 / (d1 - d3));
  Vec3 cp = p - c;
  double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return c;
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return a + ac * (d2 / (d2 - d6));
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  double sum = va + vb + vc;
  if (!(sum > 0)) return a;  // degenerate triangle: any vertex is as good, and it is not a face
  face = true;
  return a + ab * (vb / sum) + ac * (vc / sum);
}

}  // namespace

DistanceTree::DistanceTree(const Mesh& mesh) : mesh_(&mesh) {
  if (mesh.triangles.empty()) detail::fail("distance tree: the mesh has no triangles");
  const auto n = static_cast<std::uint32_t>(mesh.triangles.size());
  std::vector<Item> items(n);
  for (std::uint32_t t = 0; t < n; ++t) {
    const glm::uvec3& tri = mesh.triangles[t];
    items[t].centroid =
        (Vec3(mesh.positions[tri.x]) + Vec3(mesh.positions[tri.y]) + Vec3(mesh.positions[tri.z])) /
        3.0;
    items[t].triangle = t;
  }
  nodes_.reserve(2 * (n / kLeafSize + 1));
  build(0, n, items);
  order_.resize(n);
  for (std::uint32_t k = 0; k < n; ++k) order_[k] = items[k].triangle;
}

// The triangles and their centroids move together, so that each level reads them in sequence.
std::uint32_t DistanceTree::build(std::uint32_t first, std::uint32_t count,
                                  std::vector<Item>& items) {
  const auto index = static_cast<std::uint32_t>(nodes_.size());
  nodes_.push_back(Node{});
  const auto begin = items.begin() + first, end = begin + count;
  Aabb centre_box;
  for (auto it = begin; it != end; ++it) centre_box.extend(it->centroid);
  Vec3 size = centre_box.size();
  if (count <= kLeafSize || std::max({size.x, size.y, size.z}) <= 0) {
    Aabb box;
    for (auto it = begin; it != end; ++it) {
      const glm::uvec3& tri = mesh_->triangles[it->triangle];
      for (std::uint32_t v : {tri.x, tri.y, tri.z}) box.extend(Vec3(mesh_->positions[v]));
    }
    nodes_[index].box = box;
    nodes_[index].first = first;
    nodes_[index].count = count;
    return index;
  }
  int axis = size.x >= size.y && size.x >= size.z ? 0 : (size.y >= size.z ? 1 : 2);
  std::uint32_t half = count / 2;
  std::nth_element(begin, begin + half, end, [axis](const Item& a, const Item& b) {
    return a.centroid[axis] < b.centroid[axis];
  });
  std::uint32_t left = build(first, half, items);
  std::uint32_t right = build(first + half, count - half, items);
  // A node's box is the union of its children's: the same box as over its triangles.
  nodes_[index].box = nodes_[left].box;
  nodes_[index].box.extend(nodes_[right].box);
  nodes_[index].left = left;
  nodes_[index].right = right;
  return index;
}

DistanceTree::Nearest DistanceTree::nearest(const Vec3& p) const {
  Nearest best;
  double best2 = std::numeric_limits<double>::infinity();
  // The nodes to visit with their box distances, on a fixed stack: the tree is a median split, so
  // its depth is at most log2(triangles) + 1 and one entry per level plus one suffices.
  struct Pending {
    std::uint32_t node;
    double d2;
  };
  std::array<Pending, 2 * 64> stack;
  std::size_t top = 0;
  stack[top++] = {0, box_distance2(nodes_[0].box, p)};
  while (top > 0) {
    const Pending pending = stack[--top];
    if (pending.d2 >= best2) continue;
    const Node& node = nodes_[pending.node];
    if (node.count == 0) {
      // Nearer child last, so that it is searched first and tightens the bound.
      double dl = box_distance2(nodes_[node.left].box, p),
             dr = box_distance2(nodes_[node.right].box, p);
      if (dl < dr)
        stack[top++] = {node.right, dr}, stack[top++] = {node.left, dl};
      else
        stack[top++] = {node.left, dl}, stack[top++] = {node.right, dr};
      continue;
    }
    for (std::uint32_t k = node.first; k < node.first + node.count; ++k) {
      const glm::uvec3& tri = mesh_->triangles[order_[k]];
      Vec3 a(mesh_->positions[tri.x]), b(mesh_->positions[tri.y]), c(mesh_->positions[tri.z]);
      bool face = false;
      Vec3 q = closest_on_triangle(p, a, b, c, face);
      double d2 = glm::dot(p - q, p - q);
      if (d2 < best2) {
        best2 = d2;
        best.point = q;
        best.triangle = order_[k];
        best.on_face = face;
        best.side = face ? glm::dot(p - q, glm::normalize(glm::cross(b - a, c - a))) : 0;
      }
    }
  }
  best.distance = std::sqrt(best2);
  return best;
}

double DistanceTree::signed_distance(const Vec3& p,
                                     const std::function<bool(const Vec3&)>& inside) const {
  Nearest n = nearest(p);
  if (n.distance == 0) return 0;
  bool in = n.on_face ? n.side < 0 : inside(p);
  return in ? -n.distance : n.distance;
}

std::vector<DeviationRegion> deviation_regions(const Mesh& mesh,
                                               const std::vector<double>& deviation,
                                               const std::vector<char>& selected) {
  const std::size_t n = mesh.positions.size();
  if (deviation.size() != n || selected.size() != n)
    detail::fail("deviation regions: ", n, " vertices but ", deviation.size(), " deviations and ",
                 selected.size(), " selections");
  // Union-find over the edges whose two ends are both selected.
  std::vector<std::uint32_t> parent(n);
  std::iota(parent.begin(), parent.end(), 0u);
  auto find = [&](std::uint32_t v) {
    while (parent[v] != v) v = parent[v] = parent[parent[v]];
    return v;
  };
  for (const glm::uvec3& t : mesh.triangles)
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = t[e], b = t[(e + 1) % 3];
      if (selected[a] && selected[b]) parent[find(a)] = find(b);
    }
  std::vector<std::int64_t> region_of(n, -1);
  std::vector<DeviationRegion> regions;
  for (std::uint32_t v = 0; v < n; ++v) {
    if (!selected[v]) continue;
    std::uint32_t root = find(v);
    if (region_of[root] < 0) {
      region_of[root] = static_cast<std::int64_t>(regions.size());
      regions.emplace_back();
    }
    DeviationRegion& r = regions[static_cast<std::size_t>(region_of[root])];
    r.vertices.push_back(v);
    r.box.extend(Vec3(mesh.positions[v]));
    r.centroid += Vec3(mesh.positions[v]);
    if (std::abs(deviation[v]) >= r.depth) r.depth = std::abs(deviation[v]), r.deepest = v;
  }
  for (const glm::uvec3& t : mesh.triangles) {
    Vec3 a(mesh.positions[t.x]), b(mesh.positions[t.y]), c(mesh.positions[t.z]);
    double third = glm::length(glm::cross(b - a, c - a)) / 6;
    for (int k = 0; k < 3; ++k)
      if (selected[t[k]]) regions[static_cast<std::size_t>(region_of[find(t[k])])].area += third;
  }
  for (DeviationRegion& r : regions) r.centroid /= static_cast<double>(r.vertices.size());
  std::sort(regions.begin(), regions.end(),
            [](const DeviationRegion& a, const DeviationRegion& b) { return a.depth > b.depth; });
  return regions;
}

std::vector<Vec3> design_samples(const Mesh& design, double step, std::size_t max_samples) {
  const auto limit = static_cast<double>(max_samples);
  auto splits = [&](const glm::uvec3& t, double s) {
    Vec3 a(design.positions[t.x]), b(design.positions[t.y]), c(design.positions[t.z]);
    double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
    return std::max(1.0, std::ceil(longest / s));
  };
  const std::size_t least = design.positions.size() + design.triangles.size();
  if (static_cast<double>(least) > limit) {
    const auto stride = static_cast<std::size_t>(std::ceil(static_cast<double>(least) / limit));
    // Vertices then triangles as one sequence, every stride-th taken: ⌈least / stride⌉ samples.
    std::vector<Vec3> samples;
    samples.reserve(least / stride + 1);
    const std::size_t vertices = design.positions.size();
    for (std::size_t k = 0; k < least; k += stride) {
      if (k < vertices) {
        samples.emplace_back(design.positions[k]);
        continue;
      }
      const glm::uvec3& t = design.triangles[k - vertices];
      samples.push_back((Vec3(design.positions[t.x]) + Vec3(design.positions[t.y]) +
                         Vec3(design.positions[t.z])) /
                        3.0);
    }
    return samples;
  }
  for (;;) {
    double total = static_cast<double>(design.positions.size());
    for (const glm::uvec3& t : design.triangles) total += splits(t, step) * splits(t, step);
    if (total <= limit) break;
    step *= std::sqrt(total / limit) * 1.01;
  }
  std::vector<Vec3> samples(design.positions.begin(), design.positions.end());
  for (const glm::uvec3& t : design.triangles) {
    Vec3 a(design.positions[t.x]), ab = Vec3(design.positions[t.y]) - a,
                                   ac = Vec3(design.positions[t.z]) - a;
    const auto n = static_cast<int>(splits(t, step));
    for (int i = 0; i < n; ++i)
      for (int j = 0; i + j < n; ++j) {
        samples.push_back(a + ((i + 1.0 / 3) / n) * ab + ((j + 1.0 / 3) / n) * ac);
        if (i + j + 1 < n)
          samples.push_back(a + ((i + 2.0 / 3) / n) * ab + ((j + 2.0 / 3) / n) * ac);
      }
  }
  return samples;
}

}  // namespace tridex::cli
