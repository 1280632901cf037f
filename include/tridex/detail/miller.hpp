// tridex — the tiled milling loop (Miller): which moves reach which tiles, and the first of the
// two passes over a row of tiles; the second pass, which cuts the tiles, is tile_cuts.hpp.
//
// Speed comes from touching only what a move can still lower. S (mill.hpp) is convex (the
// lower surface of a convex swept solid), so its tangent plane at any point bounds it from below
// everywhere; for the ball end S also rises at least quadratically across the move (BallLanes).
// The grid is cut into 16×16-point tiles and the tiles into 8×8-tile work blocks, milled on all
// threads. A block is milled one row of tiles at a time, in two passes over its moves:
//   1. every move is bounded over every tile of the row it reaches, by S's tangent plane at the
//      tile's centre, and each tile is cut first by the move lowest at its centre among those
//      whose footprint covers the whole tile (if any does): that leaves it close to its final
//      shape, and that move's plane P then follows its surface;
//   2. the moves whose bound is still below the tile's highest point, and below max(height − P)
//      when measured from P (so that sloped surfaces skip as well as flat ones), cut the tile
//      row by row, each row read once and lowered by every move admitted there.
// The moves left for a tile in pass 2 are cut lowest bound first, a run of one cutter at a time,
// each run checked against what the tile holds by then: so a tile first cut by any cutter, or
// roughed deeper by another cutter, still rejects the moves that cut air. Runs of other cutters
// than the ball end are short, and each flat end move is checked against each row as it stands by
// then (its neighbouring passes cut nearly equal surfaces: Miller::cut_others). Every point ends at
// the minimum over moves of a value computed the same way whatever the order (a move is skipped
// only where it cannot lower a point), so the result is identical for any thread count and any
// move order (for one build: the vector width and FMA contraction change the last bits).
// Part of mill.hpp, which includes it after its contract (CutMove, MillOptions); not for
// inclusion on its own.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <new>
#include <span>
#include <utility>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/detail/cutter_lanes.hpp"
#include "tridex/detail/move_geometry.hpp"
#include "tridex/detail/simd_lanes.hpp"
#include "tridex/parallel.hpp"
#include "tridex/zmap.hpp"

namespace tridex::detail {

// A double's bits as an unsigned integer of the same order (−0 as +0, which compare equal; no
// NaN), and a stable radix sort by it: for keys filled in index order, the order that std::sort
// gives (value, index) pairs. On model-D's roughing (about 1,500 moves a block, tips in a few
// levels) std::sort of the pairs took 2 % of Step 1.
struct SortKey {
  std::uint64_t key;
  std::uint32_t index;
};

inline std::uint64_t order_key(double v) {
  const auto bits = std::bit_cast<std::uint64_t>(v + 0.0);
  return bits >> 63 ? ~bits : bits | (std::uint64_t{1} << 63);
}

inline void sort_by_key(std::vector<SortKey>& keys, std::vector<SortKey>& spare) {
  constexpr int kDigits = 8;
  std::array<std::array<std::uint32_t, 256>, kDigits> count{};
  for (const SortKey& k : keys)
    for (int d = 0; d < kDigits; ++d) ++count[d][(k.key >> (8 * d)) & 255];
  spare.resize(keys.size());
  for (int d = 0; d < kDigits; ++d) {
    std::array<std::uint32_t, 256>& at = count[d];
    if (keys.empty() || at[(keys.front().key >> (8 * d)) & 255] == keys.size()) continue;
    std::uint32_t offset = 0;
    for (std::uint32_t& c : at) offset += std::exchange(c, offset);
    for (const SortKey& k : keys) spare[at[(k.key >> (8 * d)) & 255]++] = k;
    keys.swap(spare);
  }
}

constexpr int kTile = 16;     // points along each side of a tile
constexpr int kBinTiles = 8;  // tiles along each side of a work block
// Moves of a flat end or a bull nose milled together before the tile is measured again (see
// Miller::cut_others): 1, 2, 4, 8 and 16 measured on the flat end's raster of bench_mill, 8 best.
constexpr std::ptrdiff_t kOtherRun = 8;

// The milling of one Z-map: moves are binned to work blocks; each block is milled by one thread,
// one row of tiles at a time (see `mill_bin`).
class Miller {
 public:
  Miller(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves)
      : map_(map), g_(map.grid), cutters_(cutters), moves_(moves) {
    tiles_x_ = (g_.nx + kTile - 1) / kTile;
    tiles_y_ = (g_.ny + kTile - 1) / kTile;
    bins_x_ = (tiles_x_ + kBinTiles - 1) / kBinTiles;
    bins_y_ = (tiles_y_ + kBinTiles - 1) / kBinTiles;
  }

