// tridex — the second pass of the tiled milling loop (miller.hpp): Miller's member functions that
// bound the moves left for a tile and cut it row by row, lowest bound first, a run of one
// cutter at a time (Inui, Chen and Umezu, CAD&A 19(4) 2022, §3.1: each point ends at the minimum
// over moves of S, computed as MoveGeometry and the lanes compute it; a move is skipped only
// where a lower bound of S shows it cannot lower a point).
// Part of mill.hpp, after miller.hpp; not for inclusion on its own.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <span>

#include "tridex/detail/miller.hpp"

namespace tridex::detail {

// Pass 2: the moves that can still cut each tile after its first cut (the same test as
// `can_cut`, kLanes tiles at a time for the ball end).
inline void Miller::find_other_cuts(TileRow& row, const BlockScratch& scratch) {
  const TileRow::Lanes& lanes = row.lanes;
  for (int col = 0; col < row.count; ++col) {
    Tile& tile = row.tiles[static_cast<std::size_t>(col)];
    const auto first = static_cast<std::uint32_t>(std::max(0.0, lanes.first[col]));
    const bool has_first = lanes.first[col] >= 0;
    std::erase_if(tile.candidates, [&](const Candidate& c) {
      return (has_first && c.move == first) || !can_cut(c, tile);
    });
  }
  // A deferred move is bounded only over the tiles whose first cut left their top above its
  // near_bound (most are not: the upper levels of a Z-level roughing, for instance), kLanes
  // tiles at a time.
  MoveBounds bounds;
  for (const DeferredMove& d : scratch.deferred) {
    const DoubleN move = splat(static_cast<double>(d.move));
    std::uint32_t tiles = 0;
    for (int lane0 = 0; lane0 < row.count; lane0 += kLanes) {
      if (((d.tiles >> lane0) & ((1u << kLanes) - 1)) == 0) continue;
      const DoubleN near = near_bound(scratch, row, d.move, lane0);
      tiles |= lane_bits((near < load_n(&lanes.top[lane0])) & (load_n(&lanes.first[lane0]) != move))
               << lane0;
    }
    for (tiles &= d.tiles; tiles != 0; tiles &= tiles - 1) {
      const int col = std::countr_zero(tiles);
      Tile& tile = row.tiles[static_cast<std::size_t>(col)];
      const Candidate c = bounds.at(scratch, row, d.move, col);
      if (can_cut(c, tile)) tile.candidates.push_back(c);
    }
  }
  for (const BallBounds& b : scratch.ball_bounds) keep_other_cuts(row, b);
  double row_top = -kInf;
  for (int col = 0; col < row.count; ++col) row_top = std::max(row_top, lanes.top[col]);
  for (const FarMove& far : scratch.far_moves) {
    const BallLanes& ball = scratch.forms[far.move].ball;
    if (ball.lowest_tip() + far.distance * far.distance * ball.inv_diameter >= row_top) continue;
    for (int lane0 = far.col0 / kLanes * kLanes; lane0 <= far.col1; lane0 += kLanes)
      keep_other_cuts(row, ball_bounds(ball, row, far.move, lane0, far.col0, far.col1));
  }
}

// The tiles of b's lanes where its move can still cut (see `can_cut`) get it as a candidate.
inline void Miller::keep_other_cuts(TileRow& row, const BallBounds& b) const {
  const TileRow::Lanes& lanes = row.lanes;
  const double hy = row.tiles[0].hy;
  const int lane0 = b.lane0;
  const DoubleN hx = load_n(&lanes.hx[lane0]);
  const DoubleN pz = load_n(&lanes.plane_z[lane0]), pgx = load_n(&lanes.plane_gx[lane0]),
                pgy = load_n(&lanes.plane_gy[lane0]);
  DoubleN with_plane = (b.z - pz) - abs_n(b.gx - pgx) * hx - abs_n(b.gy - pgy) * hy;
  DoubleN without_plane = b.bound - (pz + abs_n(pgx) * hx + abs_n(pgy) * hy);
  DoubleN above = bits_mask(b.has_plane) ? with_plane : without_plane;
  MaskN cuts = bits_mask(b.in_range) & (b.bound < load_n(&lanes.top[lane0])) &
               ((load_n(&lanes.plane_valid[lane0]) == 0) | (above < load_n(&lanes.excess[lane0]))) &
               (load_n(&lanes.first[lane0]) != static_cast<double>(b.move));
  if (!any_n(cuts)) return;
  for (int l = 0; l < kLanes; ++l) {
    if (!cuts[l]) continue;
    Candidate c{b.move, ((b.has_plane >> l) & 1) != 0, b.bound[l], kInf, Vec2(0)};
    if (c.has_plane) c.centre_z = b.z[l], c.gradient = Vec2(b.gx[l], b.gy[l]);
    row.tiles[static_cast<std::size_t>(lane0 + l)].candidates.push_back(c);
  }
}

// Cuts a tile with the moves left, lowest bound first, so that deep cuts (a roughing pass
// below the finish, say) come before the moves they leave nothing for. A run of consecutive
// moves of one cutter with a vector form is milled together, row by row (a ball end's admitted
// by what the tile held before the run: their rows are cheap, a fresher test costs more than it
// saves); each run, and each move without a vector form (its points cost far more), is checked
// again against what the tile holds by then. A run of another cutter is at most kOtherRun
// moves, and a flat end's rows are measured again after each of its moves (mill_tile): its
// neighbouring passes leave nearly equal surfaces, so that the first cut leaves a tile far from
// its final shape (a flat end's raster on a slope is lowest under the side of a neighbouring
// pass, which covers a few rows of a tile), and a test against the state after the first cut
// admitted 20 times the rows that the ball end's did. The bull nose's rows are not measured
// again: on bench_mill's bull nose raster that cost 8 % more than the rows it rejected.
inline void Miller::cut_others(Tile& tile, const BlockScratch& scratch) {
  std::vector<Candidate>& candidates = tile.candidates;
  std::sort(candidates.begin(), candidates.end(), [](const Candidate& a, const Candidate& b) {
    return a.bound < b.bound || (a.bound == b.bound && a.move < b.move);
  });
  for (auto c = candidates.begin(); c != candidates.end();) {
    if (c->bound >= tile.state.top) break;
    if (scratch.kind[c->move] == LaneKind::scalar) {
      if (can_cut(*c, tile)) mill_tile(std::span<const Candidate>(&*c, 1), tile, scratch, false);
      ++c;
      continue;
    }
    const Cutter* cutter = scratch.moves[c->move].cutter;
    auto run_end = std::find_if(c, candidates.end(), [&](const Candidate& o) {
      return scratch.kind[o.move] == LaneKind::scalar || scratch.moves[o.move].cutter != cutter;
    });
    if (scratch.kind[c->move] != LaneKind::ball && run_end - c > kOtherRun) run_end = c + kOtherRun;
    auto kept = std::remove_if(c, run_end, [&](const Candidate& o) { return !can_cut(o, tile); });
    if (kept != c)
      mill_tile(std::span<const Candidate>(&*c, static_cast<std::size_t>(kept - c)), tile, scratch,
                false);
    c = run_end;
  }
}

// bound_without_plane for the row's tiles lane0 .. lane0 + kLanes − 1 at once (+infinity where
// the footprint misses a tile), for a move of another cutter than the ball end: the lowest tip
// where the cutter has no vector form or a flat bottom (h = 0 out to R0: with it the bull
// nose's raster of bench_mill took 874 ms against 844, one sitting: two square roots more). Cheaper
// than the tile's plane, and far stronger than the tip alone for a pointed cutter (a cone's
// neighbouring passes are d·tan(angle) above their tips at a distance d: on bench_mill's cone
// raster, 10.4 M of the moves' tiles were bounded in pass 1 with the tip).
inline DoubleN Miller::near_bound(const BlockScratch& scratch, const TileRow& row, std::uint32_t k,
                                  int lane0) const {
  const MoveGeometry& m = scratch.moves[k];
  if (scratch.kind[k] != LaneKind::profile) return splat(m.lowest_tip());
  const ProfileLanes& move = scratch.forms[k].profile;
  const DoubleN ux = load_n(&row.lanes.xc[lane0]) - move.ax, uy = splat(row.tiles[0].yc - move.ay);
  return off_path_bound(move, m, row, lane0, ux, uy);
}

// The lowest tip plus the cutter's height at the distance of the row's tiles (lanes lane0 …, at
// offsets (ux, uy) from the move's start) from its path: +infinity where the footprint misses a
// tile. For a move of FlatLanes, BullLanes or ProfileLanes.
template <class Lanes>
inline DoubleN Miller::off_path_bound(const Lanes& move, const MoveGeometry& m, const TileRow& row,
                                      int lane0, DoubleN ux, DoubleN uy) {
  const DoubleN distance = sqrt_n(path_distance2(ux, uy, move.vx, move.vy, move.inv_vv));
  const DoubleN gap = max_n(distance - load_n(&row.lanes.half_diagonal[lane0]), splat(0));
  return gap > m.radius ? splat(kInf) : move.low + move.height(min_n(gap, splat(m.radius)));
}

// A lower bound of a move's swept surface over a tile where it has no plane at the centre: the
// lowest tip plus the cutter's height at the tile's distance from the path.
inline double Miller::bound_without_plane(const MoveGeometry& m, const Tile& tile) {
  double distance =
      std::max(0.0, std::sqrt(distance2_point_segment(Vec2(tile.xc, tile.yc), Vec2(m.ax, m.ay),
                                                      Vec2(m.ax + m.vx, m.ay + m.vy))) -
                        tile.half_diagonal);
  return distance <= m.radius ? m.lowest_tip() + m.cutter->lower_height(distance) : kInf;
}

// Whether the move's footprint (every point within the cutter's radius of its path) holds the
// whole tile.
inline bool Miller::covers_tile(const MoveGeometry& m, const Tile& tile) {
  const double reach = m.radius - tile.half_diagonal;
  return reach > 0 && distance2_point_segment(Vec2(tile.xc, tile.yc), Vec2(m.ax, m.ay),
                                              Vec2(m.ax + m.vx, m.ay + m.vy)) < reach * reach;
}

// The bounds of one move over one tile, for any cutter.
inline Miller::Candidate Miller::bound_at_centre(const MoveGeometry& m, const Tile& tile,
                                                 std::uint32_t index) {
  Candidate c{index, false, kInf, kInf, Vec2(0)};
  MoveGeometry::Lowest centre;
  if (m.lowest_with_plane(tile.xc, tile.yc, centre, c.gradient)) {
    c.centre_z = centre.z;
    c.has_plane = true;
    c.bound = centre.z - std::abs(c.gradient.x) * tile.hx - std::abs(c.gradient.y) * tile.hy;
    return c;
  }
  c.gradient = Vec2(0);
  c.bound = bound_without_plane(m, tile);
  return c;
}

// Whether a flat end's move c may lower row j of a tile, whose highest point is row_top and
// whose largest height above the tile's plane is row_excess (rows_may_cut for one row, without
// the ball end's rise).
inline bool Miller::row_may_cut(const Candidate& c, const Tile& tile, int j, double row_top,
                                double row_excess) const {
  double dy = g_.y(j) - tile.yc;
  double row_bound =
      c.has_plane ? c.centre_z + c.gradient.y * dy - std::abs(c.gradient.x) * tile.hx : c.bound;
  if (row_bound >= row_top) return false;
  return !tile.plane.valid || above_plane(c, tile, dy, 0) < row_excess;
}

// Whether move c may lower each row of the tile, against what the rows hold now: bit r for row
// t.j0 + r, all rows at once. Rows only get lower, so a row it rejects stays rejected whatever
// is cut after. For the ball end, its rise across the move (BallLanes::across) at its least on
// each row is added to the bounds.
inline std::uint32_t Miller::rows_may_cut(const Candidate& c, const BallLanes* ball,
                                          const Tile& tile) const {
  const IndexBox& t = tile.box;
  const TilePlane& p = tile.plane;
  const int rows = t.j1 - t.j0 + 1;
  std::uint32_t may = 0;
  for (int r0 = 0; r0 < rows; r0 += kLanes) {
    const DoubleN dy = (g_.y0 + (lane_index() + (t.j0 + r0)) * g_.cell) - tile.yc;
    DoubleN across = splat(0);
    if (ball && c.has_plane) {
      const DoubleN a = max_n(abs_n(dy * ball->ny) - tile.hx * std::abs(ball->nx), splat(0));
      across = a * a * ball->inv_diameter;
    }
    const DoubleN row_bound =
        c.has_plane ? c.centre_z + c.gradient.y * dy - std::abs(c.gradient.x) * tile.hx + across
                    : splat(c.bound);
    MaskN cuts = (lane_index() + r0 < rows) &
                 (row_bound < load_n(&tile.state.row_top[static_cast<std::size_t>(r0)]));
    if (p.valid) {
      const DoubleN above =
          c.has_plane ? (c.centre_z - p.z) + (c.gradient.y - p.gradient.y) * dy -
                            std::abs(c.gradient.x - p.gradient.x) * tile.hx
                      : c.bound - (p.z + p.gradient.y * dy + std::abs(p.gradient.x) * tile.hx);
      cuts &= above + across < load_n(&tile.state.row_excess[static_cast<std::size_t>(r0)]);
    }
    may |= lane_bits(cuts) << r0;
  }
  return may;
}

// kLanes heights of a map row as doubles; of the last `available` < kLanes of a row, the rest
// -inf (never lowered, never the top).
inline DoubleN Miller::load_heights(const float* p, int available) {
  if (available >= kLanes) {
    FloatN f;
    __builtin_memcpy(&f, p, sizeof f);
    return __builtin_convertvector(f, DoubleN);
  }
  DoubleN h = splat(-kInf);
  for (int l = 0; l < available; ++l) h[l] = p[l];
  return h;
}

inline void Miller::store_heights(float* p, DoubleN h, int available) {
  if (available >= kLanes) {
    FloatN f = __builtin_convertvector(h, FloatN);
    __builtin_memcpy(p, &f, sizeof f);
    return;
  }
  for (int l = 0; l < available; ++l) p[l] = static_cast<float>(h[l]);
}

inline void Miller::mill_tile(std::span<const Candidate> cuts, Tile& tile,
                              const BlockScratch& scratch, bool every_row) {
  if (every_row) return mill_part<RowTest::every>(cuts, tile, scratch);
  if (scratch.kind[cuts.front().move] == LaneKind::flat)
    return mill_part<RowTest::fresh>(cuts, tile, scratch);
  // A long run (of ball ends) in parts, for mill_part's fixed array.
  for (std::size_t k = 0; k < cuts.size(); k += kPart)
    mill_part<RowTest::before>(cuts.subspan(k, std::min(kPart, cuts.size() - k)), tile, scratch);
}

template <Miller::RowTest kTest>
inline void Miller::mill_part(std::span<const Candidate> cuts, Tile& tile,
                              const BlockScratch& scratch) {
  std::array<std::uint32_t, kPart> may;
  if constexpr (kTest == RowTest::before)
    for (std::size_t k = 0; k < cuts.size(); ++k) {
      const BallLanes* ball = scratch.kind[cuts[k].move] == LaneKind::ball
                                  ? &scratch.forms[cuts[k].move].ball
                                  : nullptr;
      may[k] = rows_may_cut(cuts[k], ball, tile);
    }
  const IndexBox& t = tile.box;
  const TilePlane& plane = tile.plane;
  TileState& state = tile.state;
  const double empty = map_.empty_height;
  const int count = t.i1 - t.i0 + 1;
  constexpr int kGroups = kTile / kLanes;
  DoubleN dx[kGroups], x[kGroups];
  for (int g = 0; g < kGroups; ++g) {
    // x computed as ZMapGrid::x does, so that points on a footprint's rim go the same way.
    x[g] = g_.x0 + (lane_index() + (t.i0 + g * kLanes)) * g_.cell;
    dx[g] = x[g] - tile.xc;
  }
  bool changed = false;
  for (int j = t.j0; j <= t.j1; ++j) {
    const double y = g_.y(j), dy = y - tile.yc;
    float* row = &map_.heights[g_.index(t.i0, j)];
    const double tile_row = plane.z + plane.gradient.y * dy;
    DoubleN h[kGroups];
    bool loaded = false;
    // The row's highest point and largest height above P as its moves lower it (in double: a
    // move whose bounds are not below them leaves every point as it is, rounded or not).
    const std::size_t r = static_cast<std::size_t>(j - t.j0);
    double row_top = state.row_top[r], row_excess = state.row_excess[r];
    for (std::size_t k = 0; k < cuts.size(); ++k) {
      const Candidate& c = cuts[k];
      const LaneKind kind = scratch.kind[c.move];
      if constexpr (kTest == RowTest::before) {
        if (!((may[k] >> r) & 1)) continue;
      } else if constexpr (kTest == RowTest::fresh) {
        if (!row_may_cut(c, tile, j, row_top, row_excess)) continue;
      }
      const MoveGeometry& m = scratch.moves[c.move];
      const BallLanes* ball = kind == LaneKind::ball ? &scratch.forms[c.move].ball : nullptr;
      if (!loaded) {
        for (int g = 0; g < kGroups; ++g) h[g] = load_heights(row + g * kLanes, count - g * kLanes);
        loaded = true;
      }
      if (ball) {
        const double uy = y - ball->ay;
        for (int g = 0; g < kGroups; ++g) h[g] = min_n(h[g], ball->at(x[g] - ball->ax, splat(uy)));
      } else if (kind == LaneKind::flat) {
        const FlatLanes& flat = scratch.forms[c.move].flat;
        const double uy = y - flat.ay;
        for (int g = 0; g < kGroups; ++g) h[g] = min_n(h[g], flat.at(x[g] - flat.ax, splat(uy)));
      } else if (kind == LaneKind::bull_nose) {
        // Halley steps and several square roots: only the points above the move's plane.
        const BullLanes& bull = scratch.forms[c.move].bull;
        const double move_row = (c.has_plane ? c.centre_z : -kInf) + c.gradient.y * dy,
                     uy = y - bull.ay;
        DoubleN ux[kGroups], z[kGroups];
        MaskN above[kGroups];
        for (int g = 0; g < kGroups; ++g) {
          ux[g] = x[g] - bull.ax;
          above[g] = move_row + c.gradient.x * dx[g] < h[g];
        }
        bull.at<kGroups>(ux, splat(uy), above, z);
        for (int g = 0; g < kGroups; ++g) h[g] = min_n(h[g], z[g]);
      } else if (kind == LaneKind::profile) {
        // As the bull nose: only the points above the move's plane.
        const ProfileLanes& profile = scratch.forms[c.move].profile;
        const double move_row = (c.has_plane ? c.centre_z : -kInf) + c.gradient.y * dy,
                     uy = y - profile.ay;
        for (int g = 0; g < kGroups; ++g)
          h[g] = min_n(h[g], profile.at(x[g] - profile.ax, splat(uy),
                                        move_row + c.gradient.x * dx[g] < h[g]));
      } else {
        const double move_row = (c.has_plane ? c.centre_z : -kInf) + c.gradient.y * dy;
        for (int g = 0; g < kGroups; ++g)
          for (int l = 0; l < kLanes; ++l)
            if (move_row + c.gradient.x * dx[g][l] < h[g][l]) {
              double z = m.lowest_above(x[g][l], y);
              h[g][l] =
                  std::min(h[g][l], std::max(static_cast<double>(static_cast<float>(z)), empty));
            }
      }
      if constexpr (kTest == RowTest::fresh) {  // measured again after each move (see above)
        DoubleN top = h[0], excess = h[0] - (tile_row + plane.gradient.x * dx[0]);
        for (int g = 1; g < kGroups; ++g) {
          top = max_n(top, h[g]);
          excess = max_n(excess, h[g] - (tile_row + plane.gradient.x * dx[g]));
        }
        row_top = max_lane(top);
        if (plane.valid) row_excess = max_lane(excess);
      }
    }
    if (!loaded) continue;
    changed = true;
    DoubleN top = splat(-kInf), excess = splat(-kInf);
    for (int g = 0; g < kGroups; ++g) {
      h[g] = max_n(__builtin_convertvector(__builtin_convertvector(h[g], FloatN), DoubleN),
                   splat(empty));
      store_heights(row + g * kLanes, h[g], count - g * kLanes);
      top = max_n(top, h[g]);
      excess = max_n(excess, h[g] - (tile_row + plane.gradient.x * dx[g]));
    }
    state.row_top[r] = max_lane(top);
    state.row_excess[r] = plane.valid ? max_lane(excess) : -kInf;
  }
  if (changed) state.summarise(t.j1 - t.j0 + 1);
}

}  // namespace tridex::detail
