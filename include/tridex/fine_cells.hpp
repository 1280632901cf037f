// tridex — fine cells: walls inside their Z-map cells (issue 17; the step-like errors of Inui,
// Chen and Umezu, CAD&A 19(4) 2022, §5, at walls parallel to a spindle).
//
// A milled Z-map knows its heights at grid points only. Where a wall parallel to the spindle
// crosses a cell (a pocket's side, or the edge of a cut next to stock that raise_uncut lifted),
// the cell's corners differ by much more than the cell is wide, and the polyhedron's two
// triangles ramp across it: off by up to a cell at the wall's rims. The moves know where the
// wall is. refine_steep_cells gives every such cell a sub-grid (ZMapFineCells, zmap.hpp) whose
// heights it takes from the moves exactly as milling does at a grid point:
//     H(q) = min( ceiling, min over moves of the lowest point of the swept cutter above q )
// (mill.hpp's MoveGeometry::lowest), the ceiling being the map's highest point, where
// raise_uncut put what no move cut. The polyhedron, the grid tree and the scan converter then
// place the wall within a sub-cell (a quarter cell).
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <utility>
#include <vector>

#include "tridex/dexel_ops.hpp"
#include "tridex/geometry.hpp"
#include "tridex/mill.hpp"
#include "tridex/parallel.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

// refine_steep_cells works on bands of this many cell rows (and tiles this many columns wide).
inline constexpr int kWallBandRows = 16;

struct WallOptions {
  // A cell is steep when its corners' heights differ by more than this many cell widths:
  // raise_uncut's lift (two cells) at the edge of every cut passes it, a 55° slope does not.
  double steep_slope = 1.5;
  unsigned threads = 0;  // 0: every hardware thread
};

// Whether cell (i, j) of `map` (its corners i..i+1, j..j+1) is steep: its corners' heights,
// those below the empty height raised to it, differ by more than `steep_slope` cell widths.
// refine_steep_cells makes these cells fine; the command counts them with it beforehand.
inline bool is_steep_cell(const ZMap& map, int i, int j, double steep_slope) {
  auto top = [&](int a, int b) { return double(std::max(map.height(a, b), map.empty_height)); };
  const double a = top(i, j), b = top(i + 1, j), c = top(i, j + 1), d = top(i + 1, j + 1);
  return std::max({a, b, c, d}) - std::min({a, b, c, d}) > steep_slope * map.grid.cell;
}

// The steep cells of `map` (grid.index of their (i, j) corners), ascending. Rows are split
// among `threads` threads (0: every hardware thread); the list is the same for any count.
inline std::vector<std::uint32_t> steep_cells(const ZMap& map, double steep_slope,
                                              unsigned threads = 1) {
  const ZMapGrid& g = map.grid;
  const auto bands =
      static_cast<std::size_t>((g.ny - 1 + detail::kMapBandRows - 1) / detail::kMapBandRows);
  std::vector<std::vector<std::uint32_t>> found(bands);
  detail::for_each_chunk(bands, threads, [&](std::size_t band) {
    const int j0 = static_cast<int>(band) * detail::kMapBandRows,
              j1 = std::min(g.ny - 1, j0 + detail::kMapBandRows);
    for (int j = j0; j < j1; ++j)
      for (int i = 0; i + 1 < g.nx; ++i)
        if (is_steep_cell(map, i, j, steep_slope))
          found[band].push_back(static_cast<std::uint32_t>(g.index(i, j)));
  });
  std::vector<std::uint32_t> cells;
  for (const auto& part : found) cells.insert(cells.end(), part.begin(), part.end());
  return cells;
}

