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

  std::vector<std::uint32_t>
      cells;  // grid.index(i, j) of each fine cell's (i, j) corner, ascending
  std::vector<std::uint32_t>
      row_begin;               // fine cells of cell row j: [row_begin[j], row_begin[j + 1])
  std::vector<float> heights;  // kPoints per fine cell, in the order of `cells`; tops
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
    const auto first = fine.cells.begin() + fine.row_begin[row],
               last = fine.cells.begin() + fine.row_begin[row + 1];
    if (first == last) return nullptr;
    const auto key = static_cast<std::uint32_t>(grid.index(i, j));
    const auto at = std::lower_bound(first, last, key);
    if (at == last || *at != key) return nullptr;
    return fine.heights.data() +
           static_cast<std::size_t>(at - fine.cells.begin()) * ZMapFineCells::kPoints;
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
  static ZMap from_mesh(const Frame& frame, const Mesh& stock, double cell, ZMapLimits limits = {});

  static void validate(const ZMapGrid& g, ZMapLimits limits) {
    detail::require_positive(g.cell, "Z-map cell size");
    detail::require_finite(g.x0, "Z-map origin x");
    detail::require_finite(g.y0, "Z-map origin y");
    if (g.nx < 1 || g.ny < 1) detail::fail("Z-map grid is empty (", g.nx, " x ", g.ny, " points)");
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

}  // namespace tridex

#include "tridex/detail/zmap_rows.hpp"

namespace tridex {

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

inline ZMap ZMap::from_box(const Frame& frame, const Aabb& stock, double cell, ZMapLimits limits,
                           unsigned threads) {
  // Named copies, not a structured binding: clang 14 cannot capture bindings in the lambda.
  const std::pair<ZMapGrid, float> grid_and_empty = detail::box_map_grid(frame, stock, cell);
  const ZMapGrid& g = grid_and_empty.first;
  const float empty = grid_and_empty.second;
  ZMap map(g, empty, empty, limits);
  const auto bands =
      static_cast<std::size_t>((g.ny + detail::kMapBandRows - 1) / detail::kMapBandRows);
  detail::for_each_chunk(bands, threads, [&](std::size_t band) {
    const int j0 = static_cast<int>(band) * detail::kMapBandRows,
              j1 = std::min(g.ny, j0 + detail::kMapBandRows);
    for (int j = j0; j < j1; ++j)
      detail::box_top_row(g, stock, empty, j, map.heights.data() + g.index(0, j));
  });
  return map;
}

inline ZMap ZMap::from_mesh(const Frame& frame, const Mesh& stock, double cell, ZMapLimits limits) {
  const detail::MeshTop top(frame, stock, cell);
  const ZMapGrid& g = top.grid();
  ZMap map(g, top.empty(), top.empty(), limits);
  for (std::size_t t = 0; t < top.triangles(); ++t)
    top.raster_rows(t, 0, g.ny - 1,
                    [&](int i, int j) -> float& { return map.heights[g.index(i, j)]; });
  return map;
}

inline void ZMap::set_fine_cells(std::vector<std::uint32_t> cells, std::vector<float> sub_heights) {
  constexpr int kSide = ZMapFineCells::kSide, kSteps = ZMapFineCells::kSteps;
  constexpr auto kPoints = static_cast<std::size_t>(ZMapFineCells::kPoints);
  if (sub_heights.size() != cells.size() * kPoints)
    detail::fail("Z-map fine cells: ", sub_heights.size(), " sub-heights for ", cells.size(),
                 " cells");
  // Sort the cells, carrying their heights along.
  std::vector<std::uint32_t> order(cells.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<std::uint32_t>(k);
  std::sort(order.begin(), order.end(),
            [&](std::uint32_t a, std::uint32_t b) { return cells[a] < cells[b]; });
  fine = {};
  fine.cells.reserve(cells.size());
  fine.heights.reserve(sub_heights.size());
  for (std::uint32_t k : order) {
    const std::uint32_t c = cells[k];
    const int i = static_cast<int>(c % static_cast<std::uint32_t>(grid.nx)),
              j = static_cast<int>(c / static_cast<std::uint32_t>(grid.nx));
    if (i + 1 >= grid.nx || j + 1 >= grid.ny)
      detail::fail("Z-map fine cells: point ", c, " is not the corner of a cell");
    if (!fine.cells.empty() && fine.cells.back() == c)
      detail::fail("Z-map fine cells: cell ", c, " given twice");
    fine.cells.push_back(c);
    const float* from = sub_heights.data() + k * kPoints;
    for (std::size_t p = 0; p < kPoints; ++p)
      fine.heights.push_back(std::max(from[p], empty_height));
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

inline void raise_uncut(ZMap& milled, const ZMap& initial, unsigned threads) {
  const ZMapGrid &a = milled.grid, &b = initial.grid;
  if (!detail::same_points(a, b) || milled.heights.size() != initial.heights.size())
    detail::fail("raise_uncut: the milled and initial Z-maps have different grids");
  detail::raise_uncut_rows(
      milled, initial.empty_height,
      [&](int j, float* row) { std::copy_n(initial.heights.data() + b.index(0, j), b.nx, row); },
      threads);
}

inline void raise_uncut(ZMap& milled, const Aabb& box_stock, unsigned threads) {
  const ZMapGrid& a = milled.grid;
  const std::pair<ZMapGrid, float> grid_and_empty =
      detail::box_map_grid(a.frame, box_stock, a.cell);
  const ZMapGrid& b = grid_and_empty.first;  // a structured binding: clang 14 cannot capture it
  const float empty = grid_and_empty.second;
  if (!detail::same_points(a, b) || milled.heights.size() != b.size())
    detail::fail("raise_uncut: the milled Z-map's grid is not the box stock's");
  detail::raise_uncut_rows(
      milled, empty, [&](int j, float* row) { detail::box_top_row(b, box_stock, empty, j, row); },
      threads);
}

inline void raise_uncut(ZMap& milled, const Mesh& stock, unsigned threads) {
  const ZMapGrid& a = milled.grid;
  detail::MeshTop top(a.frame, stock, a.cell);
  if (!detail::same_points(a, top.grid()) || milled.heights.size() != top.grid().size())
    detail::fail("raise_uncut: the milled Z-map's grid is not the stock mesh's");
  top.index_bands();
  detail::raise_uncut_rows(
      milled, top.empty(), [&](int j, float* row) { top.row(j, row); }, threads);
}

}  // namespace tridex
