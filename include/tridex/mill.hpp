// tridex — Z-map milling (Step 1 of Inui, Chen and Umezu, CAD&A 19(4) 2022, §3.1).
//
// Each linear move of the tool tip lowers every grid point to the lowest point of the swept
// cutter above it. For a move C(t) = a + t·(b − a), t ∈ [0, 1], and a grid point q, that is
//     min_t f(t),   f(t) = C_z(t) + h(|q − C_xy(t)|)
// with h the cutter's lower surface (cutter.hpp). f is convex in t (a convex function of an
// affine map plus a linear term), so its minimum is exact:
//   * flat end: f is linear where the disc covers q, so the minimum is at an end of that interval;
//   * ball end: setting f'(t) = 0 gives the closed form t* = t⊥ − w·k / (|v|·√(|v|² + w²)), with
//     v the move's horizontal vector, w its rise, t⊥ the foot of q on the move and k² = R² − e²
//     (e the distance from q to the move's line), clamped to the covering interval (the lowest
//     hit of a vertical line with a capsule);
//   * other cutters: bisection on the sign of f'(t), to the precision of double.
//
// Speed comes from touching only what a move can still lower. The grid is cut into 16×16-point
// tiles, each with the maximum height it holds; a move skips a tile when the lowest its cutter
// can reach there (the move's lowest tip plus h at the tile's distance from the move) is not
// below that maximum. Moves are binned to 128×128-point blocks, and the blocks are milled on all
// threads. Every point ends at the minimum over moves of a value computed the same way whatever
// the order, so the result is identical for any thread count and any move order.
#pragma once

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>
#include <thread>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/error.hpp"
#include "tridex/geometry.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

// A straight move of the tool tip in the Z-map's frame, cut with cutters[cutter].
struct CutMove {
  Segment tip;
  std::uint32_t cutter = 0;
};

struct MillOptions {
  unsigned threads = 0;  // 0: every hardware thread
};

namespace detail {

constexpr int kTile = 16;        // points along each side of a tile
constexpr int kBinTiles = 8;     // tiles along each side of a work block
constexpr double kInf = std::numeric_limits<double>::infinity();

// The geometry of one move, in coordinates relative to its start point.
struct MoveGeometry {
  const Cutter* cutter;
  double ax, ay, az;   // start of the tip path
  double vx, vy, w;    // horizontal displacement and rise
  double vv;           // vx² + vy²
  double inv_vv, inv_len, ball_factor;
  double radius, radius2;
  bool vertical;       // no horizontal displacement: a plunge, a retract or a point

  MoveGeometry(const Cutter& c, const Segment& s) : cutter(&c) {
    ax = s.a.x, ay = s.a.y, az = s.a.z;
    vx = s.b.x - s.a.x, vy = s.b.y - s.a.y, w = s.b.z - s.a.z;
    vv = vx * vx + vy * vy;
    radius = c.radius(), radius2 = radius * radius;
    // Below this the move is treated as vertical: the horizontal drift is far below float
    // resolution of any height.
    vertical = vv <= 1e-24 * std::max(1.0, radius2);
    inv_vv = vertical ? 0 : 1 / vv;
    inv_len = vertical ? 0 : 1 / std::sqrt(vv);
    ball_factor = vertical ? 0 : inv_len / std::sqrt(vv + w * w);
  }

  double lowest_tip() const { return std::min(az, az + w); }

  // The lowest point of the swept cutter above (x, y), or +infinity if it does not pass over it.
  double lowest_above(double x, double y) const {
    double ux = x - ax, uy = y - ay;
    double uu = ux * ux + uy * uy;
    if (vertical) {
      if (uu > radius2) return kInf;
      return lowest_tip() + cutter->lower_height(std::sqrt(uu));
    }
    double t_foot = (ux * vx + uy * vy) * inv_vv;           // foot of q on the move's line
    double e2 = std::max(0.0, uu - t_foot * t_foot * vv);   // squared distance to the line
    if (e2 > radius2) return kInf;
    double k = std::sqrt(radius2 - e2);
    double lo = std::max(0.0, t_foot - k * inv_len), hi = std::min(1.0, t_foot + k * inv_len);
    if (lo > hi) return kInf;
    switch (cutter->shape()) {
      case CutterShape::flat:
        return az + (w > 0 ? lo : hi) * w;
      case CutterShape::ball: {
        double t = std::clamp(t_foot - w * k * ball_factor, lo, hi);
        double s = t - t_foot;
        double d2 = e2 + s * s * vv;
        return az + t * w + radius - std::sqrt(std::max(0.0, radius2 - d2));
      }
      default:
        return convex_minimum(e2, t_foot, lo, hi);
    }
  }

