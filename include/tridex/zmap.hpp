// tridex — Z-maps: height fields on a regular grid in a spindle frame (Step 1 of the method,
// Inui, Chen and Umezu, CAD&A 19(4) 2022, §3.1).
//
// Grid point (i, j) lies at frame-local (x0 + i·cell, y0 + j·cell); its height is the frame-
// local z of the material's top surface above it. A point with no material above it (outside
// the stock's projection, or cut through) holds `empty_height`, which lies below the stock.
// Heights are float: a 5000×5000 map takes 100 MB.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <utility>
#include <vector>

#include "tridex/error.hpp"
#include "tridex/geometry.hpp"
#include "tridex/mesh.hpp"
#include "tridex/parallel.hpp"

namespace tridex {

struct ZMapGrid {
  Frame frame;            // heights are measured along frame.axis()
  double x0 = 0, y0 = 0;  // frame-local x, y of grid point (0, 0)
  double cell = 1;        // spacing of grid points along x and y
  int nx = 0, ny = 0;     // grid points along x and y

  std::size_t size() const { return static_cast<std::size_t>(nx) * static_cast<std::size_t>(ny); }
  std::size_t index(int i, int j) const {
    return static_cast<std::size_t>(i) + static_cast<std::size_t>(nx) * static_cast<std::size_t>(j);
  }
  double x(int i) const { return x0 + i * cell; }
  double y(int j) const { return y0 + j * cell; }

  // The grid whose points cover the local x-y rectangle of `local_box` with spacing `cell`.
  static ZMapGrid covering(const Frame& frame, const Aabb& local_box, double cell);
};

struct ZMapLimits {
  std::size_t max_points = std::size_t{1} << 30;  // 4 GiB of heights
};

// Steep cells in finer detail (issue 17). Where a wall parallel to the spindle crosses a cell,
// the heights at its corners say only that the surface drops somewhere inside it, and the
// two triangles ramp across the whole cell: the solid is off by up to a cell at the wall's rims,
// where other directions' cuts meet it. A fine cell carries the surface's heights on a
// kSteps × kSteps sub-grid of its own (refine_steep_cells in fine_cells.hpp takes them from the
// moves), triangulated like the grid, so the ramp spans a sub-cell only. Its corners are the
// map's points; two fine cells that share an edge share its sub-points; where a fine cell meets
// a plain one (or the grid's border) the solid's top steps vertically along their edge, between
// the fine cell's sub-points and the plain cell's straight edge.
struct ZMapFineCells {
  static constexpr int kSteps = 4;  // sub-cells along each side (a power of two: exact sub-steps)
  static constexpr int kSide = kSteps + 1;
  static constexpr int kPoints = kSide * kSide;  // sub-point (a, b) at a + kSide·b, a along x

  std::vector<std::uint32_t> cells;      // grid.index(i, j) of each fine cell's (i, j) corner, ascending
  std::vector<std::uint32_t> row_begin;  // fine cells of cell row j: [row_begin[j], row_begin[j + 1])
  std::vector<float> heights;            // kPoints per fine cell, in the order of `cells`; tops
                                         // (never below the map's empty height)
  bool empty() const { return cells.empty(); }
};

class ZMap {
 public:
  ZMapGrid grid;
  float empty_height = 0;      // height of points with no material above them
  std::vector<float> heights;  // point (i, j) at heights[grid.index(i, j)]
  ZMapFineCells fine;          // steep cells in finer detail; none unless set_fine_cells was called

  // The sub-grid heights of cell (i, j) (ZMapFineCells::kPoints of them), or nullptr for a
  // plain cell.
  const float* fine_cell(int i, int j) const {
    if (fine.cells.empty()) return nullptr;
    const auto row = static_cast<std::size_t>(j);
    const auto first = fine.cells.begin() + fine.row_begin[row], last = fine.cells.begin() + fine.row_begin[row + 1];
    if (first == last) return nullptr;
    const auto key = static_cast<std::uint32_t>(grid.index(i, j));
    const auto at = std::lower_bound(first, last, key);
    if (at == last || *at != key) return nullptr;
    return fine.heights.data() + static_cast<std::size_t>(at - fine.cells.begin()) * ZMapFineCells::kPoints;
  }

