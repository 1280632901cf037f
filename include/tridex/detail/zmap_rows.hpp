// tridex — the Z-map's machinery (zmap.hpp's contract): grid sizing, the stock's heights row by
// row (a box's tops; a mesh's triangles rasterised by bands of rows, MeshTop), and raise_uncut's
// two passes over bands of rows (Step 3's preparation, Inui, Chen and Umezu, CAD&A 19(4) 2022,
// §3.2). Rows are computed on their own, so that from_box/from_mesh and raise_uncut agree bit for
// bit and raise_uncut needs no second map.
// Part of zmap.hpp, which includes it after its contract; not for inclusion on its own.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

#include "tridex/error.hpp"
#include "tridex/geometry.hpp"
#include "tridex/mesh.hpp"
#include "tridex/parallel.hpp"

namespace tridex::detail {

// Empty points sit this far below the stock: far enough that the polyhedron built on them
// (Step 2) has a slab of non-zero thickness under the stock, and a few cells so that it is not
// confused with a cut. The grid reaches as far beyond the stock's projection, so that the
// polyhedron's side walls never lie in the plane of a stock face (a tie that loses a layer of
// rays in the intersection).
inline double empty_margin(double cell) { return 2.0 * cell; }

// The interval of s where the line p + s·d lies inside the box (slab method); false if none.
inline bool line_box_interval(const Vec3& p, const Vec3& d, const Aabb& box, double& s0,
                              double& s1) {
  s0 = -std::numeric_limits<double>::infinity();
  s1 = std::numeric_limits<double>::infinity();
  for (int a = 0; a < 3; ++a) {
    if (std::abs(d[a]) < 1e-15) {
      if (p[a] < box.min[a] || p[a] > box.max[a]) return false;
      continue;
    }
    double t0 = (box.min[a] - p[a]) / d[a], t1 = (box.max[a] - p[a]) / d[a];
    if (t0 > t1) std::swap(t0, t1);
    s0 = std::max(s0, t0);
    s1 = std::min(s1, t1);
  }
  return s0 <= s1;
}

inline int grid_count(double extent, double cell, const char* what) {
  double n = std::floor(extent / cell + 1e-9) + 2;  // one point beyond the far side
  if (!(n < 1e9)) fail(what, ": grid of ", n, " points along one side is too large");
  return static_cast<int>(n);
}

// Row j of ZMap::from_box's heights on `g`: the top of the box above each point, or `empty`
// outside its projection. raise_uncut for a box computes the same rows again, so both must come
// from here to agree bit for bit.
// It is line_box_interval at each point, taken axis by axis over blocks of points (the same
// arithmetic, no early exit), so that the compiler can vectorise the divisions.
inline void box_top_row(const ZMapGrid& g, const Aabb& stock, float empty, int j, float* row) {
  const Vec3 up = g.frame.axis();
  constexpr int kBlock = 256;
  double p[3][kBlock], s0[kBlock], s1[kBlock];
  unsigned char inside[kBlock];
  for (int i0 = 0; i0 < g.nx; i0 += kBlock) {
    const int n = std::min(kBlock, g.nx - i0);
    for (int k = 0; k < n; ++k) {
      const Vec3 w = g.frame.to_world(Vec3(g.x(i0 + k), g.y(j), 0));
      p[0][k] = w.x, p[1][k] = w.y, p[2][k] = w.z;
      s0[k] = -std::numeric_limits<double>::infinity();
      s1[k] = std::numeric_limits<double>::infinity();
      inside[k] = 1;
    }
    for (int a = 0; a < 3; ++a) {
      const double lo = stock.min[a], hi = stock.max[a], d = up[a];
      const double* pa = p[a];
      if (std::abs(d) < 1e-15) {
        for (int k = 0; k < n; ++k)
          inside[k] = static_cast<unsigned char>(inside[k] & !(pa[k] < lo) & !(pa[k] > hi));
        continue;
      }
      for (int k = 0; k < n; ++k) {
        const double t0 = (lo - pa[k]) / d, t1 = (hi - pa[k]) / d;
        const double near = t0 > t1 ? t1 : t0, far = t0 > t1 ? t0 : t1;  // the swap
        s0[k] = s0[k] < near ? near : s0[k];                             // std::max
        s1[k] = far < s1[k] ? far : s1[k];                               // std::min
      }
    }
    for (int k = 0; k < n; ++k) {
      const float top = static_cast<float>(s1[k]);
      row[i0 + k] = (inside[k] & (s0[k] <= s1[k])) ? top : empty;
    }
  }
}

// The grid and empty height of ZMap::from_box's map.
inline std::pair<ZMapGrid, float> box_map_grid(const Frame& frame, const Aabb& stock, double cell) {
  const Aabb local = local_bounds(frame, stock);
  return {ZMapGrid::covering(frame, local.inflated(empty_margin(cell)), cell),
          static_cast<float>(local.min.z - empty_margin(cell))};
}

// Whether two grids have the same points (their frames are the caller's to compare).
inline bool same_points(const ZMapGrid& a, const ZMapGrid& b) {
  return a.nx == b.nx && a.ny == b.ny && a.x0 == b.x0 && a.y0 == b.y0 && a.cell == b.cell;
}

// Rows per chunk of work for the row-parallel passes over a map.
inline constexpr int kMapBandRows = 64;

// A stock mesh seen along a frame's z, from which any row of ZMap::from_mesh's heights can be
// computed on its own: the triangles are listed by the bands of kMapBandRows rows they cross.
// ZMap::from_mesh and raise_uncut for a mesh stock both rasterise through raster_rows, so they
// agree bit for bit (a point's height is the largest of its hits, in any order).
class MeshTop {
 public:
  MeshTop(const Frame& frame, const Mesh& stock, double cell) : triangles_(stock.triangles) {
    if (stock.triangles.empty()) fail("Z-map: stock mesh has no triangles");
    local_.resize(stock.positions.size());
    Aabb box;
    for (std::size_t v = 0; v < local_.size(); ++v) {
      local_[v] = frame.to_local(Vec3(stock.positions[v]));
      if (!is_finite(local_[v])) fail("Z-map: stock mesh vertex ", v, " is not finite");
      box.extend(local_[v]);
    }
    for (const glm::uvec3& t : stock.triangles)
      if (t.x >= local_.size() || t.y >= local_.size() || t.z >= local_.size())
        fail("Z-map: stock mesh triangle refers to a missing vertex");
    grid_ = ZMapGrid::covering(frame, box.inflated(empty_margin(cell)), cell);
    empty_ = static_cast<float>(box.min.z - empty_margin(cell));
  }