  void run(unsigned threads) {
    bin_moves(threads);
    const std::size_t bin_count =
        static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(bins_y_);
    for_each_chunk_with(
        bin_count, threads, [](unsigned) { return BlockScratch{}; },
        [&](std::size_t b, BlockScratch& scratch) { mill_bin(b, scratch); });
  }

 private:
  struct IndexBox {
    int i0, j0, i1, j1;
  };

  // A move that reaches a tile, with lower bounds of its swept surface over the tile.
  struct Candidate {
    std::uint32_t move = 0;  // index into the block's moves
    bool has_plane = false;
    double bound = kInf;     // lower bound of the swept surface over the tile
    double centre_z = kInf;  // the swept surface at the tile's centre (+inf if not covered)
    Vec2 gradient{0};        // its supporting plane's slope there, if `has_plane`
  };

  // What a tile holds, row by row: the highest point and the largest height above P.
  struct TileState {
    std::array<double, kTile> row_top, row_excess;
    double top = -kInf, excess = -kInf;
    void summarise(int rows) {
      top = *std::max_element(row_top.begin(), row_top.begin() + rows);
      excess = *std::max_element(row_excess.begin(), row_excess.begin() + rows);
    }
  };

  // A plane P through the tile's centre at height z with slope `gradient`, that approximates the
  // tile's surface once a smooth move has cut it.
  struct TilePlane {
    bool valid = false;
    double z = 0;
    Vec2 gradient{0};
  };

  struct Tile {
    IndexBox box;
    double xc, yc, hx, hy;  // centre and half extents
    double half_diagonal;   // √(hx² + hy²)
    TileState state;
    TilePlane plane;
    std::vector<Candidate> candidates;
  };

  // The tiles of one row of a work block. The arrays hold, tile by tile, what the ball end's
  // vector code reads kLanes tiles at a time.
  struct TileRow {
    int first_tx = 0, count = 0;
    std::array<Tile, kBinTiles> tiles;
    struct Lanes {
      alignas(32) double xc[kBinTiles], hx[kBinTiles], half_diagonal[kBinTiles], top[kBinTiles];
      // The move to cut first: its index (as a double), centre height, plane slope and bound.
      alignas(32) double first[kBinTiles], first_z[kBinTiles], first_gx[kBinTiles],
          first_gy[kBinTiles], first_bound[kBinTiles];
      // Whether that move's footprint covers the whole tile (ball ends count as covering: see
      // find_first_cuts).
      alignas(32) double first_covers[kBinTiles];
      // The tile's plane P and its largest height above P (P valid where plane_valid ≠ 0).
      alignas(32) double plane_valid[kBinTiles], plane_z[kBinTiles], plane_gx[kBinTiles],
          plane_gy[kBinTiles], excess[kBinTiles];
    } lanes;
  };
  static_assert(kBinTiles % kLanes == 0);

  // A ball end move's bounds over kLanes tiles of a row, from pass 1 for pass 2.
  struct BallBounds {
    DoubleN z, gx, gy, bound;  // the plane at each tile's centre (where `has_plane`), the bound
    // Bit l for lane l (lane_bits; as masks they made each record 448 bytes, not 320: on model-D
    // pass 1 writes 8 M of them for pass 2 in its first direction). in_range: the move reaches the
    // tile.
    std::uint32_t has_plane, in_range;
    std::uint32_t move;
    int lane0;
  };

  // A ball end move left out of pass 1, and its distance from the row's tiles.
  struct FarMove {
    std::uint32_t move;
    int col0, col1;
    double distance;
  };

  // A move of another cutter left out of pass 1 over some tiles of the row (its near_bound is not
  // below the lowest centre height found there so far): bit `col` of `tiles` for each.
  struct DeferredMove {
    std::uint32_t move;
    std::uint32_t tiles;
  };
  static_assert(kBinTiles <= 32);

  // How a move's swept surface is evaluated on a tile's points: kLanes at a time by the ball
  // end's, the flat end's, the bull nose's or the other profiles' vector form, or one point at a
  // time (MoveGeometry::lowest: plunges, and profiles with an arc off the axis).
  enum class LaneKind : unsigned char { scalar, ball, flat, bull_nose, profile };

  static LaneKind lane_kind(const MoveGeometry& m) {
    if (m.vertical) return LaneKind::scalar;
    switch (m.cutter->shape()) {
      case CutterShape::ball:
        return LaneKind::ball;
      case CutterShape::flat:
        return LaneKind::flat;
      case CutterShape::bull_nose:
        return LaneKind::bull_nose;
      default:
        return ProfileLanes::closed_form(*m.cutter) ? LaneKind::profile : LaneKind::scalar;
    }
  }

  // A move's vector form: the one of its LaneKind, or none (scalar).
  union LaneForm {
    BallLanes ball;
    FlatLanes flat;
    BullLanes bull;
    ProfileLanes profile;
    LaneForm() {}
  };