  // Makes the cells `cells` (grid.index of their (i, j) corners, any order, no repeats) fine,
  // with `sub_heights` (ZMapFineCells::kPoints per cell, in the order given). Each fine cell's
  // corners are set to the map's heights there and every height is raised to the empty
  // height; where two fine cells meet, the cell on the right (or above) takes the shared
  // edge's sub-points from the other, so they agree exactly. Change `heights` first: the fine
  // cells' corners are read here. Throws tridex::Error for a cell outside the grid's cells.
  void set_fine_cells(std::vector<std::uint32_t> cells, std::vector<float> sub_heights);

  ZMap() = default;
  ZMap(const ZMapGrid& g, float initial_height, float empty, ZMapLimits limits = {})
      : grid(g), empty_height(empty) {
    validate(g, limits);
    if (!std::isfinite(initial_height) || !std::isfinite(empty))
      detail::fail("Z-map: heights must be finite");
    heights.assign(g.size(), initial_height);
  }

  float height(int i, int j) const { return heights[grid.index(i, j)]; }
  bool is_empty(int i, int j) const { return height(i, j) <= empty_height; }

  // Step 1 initialisation from a box stock: each point holds the top of the (possibly tilted)
  // box above it, exactly, or `empty_height` outside the box's projection. Rows are split
  // among `threads` threads (0: every hardware thread); the map is the same for any count.
  static ZMap from_box(const Frame& frame, const Aabb& stock, double cell, ZMapLimits limits = {},
                       unsigned threads = 1);

  // Initialisation from the top surface of a closed mesh seen along the frame's z.
  static ZMap from_mesh(const Frame& frame, const Mesh& stock, double cell,
                        ZMapLimits limits = {});