namespace detail {

// The moves whose swept box reaches each band of kWallBandRows cell rows, in program order: a
// counting sort (one pass to count, one to place), so that a band never scans the whole program.
// Only the bands `wanted` marks get their moves (the others stay empty): those that hold a fine
// cell, so that the lists cost in proportion to the walls, not to every move's every band.
struct MovesByBand {
  // Band b's moves are band_moves[band_begin[b]] up to band_moves[band_begin[b + 1]].
  std::vector<std::size_t> band_begin;
  std::vector<std::uint32_t> band_moves;
};
inline MovesByBand moves_by_band(const ZMapGrid& g, std::span<const Cutter> cutters,
                                 std::span<const CutMove> moves, int bands,
                                 std::span<const std::uint8_t> wanted) {
  constexpr int kBandRows = kWallBandRows;
  auto band_range = [&](const CutMove& m) {
    const double r = cutters[m.cutter].radius();
    const double lo_y = std::min(m.tip.a.y, m.tip.b.y) - r,
                 hi_y = std::max(m.tip.a.y, m.tip.b.y) + r;
    const double row0 = std::floor((lo_y - g.y0) / g.cell),
                 row1 = std::floor((hi_y - g.y0) / g.cell);
    return std::pair{
        static_cast<int>(std::clamp(row0, 0.0, double(g.ny - 1))) / kBandRows,
        row1 < 0 ? -1 : static_cast<int>(std::min(row1, double(g.ny - 2))) / kBandRows};
  };
  MovesByBand by_band;
  std::vector<std::size_t>& band_begin = by_band.band_begin;
  band_begin.assign(static_cast<std::size_t>(bands) + 1, 0);
  for (const CutMove& m : moves)
    for (auto [b0, b1] = band_range(m); b0 <= b1; ++b0)
      band_begin[static_cast<std::size_t>(b0) + 1] += wanted[static_cast<std::size_t>(b0)];
  for (std::size_t b = 0; b < static_cast<std::size_t>(bands); ++b)
    band_begin[b + 1] += band_begin[b];
  std::vector<std::uint32_t>& band_moves = by_band.band_moves;
  band_moves.resize(band_begin.back());
  {
    std::vector<std::size_t> at(band_begin.begin(), band_begin.end() - 1);
    for (std::size_t m = 0; m < moves.size(); ++m)
      for (auto [b0, b1] = band_range(moves[m]); b0 <= b1; ++b0)
        if (wanted[static_cast<std::size_t>(b0)])
          band_moves[at[static_cast<std::size_t>(b0)]++] = static_cast<std::uint32_t>(m);
  }
  return by_band;
}

// A move near a band's fine cells (lower_fine_cells): its lowest tip, and the cell rows and
// columns of the band its swept box reaches.
struct FineCellMove {
  double tip;
  std::uint32_t move, i0, i1;
  int row0, row1;
};

// The cell rows and columns a move's swept box spans (rows clamped to -1..ny, columns to 0..nx):
// computed once per move, not in each of the (a D10 at 0.026 mm: about 26) bands it crosses.
struct FineCellBox {
  int row0, row1;
  std::uint32_t i0, i1;
};
inline FineCellBox fine_cell_box(const ZMapGrid& g, const Segment& s, double r) {
  const double lo_y = std::min(s.a.y, s.b.y) - r, hi_y = std::max(s.a.y, s.b.y) + r;
  auto row = [&](double y) {
    return static_cast<int>(std::clamp(std::floor((y - g.y0) / g.cell), -1.0, double(g.ny)));
  };
  auto column = [&](double x) {
    return static_cast<std::uint32_t>(
        std::clamp(std::floor((x - g.x0) / g.cell), 0.0, double(g.nx)));
  };
  return {row(lo_y), row(hi_y), column(std::min(s.a.x, s.b.x) - r),
          column(std::max(s.a.x, s.b.x) + r)};
}

// Lowers the sub-points of the fine cells in rows n.row0..n.row1, columns n.i0..n.i1, to the
// lowest point of the swept cutter of one move above them; cell_top[k] is the highest sub-point
// of cells[k], kept so.
inline void lower_cells_under_move(const ZMapGrid& g, const Cutter& cutter, const Segment& s,
                                   const FineCellMove& n, const std::vector<std::uint32_t>& cells,
                                   const std::vector<std::size_t>& row_begin,
                                   std::vector<float>& cell_top, std::vector<float>& sub) {
  constexpr int kSteps = ZMapFineCells::kSteps, kSide = ZMapFineCells::kSide;
  constexpr auto kPoints = static_cast<std::size_t>(ZMapFineCells::kPoints);
  const double step = g.cell / kSteps;  // exact: kSteps is a power of two
  const double half_diagonal = g.cell * std::sqrt(0.5) * (1 + 1e-9);
  const double tile_half_diagonal = kWallBandRows * half_diagonal;
  const double r = cutter.radius();
  // Built here, for the few (band, move) pairs that come this far: kept for every move up
  // front, the program's geometry took longer to write than the bands take to read.
  const detail::MoveGeometry move(cutter, s);
  const double tip = move.lowest_tip();
  for (int j = n.row0; j <= n.row1; ++j) {
    const auto row = static_cast<std::size_t>(j), base = row * static_cast<std::size_t>(g.nx);
    const auto first = cells.begin() + static_cast<std::ptrdiff_t>(row_begin[row]);
    const auto last = cells.begin() + static_cast<std::ptrdiff_t>(row_begin[row + 1]);
    for (auto c = std::lower_bound(first, last, static_cast<std::uint32_t>(base + n.i0));
         c != last && *c <= base + n.i1; ++c) {
      const auto index = static_cast<std::size_t>(c - cells.begin());
      if (tip >= double(cell_top[index])) continue;
      const int i = static_cast<int>(*c - base);
      // The cell's sub-points lie at least `reach` from the tip path in XY. Beyond the radius
      // the cutter never passes over them; within it, the swept cutter stands at least the
      // profile's height at `reach` above its lowest tip there (profiles rise outward), less a
      // rounding margin far below float heights.
      const double cx = g.x0 + (i + 0.5) * g.cell, cy = g.y0 + (j + 0.5) * g.cell;
      const double reach =
          std::sqrt(distance2_point_segment(Vec2(cx, cy), Vec2(s.a.x, s.a.y), Vec2(s.b.x, s.b.y))) -
          half_diagonal;
      if (reach > r + tile_half_diagonal) continue;
      const double bound = tip + cutter.lower_height(std::max(0.0, reach)) - 1e-6;
      if (bound >= double(cell_top[index])) continue;
      // The same bound, sub-point by sub-point: a wall cell next to uncut stock keeps its top at
      // the ceiling, so the cell's test passes for every move near it, while its sub-points
      // already cut at or below the bound cannot be lowered by this move.
      float* h = sub.data() + index * kPoints;
      for (int b = 0; b < kSide; ++b)
        for (int a = 0; a < kSide; ++a) {
          float& to = h[a + kSide * b];
          if (bound >= double(to)) continue;
          const double x = g.x0 + (kSteps * i + a) * step, y = g.y0 + (kSteps * j + b) * step;
          const double z = move.lowest(x, y).z;
          if (z < double(to)) to = static_cast<float>(z);
        }
      cell_top[index] = *std::max_element(h, h + kPoints);
    }
  }
}

// The heart of refine_steep_cells: lowers `sub` (the fine cells' sub-point heights, kPoints per
// cell of `cells`, all starting at `ceiling`) to the lowest point of every move's swept cutter
// above them, band by band on `threads` threads (0: every hardware thread). row_begin[j] is the
// first of `cells` in cell row j (cells.size() where the row has none).
inline void lower_fine_cells(const ZMapGrid& g, std::span<const Cutter> cutters,
                             std::span<const CutMove> moves,
                             const std::vector<std::uint32_t>& cells,
                             const std::vector<std::size_t>& row_begin, float ceiling,
                             unsigned threads, std::vector<float>& sub) {
  // Bands of cell rows, one thread each at a time. Each band gets the moves whose swept box
  // reaches it, in program order (a counting sort: one pass to count, one to place), so that a
  // band never scans the whole program: a 5000-row map has 313 bands.
  constexpr int kBandRows = kWallBandRows;
  const int bands = (g.ny - 1 + kBandRows - 1) / kBandRows;
  std::vector<std::uint8_t> wanted(static_cast<std::size_t>(bands));
  for (int band = 0; band < bands; ++band)
    wanted[static_cast<std::size_t>(band)] =
        row_begin[static_cast<std::size_t>(band * kBandRows)] !=
        row_begin[static_cast<std::size_t>(std::min(g.ny - 1, (band + 1) * kBandRows))];
  const MovesByBand by_band = moves_by_band(g, cutters, moves, bands, wanted);
  const std::vector<std::size_t>& band_begin = by_band.band_begin;
  const std::vector<std::uint32_t>& band_moves = by_band.band_moves;
  // The highest sub-point of each fine cell so far: a move whose swept cutter cannot reach below
  // it over the cell cannot lower any of them, and is skipped.
  std::vector<float> cell_top(cells.size(), ceiling);
  const double half_diagonal = g.cell * std::sqrt(0.5) * (1 + 1e-9);
  // Which tiles (a band's rows by as many columns) hold a fine cell.
  constexpr std::size_t kBandTile = kBandRows;
  const std::size_t tiles_x = (static_cast<std::size_t>(g.nx) - 1 + kBandTile - 1) / kBandTile;
  const double tile_half_diagonal = kBandTile * half_diagonal;
  std::vector<std::uint8_t> tile_walls(static_cast<std::size_t>(bands) * tiles_x, 0);
  for (std::uint32_t c : cells)
    tile_walls[c / static_cast<std::uint32_t>(g.nx) / kBandRows * tiles_x +
               c % static_cast<std::uint32_t>(g.nx) / kBandTile] = 1;
  // Each band's wall tiles in ascending order (band b's are wall_tiles[wall_begin[b]] up to
  // wall_tiles[wall_begin[b + 1]]): a move's box is matched against them by binary search
  // instead of a scan over every tile it spans (a raster line spans the whole map).
  std::vector<std::size_t> wall_begin(static_cast<std::size_t>(bands) + 1, 0);
  std::vector<std::uint32_t> wall_tiles;
  for (std::size_t t = 0; t < tile_walls.size(); ++t)
    if (tile_walls[t]) {
      wall_tiles.push_back(static_cast<std::uint32_t>(t % tiles_x));
      ++wall_begin[t / tiles_x + 1];
    }
  for (std::size_t b = 0; b < static_cast<std::size_t>(bands); ++b)
    wall_begin[b + 1] += wall_begin[b];
  std::vector<FineCellBox> boxes(moves.size());
  detail::for_each_chunk((moves.size() + 65535) / 65536, threads, [&](std::size_t chunk) {
    for (std::size_t m = chunk * 65536; m < std::min(moves.size(), (chunk + 1) * 65536); ++m)
      boxes[m] = fine_cell_box(g, moves[m].tip, cutters[moves[m].cutter].radius());
  });
  detail::for_each_chunk(static_cast<std::size_t>(bands), threads, [&](std::size_t band_index) {
    const int band = static_cast<int>(band_index);
    const int j0 = band * kBandRows, j1 = std::min(g.ny - 1, j0 + kBandRows);
    if (row_begin[static_cast<std::size_t>(j0)] == row_begin[static_cast<std::size_t>(j1)]) return;
    const auto band_tiles_begin =
                   wall_tiles.begin() + static_cast<std::ptrdiff_t>(wall_begin[band_index]),
               band_tiles_end =
                   wall_tiles.begin() + static_cast<std::ptrdiff_t>(wall_begin[band_index + 1]);
    // The band's moves that come near one of its fine cells, lowest first: a sub-point's height
    // is the minimum over the moves, whatever their order, and taken deepest first it is near
    // its end at once, so that the moves above (a roughing program's earlier layers) fail the
    // bound below instead of lowering it again, layer by layer.
    std::vector<FineCellMove> near;
    for (std::size_t at = band_begin[static_cast<std::size_t>(band)];
         at < band_begin[static_cast<std::size_t>(band) + 1]; ++at) {
      const std::uint32_t m = band_moves[at];
      const FineCellBox& box = boxes[m];
      const int row0 = std::max(j0, box.row0), row1 = std::min(j1 - 1, box.row1);
      if (row0 > row1) continue;
      std::uint32_t i0 = box.i0, i1 = box.i1;
      const Segment& s = moves[m].tip;
      const double r = cutters[moves[m].cutter].radius();
      // Only the band's tiles that hold a fine cell and come within the radius of the tip
      // path: most of a map has no wall, and a move's box spans many cell rows.
      constexpr auto kWallTile = static_cast<std::uint32_t>(kBandTile);
      const std::uint32_t tx0 = i0 / kWallTile,
                          tx1 = std::min(i1, static_cast<std::uint32_t>(g.nx - 2)) / kWallTile;
      auto near_tile = [&](std::uint32_t tx) {
        const double cx = g.x0 + (double(tx) + 0.5) * kBandTile * g.cell,
                     cy = g.y0 + 0.5 * (j0 + j1) * g.cell;
        return distance2_point_segment(Vec2(cx, cy), Vec2(s.a.x, s.a.y), Vec2(s.b.x, s.b.y)) <=
               (r + tile_half_diagonal) * (r + tile_half_diagonal);
      };
      // The first and the last of the band's wall tiles in tx0..tx1 that pass near_tile.
      const auto first = std::lower_bound(band_tiles_begin, band_tiles_end, tx0);
      const auto last = std::upper_bound(first, band_tiles_end, tx1);
      auto lo = first;
      while (lo != last && !near_tile(*lo)) ++lo;
      if (lo == last) continue;
      auto hi = last - 1;
      while (!near_tile(*hi)) --hi;  // stops at lo, which passes
      const std::size_t first_tile = *lo, last_tile = *hi;
      i0 = std::max(i0, static_cast<std::uint32_t>(first_tile * kBandTile));
      i1 = std::min(i1, static_cast<std::uint32_t>(last_tile * kBandTile + kBandTile - 1));
      near.push_back({std::min(s.a.z, s.b.z), m, i0, i1, row0, row1});
    }
    std::sort(near.begin(), near.end(), [](const FineCellMove& a, const FineCellMove& b) {
      return a.tip < b.tip || (a.tip == b.tip && a.move < b.move);
    });
    for (const FineCellMove& n : near)
      lower_cells_under_move(g, cutters[moves[n.move].cutter], moves[n.move].tip, n, cells,
                             row_begin, cell_top, sub);
  });
}

}  // namespace detail

