// Accuracy along the edges where two spindle directions' cuts meet, measured against a
// point-membership reference (issue 17; used by tests/kernel/test_edges.cpp and the bundled
// example's test in tests/tools).
//
// Uniform samples in the stock almost never land within a spacing of such an edge. Here points
// are sampled only where, within one dexel spacing h, the reference holds kept material and
// material removed by each of two directions alone; each is classified by the result's mesh, and
// a wrong one is measured by its distance to the reference's surface (bisection along 64
// directions).
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <functional>
#include <limits>
#include <random>
#include <utility>
#include <vector>

#include <doctest/doctest.h>

#include "tridex/geometry.hpp"
#include "tridex/mesh.hpp"

namespace tridex::test {

// Point membership in a closed mesh: the parity of its crossings with the ray along +z.
class MeshInside {
 public:
  // Triangles are bucketed by their x-y boxes on a grid of side `bucket`.
  MeshInside(const Mesh& mesh, double bucket) : mesh_(mesh), box_(mesh.bounds()), bucket_(bucket) {
    nx_ = static_cast<int>(std::ceil(box_.size().x / bucket_)) + 1;
    ny_ = static_cast<int>(std::ceil(box_.size().y / bucket_)) + 1;
    cells_.resize(static_cast<std::size_t>(nx_ * ny_));
    for (std::uint32_t t = 0; t < mesh.triangles.size(); ++t) {
      Aabb b;
      for (int k = 0; k < 3; ++k) b.extend(Vec3(mesh.positions[mesh.triangles[t][k]]));
      for (int j = bin(b.min.y, box_.min.y, ny_); j <= bin(b.max.y, box_.min.y, ny_); ++j)
        for (int i = bin(b.min.x, box_.min.x, nx_); i <= bin(b.max.x, box_.min.x, nx_); ++i)
          cells_[static_cast<std::size_t>(i + nx_ * j)].push_back(t);
    }
  }
  bool inside(const Vec3& p) const {
    if (!box_.contains(p)) return false;
    int crossings = 0;
    for (std::uint32_t t : cells_[static_cast<std::size_t>(bin(p.x, box_.min.x, nx_) +
                                                           nx_ * bin(p.y, box_.min.y, ny_))]) {
      const Vec3 a(mesh_.positions[mesh_.triangles[t].x]), b(mesh_.positions[mesh_.triangles[t].y]),
          c(mesh_.positions[mesh_.triangles[t].z]);
      const double det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
      if (det == 0) continue;
      const double wb = ((p.x - a.x) * (c.y - a.y) - (c.x - a.x) * (p.y - a.y)) / det;
      const double wc = ((b.x - a.x) * (p.y - a.y) - (p.x - a.x) * (b.y - a.y)) / det;
      const double wa = 1 - wb - wc;
      if (wa < 0 || wb < 0 || wc < 0) continue;
      if (wa * a.z + wb * b.z + wc * c.z > p.z) ++crossings;
    }
    return crossings % 2 == 1;
  }