  static void validate(const ZMapGrid& g, ZMapLimits limits) {
    detail::require_positive(g.cell, "Z-map cell size");
    detail::require_finite(g.x0, "Z-map origin x");
    detail::require_finite(g.y0, "Z-map origin y");
    if (g.nx < 1 || g.ny < 1)
      detail::fail("Z-map grid is empty (", g.nx, " x ", g.ny, " points)");
    if (g.size() > limits.max_points)
      detail::fail("Z-map grid of ", g.nx, " x ", g.ny, " points needs ",
                   static_cast<double>(g.size()) * 4.0 / (1 << 20), " MiB, over the limit of ",
                   limits.max_points, " points");
  }
};

// Prepares a milled map for the intersection W0 ∩ M1 ∩ … ∩ MN (Step 3): every point that still
// holds its height in `initial` (the same map before milling) is raised above the stock. W0
// carries the stock's shape exactly, so M_i needs only the cuts; left at the stock's own top,
// M_i's polyhedron would interpolate that top linearly, which lies below it in every cell that
// straddles a ridge or the silhouette of a tilted stock (and ramps down to the empty points
// around it), and so would shave W0 where direction i cut nothing. A point cut below the stock
// (to the empty height) stays low.
// A grid point just outside the stock's footprint, next to points that were cut, takes the cut
// surface extrapolated from them (the largest such value): between it and its neighbour the
// polyhedron spans the strip of stock up to the footprint's edge, and a raised point there
// would leave a fin of uncut stock in that strip, as thin as a cell and as tall as the cut
// (seen by the dexel rays across the edge only). Throws if the grids differ. Rows are split
// among `threads` threads (0: every hardware thread); the result is the same for any count.
void raise_uncut(ZMap& milled, const ZMap& initial, unsigned threads = 1);

// The same for a map that ZMap::from_box(milled.grid.frame, box_stock, milled.grid.cell) started:
// its initial heights are computed again row by row where they are needed, never stored, so a
// box stock costs no second map. Throws if that map's grid differs from `milled`'s.
void raise_uncut(ZMap& milled, const Aabb& box_stock, unsigned threads = 1);

// And for a map that ZMap::from_mesh(milled.grid.frame, stock, milled.grid.cell) started, its rows
// rasterised again from the triangles that cross them.
void raise_uncut(ZMap& milled, const Mesh& stock, unsigned threads = 1);

// ---------------------------------------------------------------------------------------------

namespace detail {

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

}  // namespace detail

inline ZMapGrid ZMapGrid::covering(const Frame& frame, const Aabb& local_box, double cell) {
  detail::require_positive(cell, "Z-map cell size");
  if (local_box.empty() || !is_finite(local_box.min) || !is_finite(local_box.max))
    detail::fail("Z-map: stock bounds are empty or not finite");
  ZMapGrid g;
  g.frame = frame;
  g.cell = cell;
  g.x0 = local_box.min.x;
  g.y0 = local_box.min.y;
  g.nx = detail::grid_count(local_box.max.x - local_box.min.x, cell, "Z-map");
  g.ny = detail::grid_count(local_box.max.y - local_box.min.y, cell, "Z-map");
  return g;
}

namespace detail {

// Row j of ZMap::from_box's heights on `g`: the top of the box above each point, or `empty`
// outside its projection. raise_uncut for a box computes the same rows again, so both must come
// from here to agree bit for bit.
inline void box_top_row(const ZMapGrid& g, const Aabb& stock, float empty, int j, float* row) {
  const Vec3 up = g.frame.axis();
  for (int i = 0; i < g.nx; ++i) {
    double s0, s1;
    const Vec3 p = g.frame.to_world(Vec3(g.x(i), g.y(j), 0));
    row[i] = line_box_interval(p, up, stock, s0, s1) ? static_cast<float>(s1) : empty;
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

}  // namespace detail

inline ZMap ZMap::from_box(const Frame& frame, const Aabb& stock, double cell, ZMapLimits limits, unsigned threads) {
  const auto [g, empty] = detail::box_map_grid(frame, stock, cell);
  ZMap map(g, empty, empty, limits);
  const auto bands = static_cast<std::size_t>((g.ny + detail::kMapBandRows - 1) / detail::kMapBandRows);
  detail::for_each_chunk(bands, threads, [&](std::size_t band) {
    const int j0 = static_cast<int>(band) * detail::kMapBandRows, j1 = std::min(g.ny, j0 + detail::kMapBandRows);
    for (int j = j0; j < j1; ++j) detail::box_top_row(g, stock, empty, j, map.heights.data() + g.index(0, j));
  });
  return map;
}

namespace detail {

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
    return {std::max(0, static_cast<int>(std::ceil((loy - grid_.y0) / grid_.cell - 1e-9))),
            std::min(grid_.ny - 1, static_cast<int>(std::floor((hiy - grid_.y0) / grid_.cell + 1e-9)))};
  }

  const std::vector<glm::uvec3>& triangles_;  // the stock's, which outlives this
  std::vector<Vec3> local_;
  ZMapGrid grid_;
  float empty_ = 0;
  std::vector<std::vector<std::uint32_t>> bands_;
};

}  // namespace detail

inline ZMap ZMap::from_mesh(const Frame& frame, const Mesh& stock, double cell,
                            ZMapLimits limits) {
  const detail::MeshTop top(frame, stock, cell);
  const ZMapGrid& g = top.grid();
  ZMap map(g, top.empty(), top.empty(), limits);
  for (std::size_t t = 0; t < top.triangles(); ++t)
    top.raster_rows(t, 0, g.ny - 1, [&](int i, int j) -> float& { return map.heights[g.index(i, j)]; });
  return map;
}

inline void ZMap::set_fine_cells(std::vector<std::uint32_t> cells, std::vector<float> sub_heights) {
  constexpr int kSide = ZMapFineCells::kSide, kSteps = ZMapFineCells::kSteps;
  constexpr auto kPoints = static_cast<std::size_t>(ZMapFineCells::kPoints);
  if (sub_heights.size() != cells.size() * kPoints)
    detail::fail("Z-map fine cells: ", sub_heights.size(), " sub-heights for ", cells.size(), " cells");
  // Sort the cells, carrying their heights along.
  std::vector<std::uint32_t> order(cells.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<std::uint32_t>(k);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) { return cells[a] < cells[b]; });
  fine = {};
  fine.cells.reserve(cells.size());
  fine.heights.reserve(sub_heights.size());
  for (std::uint32_t k : order) {
    const std::uint32_t c = cells[k];
    const int i = static_cast<int>(c % static_cast<std::uint32_t>(grid.nx)), j = static_cast<int>(c / static_cast<std::uint32_t>(grid.nx));
    if (i + 1 >= grid.nx || j + 1 >= grid.ny) detail::fail("Z-map fine cells: point ", c, " is not the corner of a cell");
    if (!fine.cells.empty() && fine.cells.back() == c) detail::fail("Z-map fine cells: cell ", c, " given twice");
    fine.cells.push_back(c);
    const float* from = sub_heights.data() + k * kPoints;
    for (std::size_t p = 0; p < kPoints; ++p) fine.heights.push_back(std::max(from[p], empty_height));
    float* h = fine.heights.data() + fine.heights.size() - kPoints;
    auto corner = [&](int di, int dj) { return std::max(height(i + di, j + dj), empty_height); };
    h[0] = corner(0, 0), h[kSteps] = corner(1, 0);
    h[kSteps * kSide] = corner(0, 1), h[kSteps + kSteps * kSide] = corner(1, 1);
  }
  fine.row_begin.assign(static_cast<std::size_t>(grid.ny), 0);
  for (std::size_t k = 0, row = 0; row < fine.row_begin.size(); ++row) {
    while (k < fine.cells.size() && fine.cells[k] < row * static_cast<std::size_t>(grid.nx)) ++k;
    fine.row_begin[row] = static_cast<std::uint32_t>(k);
  }
  // Shared edges: copied from the left or lower neighbour, which comes first in the order.
  for (std::size_t k = 0; k < fine.cells.size(); ++k) {
    const int i = static_cast<int>(fine.cells[k] % static_cast<std::uint32_t>(grid.nx)),
              j = static_cast<int>(fine.cells[k] / static_cast<std::uint32_t>(grid.nx));
    float* h = fine.heights.data() + k * kPoints;
    if (const float* left = i > 0 ? fine_cell(i - 1, j) : nullptr)
      for (int b = 0; b < kSide; ++b) h[b * kSide] = left[kSteps + b * kSide];
    if (const float* below = j > 0 ? fine_cell(i, j - 1) : nullptr)
      for (int a = 0; a < kSide; ++a) h[a] = below[a + kSteps * kSide];
  }
}