  struct Reach {
    std::int8_t row0, row1, col0, col1;
  };

  struct BlockScratch {
    std::vector<BallBounds> ball_bounds;        // of the current row
    std::vector<FarMove> far_moves;             // of the current row
    std::vector<DeferredMove> deferred;         // of the current row
    std::vector<std::uint32_t> by_tip;          // the other cutters' moves, lowest tip first
    std::vector<SortKey> tip_keys, spare_keys;  // by_tip's sort keys
    std::vector<MoveGeometry> moves;
    // Parallel to `moves`: how each is evaluated, and its vector form where it has one (only
    // that form is made: the four of every move took 584 bytes, and a block of model-D's
    // roughing holds 6,000 moves).
    std::vector<LaneKind> kind;
    std::vector<LaneForm> forms;
    // Which tile rows and columns of the block each move reaches (block-relative).
    std::vector<Reach> reach;
    // The ball end moves (in block order) and the other cutters' (in by_tip order) that reach
    // each tile row of the block.
    std::array<std::vector<std::uint32_t>, kBinTiles> ball_rows, other_rows;
    TileRow row;
  };

  // Grid-index box of a move's footprint, clipped to the grid; false if it misses the grid.
  bool footprint_box(const CutMove& move, IndexBox& box) const {
    double r = cutters_[move.cutter].radius();
    double x_lo = std::min(move.tip.a.x, move.tip.b.x) - r,
           x_hi = std::max(move.tip.a.x, move.tip.b.x) + r;
    double y_lo = std::min(move.tip.a.y, move.tip.b.y) - r,
           y_hi = std::max(move.tip.a.y, move.tip.b.y) + r;
    double fi0 = std::ceil((x_lo - g_.x0) / g_.cell), fi1 = std::floor((x_hi - g_.x0) / g_.cell);
    double fj0 = std::ceil((y_lo - g_.y0) / g_.cell), fj1 = std::floor((y_hi - g_.y0) / g_.cell);
    // One point of slack on each side against rounding; the exact test is per point.
    fi0 = std::max(fi0 - 1, 0.0), fj0 = std::max(fj0 - 1, 0.0);
    fi1 = std::min(fi1 + 1, g_.nx - 1.0), fj1 = std::min(fj1 + 1, g_.ny - 1.0);
    if (fi0 > fi1 || fj0 > fj1) return false;
    box = {static_cast<int>(fi0), static_cast<int>(fj0), static_cast<int>(fi1),
           static_cast<int>(fj1)};
    return true;
  }

  // The moves' footprint boxes (boxes_, empty where a move misses the grid), and a counting sort
  // of move indices into blocks (bin_moves_) keeping program order within each block. On the
  // threads: the moves in chunks of program order, each chunk counted and filed by one worker at
  // offsets that put the chunks of one block in order (about 1 % of Step 1's CPU on model-D, and
  // it ran on one thread while the other waited).
  void bin_moves(unsigned threads) {
    const std::size_t bin_count =
        static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(bins_y_);
    const int span = kTile * kBinTiles;
    auto for_each_bin = [&](const IndexBox& b, auto&& visit) {
      if (b.i0 > b.i1) return;
      for (int by = b.j0 / span; by <= b.j1 / span; ++by)
        for (int bx = b.i0 / span; bx <= b.i1 / span; ++bx)
          visit(static_cast<std::size_t>(bx) +
                static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(by));
    };
    constexpr std::size_t kChunkMoves = 1 << 15, kMostChunks = 64;
    const std::size_t chunks =
        std::min(kMostChunks, (moves_.size() + kChunkMoves - 1) / kChunkMoves);
    const std::size_t per_chunk = chunks ? (moves_.size() + chunks - 1) / chunks : 0;
    auto chunk_moves = [&](std::size_t c) {
      return std::pair(c * per_chunk, std::min(moves_.size(), (c + 1) * per_chunk));
    };
    boxes_.resize(moves_.size());
    std::vector<std::size_t> counts(chunks * bin_count, 0);
    for_each_chunk(chunks, threads, [&](std::size_t c) {
      std::size_t* count = &counts[c * bin_count];
      const auto [m0, m1] = chunk_moves(c);
      for (std::size_t m = m0; m < m1; ++m) {
        if (!footprint_box(moves_[m], boxes_[m])) boxes_[m] = {0, 0, -1, -1};
        for_each_bin(boxes_[m], [&](std::size_t b) { ++count[b]; });
      }
    });
    bin_start_.assign(bin_count + 1, 0);
    std::size_t total = 0;
    for (std::size_t b = 0; b < bin_count; ++b) {
      bin_start_[b] = total;
      for (std::size_t c = 0; c < chunks; ++c)
        total += std::exchange(counts[c * bin_count + b], total);
    }
    bin_start_[bin_count] = total;
    bin_moves_.resize(total);
    for_each_chunk(chunks, threads, [&](std::size_t c) {
      std::size_t* fill = &counts[c * bin_count];
      const auto [m0, m1] = chunk_moves(c);
      for (std::size_t m = m0; m < m1; ++m)
        for_each_bin(boxes_[m],
                     [&](std::size_t b) { bin_moves_[fill[b]++] = static_cast<std::uint32_t>(m); });
    });
  }

