// tridex — walls inside their Z-map cells (issue 17; the step-like errors of Inui, Chen and
// Umezu, CAD&A 19(4) 2022, §5, at walls parallel to a spindle).
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
#include <atomic>
#include <cmath>
#include <cstdint>
#include <span>
#include <thread>
#include <vector>

#include "tridex/dexel_ops.hpp"
#include "tridex/mill.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

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

// Makes the steep cells of `map` fine, with sub-point heights from the moves it was milled with
// (the same cutters and moves, in its frame). Call it on a map prepared by raise_uncut, last:
// it reads the map's heights. Throws tridex::Error for a move with a cutter out of range.
inline void refine_steep_cells(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves,
                               WallOptions options = {}) {
  constexpr int kSteps = ZMapFineCells::kSteps, kSide = ZMapFineCells::kSide;
  constexpr auto kPoints = static_cast<std::size_t>(ZMapFineCells::kPoints);
  for (std::size_t k = 0; k < moves.size(); ++k)
    if (moves[k].cutter >= cutters.size())
      detail::fail("refine steep cells: move ", k, " uses cutter ", moves[k].cutter, " but only ", cutters.size(),
                   " are given");
  const ZMapGrid& g = map.grid;
  float ceiling = map.empty_height;
  for (float h : map.heights) ceiling = std::max(ceiling, h);
  std::vector<std::uint32_t> cells;
  for (int j = 0; j + 1 < g.ny; ++j)
    for (int i = 0; i + 1 < g.nx; ++i)
      if (is_steep_cell(map, i, j, options.steep_slope)) cells.push_back(static_cast<std::uint32_t>(g.index(i, j)));
  if (cells.empty()) {
    map.fine = {};
    return;
  }
  // Cells come out ascending, so a row's fine cells are a contiguous, sorted run.
  std::vector<std::size_t> row_begin(static_cast<std::size_t>(g.ny), cells.size());
  for (std::size_t k = cells.size(); k-- > 0;) row_begin[cells[k] / static_cast<std::uint32_t>(g.nx)] = k;
  for (std::size_t row = row_begin.size() - 1; row-- > 0;) row_begin[row] = std::min(row_begin[row], row_begin[row + 1]);

  std::vector<float> sub(cells.size() * kPoints, ceiling);
  std::vector<detail::MoveGeometry> geometry;
  geometry.reserve(moves.size());
  for (const CutMove& m : moves) geometry.emplace_back(cutters[m.cutter], m.tip);
  const double step = g.cell / kSteps;  // exact: kSteps is a power of two
  // Bands of cell rows, one thread each at a time; a band looks at the moves whose swept box
  // reaches it.
  constexpr int kBandRows = 16;
  const int bands = (g.ny - 1 + kBandRows - 1) / kBandRows;
  std::atomic<int> next{0};
  auto worker = [&] {
    for (int band; (band = next.fetch_add(1)) < bands;) {
      const int j0 = band * kBandRows, j1 = std::min(g.ny - 1, j0 + kBandRows);
      if (row_begin[static_cast<std::size_t>(j0)] == row_begin[static_cast<std::size_t>(j1)]) continue;
      for (std::size_t m = 0; m < moves.size(); ++m) {
        const Segment& s = moves[m].tip;
        const double r = cutters[moves[m].cutter].radius();
        const double lo_y = std::min(s.a.y, s.b.y) - r, hi_y = std::max(s.a.y, s.b.y) + r;
        const int row0 = std::max(j0, static_cast<int>(std::floor((lo_y - g.y0) / g.cell)));
        const int row1 = std::min(j1 - 1, static_cast<int>(std::floor((hi_y - g.y0) / g.cell)));
        if (row0 > row1) continue;
        const double lo_x = std::min(s.a.x, s.b.x) - r, hi_x = std::max(s.a.x, s.b.x) + r;
        const auto i0 = static_cast<std::uint32_t>(std::clamp(std::floor((lo_x - g.x0) / g.cell), 0.0, double(g.nx)));
        const auto i1 = static_cast<std::uint32_t>(std::clamp(std::floor((hi_x - g.x0) / g.cell), 0.0, double(g.nx)));
        for (int j = row0; j <= row1; ++j) {
          const auto row = static_cast<std::size_t>(j), base = row * static_cast<std::size_t>(g.nx);
          const auto first = cells.begin() + static_cast<std::ptrdiff_t>(row_begin[row]);
          const auto last = cells.begin() + static_cast<std::ptrdiff_t>(row_begin[row + 1]);
          for (auto c = std::lower_bound(first, last, static_cast<std::uint32_t>(base + i0));
               c != last && *c <= base + i1; ++c) {
            const int i = static_cast<int>(*c - base);
            float* h = sub.data() + static_cast<std::size_t>(c - cells.begin()) * kPoints;
            for (int b = 0; b < kSide; ++b)
              for (int a = 0; a < kSide; ++a) {
                const double x = g.x0 + (kSteps * i + a) * step, y = g.y0 + (kSteps * j + b) * step;
                const double z = geometry[m].lowest(x, y).z;
                float& to = h[a + kSide * b];
                if (z < double(to)) to = static_cast<float>(z);
              }
          }
        }
      }
    }
  };
  {
    const unsigned threads = std::min<unsigned>(detail::resolve_threads(options.threads), static_cast<unsigned>(bands));
    std::vector<std::thread> pool;
    for (unsigned id = 1; id < threads; ++id) pool.emplace_back(worker);
    worker();
    for (std::thread& th : pool) th.join();
  }
  map.set_fine_cells(std::move(cells), std::move(sub));
}

}  // namespace tridex