 private:
  int bin(double v, double lo, int count) const {
    return std::clamp(static_cast<int>(std::floor((v - lo) / bucket_)), 0, count - 1);
  }
  const Mesh& mesh_;
  Aabb box_;
  double bucket_;
  int nx_ = 0, ny_ = 0;
  std::vector<std::vector<std::uint32_t>> cells_;
};

struct EdgeErrors {
  int samples = 0, wrong = 0, beyond_half = 0, beyond_one_and_half = 0;
  double worst = 0;                                     // in spacings
  std::vector<std::pair<Vec3, double>> beyond_half_at;  // where, and how far (spacings)
};

// 64 directions spread over the sphere (a Fibonacci lattice).
inline std::vector<Vec3> sphere_directions() {
  std::vector<Vec3> dirs;
  for (int k = 0; k < 64; ++k) {
    const double z = 1 - (k + 0.5) * 2 / 64, r = std::sqrt(1 - z * z), phi = k * 2.399963229728653;
    dirs.emplace_back(r * std::cos(phi), r * std::sin(phi), z);
  }
  return dirs;
}

// Samples `count` points within h of the edges where two directions' cuts meet and classifies
// them by the mesh. Candidates come from a coarse grid (4h) whose cells see kept material and
// material removed by two directions at their corners.
// `label(p)`: 0 outside the stock, 1 kept, otherwise a bit (2 << i) for each direction i whose
// moves remove p.
inline EdgeErrors measure_edges(const Aabb& stock,
                                const std::function<unsigned(const Vec3&)>& label, const Mesh& mesh,
                                double h, int count, std::mt19937& rng) {
  auto kept = [&](const Vec3& p) { return label(p) == 1; };
  const std::vector<Vec3> dirs = sphere_directions();
  auto near_edge = [&](const Vec3& p) {
    bool any_kept = false;
    unsigned alone = 0;
    for (std::size_t s = 0; s <= dirs.size(); ++s) {
      const unsigned l = label(s == dirs.size() ? p : p + h * dirs[s]);
      any_kept = any_kept || l == 1;
      if (l > 1 && std::popcount(l) == 1) alone |= l;
    }
    return any_kept && std::popcount(alone) >= 2;
  };
  auto distance = [&](const Vec3& p) {
    const bool side = kept(p);
    double best = std::numeric_limits<double>::infinity();
    for (const Vec3& d : dirs) {
      double lo = 0, hi = 3 * h;
      if (kept(p + hi * d) == side) continue;
      for (int it = 0; it < 30; ++it) {
        const double mid = 0.5 * (lo + hi);
        (kept(p + mid * d) == side ? lo : hi) = mid;
      }
      best = std::min(best, hi);
    }
    return best;
  };
  const double g = 4 * h;
  const glm::ivec3 n = glm::ivec3(glm::ceil(stock.size() / g)) + 1;
  std::vector<unsigned> labels(static_cast<std::size_t>(n.x * n.y * n.z));
  auto at = [&](int i, int j, int k) -> unsigned& {
    return labels[static_cast<std::size_t>(i + n.x * (j + n.y * k))];
  };
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) at(i, j, k) = label(stock.min + g * Vec3(i, j, k) + Vec3(1e-4));
  std::vector<glm::ivec3> cells;
  for (int k = 0; k + 1 < n.z; ++k)
    for (int j = 0; j + 1 < n.y; ++j)
      for (int i = 0; i + 1 < n.x; ++i) {
        bool any_kept = false;
        unsigned removed = 0;
        for (int c = 0; c < 8; ++c) {
          const unsigned l = at(i + (c & 1), j + ((c >> 1) & 1), k + (c >> 2));
          any_kept = any_kept || l == 1;
          if (l > 1) removed |= l;
        }
        if (any_kept && std::popcount(removed) >= 2) cells.emplace_back(i, j, k);
      }
  REQUIRE(!cells.empty());
  const MeshInside inside(mesh, 0.5);
  std::uniform_real_distribution<double> unit(0, 1);
  EdgeErrors e;
  for (int t = 0; t < 400 * count && e.samples < count; ++t) {
    const glm::ivec3 c = cells[std::min(
        cells.size() - 1, static_cast<std::size_t>(unit(rng) * double(cells.size())))];
    const Vec3 p = stock.min + g * (Vec3(c) + Vec3(unit(rng), unit(rng), unit(rng)));
    if (!near_edge(p)) continue;
    ++e.samples;
    if (inside.inside(p) == kept(p)) continue;
    ++e.wrong;
    const double d = distance(p) / h;
    e.worst = std::max(e.worst, d);
    e.beyond_half += d > 0.5;
    if (d > 0.5) e.beyond_half_at.emplace_back(p, d);
    e.beyond_one_and_half += d > 1.5;
  }
  return e;
}

}  // namespace tridex::test