namespace detail {

// raise_uncut on the initial heights that initial_row(j, row) writes, row j of them into `row`
// (grid.nx floats), `initial_empty` being their empty height. The map is split into bands of
// rows. A first pass reads only: each band computes its initial rows (and two more on each
// side, which its points' neighbourhoods reach), marks the points still at their initial
// height and lists the extrapolated points outside the footprint. The second writes, each band
// its own rows: the marked points are raised, then the listed ones set, as before any band
// had written.
template <class InitialRow>
void raise_uncut_rows(ZMap& milled, float initial_empty, InitialRow&& initial_row, unsigned threads) {
  const ZMapGrid& a = milled.grid;
  const std::size_t nx = static_cast<std::size_t>(a.nx);
  const auto bands = static_cast<std::size_t>((a.ny + kMapBandRows - 1) / kMapBandRows);
  std::vector<std::uint8_t> uncut(a.size());
  std::vector<float> band_top(bands, milled.empty_height);
  // Each outside point next to a cut: its index and the largest continued height (unclamped).
  std::vector<std::vector<std::pair<std::size_t, float>>> continued(bands);
  for_each_chunk(bands, threads, [&](std::size_t band) {
    const int j0 = static_cast<int>(band) * kMapBandRows, j1 = std::min(a.ny, j0 + kMapBandRows);
    const int w0 = std::max(0, j0 - 2), w1 = std::min(a.ny, j1 + 2);  // rows of the window
    std::vector<float> window(static_cast<std::size_t>(w1 - w0) * nx);
    for (int j = w0; j < w1; ++j) initial_row(j, window.data() + static_cast<std::size_t>(j - w0) * nx);
    auto initial = [&](int i, int j) { return window[static_cast<std::size_t>(j - w0) * nx + static_cast<std::size_t>(i)]; };
    auto inside = [&](int i, int j) { return i >= 0 && j >= 0 && i < a.nx && j < a.ny && initial(i, j) > initial_empty; };
    auto cut = [&](int i, int j) { return inside(i, j) && milled.height(i, j) != initial(i, j); };
    float top = band_top[band];
    for (int j = j0; j < j1; ++j)
      for (int i = 0; i < a.nx; ++i) {
        const std::size_t p = a.index(i, j);
        top = std::max(top, initial(i, j));
        uncut[p] = milled.heights[p] == initial(i, j);
        if (inside(i, j)) continue;
        float best = -std::numeric_limits<float>::infinity();
        for (int dj = -1; dj <= 1; ++dj)
          for (int di = -1; di <= 1; ++di) {
            if ((di == 0 && dj == 0) || !cut(i + di, j + dj)) continue;
            const float near = milled.height(i + di, j + dj);
            const float far = cut(i + 2 * di, j + 2 * dj) ? milled.height(i + 2 * di, j + 2 * dj) : near;
            best = std::max(best, 2 * near - far);
          }
        if (best > -std::numeric_limits<float>::infinity()) continued[band].emplace_back(p, best);
      }
    band_top[band] = top;
  });
  const float top = *std::max_element(band_top.begin(), band_top.end());
  const float above = static_cast<float>(top + empty_margin(a.cell));
  milled.fine = {};  // the heights change under any fine cells
  for_each_chunk(bands, threads, [&](std::size_t band) {
    const std::size_t p0 = band * kMapBandRows * nx, p1 = std::min(a.size(), p0 + kMapBandRows * nx);
    for (std::size_t p = p0; p < p1; ++p)
      if (uncut[p]) milled.heights[p] = above;
    for (const auto& [p, h] : continued[band]) milled.heights[p] = std::clamp(h, milled.empty_height, above);
  });
}

}  // namespace detail