  // Mills one work block, one row of tiles at a time, in the two passes of the header comment:
  // find_first_cuts and cut_first (pass 1), find_other_cuts and cut_others (pass 2). A move is
  // skipped over a tile (or one of its rows) when its bound is not below the highest point there,
  // or when min(S − P) ≥ max(height − P), P the first cut's plane.
  void mill_bin(std::size_t bin, BlockScratch& scratch) {
    if (bin_start_[bin] == bin_start_[bin + 1]) return;
    scratch.moves.clear();
    scratch.kind.clear();
    scratch.forms.clear();
    for (std::size_t k = bin_start_[bin]; k < bin_start_[bin + 1]; ++k) {
      const CutMove& move = moves_[bin_moves_[k]];
      const MoveGeometry& m = scratch.moves.emplace_back(cutters_[move.cutter], move.tip);
      const LaneKind kind = lane_kind(m);
      scratch.kind.push_back(kind);
      LaneForm& form = scratch.forms.emplace_back();
      if (kind == LaneKind::ball) new (&form.ball) BallLanes(m);
      if (kind == LaneKind::flat) new (&form.flat) FlatLanes(m);
      if (kind == LaneKind::bull_nose) new (&form.bull) BullLanes(m);
      if (kind == LaneKind::profile) new (&form.profile) ProfileLanes(m);
    }
    // Sorted by (lowest tip, index) (sort_by_key), without reaching into a MoveGeometry (over 100
    // bytes each) at every step.
    scratch.tip_keys.clear();
    for (std::size_t k = 0; k < scratch.moves.size(); ++k)
      if (scratch.kind[k] != LaneKind::ball)
        scratch.tip_keys.push_back(
            {order_key(scratch.moves[k].lowest_tip()), static_cast<std::uint32_t>(k)});
    sort_by_key(scratch.tip_keys, scratch.spare_keys);
    scratch.by_tip.clear();
    for (const SortKey& key : scratch.tip_keys) scratch.by_tip.push_back(key.index);
    int bx = static_cast<int>(bin % static_cast<std::size_t>(bins_x_));
    int by = static_cast<int>(bin / static_cast<std::size_t>(bins_x_));
    int tx1 = std::min(tiles_x_, (bx + 1) * kBinTiles),
        ty1 = std::min(tiles_y_, (by + 1) * kBinTiles);
    file_by_row(bin, bx * kBinTiles, tx1 - bx * kBinTiles, by * kBinTiles, ty1 - by * kBinTiles,
                scratch);
    TileRow& row = scratch.row;
    for (int ty = by * kBinTiles; ty < ty1; ++ty) {
      start_row(row, bx * kBinTiles, tx1 - bx * kBinTiles, ty);
      find_first_cuts(row, ty - by * kBinTiles, scratch);
      for (int col = 0; col < row.count; ++col) cut_first(row, col, scratch);
      find_other_cuts(row, scratch);
      for (int col = 0; col < row.count; ++col)
        cut_others(row.tiles[static_cast<std::size_t>(col)], scratch);
    }
  }

  // Sets up the tiles of one row of a block: their extents and what they hold now.
  void start_row(TileRow& row, int first_tx, int count, int ty) {
    row.first_tx = first_tx, row.count = count;
    const int j0 = ty * kTile, j1 = std::min(g_.ny, (ty + 1) * kTile) - 1;
    TileRow::Lanes& lanes = row.lanes;
    for (int col = 0; col < kBinTiles; ++col) {
      // Columns past the grid's edge repeat the last tile (their lanes are computed, not used).
      const int tx = first_tx + std::min(col, count - 1);
      const int i0 = tx * kTile, i1 = std::min(g_.nx, (tx + 1) * kTile) - 1;
      Tile& tile = row.tiles[static_cast<std::size_t>(col)];
      tile.box = {i0, j0, i1, j1};
      tile.xc = 0.5 * (g_.x(i0) + g_.x(i1)), tile.yc = 0.5 * (g_.y(j0) + g_.y(j1));
      tile.hx = 0.5 * (g_.x(i1) - g_.x(i0)), tile.hy = 0.5 * (g_.y(j1) - g_.y(j0));
      tile.half_diagonal = std::sqrt(tile.hx * tile.hx + tile.hy * tile.hy);
      tile.plane = {};
      tile.candidates.clear();
      for (int j = j0; j <= j1; ++j) {
        const float* heights = &map_.heights[g_.index(i0, j)];
        DoubleN top = load_heights(heights, i1 - i0 + 1);
        for (int i = kLanes; i < kTile; i += kLanes)
          top = max_n(top, load_heights(heights + i, i1 - i0 + 1 - i));
        tile.state.row_top[static_cast<std::size_t>(j - j0)] = max_lane(top);
        tile.state.row_excess[static_cast<std::size_t>(j - j0)] = -kInf;
      }
      tile.state.summarise(j1 - j0 + 1);
      lanes.xc[col] = tile.xc, lanes.hx[col] = tile.hx, lanes.top[col] = tile.state.top;
      lanes.half_diagonal[col] = tile.half_diagonal;
      lanes.first[col] = -1, lanes.first_z[col] = kInf, lanes.first_bound[col] = kInf;
      lanes.first_gx[col] = lanes.first_gy[col] = 0;
      lanes.first_covers[col] = 0;
    }
  }

