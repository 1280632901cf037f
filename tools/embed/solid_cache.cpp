// tridex embedded — the session's solid kept up to date piece by piece (solid_cache.hpp). The
// stages follow simulate's (tools/cli/pipeline/pipeline.cpp: intersect_directions, refine_walls)
// and the kernel's (zmap.hpp raise_uncut, fine_cells.hpp refine_steep_cells, scan_dexelize.hpp
// scan_intersect_milled) on a part of each map: a change there must be made here too, and the
// session-vs-simulate tests (tests/embed) say when they part.
#include "solid_cache.hpp"

#include <algorithm>
#include <cmath>
#include <optional>
#include <utility>

#include "tridex/dexelize.hpp"
#include "tridex/fine_cells.hpp"
#include "tridex/parallel.hpp"
#include "tridex/polyhedron.hpp"
#include "tridex/scan_dexelize.hpp"

namespace tridex::embed {

namespace {

constexpr int kRaiseReach = 2;  // raise_uncut reads points this many rows away

// A direction's stock map before milling, row by row, as raise_uncut computes it again: a box's
// tops (ZMap::from_box) or a mesh's triangles rasterised (ZMap::from_mesh).
class StockRows {
 public:
  StockRows(const ZMap& live, const Aabb& box, const Mesh* mesh) : box_(box) {
    if (mesh) {
      top_.emplace(live.grid.frame, *mesh, live.grid.cell);
      top_->index_bands();
      grid_ = top_->grid(), empty_ = top_->empty();
    } else {
      const std::pair<ZMapGrid, float> grid_and_empty =
          detail::box_map_grid(live.grid.frame, box, live.grid.cell);
      grid_ = grid_and_empty.first, empty_ = grid_and_empty.second;
    }
  }
  float empty() const { return empty_; }
  void row(int j, float* out) const {
    if (top_)
      top_->row(j, out);
    else
      detail::box_top_row(grid_, box_, empty_, j, out);
  }