inline void raise_uncut(ZMap& milled, const ZMap& initial, unsigned threads) {
  const ZMapGrid &a = milled.grid, &b = initial.grid;
  if (!detail::same_points(a, b) || milled.heights.size() != initial.heights.size())
    detail::fail("raise_uncut: the milled and initial Z-maps have different grids");
  detail::raise_uncut_rows(
      milled, initial.empty_height,
      [&](int j, float* row) { std::copy_n(initial.heights.data() + b.index(0, j), b.nx, row); }, threads);
}

inline void raise_uncut(ZMap& milled, const Aabb& box_stock, unsigned threads) {
  const ZMapGrid& a = milled.grid;
  const auto [b, empty] = detail::box_map_grid(a.frame, box_stock, a.cell);
  if (!detail::same_points(a, b) || milled.heights.size() != b.size())
    detail::fail("raise_uncut: the milled Z-map's grid is not the box stock's");
  detail::raise_uncut_rows(
      milled, empty, [&](int j, float* row) { detail::box_top_row(b, box_stock, empty, j, row); }, threads);
}

inline void raise_uncut(ZMap& milled, const Mesh& stock, unsigned threads) {
  const ZMapGrid& a = milled.grid;
  detail::MeshTop top(a.frame, stock, a.cell);
  if (!detail::same_points(a, top.grid()) || milled.heights.size() != top.grid().size())
    detail::fail("raise_uncut: the milled Z-map's grid is not the stock mesh's");
  top.index_bands();
  detail::raise_uncut_rows(milled, top.empty(), [&](int j, float* row) { top.row(j, row); }, threads);
}

}  // namespace tridex