  // Which of the block's tile rows and columns each of its moves reaches (from its footprint
  // box), and the moves filed by tile row: the ball ends in block order, the others in by_tip
  // order. Pass 1 then visits only the moves that reach a row (on model-D, 20 M visits of ball
  // ends against 76 M tests of every move on every row of its block).
  void file_by_row(std::size_t bin, int first_tx, int cols, int first_ty, int rows,
                   BlockScratch& scratch) const {
    scratch.reach.clear();
    for (std::size_t k = bin_start_[bin]; k < bin_start_[bin + 1]; ++k) {
      const IndexBox& b = boxes_[bin_moves_[k]];
      // Clipped to the block, which the box reaches (bin_moves).
      scratch.reach.push_back(
          {static_cast<std::int8_t>(std::max(0, b.j0 / kTile - first_ty)),
           static_cast<std::int8_t>(std::min(rows - 1, b.j1 / kTile - first_ty)),
           static_cast<std::int8_t>(std::max(0, b.i0 / kTile - first_tx)),
           static_cast<std::int8_t>(std::min(cols - 1, b.i1 / kTile - first_tx))});
      Reach& reach = scratch.reach.back();
      if (reach.col0 > reach.col1) reach.row1 = static_cast<std::int8_t>(reach.row0 - 1);
    }
    for (auto& rows_of : {&scratch.ball_rows, &scratch.other_rows})
      for (std::vector<std::uint32_t>& filed : *rows_of) filed.clear();
    for (std::size_t k = 0; k < scratch.moves.size(); ++k)
      if (scratch.kind[k] == LaneKind::ball)
        for (int r = scratch.reach[k].row0; r <= scratch.reach[k].row1; ++r)
          scratch.ball_rows[static_cast<std::size_t>(r)].push_back(static_cast<std::uint32_t>(k));
    for (std::uint32_t k : scratch.by_tip)
      for (int r = scratch.reach[k].row0; r <= scratch.reach[k].row1; ++r)
        scratch.other_rows[static_cast<std::size_t>(r)].push_back(k);
  }

  // A ball end move's bounds over the row's tiles lane0 .. lane0 + kLanes − 1 (those in
  // col0..col1 are in range).
  BallBounds ball_bounds(const BallLanes& ball, const TileRow& row, std::uint32_t move, int lane0,
                         int col0, int col1) const {
    const Tile& tile = row.tiles[0];
    const DoubleN hx = load_n(&row.lanes.hx[lane0]);
    const DoubleN ux = load_n(&row.lanes.xc[lane0]) - ball.ax, uy = splat(tile.yc - ball.ay);
    BallLanes::Plane p = ball.plane_at(ux, uy);
    // Without a plane: the lowest tip plus the ball's height at the tile's distance s from the
    // path, bounded below by s²/2R (h(s) = R − √(R² − s²) = s² / (R + √(R² − s²))).
    DoubleN bound = p.z - abs_n(p.gx) * hx - abs_n(p.gy) * tile.hy;
    if (!all_n(p.has_plane)) {
      DoubleN gap = max_n(sqrt_n(path_distance2(ux, uy, ball.vx, ball.vy, ball.inv_vv)) -
                              load_n(&row.lanes.half_diagonal[lane0]),
                          splat(0));
      DoubleN far =
          gap * gap > ball.r2 ? splat(kInf) : ball.lowest_tip() + gap * gap * ball.inv_diameter;
      bound = p.has_plane ? bound : far;
    }
    const DoubleN col = lane_index() + lane0;
    return {
        p.z,  p.gx, p.gy, bound, lane_bits(p.has_plane), lane_bits((col >= col0) & (col <= col1)),
        move, lane0};
  }

