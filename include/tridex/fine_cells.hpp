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
#include <limits>
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
// among `threads` threads (0: every hardware thread); the list is the same for any count. Each
// row is tested as is_steep_cell does, in float where that is exact (the corners' maximum and
// minimum), so that the compiler can vectorise it, and its few steep cells picked out after.
inline std::vector<std::uint32_t> steep_cells(const ZMap& map, double steep_slope,
                                              unsigned threads = 1) {
  const ZMapGrid& g = map.grid;
  const auto bands =
      static_cast<std::size_t>((g.ny - 1 + detail::kMapBandRows - 1) / detail::kMapBandRows);
  const auto nx = static_cast<std::size_t>(g.nx), cells_x = nx - 1;  // a grid has a point
  const double threshold = steep_slope * g.cell;
  const float e = map.empty_height;
  std::vector<std::vector<std::uint32_t>> found(bands);
  detail::for_each_chunk(bands, threads, [&](std::size_t band) {
    const int j0 = static_cast<int>(band) * detail::kMapBandRows,
              j1 = std::min(g.ny - 1, j0 + detail::kMapBandRows);
    // Copies: the flags are bytes, which may alias anything captured by reference.
    const std::size_t n = cells_x;
    const float empty = e;
    const double limit = threshold;
    std::vector<std::uint8_t> steep(nx);
    for (int j = j0; j < j1; ++j) {
      const float* h0 = map.heights.data() + g.index(0, j);
      const float* h1 = h0 + nx;
      for (std::size_t i = 0; i < n; ++i) {
        const float a = h0[i] < empty ? empty : h0[i], b = h0[i + 1] < empty ? empty : h0[i + 1];
        const float c = h1[i] < empty ? empty : h1[i], d = h1[i + 1] < empty ? empty : h1[i + 1];
        const float ab_hi = a < b ? b : a, cd_hi = c < d ? d : c;
        const float ab_lo = b < a ? b : a, cd_lo = d < c ? d : c;
        const float hi = ab_hi < cd_hi ? cd_hi : ab_hi, lo = cd_lo < ab_lo ? cd_lo : ab_lo;
        steep[i] = double(hi) - double(lo) > limit;
      }
      for (std::size_t i = 0; i < n; ++i)
        if (steep[i]) found[band].push_back(static_cast<std::uint32_t>(g.index(0, j) + i));
    }
  });
  std::vector<std::uint32_t> cells;
  for (const auto& part : found) cells.insert(cells.end(), part.begin(), part.end());
  return cells;
}

namespace detail {

// The tiles (kWallBandRows cell rows by as many columns) that hold a fine cell, listed band by
// band and counted in a summed-area table, so that a move learns from four numbers whether its
// swept box reaches any wall: on a whole program's map most moves' boxes reach none.
struct WallTiles {
  std::size_t tiles_x = 0, bands = 0;
  // (bands + 1) × (tiles_x + 1): the wall tiles in the bands before b and the columns before t.
  std::vector<std::uint32_t> area;
  std::vector<std::size_t> band_begin;  // band b's: tiles[band_begin[b]] up to band_begin[b + 1]
  std::vector<std::uint32_t> tiles;     // their tile columns, ascending within a band