 private:
  Aabb box_;
  std::optional<detail::MeshTop> top_;
  ZMapGrid grid_;
  float empty_ = 0;
};

// The highest point of the stock's Z-map before milling (raise_uncut_rows' `top`).
float stock_top(const ZMap& live, const StockRows& stock, unsigned threads) {
  const ZMapGrid& b = live.grid;
  const auto bands =
      static_cast<std::size_t>((b.ny + detail::kMapBandRows - 1) / detail::kMapBandRows);
  std::vector<float> band_top(bands, live.empty_height);
  detail::for_each_chunk(bands, threads, [&](std::size_t band) {
    std::vector<float> row(static_cast<std::size_t>(b.nx));
    const int j0 = static_cast<int>(band) * detail::kMapBandRows,
              j1 = std::min(b.ny, j0 + detail::kMapBandRows);
    for (int j = j0; j < j1; ++j) {
      stock.row(j, row.data());
      for (float h : row) band_top[band] = std::max(band_top[band], h);
    }
  });
  return *std::max_element(band_top.begin(), band_top.end());
}

// Cell row j's first cell in `cells` (ascending), as refine_steep_cells indexes them.
std::vector<std::size_t> rows_of(const std::vector<std::uint32_t>& cells, const ZMapGrid& g) {
  std::vector<std::size_t> row_begin(static_cast<std::size_t>(g.ny), cells.size());
  for (std::size_t k = cells.size(); k-- > 0;)
    row_begin[cells[k] / static_cast<std::uint32_t>(g.nx)] = k;
  for (std::size_t row = row_begin.size() - 1; row-- > 0;)
    row_begin[row] = std::min(row_begin[row], row_begin[row + 1]);
  return row_begin;
}

}  // namespace

SolidCache::SolidCache(const Aabb& stock, std::shared_ptr<const Mesh> stock_mesh,
                       const DexelLattice& lattice, unsigned threads)
    : stock_(stock),
      stock_mesh_(std::move(stock_mesh)),
      threads_(threads),
      stock_dexel_(stock_mesh_ ? dexelize(*stock_mesh_, lattice, DexelizeOptions{threads})
                               : TripleDexel::box(lattice, stock)) {}

void SolidCache::milled(std::size_t g, const ZMap& live, std::span<const Cutter> cutters,
                        std::span<const CutMove> batch) {
  if (g >= directions_.size()) return;  // a new direction is prepared whole
  Direction& d = directions_[g];
  const ZMapGrid& grid = live.grid;
  for (const CutMove& m : batch) {
    // The rows under the swept cutter's box, as lower_fine_cells bounds a move, and one more on
    // each side for the rounding of the floor.
    const double r = cutters[m.cutter].radius();
    const double lo = (std::min(m.tip.a.y, m.tip.b.y) - r - grid.y0) / grid.cell;
    const double hi = (std::max(m.tip.a.y, m.tip.b.y) + r - grid.y0) / grid.cell;
    if (!(hi >= -2) || !(lo <= grid.ny + 1)) continue;  // beside the map (or not a number)
    d.row0 = std::min(d.row0, static_cast<int>(std::max(0.0, std::floor(lo) - 1)));
    d.row1 = std::max(d.row1, static_cast<int>(std::min(grid.ny - 1.0, std::floor(hi) + 2)));
  }
}

// raise_uncut (zmap_rows.hpp, raise_uncut_rows) on rows [r0, r1], from the live map into the
// prepared one: uncut points raised to `above`, outside points next to a cut continuing it.
void SolidCache::raise_rows(std::size_t g, const ZMap& live, int r0, int r1) {
  const float above = directions_[g].above;
  ZMap& out = prepared_[g];
  const StockRows stock(live, stock_, stock_mesh_.get());
  const float initial_empty = stock.empty();
  const ZMapGrid& a = live.grid;
  const auto nx = static_cast<std::size_t>(a.nx);
  const int rows = r1 - r0 + 1;
  const auto bands =
      static_cast<std::size_t>((rows + detail::kMapBandRows - 1) / detail::kMapBandRows);
  detail::for_each_chunk(bands, threads_, [&](std::size_t band) {
    const int j0 = r0 + static_cast<int>(band) * detail::kMapBandRows,
              j1 = std::min(r1 + 1, j0 + detail::kMapBandRows);
    const int w0 = std::max(0, j0 - kRaiseReach), w1 = std::min(a.ny, j1 + kRaiseReach);
    std::vector<float> window(static_cast<std::size_t>(w1 - w0) * nx);
    for (int j = w0; j < w1; ++j)
      stock.row(j, window.data() + static_cast<std::size_t>(j - w0) * nx);
    auto initial = [&](int i, int j) {
      return window[static_cast<std::size_t>(j - w0) * nx + static_cast<std::size_t>(i)];
    };
    auto inside = [&](int i, int j) {
      return i >= 0 && j >= 0 && i < a.nx && j < a.ny && initial(i, j) > initial_empty;
    };
    auto cut = [&](int i, int j) { return inside(i, j) && live.height(i, j) != initial(i, j); };
    for (int j = j0; j < j1; ++j)
      for (int i = 0; i < a.nx; ++i) {
        const std::size_t p = a.index(i, j);
        float h = live.heights[p] == initial(i, j) ? above : live.heights[p];
        if (!inside(i, j)) {
          float best = -std::numeric_limits<float>::infinity();
          for (int dj = -1; dj <= 1; ++dj)
            for (int di = -1; di <= 1; ++di) {
              if ((di == 0 && dj == 0) || !cut(i + di, j + dj)) continue;
              const float near = live.height(i + di, j + dj);
              const float far =
                  cut(i + 2 * di, j + 2 * dj) ? live.height(i + 2 * di, j + 2 * dj) : near;
              best = std::max(best, 2 * near - far);
            }
          if (best > -std::numeric_limits<float>::infinity())
            h = std::clamp(best, live.empty_height, above);
        }
        out.heights[p] = h;
      }
  });
}

// refine_steep_cells (fine_cells.hpp) on cell rows [c0, c1]: the steep cells there, their
// sub-heights lowered from the ceiling by every move, or, for a cell already fine, from its
// sub-heights by the moves since.
void SolidCache::refine_rows(std::size_t g, std::span<const Cutter> cutters,
                             std::span<const CutMove> moves, int c0, int c1) {
  constexpr auto kPoints = static_cast<std::size_t>(ZMapFineCells::kPoints);
  Direction& d = directions_[g];
  ZMap& map = prepared_[g];
  const ZMapGrid& grid = map.grid;
  std::vector<std::uint32_t> kept, fresh;
  std::vector<float> kept_sub, fresh_sub;
  const double slope = WallOptions{}.steep_slope;
  for (int j = c0; j <= c1; ++j)
    for (int i = 0; i + 1 < grid.nx; ++i) {
      if (!is_steep_cell(map, i, j, slope)) continue;
      const auto c = static_cast<std::uint32_t>(grid.index(i, j));
      const auto at = std::lower_bound(d.raw_cells.begin(), d.raw_cells.end(), c);
      if (at != d.raw_cells.end() && *at == c) {
        kept.push_back(c);
        const auto from =
            d.raw_sub.begin() + static_cast<std::ptrdiff_t>(at - d.raw_cells.begin()) *
                                    static_cast<std::ptrdiff_t>(kPoints);
        kept_sub.insert(kept_sub.end(), from, from + static_cast<std::ptrdiff_t>(kPoints));
      } else {
        fresh.push_back(c);
      }
    }
  fresh_sub.assign(fresh.size() * kPoints, d.ceiling);
  const std::span<const CutMove> since = moves.subspan(std::min(d.moves_done, moves.size()));
  if (!kept.empty() && !since.empty())
    detail::lower_fine_cells(grid, cutters, since, kept, rows_of(kept, grid), d.ceiling, threads_,
                             kept_sub);
  if (!fresh.empty())
    detail::lower_fine_cells(grid, cutters, moves, fresh, rows_of(fresh, grid), d.ceiling, threads_,
                             fresh_sub);
  // The rows' new fine cells in place of their old ones, all ascending.
  const auto first = static_cast<std::uint32_t>(grid.index(0, c0));
  const auto last = static_cast<std::uint32_t>(grid.index(0, c1 + 1));
  const auto lo = std::lower_bound(d.raw_cells.begin(), d.raw_cells.end(), first);
  const auto hi = std::lower_bound(d.raw_cells.begin(), d.raw_cells.end(), last);
  std::vector<std::uint32_t> cells(d.raw_cells.begin(), lo);
  std::vector<float> sub(
      d.raw_sub.begin(),
      d.raw_sub.begin() + (lo - d.raw_cells.begin()) * static_cast<std::ptrdiff_t>(kPoints));
  for (std::size_t a = 0, f = 0; a < kept.size() || f < fresh.size();) {
    const bool take_kept = f == fresh.size() || (a < kept.size() && kept[a] < fresh[f]);
    const std::vector<float>& from = take_kept ? kept_sub : fresh_sub;
    const std::size_t k = take_kept ? a++ : f++;
    cells.push_back(take_kept ? kept[k] : fresh[k]);
    sub.insert(sub.end(), from.begin() + static_cast<std::ptrdiff_t>(k * kPoints),
               from.begin() + static_cast<std::ptrdiff_t>((k + 1) * kPoints));
  }
  cells.insert(cells.end(), hi, d.raw_cells.end());
  sub.insert(sub.end(),
             d.raw_sub.begin() + (hi - d.raw_cells.begin()) * static_cast<std::ptrdiff_t>(kPoints),
             d.raw_sub.end());
  d.raw_cells = std::move(cells);
  d.raw_sub = std::move(sub);
  if (d.raw_cells.empty())
    map.fine = {};
  else
    map.set_fine_cells(d.raw_cells, d.raw_sub);
}

bool SolidCache::prepare(std::size_t g, const ZMap& live, std::span<const Cutter> cutters,
                         std::span<const CutMove> moves) {
  Direction& d = directions_[g];
  ZMap& map = prepared_[g];
  const ZMapGrid& grid = live.grid;
  const int r0 = d.whole ? 0 : std::max(0, d.row0 - kRaiseReach);
  const int r1 = d.whole ? grid.ny - 1 : std::min(grid.ny - 1, d.row1 + kRaiseReach);
  if (d.whole) {
    map = ZMap();
    map.grid = live.grid;
    map.empty_height = live.empty_height;
    map.heights.resize(live.heights.size());
    d.above =
        static_cast<float>(stock_top(live, StockRows(live, stock_, stock_mesh_.get()), threads_) +
                           detail::empty_margin(grid.cell));
    d.raw_cells.clear();
    d.raw_sub.clear();
    d.moves_done = 0;
  }
  raise_rows(g, live, r0, r1);
  // refine_steep_cells' ceiling: the highest prepared point.
  float ceiling = map.empty_height;
  for (float h : map.heights) ceiling = std::max(ceiling, h);
  if (!d.whole && ceiling != d.ceiling) return false;
  d.ceiling = ceiling;
  const int c0 = std::max(0, r0 - 1), c1 = std::min(grid.ny - 2, r1);
  refine_rows(g, cutters, moves, c0, c1);
  if (!d.whole) {
    // The polyhedron changed over cell rows [c0, c1] and, through the fine cells' shared edges
    // and steps, one row beyond each: from its bottom to its top.
    const Aabb box{Vec3(grid.x(0), grid.y(std::max(0, c0 - 1)), detail::zmap_bottom(map)),
                   Vec3(grid.x(grid.nx - 1), grid.y(std::min(grid.ny - 1, c1 + 2)),
                        std::max(d.ceiling, map.empty_height))};
    mark_rays(grid.frame, box);
  }
  return true;
}

void SolidCache::mark_rays(const Frame& frame, const Aabb& box) {
  Aabb world;
  for (const Vec3& c : box.corners()) world.extend(frame.to_world(c));
  const TripleDexel& s = stock_dexel_;
  for (int axis = 0; axis < 3; ++axis) {
    const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
    auto range = [&](int w) {  // one ray of margin on each side: rounding
      const double lo = std::ceil((world.min[w] - s.origin[w]) / s.spacing) - 1;
      const double hi = std::floor((world.max[w] - s.origin[w]) / s.spacing) + 1;
      return std::pair<int, int>(static_cast<int>(std::clamp(lo, 0.0, double(s.n[w] - 1))),
                                 static_cast<int>(std::clamp(hi, -1.0, double(s.n[w] - 1))));
    };
    const std::pair<int, int> ru = range(u), rv = range(v);
    for (int iv = rv.first; iv <= rv.second; ++iv)
      for (int iu = ru.first; iu <= ru.second; ++iu)
        redo_[axis][static_cast<std::size_t>(iu) +
                    static_cast<std::size_t>(s.n[u]) * static_cast<std::size_t>(iv)] = 1;
  }
}

void SolidCache::redo_marked_rays() {
  TripleDexel part = stock_dexel_;  // the stock on the marked rays only
  std::size_t redone = 0, rays = 0;
  for (int axis = 0; axis < 3; ++axis) {
    const DexelGrid& from = stock_dexel_.grids[axis];
    DexelGrid& to = part.grids[axis];
    to.intervals.clear();
    for (std::size_t r = 0; r < from.ray_count(); ++r) {
      if (redo_[axis][r]) {
        const std::span<const DexelInterval> ray = from.ray(r);
        to.intervals.insert(to.intervals.end(), ray.begin(), ray.end());
        ++redone;
      }
      to.offsets[r + 1] = static_cast<std::uint32_t>(to.intervals.size());
    }
    rays += from.ray_count();
  }
  last_rays_redone_ = static_cast<double>(redone) / static_cast<double>(rays);
  if (redone == 0) return;
  const TripleDexel again = scan_intersect_milled(part, prepared_, threads_);
  for (int axis = 0; axis < 3; ++axis) {
    const DexelGrid& old = result_.grids[axis];
    const DexelGrid& fresh = again.grids[axis];
    DexelGrid merged;
    merged.axis = old.axis, merged.nu = old.nu, merged.nv = old.nv;
    merged.offsets.assign(old.offsets.size(), 0);
    merged.intervals.reserve(old.intervals.size());
    for (std::size_t r = 0; r < old.ray_count(); ++r) {
      const std::span<const DexelInterval> ray = redo_[axis][r] ? fresh.ray(r) : old.ray(r);
      merged.intervals.insert(merged.intervals.end(), ray.begin(), ray.end());
      merged.offsets[r + 1] = static_cast<std::uint32_t>(merged.intervals.size());
    }
    result_.grids[axis] = std::move(merged);
  }
}

const TripleDexel& SolidCache::update(std::span<const ZMap> live, std::span<const Cutter> cutters,
                                      std::span<const std::vector<CutMove>> cuts) {
  bool everything = !result_valid_;
  for (int axis = 0; axis < 3; ++axis) redo_[axis].assign(stock_dexel_.grids[axis].ray_count(), 0);
  for (std::size_t g = 0; g < live.size(); ++g) {
    if (g == directions_.size()) {
      directions_.emplace_back();
      prepared_.emplace_back();
    }
    Direction& d = directions_[g];
    if (!d.whole && d.row1 < 0 && d.moves_done == cuts[g].size()) continue;  // unchanged
    everything = everything || d.whole;
    if (!prepare(g, live[g], cutters, cuts[g])) {
      d.whole = everything = true;  // the ceiling moved: the whole map again
      prepare(g, live[g], cutters, cuts[g]);
    }
    d.moves_done = cuts[g].size();
    d.row0 = std::numeric_limits<int>::max(), d.row1 = -1;
    d.whole = false;
  }
  if (everything) {
    result_ = scan_intersect_milled(stock_dexel_, prepared_, threads_);
    result_valid_ = true;
    last_rays_redone_ = 1;
  } else {
    redo_marked_rays();
  }
  return result_;
}

}  // namespace tridex::embed