  const ZMapGrid& grid() const { return grid_; }
  float empty() const { return empty_; }

  // Lists the triangles by band; needed before row(), not by raster_rows over the whole grid.
  void index_bands() {
    bands_.assign(static_cast<std::size_t>((grid_.ny + kMapBandRows - 1) / kMapBandRows), {});
    for (std::size_t t = 0; t < triangles_.size(); ++t) {
      const auto [j0, j1] = rows_of(t);
      for (int b = j0 / kMapBandRows; j0 <= j1 && b <= j1 / kMapBandRows; ++b)
        bands_[static_cast<std::size_t>(b)].push_back(static_cast<std::uint32_t>(t));
    }
  }

  // Row j of the heights into `out` (grid().nx floats).
  void row(int j, float* out) const {
    std::fill_n(out, grid_.nx, empty_);
    for (std::uint32_t t : bands_[static_cast<std::size_t>(j / kMapBandRows)])
      raster_rows(t, j, j, [&](int i, int) -> float& { return out[i]; });
  }

  // Rasterises triangle t's projection over rows [row_lo, row_hi]; at(i, j) is the height of
  // point (i, j), raised to each hit. Barycentric tests are inclusive with a small tolerance
  // so that points on shared edges or vertices are never lost (a doubled hit does no harm to
  // a maximum); a triangle seen edge-on adds no height of its own.
  template <class At>
  void raster_rows(std::size_t t, int row_lo, int row_hi, At&& at) const {
    const glm::uvec3& tri = triangles_[t];
    const Vec3 &a = local_[tri.x], &b = local_[tri.y], &c = local_[tri.z];
    const double det = (b.x - a.x) * (c.y - a.y) - (c.x - a.x) * (b.y - a.y);
    if (std::abs(det) < 1e-18) return;
    const ZMapGrid& g = grid_;
    const double lox = std::min({a.x, b.x, c.x}), hix = std::max({a.x, b.x, c.x});
    const int i0 = std::max(0, static_cast<int>(std::ceil((lox - g.x0) / g.cell - 1e-9)));
    const int i1 = std::min(g.nx - 1, static_cast<int>(std::floor((hix - g.x0) / g.cell + 1e-9)));
    const auto [j0, j1] = rows_of(t);
    const double eps = 1e-9;
    for (int j = std::max(j0, row_lo); j <= std::min(j1, row_hi); ++j)
      for (int i = i0; i <= i1; ++i) {
        const double px = g.x(i), py = g.y(j);
        const double wb = ((px - a.x) * (c.y - a.y) - (c.x - a.x) * (py - a.y)) / det;
        const double wc = ((b.x - a.x) * (py - a.y) - (px - a.x) * (b.y - a.y)) / det;
        const double wa = 1 - wb - wc;
        if (wa < -eps || wb < -eps || wc < -eps) continue;
        float& h = at(i, j);
        h = std::max(h, static_cast<float>(wa * a.z + wb * b.z + wc * c.z));
      }
  }