  // min over t ∈ [lo, hi] of f(t) = az + t·w + h(√(e² + (t − t⊥)²·|v|²)) by bisection on the
  // sign of f', which is non-decreasing because f is convex.
  double convex_minimum(double e2, double t_foot, double lo, double hi) const {
    auto f = [&](double t) {
      double s = t - t_foot;
      return az + t * w + cutter->lower_height(std::sqrt(e2 + s * s * vv));
    };
    auto slope = [&](double t) {
      double s = t - t_foot;
      double d = std::sqrt(e2 + s * s * vv);
      if (d == 0) return w;
      double ds = s * vv / d;  // dd/dt
      double dh = cutter->lower_slope(std::min(d, radius));
      return w + (ds == 0 ? 0 : dh * ds);
    };
    if (slope(lo) >= 0) return f(lo);
    if (slope(hi) <= 0) return f(hi);
    for (int iteration = 0; iteration < 64 && hi - lo > 1e-15; ++iteration) {
      double mid = 0.5 * (lo + hi);
      (slope(mid) > 0 ? hi : lo) = mid;
    }
    return std::min(f(lo), f(hi));
  }
};

inline double distance_to_rect(double px, double py, double x0, double y0, double x1, double y1) {
  double dx = std::max({x0 - px, 0.0, px - x1}), dy = std::max({y0 - py, 0.0, py - y1});
  return std::sqrt(dx * dx + dy * dy);
}

// Distance between the horizontal projection of a move and a rectangle.
inline double distance_move_rect(const MoveGeometry& m, double x0, double y0, double x1,
                                 double y1) {
  double bx = m.ax + m.vx, by = m.ay + m.vy;
  // Does the segment cross the rectangle? Clip it (Liang–Barsky).
  double t0 = 0, t1 = 1;
  auto clip = [&](double p, double q) {
    if (p == 0) return q >= 0;
    double r = q / p;
    if (p < 0) t0 = std::max(t0, r);
    else t1 = std::min(t1, r);
    return t0 <= t1;
  };
  if (clip(-m.vx, m.ax - x0) && clip(m.vx, x1 - m.ax) && clip(-m.vy, m.ay - y0) &&
      clip(m.vy, y1 - m.ay))
    return 0;
  double best = std::min(distance_to_rect(m.ax, m.ay, x0, y0, x1, y1),
                         distance_to_rect(bx, by, x0, y0, x1, y1));
  Vec2 a(m.ax, m.ay), b(bx, by);
  for (Vec2 corner : {Vec2(x0, y0), Vec2(x1, y0), Vec2(x0, y1), Vec2(x1, y1)})
    best = std::min(best, std::sqrt(distance2_point_segment(corner, a, b)));
  return best;
}

// The x-interval where the cutter's footprint (a capsule of the cutter radius around the move)
// meets the row y; false if it does not.
inline bool footprint_row(const MoveGeometry& m, double y, double& x_lo, double& x_hi) {
  x_lo = kInf, x_hi = -kInf;
  auto disc = [&](double cx, double cy) {
    double dy = y - cy;
    if (dy * dy > m.radius2) return;
    double half = std::sqrt(m.radius2 - dy * dy);
    x_lo = std::min(x_lo, cx - half), x_hi = std::max(x_hi, cx + half);
  };
  disc(m.ax, m.ay);
  disc(m.ax + m.vx, m.ay + m.vy);
  if (!m.vertical && m.vy != 0) {
    // The band between the end discs: 0 ≤ (p − a)·v ≤ |v|² and |(p − a) × v| ≤ R·|v|. The
    // rectangle's x-extent on this row lies between its two long sides' crossings.
    double uy = y - m.ay, len = std::sqrt(m.vv);
    // (x − ax)·vx + uy·vy ∈ [0, vv] and (x − ax)·vy − uy·vx ∈ [−R·len, R·len]
    double lo = -kInf, hi = kInf;
    auto constrain = [&](double coefficient, double offset, double low, double high) {
      if (coefficient == 0) {
        if (offset < low || offset > high) lo = kInf;
        return;
      }
      double r0 = (low - offset) / coefficient, r1 = (high - offset) / coefficient;
      if (r0 > r1) std::swap(r0, r1);
      lo = std::max(lo, r0), hi = std::min(hi, r1);
    };
    constrain(m.vx, uy * m.vy, 0, m.vv);
    constrain(m.vy, -uy * m.vx, -m.radius * len, m.radius * len);
    if (lo <= hi) x_lo = std::min(x_lo, m.ax + lo), x_hi = std::max(x_hi, m.ax + hi);
  } else if (!m.vertical) {
    // A move along x: the band is the rows within R of the line.
    if (std::abs(y - m.ay) <= m.radius)
      x_lo = std::min(x_lo, std::min(m.ax, m.ax + m.vx)),
      x_hi = std::max(x_hi, std::max(m.ax, m.ax + m.vx));
  }
  return x_lo <= x_hi;
}

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
    bin_moves();
    tile_max_.assign(static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_), 0);
    std::atomic<std::size_t> next_bin{0};
    std::size_t bin_count = static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(bins_y_);
    auto worker = [&] {
      for (std::size_t b; (b = next_bin.fetch_add(1)) < bin_count;) mill_bin(b);
    };
    threads = std::max(1u, std::min<unsigned>(threads, static_cast<unsigned>(bin_count)));
    std::vector<std::thread> pool;
    for (unsigned t = 1; t < threads; ++t) pool.emplace_back(worker);
    worker();
    for (std::thread& t : pool) t.join();
  }

 private:
  // Grid-index box of a move's footprint, clipped to the grid; false if it misses the grid.
  bool footprint_box(const CutMove& move, int& i0, int& j0, int& i1, int& j1) const {
    double r = cutters_[move.cutter].radius();
    double x_lo = std::min(move.tip.a.x, move.tip.b.x) - r, x_hi = std::max(move.tip.a.x, move.tip.b.x) + r;
    double y_lo = std::min(move.tip.a.y, move.tip.b.y) - r, y_hi = std::max(move.tip.a.y, move.tip.b.y) + r;
    double fi0 = std::ceil((x_lo - g_.x0) / g_.cell), fi1 = std::floor((x_hi - g_.x0) / g_.cell);
    double fj0 = std::ceil((y_lo - g_.y0) / g_.cell), fj1 = std::floor((y_hi - g_.y0) / g_.cell);
    // One point of slack on each side against rounding; the exact test is per point.
    fi0 = std::max(fi0 - 1, 0.0), fj0 = std::max(fj0 - 1, 0.0);
    fi1 = std::min(fi1 + 1, g_.nx - 1.0), fj1 = std::min(fj1 + 1, g_.ny - 1.0);
    if (fi0 > fi1 || fj0 > fj1) return false;
    i0 = static_cast<int>(fi0), i1 = static_cast<int>(fi1);
    j0 = static_cast<int>(fj0), j1 = static_cast<int>(fj1);
    return true;
  }

  // Counting sort of move indices into blocks, keeping program order within each block.
  void bin_moves() {
    std::size_t bin_count = static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(bins_y_);
    bin_start_.assign(bin_count + 1, 0);
    const int span = kTile * kBinTiles;
    auto for_each_bin = [&](const CutMove& move, auto&& visit) {
      int i0, j0, i1, j1;
      if (!footprint_box(move, i0, j0, i1, j1)) return;
      for (int by = j0 / span; by <= j1 / span; ++by)
        for (int bx = i0 / span; bx <= i1 / span; ++bx)
          visit(static_cast<std::size_t>(bx) + static_cast<std::size_t>(bins_x_) * static_cast<std::size_t>(by));
    };
    for (const CutMove& move : moves_) for_each_bin(move, [&](std::size_t b) { ++bin_start_[b + 1]; });
    for (std::size_t b = 0; b < bin_count; ++b) bin_start_[b + 1] += bin_start_[b];
    bin_moves_.resize(bin_start_[bin_count]);
    std::vector<std::size_t> fill(bin_start_.begin(), bin_start_.end() - 1);
    for (std::size_t m = 0; m < moves_.size(); ++m)
      for_each_bin(moves_[m], [&](std::size_t b) { bin_moves_[fill[b]++] = static_cast<std::uint32_t>(m); });
  }

  float tile_maximum(int tx, int ty) const {
    float top = -std::numeric_limits<float>::infinity();
    int i_end = std::min(g_.nx, (tx + 1) * kTile), j_end = std::min(g_.ny, (ty + 1) * kTile);
    for (int j = ty * kTile; j < j_end; ++j) {
      const float* row = &map_.heights[g_.index(0, j)];
      for (int i = tx * kTile; i < i_end; ++i) top = std::max(top, row[i]);
    }
    return top;
  }

  void mill_bin(std::size_t bin) {
    int bx = static_cast<int>(bin % static_cast<std::size_t>(bins_x_));
    int by = static_cast<int>(bin / static_cast<std::size_t>(bins_x_));
    int tx0 = bx * kBinTiles, ty0 = by * kBinTiles;
    int tx1 = std::min(tiles_x_, tx0 + kBinTiles) - 1, ty1 = std::min(tiles_y_, ty0 + kBinTiles) - 1;
    if (bin_start_[bin] == bin_start_[bin + 1]) return;
    for (int ty = ty0; ty <= ty1; ++ty)
      for (int tx = tx0; tx <= tx1; ++tx) tile_max_[tile_index(tx, ty)] = tile_maximum(tx, ty);

    const float empty = map_.empty_height;
    for (std::size_t k = bin_start_[bin]; k < bin_start_[bin + 1]; ++k) {
      const CutMove& move = moves_[bin_moves_[k]];
      MoveGeometry m(cutters_[move.cutter], move.tip);
      int i0 = 0, j0 = 0, i1 = -1, j1 = -1;
      footprint_box(move, i0, j0, i1, j1);
      int mtx0 = std::max(tx0, i0 / kTile), mtx1 = std::min(tx1, i1 / kTile);
      int mty0 = std::max(ty0, j0 / kTile), mty1 = std::min(ty1, j1 / kTile);
      double lowest_tip = m.lowest_tip();
      for (int ty = mty0; ty <= mty1; ++ty)
        for (int tx = mtx0; tx <= mtx1; ++tx) {
          float& top = tile_max_[tile_index(tx, ty)];
          int ti0 = tx * kTile, tj0 = ty * kTile;
          int ti1 = std::min(g_.nx, ti0 + kTile) - 1, tj1 = std::min(g_.ny, tj0 + kTile) - 1;
          // The lowest the cutter can reach over this tile; h is non-decreasing in distance.
          double distance = distance_move_rect(m, g_.x(ti0), g_.y(tj0), g_.x(ti1), g_.y(tj1));
          if (distance > m.radius) continue;
          if (lowest_tip + m.cutter->lower_height(distance) >= top) continue;
          if (mill_tile(m, ti0, tj0, ti1, tj1, empty)) top = tile_maximum(tx, ty);
        }
    }
  }

  // Lowers the points of one tile; true if any point changed.
  bool mill_tile(const MoveGeometry& m, int ti0, int tj0, int ti1, int tj1, float empty) {
    bool changed = false;
    for (int j = tj0; j <= tj1; ++j) {
      double y = g_.y(j), x_lo, x_hi;
      if (!footprint_row(m, y, x_lo, x_hi)) continue;
      int i_lo = std::max(ti0, static_cast<int>(std::ceil((x_lo - g_.x0) / g_.cell)) - 1);
      int i_hi = std::min(ti1, static_cast<int>(std::floor((x_hi - g_.x0) / g_.cell)) + 1);
      float* row = &map_.heights[g_.index(0, j)];
      for (int i = i_lo; i <= i_hi; ++i) {
        double z = m.lowest_above(g_.x(i), y);
        if (z < row[i]) {
          float lowered = std::max(static_cast<float>(z), empty);
          if (lowered < row[i]) row[i] = lowered, changed = true;
        }
      }
    }
    return changed;
  }

  std::size_t tile_index(int tx, int ty) const {
    return static_cast<std::size_t>(tx) + static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(ty);
  }

  ZMap& map_;
  const ZMapGrid& g_;
  std::span<const Cutter> cutters_;
  std::span<const CutMove> moves_;
  int tiles_x_, tiles_y_, bins_x_, bins_y_;
  std::vector<float> tile_max_;
  std::vector<std::size_t> bin_start_;
  std::vector<std::uint32_t> bin_moves_;
};

}  // namespace detail

// Mills `moves` (tool-tip segments in the Z-map's frame) into `map`. Throws tridex::Error, before
// changing anything, if a move is not finite or names a missing cutter.
inline void mill(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves,
                 MillOptions options = {}) {
  if (moves.size() > std::numeric_limits<std::uint32_t>::max())
    detail::fail("mill: too many moves in one call (", moves.size(), ")");
  for (std::size_t k = 0; k < moves.size(); ++k) {
    if (!is_finite(moves[k].tip.a) || !is_finite(moves[k].tip.b))
      detail::fail("mill: move ", k, " has a coordinate that is not finite");
    if (moves[k].cutter >= cutters.size())
      detail::fail("mill: move ", k, " uses cutter ", moves[k].cutter, " but only ",
                   cutters.size(), " are given");
  }
  if (map.heights.size() != map.grid.size()) detail::fail("mill: Z-map heights do not match its grid");
  unsigned threads = options.threads ? options.threads : std::max(1u, std::thread::hardware_concurrency());
  detail::Miller(map, cutters, moves).run(threads);
}

}  // namespace tridex