  // The wall tiles in bands b0..b1 and tile columns t0..t1 (none when either range is empty).
  std::uint32_t count(std::size_t b0, std::size_t b1, std::size_t t0, std::size_t t1) const {
    if (b0 > b1 || t0 > t1) return 0;
    const std::size_t w = tiles_x + 1;
    return area[(b1 + 1) * w + t1 + 1] - area[b0 * w + t1 + 1] - area[(b1 + 1) * w + t0] +
           area[b0 * w + t0];
  }
};
inline WallTiles wall_tiles(const ZMapGrid& g, std::size_t bands,
                            const std::vector<std::uint32_t>& cells) {
  constexpr auto kWallTile = static_cast<std::uint32_t>(kWallBandRows);
  WallTiles w;
  w.bands = bands;
  w.tiles_x = (static_cast<std::size_t>(g.nx) - 1 + kWallTile - 1) / kWallTile;
  std::vector<std::uint8_t> wall(bands * w.tiles_x, 0);
  const auto nx = static_cast<std::uint32_t>(g.nx);
  for (std::uint32_t c : cells) wall[c / nx / kWallTile * w.tiles_x + c % nx / kWallTile] = 1;
  const std::size_t width = w.tiles_x + 1;
  w.area.assign((bands + 1) * width, 0);
  w.band_begin.assign(bands + 1, 0);
  for (std::size_t b = 0; b < bands; ++b) {
    std::uint32_t in_row = 0;
    for (std::size_t t = 0; t < w.tiles_x; ++t) {
      if (wall[b * w.tiles_x + t]) w.tiles.push_back(static_cast<std::uint32_t>(t)), ++in_row;
      w.area[(b + 1) * width + t + 1] = w.area[b * width + t + 1] + in_row;
    }
    w.band_begin[b + 1] = w.tiles.size();
  }
  return w;
}

// A move near a band's fine cells (lower_fine_cells): its lowest tip (MoveGeometry::lowest_tip),
// and the cell rows and columns of the band its swept box reaches.
struct FineCellMove {
  double tip;
  std::uint32_t move, i0, i1;
  int row0, row1;
};

// The cell rows and columns a move's swept box spans (rows clamped to -1..ny, columns to 0..nx).
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

// Whether wall tile column tx of the band of cell rows j0..j1 comes within the radius r of the
// tip path s: no sub-point of a tile that does not can be passed over by the move.
inline bool near_wall_tile(const ZMapGrid& g, int j0, int j1, std::uint32_t tx, const Segment& s,
                           double r) {
  const double tile_half_diagonal = kWallBandRows * g.cell * std::sqrt(0.5) * (1 + 1e-9);
  const double cx = g.x0 + (double(tx) + 0.5) * kWallBandRows * g.cell,
               cy = g.y0 + 0.5 * (j0 + j1) * g.cell;
  return distance2_point_segment(Vec2(cx, cy), Vec2(s.a.x, s.a.y), Vec2(s.b.x, s.b.y)) <=
         (r + tile_half_diagonal) * (r + tile_half_diagonal);
}

// Each band's moves that come near one of its wall tiles, in program order (tip not yet set),
// their columns cut to the span of the wall tiles they come near. Moves are taken in chunks on
// `threads` threads; a move whose swept box holds no wall tile costs one look at the table.
inline std::vector<std::vector<FineCellMove>> near_moves_by_band(const ZMapGrid& g,
                                                                 std::span<const Cutter> cutters,
                                                                 std::span<const CutMove> moves,
                                                                 const WallTiles& walls,
                                                                 unsigned threads) {
  constexpr int kBandRows = kWallBandRows;
  constexpr auto kWallTile = static_cast<std::uint32_t>(kWallBandRows);
  constexpr std::size_t kChunk = 65536;
  const std::size_t chunks = (moves.size() + kChunk - 1) / kChunk;
  std::vector<std::vector<FineCellMove>> found(chunks);
  for_each_chunk(chunks, threads, [&](std::size_t chunk) {
    for (std::size_t m = chunk * kChunk; m < std::min(moves.size(), (chunk + 1) * kChunk); ++m) {
      const Segment& s = moves[m].tip;
      const double r = cutters[moves[m].cutter].radius();
      const FineCellBox box = fine_cell_box(g, s, r);
      if (box.row1 < 0 || box.row0 > g.ny - 2) continue;
      const auto b0 = static_cast<std::size_t>(std::max(box.row0, 0) / kBandRows),
                 b1 = static_cast<std::size_t>(std::min(box.row1, g.ny - 2) / kBandRows);
      const std::uint32_t tx0 = box.i0 / kWallTile,
                          tx1 = std::min(box.i1, static_cast<std::uint32_t>(g.nx - 2)) / kWallTile;
      if (walls.count(b0, b1, tx0, tx1) == 0) continue;
      for (std::size_t band = b0; band <= b1; ++band) {
        if (walls.count(band, band, tx0, tx1) == 0) continue;
        const int j0 = static_cast<int>(band) * kBandRows, j1 = std::min(g.ny - 1, j0 + kBandRows);
        const int row0 = std::max(j0, box.row0), row1 = std::min(j1 - 1, box.row1);
        if (row0 > row1) continue;
        const auto begin =
                       walls.tiles.begin() + static_cast<std::ptrdiff_t>(walls.band_begin[band]),
                   end = walls.tiles.begin() +
                         static_cast<std::ptrdiff_t>(walls.band_begin[band + 1]);
        const auto first = std::lower_bound(begin, end, tx0);
        const auto last = std::upper_bound(first, end, tx1);
        auto lo = first;
        while (lo != last && !near_wall_tile(g, j0, j1, *lo, s, r)) ++lo;
        if (lo == last) continue;
        auto hi = last - 1;
        while (!near_wall_tile(g, j0, j1, *hi, s, r)) --hi;  // stops at lo, which passes
        found[chunk].push_back({0.0, static_cast<std::uint32_t>(m),
                                std::max(box.i0, *lo * kWallTile),
                                std::min(box.i1, *hi * kWallTile + kWallTile - 1), row0, row1});
      }
    }
  });
  std::vector<std::vector<FineCellMove>> by_band(walls.bands);
  std::vector<std::size_t> count(walls.bands, 0);
  for (const auto& part : found)
    for (const FineCellMove& n : part) ++count[static_cast<std::size_t>(n.row0 / kBandRows)];
  for (std::size_t b = 0; b < walls.bands; ++b) by_band[b].reserve(count[b]);
  for (auto& part : found) {
    for (const FineCellMove& n : part)
      by_band[static_cast<std::size_t>(n.row0 / kBandRows)].push_back(n);
    part = {};
  }
  return by_band;
}

// Lowers the kPoints sub-point heights `h` of fine cell (i, j) under the moves `listed` (indices
// into `near` and `geometry`, lowest tip first): to the lowest point of each swept cutter above
// them. A move whose lowest tip is no lower than the cell's highest sub-point cannot lower one,
// nor can any move after it in the list. Each other move gets a bound (its lowest tip plus the
// profile's height at the cell's distance from its tip path) and waits in a heap; the moves are
// evaluated lowest bound first, each once the list has passed its bound (no later move can have
// a lower one), so that the deepest cuts come first and the rest mostly fail the bound, cell
// and sub-point. `candidates` is scratch. The heights are a minimum, whatever the order.
inline void lower_cell(const ZMapGrid& g, std::span<const CutMove> moves,
                       const std::vector<FineCellMove>& near,
                       const std::vector<MoveGeometry>& geometry,
                       const std::vector<std::uint32_t>& listed, int i, int j, float* h,
                       std::vector<std::pair<double, std::uint32_t>>& candidates) {
  constexpr int kSteps = ZMapFineCells::kSteps, kSide = ZMapFineCells::kSide;
  constexpr auto kPoints = static_cast<std::size_t>(ZMapFineCells::kPoints);
  const double step = g.cell / kSteps;  // exact: kSteps is a power of two
  const double half_diagonal = g.cell * std::sqrt(0.5) * (1 + 1e-9);
  const double cx = g.x0 + (i + 0.5) * g.cell, cy = g.y0 + (j + 0.5) * g.cell;
  float top = *std::max_element(h, h + kPoints);
  candidates.clear();
  const auto later = [](const std::pair<double, std::uint32_t>& p,
                        const std::pair<double, std::uint32_t>& q) { return p > q; };
  const auto evaluate_below = [&](double limit) {
    while (!candidates.empty() && candidates.front().first < limit) {
      std::pop_heap(candidates.begin(), candidates.end(), later);
      const double bound = candidates.back().first;
      const MoveGeometry& move = geometry[candidates.back().second];
      candidates.pop_back();
      if (bound >= double(top)) continue;
      // The same bound, sub-point by sub-point: a wall cell next to uncut stock keeps its top at
      // the ceiling, so the cell's test passes for every move near it, while its sub-points
      // already cut at or below the bound cannot be lowered by this move.
      for (int b = 0; b < kSide; ++b)
        for (int a = 0; a < kSide; ++a) {
          float& to = h[a + kSide * b];
          if (bound >= double(to)) continue;
          const double x = g.x0 + (kSteps * i + a) * step, y = g.y0 + (kSteps * j + b) * step;
          const double z = move.lowest(x, y).z;
          if (z < double(to)) to = static_cast<float>(z);
        }
      top = *std::max_element(h, h + kPoints);
    }
  };
  for (std::uint32_t k : listed) {
    const FineCellMove& n = near[k];
    evaluate_below(n.tip);
    if (n.tip >= double(top)) break;
    if (j < n.row0 || j > n.row1 || static_cast<std::uint32_t>(i) < n.i0 ||
        static_cast<std::uint32_t>(i) > n.i1)
      continue;
    const MoveGeometry& move = geometry[k];
    const Segment& s = moves[n.move].tip;
    // The cell's sub-points lie at least `reach` from the tip path in XY. Beyond the radius
    // the cutter never passes over them; within it, the swept cutter stands at least the
    // profile's height at `reach` above its lowest tip there (profiles rise outward), less a
    // rounding margin far below float heights.
    const double reach =
        std::sqrt(distance2_point_segment(Vec2(cx, cy), Vec2(s.a.x, s.a.y), Vec2(s.b.x, s.b.y))) -
        half_diagonal;
    if (reach > move.radius) continue;
    const double bound = n.tip + move.cutter->lower_height(std::max(0.0, reach)) - 1e-6;
    if (bound >= double(top)) continue;
    candidates.emplace_back(bound, k);
    std::push_heap(candidates.begin(), candidates.end(), later);
  }
  evaluate_below(std::numeric_limits<double>::infinity());
}

// Lowers the fine cells of one band (lower_fine_cells) under its `near` moves: each wall tile
// lists the moves that come within the radius of it, lowest tip first (a sub-point's height is
// the minimum over the moves, whatever their order), and each fine cell of the tile runs down
// its tile's list (lower_cell). A cell cut to its depth stops at the first move above it, so the
// cost follows the walls and the moves that reach them, not every move over the band.
inline void lower_band(const ZMapGrid& g, std::span<const Cutter> cutters,
                       std::span<const CutMove> moves, const std::vector<std::uint32_t>& cells,
                       const std::vector<std::size_t>& row_begin, const WallTiles& walls,
                       std::size_t band, std::vector<FineCellMove>& near, std::vector<float>& sub) {
  constexpr auto kWallTile = static_cast<std::uint32_t>(kWallBandRows);
  constexpr auto kPoints = static_cast<std::size_t>(ZMapFineCells::kPoints);
  const int j0 = static_cast<int>(band) * kWallBandRows,
            j1 = std::min(g.ny - 1, j0 + kWallBandRows);
  std::vector<MoveGeometry> geometry;
  geometry.reserve(near.size());
  for (FineCellMove& n : near) {
    geometry.emplace_back(cutters[moves[n.move].cutter], moves[n.move].tip);
    n.tip = geometry.back().lowest_tip();
  }
  std::vector<std::uint32_t> order(near.size());
  for (std::size_t k = 0; k < order.size(); ++k) order[k] = static_cast<std::uint32_t>(k);
  std::sort(order.begin(), order.end(), [&](std::uint32_t a, std::uint32_t b) {
    return near[a].tip < near[b].tip || (near[a].tip == near[b].tip && near[a].move < near[b].move);
  });
  const auto tiles = walls.tiles.begin() + static_cast<std::ptrdiff_t>(walls.band_begin[band]),
             tiles_end =
                 walls.tiles.begin() + static_cast<std::ptrdiff_t>(walls.band_begin[band + 1]);
  std::vector<std::vector<std::uint32_t>> listed(static_cast<std::size_t>(tiles_end - tiles));
  for (std::uint32_t k : order) {
    const FineCellMove& n = near[k];
    for (auto t = std::lower_bound(tiles, tiles_end, n.i0 / kWallTile);
         t != tiles_end && *t <= n.i1 / kWallTile; ++t)
      if (near_wall_tile(g, j0, j1, *t, moves[n.move].tip, geometry[k].radius))
        listed[static_cast<std::size_t>(t - tiles)].push_back(k);
  }
  const auto nx = static_cast<std::size_t>(g.nx);
  std::vector<std::pair<double, std::uint32_t>> candidates;
  for (std::size_t t = 0; t < listed.size(); ++t) {
    if (listed[t].empty()) continue;
    const std::size_t c0 = tiles[static_cast<std::ptrdiff_t>(t)] * kWallTile,
                      c1 = c0 + kWallTile - 1;
    for (int j = j0; j < j1; ++j) {
      const std::size_t base = static_cast<std::size_t>(j) * nx;
      const auto first =
          cells.begin() + static_cast<std::ptrdiff_t>(row_begin[static_cast<std::size_t>(j)]);
      const auto last =
          cells.begin() + static_cast<std::ptrdiff_t>(row_begin[static_cast<std::size_t>(j) + 1]);
      for (auto c = std::lower_bound(first, last, static_cast<std::uint32_t>(base + c0));
           c != last && *c <= base + c1; ++c)
        lower_cell(g, moves, near, geometry, listed[t], static_cast<int>(*c - base), j,
                   sub.data() + static_cast<std::size_t>(c - cells.begin()) * kPoints, candidates);
    }
  }
}

// The heart of refine_steep_cells: lowers `sub` (the fine cells' sub-point heights, kPoints per
// cell of `cells`, from `ceiling` or lower: an embedder's cells already lowered by earlier moves)
// to the lowest point of every move's swept cutter above them, band by band on `threads`
// threads (0: every hardware thread). row_begin[j] is the first of `cells` in cell row j
// (cells.size() where the row has none). The heights do not depend on the thread count.
inline void lower_fine_cells(const ZMapGrid& g, std::span<const Cutter> cutters,
                             std::span<const CutMove> moves,
                             const std::vector<std::uint32_t>& cells,
                             const std::vector<std::size_t>& row_begin, float /*ceiling*/,
                             unsigned threads, std::vector<float>& sub) {
  const auto bands = static_cast<std::size_t>((g.ny - 1 + kWallBandRows - 1) / kWallBandRows);
  const WallTiles walls = wall_tiles(g, bands, cells);
  std::vector<std::vector<FineCellMove>> near =
      near_moves_by_band(g, cutters, moves, walls, threads);
  detail::for_each_chunk(bands, threads, [&](std::size_t band) {
    if (!near[band].empty())
      lower_band(g, cutters, moves, cells, row_begin, walls, band, near[band], sub);
    near[band] = {};
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