  // Pass 1: for each tile, the move whose swept surface is lowest at its centre among those with
  // a supporting plane there (ties: the lower bound). Moves other than ball ends are kept.
  //
  // A ball end move whose path stays farther than R/2 from the row's tiles is left for pass 2,
  // where most such moves fall to a scalar test: the lowest point of the ball within a distance d
  // of its path is at least d²/2R above the tip, and a tile's surface comes within d of the move
  // only if the move passes within d of it. The first cut is only a choice (any move gives a
  // correct result); in a raster it is the nearby move a little downhill, well within R/2.
  void find_first_cuts(TileRow& row, int r, BlockScratch& scratch) {
    TileRow::Lanes& lanes = row.lanes;
    scratch.ball_bounds.clear();
    scratch.far_moves.clear();
    const Tile& last = row.tiles[static_cast<std::size_t>(row.count - 1)];
    const double row_x0 = g_.x(row.tiles[0].box.i0), row_x1 = g_.x(last.box.i1);
    const double row_y0 = g_.y(last.box.j0), row_y1 = g_.y(last.box.j1);
    for (const std::uint32_t k : scratch.ball_rows[static_cast<std::size_t>(r)]) {
      const MoveGeometry& m = scratch.moves[k];
      const BallLanes& ball = scratch.forms[k].ball;
      const int col0 = scratch.reach[k].col0, col1 = scratch.reach[k].col1;
      // Distance between the path's bounding box and the row's rectangle.
      const double dx = std::max(
          {0.0, std::min(m.ax, m.ax + m.vx) - row_x1, row_x0 - std::max(m.ax, m.ax + m.vx)});
      const double dy = std::max(
          {0.0, std::min(m.ay, m.ay + m.vy) - row_y1, row_y0 - std::max(m.ay, m.ay + m.vy)});
      const double distance = std::sqrt(dx * dx + dy * dy);
      if (distance > 0.5 * m.radius) {
        scratch.far_moves.push_back({k, col0, col1, distance});
        continue;
      }
      for (int lane0 = col0 / kLanes * kLanes; lane0 <= col1; lane0 += kLanes) {
        const BallBounds& b =
            scratch.ball_bounds.emplace_back(ball_bounds(ball, row, k, lane0, col0, col1));
        const DoubleN first_z = load_n(&lanes.first_z[lane0]),
                      first_bound = load_n(&lanes.first_bound[lane0]);
        const MaskN better = bits_mask(b.in_range & b.has_plane) &
                             (b.bound < load_n(&lanes.top[lane0])) &
                             ((load_n(&lanes.first_covers[lane0]) == 0) | (b.z < first_z) |
                              ((b.z == first_z) & (b.bound < first_bound)));
        if (!any_n(better)) continue;
        store_n(&lanes.first_covers[lane0], better ? splat(1) : load_n(&lanes.first_covers[lane0]));
        store_n(&lanes.first[lane0],
                better ? splat(static_cast<double>(k)) : load_n(&lanes.first[lane0]));
        store_n(&lanes.first_z[lane0], better ? b.z : first_z);
        store_n(&lanes.first_gx[lane0], better ? b.gx : load_n(&lanes.first_gx[lane0]));
        store_n(&lanes.first_gy[lane0], better ? b.gy : load_n(&lanes.first_gy[lane0]));
        store_n(&lanes.first_bound[lane0], better ? b.bound : first_bound);
      }
    }
    // The other cutters' moves, lowest tip first; one whose tip is not below the lowest centre
    // height found for a tile cannot be its first cut, and waits for pass 2 (where, after the
    // first cut, most such moves fall to the same cheap test against the tile's top: the upper
    // levels of a Z-level roughing, for instance).
    //
    // A move whose footprint covers the whole tile is preferred to one lower at the centre that
    // does not: a flat end's surface is lowest at the side of its footprint wherever the program
    // slopes across its passes (the bench's raster), and a first cut that leaves part of the tile
    // untouched leaves its top where it was, so that no later move is rejected (on bench_mill's
    // flat raster, 84 moves a tile were left for pass 2, against 4 for the ball). Ball ends count
    // as covering: their first cut is chosen as before.
    scratch.deferred.clear();
    for (const std::uint32_t k : scratch.other_rows[static_cast<std::size_t>(r)]) {
      const int col0 = scratch.reach[k].col0, col1 = scratch.reach[k].col1;
      const MoveGeometry& m = scratch.moves[k];
      // Which tiles the move can reach below their top, and which of those it is deferred on (its
      // near_bound not below their first cut's centre height), kLanes tiles at a time: a move
      // spans most of a row, and on bench_mill's bull nose raster one test per tile made 16.5 M
      // tests and 13.4 M deferred records. Each tile's test reads only its own first cut, so
      // testing them together before any is updated changes nothing.
      std::uint32_t bounded = 0, deferred = 0;
      for (int lane0 = col0 / kLanes * kLanes; lane0 <= col1; lane0 += kLanes) {
        const DoubleN col = lane_index() + lane0, near = near_bound(scratch, row, k, lane0);
        const MaskN below = (col >= col0) & (col <= col1) & (near < load_n(&lanes.top[lane0]));
        const MaskN defer = below & (load_n(&lanes.first_covers[lane0]) != 0) &
                            (near >= load_n(&lanes.first_z[lane0]));
        bounded |= lane_bits(below & ~defer) << lane0;
        deferred |= lane_bits(defer) << lane0;
      }
      if (deferred != 0) scratch.deferred.push_back({k, deferred});
      // Bounds kLanes tiles at a time where the move has a vector form (MoveBounds).
      MoveBounds bounds;
      for (; bounded != 0; bounded &= bounded - 1) {
        const int col = std::countr_zero(bounded);
        Tile& tile = row.tiles[static_cast<std::size_t>(col)];
        const bool first_covers = lanes.first_covers[col] != 0;
        Candidate c = bounds.at(scratch, row, k, col);
        if (c.bound >= tile.state.top) continue;
        tile.candidates.push_back(c);
        if (!c.has_plane) continue;
        const bool lower = c.centre_z < lanes.first_z[col] ||
                           (c.centre_z == lanes.first_z[col] && c.bound < lanes.first_bound[col]);
        if (!lower && first_covers) continue;
        const bool covers = covers_tile(m, tile);
        if (covers ? (lower || !first_covers) : (lower && !first_covers)) {
          lanes.first[col] = static_cast<double>(k), lanes.first_z[col] = c.centre_z;
          lanes.first_gx[col] = c.gradient.x, lanes.first_gy[col] = c.gradient.y;
          lanes.first_bound[col] = c.bound, lanes.first_covers[col] = covers;
        }
      }
    }
  }