// Makes the steep cells of `map` fine, with sub-point heights from the moves it was milled with
// (the same cutters and moves, in its frame). Call it on a map prepared by raise_uncut, last:
// it reads the map's heights. `cells` are the map's steep cells as steep_cells gives them
// (with options.steep_slope), for a caller that needed them beforehand. Throws tridex::Error
// for a move with a cutter out of range.
inline void refine_steep_cells(ZMap& map, std::span<const Cutter> cutters,
                               std::span<const CutMove> moves, WallOptions options,
                               std::vector<std::uint32_t> cells) {
  constexpr auto kPoints = static_cast<std::size_t>(ZMapFineCells::kPoints);
  for (std::size_t k = 0; k < moves.size(); ++k)
    if (moves[k].cutter >= cutters.size())
      detail::fail("refine steep cells: move ", k, " uses cutter ", moves[k].cutter, " but only ",
                   cutters.size(), " are given");
  const ZMapGrid& g = map.grid;
  const auto map_bands =
      static_cast<std::size_t>((g.ny + detail::kMapBandRows - 1) / detail::kMapBandRows);
  std::vector<float> band_ceiling(map_bands, map.empty_height);
  detail::for_each_chunk(map_bands, options.threads, [&](std::size_t band) {
    const std::size_t p0 = band * detail::kMapBandRows * static_cast<std::size_t>(g.nx);
    const std::size_t p1 =
        std::min(g.size(), p0 + detail::kMapBandRows * static_cast<std::size_t>(g.nx));
    for (std::size_t p = p0; p < p1; ++p)
      band_ceiling[band] = std::max(band_ceiling[band], map.heights[p]);
  });
  const float ceiling = *std::max_element(band_ceiling.begin(), band_ceiling.end());
  if (cells.empty()) {
    map.fine = {};
    return;
  }
  // Cells come out ascending, so a row's fine cells are a contiguous, sorted run.
  std::vector<std::size_t> row_begin(static_cast<std::size_t>(g.ny), cells.size());
  for (std::size_t k = cells.size(); k-- > 0;)
    row_begin[cells[k] / static_cast<std::uint32_t>(g.nx)] = k;
  for (std::size_t row = row_begin.size() - 1; row-- > 0;)
    row_begin[row] = std::min(row_begin[row], row_begin[row + 1]);

  std::vector<float> sub(cells.size() * kPoints, ceiling);
  detail::lower_fine_cells(g, cutters, moves, cells, row_begin, ceiling, options.threads, sub);
  map.set_fine_cells(std::move(cells), std::move(sub));
}

// The same, finding the steep cells itself.
inline void refine_steep_cells(ZMap& map, std::span<const Cutter> cutters,
                               std::span<const CutMove> moves, WallOptions options = {}) {
  refine_steep_cells(map, cutters, moves, options,
                     steep_cells(map, options.steep_slope, options.threads));
}

}  // namespace tridex