  std::size_t triangles() const { return triangles_.size(); }

 private:
  // The rows triangle t's projection spans (j0 > j1 when it misses the grid).
  std::pair<int, int> rows_of(std::size_t t) const {
    const glm::uvec3& tri = triangles_[t];
    const double loy = std::min({local_[tri.x].y, local_[tri.y].y, local_[tri.z].y});
    const double hiy = std::max({local_[tri.x].y, local_[tri.y].y, local_[tri.z].y});
    return {
        std::max(0, static_cast<int>(std::ceil((loy - grid_.y0) / grid_.cell - 1e-9))),
        std::min(grid_.ny - 1, static_cast<int>(std::floor((hiy - grid_.y0) / grid_.cell + 1e-9)))};
  }

  const std::vector<glm::uvec3>& triangles_;  // the stock's, which outlives this
  std::vector<Vec3> local_;
  ZMapGrid grid_;
  float empty_ = 0;
  std::vector<std::vector<std::uint32_t>> bands_;
};

// raise_uncut on the initial heights that initial_row(j, row) writes, row j of them into `row`
// (grid.nx floats), `initial_empty` being their empty height. The map is split into bands of
// rows. A first pass reads only: each band computes its initial rows (and two more on each
// side, which its points' neighbourhoods reach), marks the points still at their initial
// height and lists the extrapolated points outside the footprint. The second writes, each band
// its own rows: the marked points are raised, then the listed ones set, as before any band
// had written.
template <class InitialRow>
void raise_uncut_rows(ZMap& milled, float initial_empty, InitialRow&& initial_row,
                      unsigned threads) {
  const ZMapGrid& a = milled.grid;
  const std::size_t nx = static_cast<std::size_t>(a.nx);
  constexpr std::size_t kPartials = 16;
  const auto bands = static_cast<std::size_t>((a.ny + kMapBandRows - 1) / kMapBandRows);
  // Every point's mark is written by the first pass (its band's rows), so the marks start
  // uninitialised: a vector's zeroing faulted in every fresh page on the calling thread alone
  // (bench/README.md, issue 37); here each band's worker touches its own.
  const std::unique_ptr<std::uint8_t[]> uncut(new std::uint8_t[a.size()]);
  std::vector<float> band_top(bands, milled.empty_height);
  // Each outside point next to a cut: its index and the largest continued height (unclamped).
  std::vector<std::vector<std::pair<std::size_t, float>>> continued(bands);
  for_each_chunk(bands, threads, [&](std::size_t band) {
    const int j0 = static_cast<int>(band) * kMapBandRows, j1 = std::min(a.ny, j0 + kMapBandRows);
    const int w0 = std::max(0, j0 - 2), w1 = std::min(a.ny, j1 + 2);  // rows of the window
    std::vector<float> window(static_cast<std::size_t>(w1 - w0) * nx);
    for (int j = w0; j < w1; ++j)
      initial_row(j, window.data() + static_cast<std::size_t>(j - w0) * nx);
    auto initial = [&](int i, int j) {
      return window[static_cast<std::size_t>(j - w0) * nx + static_cast<std::size_t>(i)];
    };
    auto inside = [&](int i, int j) {
      return i >= 0 && j >= 0 && i < a.nx && j < a.ny && initial(i, j) > initial_empty;
    };
    auto cut = [&](int i, int j) { return inside(i, j) && milled.height(i, j) != initial(i, j); };
    float top[kPartials];          // independent maxima, so that the loop below vectorises
    const std::size_t width = nx;  // a copy: the marks are bytes, which may alias a reference
    std::fill_n(top, kPartials, band_top[band]);
    for (int j = j0; j < j1; ++j) {
      const float* init = window.data() + static_cast<std::size_t>(j - w0) * nx;
      const float* height = milled.heights.data() + a.index(0, j);
      std::uint8_t* mark = uncut.get() + a.index(0, j);
      for (std::size_t k = 0; k < width; ++k) mark[k] = height[k] == init[k];
      std::size_t k = 0;
      for (; k + kPartials <= width; k += kPartials)
        for (std::size_t l = 0; l < kPartials; ++l)
          top[l] = init[k + l] > top[l] ? init[k + l] : top[l];
      for (; k < width; ++k) top[0] = init[k] > top[0] ? init[k] : top[0];
      for (int i = 0; i < a.nx; ++i) {
        if (init[static_cast<std::size_t>(i)] > initial_empty) continue;  // inside the footprint
        const std::size_t p = a.index(i, j);
        float best = -std::numeric_limits<float>::infinity();
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            if ((di == 0 && dj == 0) || !cut(i + di, j + dj)) continue;
            const float near = milled.height(i + di, j + dj);
            const float far =
                cut(i + 2 * di, j + 2 * dj) ? milled.height(i + 2 * di, j + 2 * dj) : near;
            best = std::max(best, 2 * near - far);
          }
        if (best > -std::numeric_limits<float>::infinity()) continued[band].emplace_back(p, best);
      }
    }
    band_top[band] = *std::max_element(top, top + kPartials);
  });
  const float top = *std::max_element(band_top.begin(), band_top.end());
  const float above = static_cast<float>(top + empty_margin(a.cell));
  milled.fine = {};  // the heights change under any fine cells
  for_each_chunk(bands, threads, [&](std::size_t band) {
    const std::size_t p0 = band * kMapBandRows * nx,
                      p1 = std::min(a.size(), p0 + kMapBandRows * nx);
    float* height = milled.heights.data();
    const std::uint8_t* raise = uncut.get();
    const float lifted = above;
    for (std::size_t p = p0; p < p1; ++p) height[p] = raise[p] ? lifted : height[p];
    for (const auto& [p, h] : continued[band])
      milled.heights[p] = std::clamp(h, milled.empty_height, above);
  });
}

}  // namespace tridex::detail