  // Cuts a tile with its first move (if it has one), and records the plane and state that the
  // other moves are then measured against.
  void cut_first(TileRow& row, int col, const BlockScratch& scratch) {
    Tile& tile = row.tiles[static_cast<std::size_t>(col)];
    TileRow::Lanes& lanes = row.lanes;
    if (lanes.first[col] >= 0) {
      Candidate first{static_cast<std::uint32_t>(lanes.first[col]), true, lanes.first_bound[col],
                      lanes.first_z[col], Vec2(lanes.first_gx[col], lanes.first_gy[col])};
      tile.plane = {true, first.centre_z, first.gradient};
      mill_tile(std::span<const Candidate>(&first, 1), tile, scratch, true);
    }
    lanes.top[col] = tile.state.top, lanes.excess[col] = tile.state.excess;
    lanes.plane_valid[col] = tile.plane.valid, lanes.plane_z[col] = tile.plane.z;
    lanes.plane_gx[col] = tile.plane.gradient.x, lanes.plane_gy[col] = tile.plane.gradient.y;
  }

  // min(S − P) over a tile (or over one of its rows, with half_height = 0 and dy its offset).
  static double above_plane(const Candidate& c, const Tile& tile, double dy, double half_height) {
    const TilePlane& p = tile.plane;
    if (!c.has_plane)
      return c.bound - (p.z + p.gradient.y * dy + std::abs(p.gradient.x) * tile.hx +
                        std::abs(p.gradient.y) * half_height);
    return (c.centre_z - p.z) + (c.gradient.y - p.gradient.y) * dy -
           std::abs(c.gradient.x - p.gradient.x) * tile.hx -
           std::abs(c.gradient.y - p.gradient.y) * half_height;
  }

  static bool can_cut(const Candidate& c, const Tile& tile) {
    return c.bound < tile.state.top &&
           (!tile.plane.valid || above_plane(c, tile, 0, tile.hy) < tile.state.excess);
  }

  // Pass 2: the moves left for each tile, and the cutting (defined in tile_cuts.hpp).
  void find_other_cuts(TileRow& row, const BlockScratch& scratch);

  void keep_other_cuts(TileRow& row, const BallBounds& b) const;

  void cut_others(Tile& tile, const BlockScratch& scratch);

  // bound_at_centre for a flat end's, a bull nose's or a profile's move, from the plane_at of
  // FlatLanes, BullLanes or ProfileLanes at the centres of kLanes tiles of a row at once (`at`
  // computes them for the tiles around column col when needed).
  template <class Lanes>
  struct LaneBounds {
    FlatLanes::Plane plane;
    DoubleN bound;
    std::uint32_t move = 0;
    int lane0 = -1;

    Candidate at(const Lanes& lanes, const MoveGeometry& m, const TileRow& row, std::uint32_t index,
                 int col) {
      if (index != move || col / kLanes * kLanes != lane0) {
        move = index, lane0 = col / kLanes * kLanes;
        const DoubleN ux = load_n(&row.lanes.xc[lane0]) - lanes.ax,
                      uy = splat(row.tiles[0].yc - lanes.ay);
        plane = lanes.plane_at(ux, uy);
        bound = plane.z - abs_n(plane.gx) * load_n(&row.lanes.hx[lane0]) -
                abs_n(plane.gy) * row.tiles[0].hy;
        if (!all_n(plane.has_plane)) {
          // bound_without_plane at once (on bench_mill's bull nose raster, half the tiles a move
          // is bounded over in pass 1 have no plane at their centre: the passes at the edge of
          // the footprint).
          bound = plane.has_plane ? bound : off_path_bound(lanes, m, row, lane0, ux, uy);
        }
      }
      const int l = col - lane0;
      if (plane.has_plane[l])
        return {index, true, bound[l], plane.z[l], Vec2(plane.gx[l], plane.gy[l])};
      return {index, false, bound[l], kInf, Vec2(0)};
    }
  };

  // The bounds of one move over the tile at column col, kLanes tiles at a time where the move has
  // a vector form for them.
  struct MoveBounds {
    LaneBounds<FlatLanes> flat;
    LaneBounds<BullLanes> bull;
    LaneBounds<ProfileLanes> profile;

    Candidate at(const BlockScratch& scratch, const TileRow& row, std::uint32_t k, int col) {
      const MoveGeometry& m = scratch.moves[k];
      switch (scratch.kind[k]) {
        case LaneKind::flat:
          return flat.at(scratch.forms[k].flat, m, row, k, col);
        case LaneKind::bull_nose:
          return bull.at(scratch.forms[k].bull, m, row, k, col);
        case LaneKind::profile:
          return profile.at(scratch.forms[k].profile, m, row, k, col);
        default:
          return bound_at_centre(m, row.tiles[static_cast<std::size_t>(col)], k);
      }
    }
  };

  DoubleN near_bound(const BlockScratch& scratch, const TileRow& row, std::uint32_t k,
                     int lane0) const;

  template <class Lanes>
  static DoubleN off_path_bound(const Lanes& move, const MoveGeometry& m, const TileRow& row,
                                int lane0, DoubleN ux, DoubleN uy);

  static double bound_without_plane(const MoveGeometry& m, const Tile& tile);

  static bool covers_tile(const MoveGeometry& m, const Tile& tile);

  static Candidate bound_at_centre(const MoveGeometry& m, const Tile& tile, std::uint32_t index);

  bool row_may_cut(const Candidate& c, const Tile& tile, int j, double row_top,
                   double row_excess) const;

  std::uint32_t rows_may_cut(const Candidate& c, const BallLanes* ball, const Tile& tile) const;

  static DoubleN load_heights(const float* p, int available);
  static void store_heights(float* p, DoubleN h, int available);

  // Lowers a tile to the swept surfaces of `cuts` (moves of one cutter), row by row: each row is
  // read once, lowered by every move whose bounds admit it, and its state (measured against the
  // tile's plane) updated once. Which rows a move may lower (RowTest): all of them for the first
  // cut; for a flat end's run, each row by its state after the moves before (its neighbouring
  // passes cut nearly equal surfaces, see cut_others); for the others, every row by its state
  // before the run, all rows of a move at once. Other cutters than the ball end and the flat end
  // skip the points already below the move's supporting plane.
  enum class RowTest { every, fresh, before };
  void mill_tile(std::span<const Candidate> cuts, Tile& tile, const BlockScratch& scratch,
                 bool every_row);
  static constexpr std::size_t kPart = 64;
  // mill_tile for at most kPart moves. The ball end's and the flat end's moves are evaluated at
  // every point of a row: a test per group costs more in mispredicted branches and in the chain
  // through h than the evaluations it saves (measured; the flat end's is a closed form with one
  // square root, cheaper than a test). Their values are rounded to float and raised to the empty
  // height once per row, at the end: heights are floats and never below it, so min(h, round(max(z,
  // empty))) = round(max(min(h, z), empty)). With RowTest::fresh (the other cutters' near-equal
  // surfaces, a flat end's neighbouring passes, leave a row's first cut far from its final shape,
  // often not covering it all) the row is measured again after each move, and rejects the moves
  // that it has become lower than.
  template <RowTest kTest>
  void mill_part(std::span<const Candidate> cuts, Tile& tile, const BlockScratch& scratch);

  ZMap& map_;
  const ZMapGrid& g_;
  std::span<const Cutter> cutters_;
  std::span<const CutMove> moves_;
  int tiles_x_, tiles_y_, bins_x_, bins_y_;
  std::vector<std::size_t> bin_start_;
  std::vector<std::uint32_t> bin_moves_;
  std::vector<IndexBox> boxes_;  // each move's footprint_box
};

}  // namespace tridex::detail
