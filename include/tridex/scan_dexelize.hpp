// tridex — scan-conversion dexelization of a Z-map (Step 2 of Inui, Chen and Umezu, CAD&A 19(4)
// 2022, §4.2, done without the paper's AABB tree).
//
// The rays of a triple dexel are axis-parallel and sit on a regular grid, so a triangle can be
// scan-converted onto each family's ray grid the way a rasteriser fills pixels: the rays it
// covers are the lattice points inside its projection. The Z-map's polyhedron (polyhedron.hpp)
// is never built: its top triangles come straight from the height grid, two per cell along the
// diagonal (i, j)–(i+1, j+1); the walls drop from the border to the bottom; the bottom is one
// rectangle. Most cells are smaller than a ray spacing and are rejected by a bounding-box test
// on four projected points. A fine cell (ZMapFineCells) is scanned as its sub-grid's triangles
// and its vertical steps to plain neighbours (polyhedron.hpp).
//
// Exactness follows dexelize.hpp (b): projected points live on a fixed-point grid of 2^F
// subdivisions of the lattice spacing, where point-in-triangle tests are exact, and a ray lying
// on a projected edge or vertex is moved to (u + ε, v + ε²) (Edelsbrunner & Mücke 1990), so it
// crosses the closed surface an even number of times and never loses or doubles a hit. One
// difference: the fixed-point projection of grid point (i, j) at height h is taken as
//     Q(i, j, h) = q0 + i·qx + j·qy + round(h·qz)
// with the affine map's coefficients rounded once, not each point's position. The bottom's
// border points then lie exactly on the lines between its corners, so the bottom can be two
// triangles (the wall triangles meeting it at exactly collinear T-junctions classify every ray
// the same way). Edge functions use 128-bit products, so F can be large (up to 40 bits) and
// the rounding of the coefficients moves no point by more than ~1e-8 spacings.
//
// Crossings are sorted per ray; the solid is where the winding number (enter +1, leave −1) is
// positive. The result equals dexelize(map, lattice) (the grid tree) up to float rounding of the
// end points, except where a ray grazes the surface exactly.
#pragma once

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstdint>
#include <limits>
#include <span>
#include <vector>

#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/error.hpp"
#include "tridex/parallel.hpp"
#include "tridex/polyhedron.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

namespace detail {

// The 128-bit integer type of the exact edge functions (GCC and Clang).
__extension__ using ScanWide = __int128;

// double(x) rounded to nearest, ties to even, as the compiler's conversion (__floattidf, a
// library call that was a tenth of the scan) gives it: a value of 64 bits converts directly;
// a wider one is shifted right to 62 or 63 bits with the bits shifted out kept as one sticky
// bit (rounding to odd), which the 64-bit conversion then rounds correctly (Boldo & Melquiond,
// "Emulation of FMA and correctly rounded sums: proved algorithms using rounding to odd", IEEE
// Trans. Computers 57(4) 2008: rounding to odd at p + 2 or more bits, then to nearest at p).
inline double wide_to_double(ScanWide x) {
  __extension__ using Unsigned = unsigned __int128;
  const auto low = static_cast<std::int64_t>(x);
  if (static_cast<ScanWide>(low) == x) return static_cast<double>(low);
  const auto high = static_cast<std::int64_t>(x >> 64);
  const int width = 64 - std::countl_zero(static_cast<std::uint64_t>(high < 0 ? ~high : high));
  const int shift = width + 2;  // |x >> shift| < 2^62, and at least 2^61
  auto kept = static_cast<std::int64_t>(x >> shift);
  kept |= (static_cast<Unsigned>(x) & ((Unsigned{1} << shift) - 1)) != 0 ? 1 : 0;
  return static_cast<double>(kept) *
         std::bit_cast<double>(static_cast<std::uint64_t>(1023 + shift) << 52);  // 2^shift
}

// A projected vertex: fixed-point (u, v) and the world coordinate along the ray axis.
struct ScanVertex {
  std::int64_t u, v;
  double t;
};

// Scan-converts the polyhedron of one Z-map onto the rays of one family.
class ZMapScanner {
 public:
  // `highest` is the map's highest height (highest_height).
  ZMapScanner(const ZMap& map, const DexelLattice& lattice, int axis, const DexelGrid* mask,
              float highest)
      : map_(map), grid_(map.grid), lattice_(lattice), axis_(axis), mask_(mask) {
    u_ = TripleDexel::u_axis(axis), v_ = TripleDexel::v_axis(axis);
    nu_ = lattice.n[u_], nv_ = lattice.n[v_];
    bottom_ = zmap_bottom(map);
    const Mat3& r = grid_.frame.rotation;  // r[column][row]: column = local axis
    const Vec3& o = grid_.frame.origin;
    const double s = lattice.spacing, c = grid_.cell;
    // Lattice units along u and v, and world coordinate along the axis, as affine maps of (i, j,
    // h).
    double a[2], bx[2], by[2], bz[2];
    const int comps[2] = {u_, v_};
    for (int k = 0; k < 2; ++k) {
      int w = comps[k];
      a[k] = (r[0][w] * grid_.x0 + r[1][w] * grid_.y0 + o[w] - lattice.origin[w]) / s;
      bx[k] = r[0][w] * c / s, by[k] = r[1][w] * c / s, bz[k] = r[2][w] / s;
    }
    t0_ = r[0][axis] * grid_.x0 + r[1][axis] * grid_.y0 + o[axis];
    // Per sub-step of a fine cell (kSteps a power of two, so a grid step is exactly kSteps of
    // them and a grid point's t is the same computed either way).
    tx_ = r[0][axis] * c / kSteps, ty_ = r[1][axis] * c / kSteps, tz_ = r[2][axis];
    // Fixed point: every |Q| below 2^61 so that differences stay below 2^62 and the edge
    // functions (sums of two products) below 2^125.
    const double top = std::max({bottom_, double(highest), double(map.empty_height)});
    double reach = std::max(nu_, nv_) + 2.0;
    for (int ci = 0; ci < 2; ++ci)
      for (int cj = 0; cj < 2; ++cj)
        for (double h : {bottom_, top}) {
          double i = ci ? grid_.nx - 1 : 0, j = cj ? grid_.ny - 1 : 0;
          for (int k = 0; k < 2; ++k)
            reach = std::max(reach, std::abs(a[k] + i * bx[k] + j * by[k] + h * bz[k]));
        }
    int bits = 59 - static_cast<int>(std::ceil(std::log2(reach + 2)));
    if (bits < 16)
      fail("scan dexelize: the Z-map reaches ", reach,
           " spacings from the lattice origin, too far for exact ray tests");
    bits_ = std::min(bits, 40);
    const double scale = std::ldexp(1.0, bits_);
    // A grid step is exactly kSteps fine sub-steps, so a grid point has the same fixed-point
    // coordinates whether a plain cell or a fine one asks.
    for (int k = 0; k < 2; ++k) {
      q0_[k] = std::llround(a[k] * scale), qz_[k] = bz[k] * scale;
      qx_[k] = kSteps * std::llround(bx[k] / kSteps * scale),
      qy_[k] = kSteps * std::llround(by[k] / kSteps * scale);
    }
    // Every vertex of the top lies between these heights (fine sub-points too).
    low_ = double(map.empty_height), high_ = top;
    for (float h : map.fine.heights)
      low_ = std::min(low_, double(h)), high_ = std::max(high_, double(h));
    for (int i = 0; i + 1 < grid_.nx; ++i)
      if (reaches_rays(std::int64_t{kSteps} * i, std::int64_t{kSteps} * (i + 1), 0,
                       std::int64_t{kSteps} * (grid_.ny - 1)))
        live_columns_.push_back(i);
  }

  // Appends the crossings of the top triangles of cell rows [j0, j1) to `hits`. Only the rows
  // and the columns of cells whose vertices can reach a ray are visited: a family's rays cross
  // the grid's rows (or columns) a ray spacing apart, when a lattice axis lies in the map's
  // plane, and most cells lie between them.
  void scan_rows(int j0, int j1, std::vector<MeshHit>& hits) const {
    if (2 * live_columns_.size() < static_cast<std::size_t>(grid_.nx))
      scan_live_columns(j0, j1, hits);
    else
      scan_all_columns(j0, j1, hits);
  }

  // Appends the crossings of the four walls to `hits`.
  void scan_walls(std::vector<MeshHit>& hits) const {
    const int nx = grid_.nx, ny = grid_.ny;
    // Each border edge p0 → p1, counter-clockwise seen from above; the outside is to the right.
    auto wall = [&](int i0, int j0, int i1, int j1) {
      double h0 = zmap_top(map_, grid_.index(i0, j0)), h1 = zmap_top(map_, grid_.index(i1, j1));
      ScanVertex t0 = vertex(i0, j0, h0), t1 = vertex(i1, j1, h1);
      ScanVertex b0 = vertex(i0, j0, bottom_), b1 = vertex(i1, j1, bottom_);
      triangle(b0, b1, t1, hits);
      triangle(b0, t1, t0, hits);
    };
    for (int i = 0; i + 1 < nx; ++i) wall(i, 0, i + 1, 0);
    for (int j = 0; j + 1 < ny; ++j) wall(nx - 1, j, nx - 1, j + 1);
    for (int i = nx - 1; i > 0; --i) wall(i, ny - 1, i - 1, ny - 1);
    for (int j = ny - 1; j > 0; --j) wall(0, j, 0, j - 1);
  }

  // Appends the crossings of the bottom to `hits`: two triangles under the whole map, so one
  // crossing on every ray of the family along the spindle.
  void scan_bottom(std::vector<MeshHit>& hits) const {
    const int nx = grid_.nx, ny = grid_.ny;
    ScanVertex c0 = vertex(0, 0, bottom_), c1 = vertex(nx - 1, 0, bottom_);
    ScanVertex c2 = vertex(nx - 1, ny - 1, bottom_), c3 = vertex(0, ny - 1, bottom_);
    triangle(c0, c2, c1, hits);  // facing down
    triangle(c0, c3, c2, hits);
  }

  int bits() const { return bits_; }

 private:
  static constexpr int kSteps = ZMapFineCells::kSteps;

  // Whether a ray of the family can meet a vertex rectangle: the fine sub-points I0..I1, J0..J1
  // (grid point (i, j) is (kSteps·i, kSteps·j)) at any height of the top. Each coordinate is an
  // affine map of (I, J) plus a rounding monotone in the height, so its extremes lie at the
  // corners; a triangle's rays (triangle()) lie within its vertices' range.
  bool reaches_rays(std::int64_t I0, std::int64_t I1, std::int64_t J0, std::int64_t J1) const {
    const std::int64_t n[2] = {nu_, nv_};
    for (int k = 0; k < 2; ++k) {
      const std::int64_t sx = qx_[k] / kSteps, sy = qy_[k] / kSteps;
      const std::int64_t r0 = round_fixed(low_ * qz_[k]), r1 = round_fixed(high_ * qz_[k]);
      const std::int64_t lo =
          q0_[k] + std::min(I0 * sx, I1 * sx) + std::min(J0 * sy, J1 * sy) + std::min(r0, r1);
      const std::int64_t hi =
          q0_[k] + std::max(I0 * sx, I1 * sx) + std::max(J0 * sy, J1 * sy) + std::max(r0, r1);
      if (std::max<std::int64_t>(0, ceil_units(lo)) > std::min(n[k] - 1, ceil_units(hi) - 1))
        return false;
    }
    return true;
  }

  bool row_reaches_rays(int j) const {
    return reaches_rays(0, std::int64_t{kSteps} * (grid_.nx - 1), std::int64_t{kSteps} * j,
                        std::int64_t{kSteps} * (j + 1));
  }

  // The fine cells of cell row j, ascending (both null when the map has none).
  std::pair<const std::uint32_t*, const std::uint32_t*> row_fine_cells(int j) const {
    if (map_.fine.empty()) return {nullptr, nullptr};
    const std::uint32_t* cells = map_.fine.cells.data();
    return {cells + map_.fine.row_begin[static_cast<std::size_t>(j)],
            cells + map_.fine.row_begin[static_cast<std::size_t>(j) + 1]};
  }

  const float* fine_heights(const std::uint32_t* fine) const {
    return map_.fine.heights.data() +
           static_cast<std::size_t>(fine - map_.fine.cells.data()) * ZMapFineCells::kPoints;
  }

  // Every cell of the rows that can reach a ray, from rows of vertices filled once each.
  void scan_all_columns(int j0, int j1, std::vector<MeshHit>& hits) const {
    const int nx = grid_.nx;
    std::vector<ScanVertex> lower(static_cast<std::size_t>(nx)),
        upper(static_cast<std::size_t>(nx));
    std::vector<double> hl(static_cast<std::size_t>(nx)), hu(static_cast<std::size_t>(nx));
    int filled = -1;  // the row `lower` holds
    for (int j = j0; j < j1; ++j) {
      if (!row_reaches_rays(j)) continue;
      if (filled != j) fill_row(j, lower, hl);
      fill_row(j + 1, upper, hu);
      filled = j + 1;
      // The row's fine cells, in ascending order: each is scanned as its sub-grid instead.
      auto [fine, fine_end] = row_fine_cells(j);
      const std::size_t row_base = grid_.index(0, j);
      for (int i = 0; i + 1 < nx; ++i) {
        const auto ii = static_cast<std::size_t>(i);
        if (fine != fine_end && *fine == row_base + ii) {
          fine_cell(i, j, fine_heights(fine), hits);
          ++fine;
          continue;
        }
        plain_cell(i, j, lower[ii], lower[ii + 1], upper[ii], upper[ii + 1], hl[ii], hl[ii + 1],
                   hu[ii], hu[ii + 1], hits);
      }
      std::swap(lower, upper);
      std::swap(hl, hu);
    }
  }

  // Only the columns that can reach a ray (live_columns_), their vertices computed cell by cell.
  // A row's vertices are kept for the next row, whose lower corners they are.
  void scan_live_columns(int j0, int j1, std::vector<MeshHit>& hits) const {
    const std::size_t m = live_columns_.size();
    std::vector<ScanVertex> lower(2 * m), upper(2 * m);  // columns i and i + 1 of each
    std::vector<double> hl(2 * m), hu(2 * m);
    auto fill = [&](int j, std::vector<ScanVertex>& row, std::vector<double>& h) {
      for (std::size_t k = 0; k < m; ++k)
        for (std::size_t c = 0; c < 2; ++c)
          row[2 * k + c] = grid_vertex(live_columns_[k] + static_cast<int>(c), j, h[2 * k + c]);
    };
    int filled = -1;  // the row `lower` holds
    for (int j = j0; j < j1; ++j) {
      if (!row_reaches_rays(j)) continue;
      if (filled != j) fill(j, lower, hl);
      fill(j + 1, upper, hu);
      filled = j + 1;
      auto [fine, fine_end] = row_fine_cells(j);
      const std::size_t row_base = grid_.index(0, j);
      for (std::size_t k = 0; k < m; ++k) {
        const int i = live_columns_[k];
        const auto ii = static_cast<std::size_t>(i);
        while (fine != fine_end && *fine < row_base + ii) ++fine;
        if (fine != fine_end && *fine == row_base + ii) {
          fine_cell(i, j, fine_heights(fine), hits);
          ++fine;
          continue;
        }
        plain_cell(i, j, lower[2 * k], lower[2 * k + 1], upper[2 * k], upper[2 * k + 1], hl[2 * k],
                   hl[2 * k + 1], hu[2 * k], hu[2 * k + 1], hits);
      }
      std::swap(lower, upper);
      std::swap(hl, hu);
    }
  }

  // Grid point (i, j)'s vertex as fill_row gives it (its t unset), and its height in `h`.
  ScanVertex grid_vertex(int i, int j, double& h) const {
    h = std::max(double(map_.heights[grid_.index(i, j)]), double(map_.empty_height));
    return {q0_[0] + j * qy_[0] + i * qx_[0] + round_fixed(h * qz_[0]),
            q0_[1] + j * qy_[1] + i * qx_[1] + round_fixed(h * qz_[1]), 0};
  }

  // A plain cell: its two top triangles, from its corners' vertices (t unset) and heights.
  void plain_cell(int i, int j, const ScanVertex& p00, const ScanVertex& p10, const ScanVertex& p01,
                  const ScanVertex& p11, double h00, double h10, double h01, double h11,
                  std::vector<MeshHit>& hits) const {
    std::int64_t lo_u = std::min(std::min(p00.u, p10.u), std::min(p01.u, p11.u));
    std::int64_t hi_u = std::max(std::max(p00.u, p10.u), std::max(p01.u, p11.u));
    std::int64_t iu0 = ceil_units(lo_u), iu1 = ceil_units(hi_u) - 1;
    if (iu0 > iu1) return;  // no ray column inside the cell's projection: the common case
    std::int64_t lo_v = std::min(std::min(p00.v, p10.v), std::min(p01.v, p11.v));
    std::int64_t hi_v = std::max(std::max(p00.v, p10.v), std::max(p01.v, p11.v));
    std::int64_t iv0 = ceil_units(lo_v), iv1 = ceil_units(hi_v) - 1;
    if (iv0 > iv1) return;
    // The t of each corner is only needed now.
    ScanVertex a = p00, b = p10, c = p11, d = p01;
    const std::int64_t I = std::int64_t{kSteps} * i, J = std::int64_t{kSteps} * j;
    a.t = world_t(I, J, h00), b.t = world_t(I + kSteps, J, h10);
    c.t = world_t(I + kSteps, J + kSteps, h11), d.t = world_t(I, J + kSteps, h01);
    triangle(a, b, c, hits);
    triangle(a, c, d, hits);
  }

  // A fine cell (ZMapFineCells): the triangles of its sub-grid, and the vertical steps along its
  // edges to plain neighbours (polyhedron.hpp, fine_cell_step).
  void fine_cell(int i, int j, const float* f, std::vector<MeshHit>& hits) const {
    constexpr int kSide = ZMapFineCells::kSide;
    ScanVertex p[ZMapFineCells::kPoints];
    std::int64_t lo_u = std::numeric_limits<std::int64_t>::max(),
                 hi_u = std::numeric_limits<std::int64_t>::min();
    std::int64_t lo_v = lo_u, hi_v = hi_u;
    for (int b = 0; b < kSide; ++b)
      for (int a = 0; a < kSide; ++a) {
        ScanVertex& q = p[a + kSide * b];
        q = sub_vertex(std::int64_t{kSteps} * i + a, std::int64_t{kSteps} * j + b,
                       double(f[a + kSide * b]));
        lo_u = std::min(lo_u, q.u), hi_u = std::max(hi_u, q.u), lo_v = std::min(lo_v, q.v),
        hi_v = std::max(hi_v, q.v);
      }
    // The steps lie between the cell's sub-points and its straight edges, so within this box too.
    if (ceil_units(lo_u) > ceil_units(hi_u) - 1 || ceil_units(lo_v) > ceil_units(hi_v) - 1) return;
    for (int b = 0; b < kSteps; ++b)
      for (int a = 0; a < kSteps; ++a) {
        const ScanVertex &p00 = p[a + kSide * b], &p10 = p[a + 1 + kSide * b];
        const ScanVertex &p01 = p[a + kSide * (b + 1)], &p11 = p[a + 1 + kSide * (b + 1)];
        triangle(p00, p10, p11, hits);
        triangle(p00, p11, p01, hits);
      }
    for (const FineSide& side : fine_sides()) {
      if (is_fine_cell(map_, i + side.di, j + side.dj)) continue;
      const ScanVertex* q[kSide];
      for (int m = 0; m < kSide; ++m) q[m] = &p[side.point[m]];
      fine_cell_step(q, [&](const ScanVertex* a, const ScanVertex* b, const ScanVertex* c) {
        triangle(*a, *b, *c, hits);
      });
    }
  }

  // The vertex at fine sub-point (I, J) (grid point (i, j) is (kSteps·i, kSteps·j)).
  ScanVertex sub_vertex(std::int64_t I, std::int64_t J, double h) const {
    return {q0_[0] + I * (qx_[0] / kSteps) + J * (qy_[0] / kSteps) + round_fixed(h * qz_[0]),
            q0_[1] + I * (qx_[1] / kSteps) + J * (qy_[1] / kSteps) + round_fixed(h * qz_[1]),
            world_t(I, J, h)};
  }

  std::int64_t ceil_units(std::int64_t x) const { return -((-x) >> bits_); }

  // Rounding to the nearest fixed-point unit (ties away from zero), inline: llround is a libm
  // call and was a seventh of the scan. |x| < 2^62 here.
  static std::int64_t round_fixed(double x) {
    return static_cast<std::int64_t>(x + (x >= 0 ? 0.5 : -0.5));
  }

  // The world coordinate along the ray axis at fine sub-point (I, J) and height h.
  double world_t(std::int64_t I, std::int64_t J, double h) const {
    return t0_ + double(I) * tx_ + double(J) * ty_ + h * tz_;
  }

  ScanVertex vertex(int i, int j, double h) const {
    return {q0_[0] + i * qx_[0] + j * qy_[0] + round_fixed(h * qz_[0]),
            q0_[1] + i * qx_[1] + j * qy_[1] + round_fixed(h * qz_[1]),
            world_t(std::int64_t{kSteps} * i, std::int64_t{kSteps} * j, h)};
  }

  void fill_row(int j, std::vector<ScanVertex>& row, std::vector<double>& h) const {
    const std::int64_t bu = q0_[0] + j * qy_[0], bv = q0_[1] + j * qy_[1];
    const float* heights = map_.heights.data() + grid_.index(0, j);
    const double empty = map_.empty_height;
    for (int i = 0; i < grid_.nx; ++i) {
      const auto ii = static_cast<std::size_t>(i);
      double z = std::max(double(heights[i]), empty);
      h[ii] = z;
      row[ii].u = bu + i * qx_[0] + round_fixed(z * qz_[0]);
      row[ii].v = bv + i * qx_[1] + round_fixed(z * qz_[1]);
    }
  }

  // The crossings of triangle a, b, c (counter-clockwise seen from outside) with the rays.
  void triangle(const ScanVertex& a, const ScanVertex& b, const ScanVertex& c,
                std::vector<MeshHit>& hits) const {
    // The rays within its bounding box first: most triangles of a fine cell have none.
    const std::int64_t lo[2] = {std::max<std::int64_t>(0, ceil_units(std::min({a.u, b.u, c.u}))),
                                std::max<std::int64_t>(0, ceil_units(std::min({a.v, b.v, c.v})))};
    const std::int64_t hi[2] = {
        std::min<std::int64_t>(nu_ - 1, ceil_units(std::max({a.u, b.u, c.u})) - 1),
        std::min<std::int64_t>(nv_ - 1, ceil_units(std::max({a.v, b.v, c.v})) - 1)};
    if (lo[0] > hi[0] || lo[1] > hi[1]) return;
    const ScanWide area = ScanWide(b.u - a.u) * (c.v - a.v) - ScanWide(b.v - a.v) * (c.u - a.u);
    if (area == 0) return;  // seen edge-on: the perturbed ray misses it
    const int orientation = area > 0 ? 1 : -1;
    const double lo_t = std::min({a.t, b.t, c.t}), hi_t = std::max({a.t, b.t, c.t});
    double inverse_area = 0;  // found with the first crossing: most triangles have none
    // Lines of rays along the box's longer side, one per ray of its shorter side; where a line
    // holds more than two rays, only those within the triangle's extent on it are tested (a
    // long thin triangle seen at a slant, a wall of a tilted map, has a large box and covers
    // few of its rays). The exact tests below decide.
    const int outer = hi[0] - lo[0] < hi[1] - lo[1] ? 0 : 1, inner = 1 - outer;
    const bool narrow = hi[inner] - lo[inner] > 1;
    for (std::int64_t line = lo[outer]; line <= hi[outer]; ++line) {
      std::int64_t first = lo[inner], last = hi[inner];
      if (narrow && !line_extent(a, b, c, outer, line, first, last)) continue;
      for (std::int64_t k = first; k <= last; ++k) {
        const std::int64_t iu = outer == 0 ? line : k, iv = outer == 0 ? k : line;
        const std::int64_t pu = iu << bits_, pv = iv << bits_;
        ScanWide wc =
            ScanWide(b.u - a.u) * (pv - a.v) - ScanWide(b.v - a.v) * (pu - a.u);  // edge a→b
        if (perturbed_sign_wide(wc, b.u - a.u, b.v - a.v) != orientation) continue;
        ScanWide wa =
            ScanWide(c.u - b.u) * (pv - b.v) - ScanWide(c.v - b.v) * (pu - b.u);  // edge b→c
        if (perturbed_sign_wide(wa, c.u - b.u, c.v - b.v) != orientation) continue;
        ScanWide wb =
            ScanWide(a.u - c.u) * (pv - c.v) - ScanWide(a.v - c.v) * (pu - c.u);  // edge c→a
        if (perturbed_sign_wide(wb, a.u - c.u, a.v - c.v) != orientation) continue;
        auto ray = static_cast<std::uint32_t>(iu + std::int64_t{nu_} * iv);
        // Looked up for the crossings only: the mask is large and the tests above are not.
        if (mask_ && mask_->offsets[ray] == mask_->offsets[ray + 1])
          continue;  // nothing left to cut
        if (inverse_area == 0) inverse_area = 1.0 / wide_to_double(area);
        double t =
            (wide_to_double(wa) * a.t + wide_to_double(wb) * b.t + wide_to_double(wc) * c.t) *
            inverse_area;
        t = std::clamp(t, lo_t, hi_t);  // rounding: the crossing lies within the triangle's extent
        // Normal along +axis (counter-clockwise in (u, v)) means the ray leaves there.
        hits.push_back({ray, static_cast<float>(t), -orientation});
      }
    }
  }

  // Narrows [first, last], the rays of a line (coordinate `outer` of its rays = line), to those
  // within the triangle's extent on it, widened by a few fixed-point units for rounding; false
  // when none is left. The extent is computed in double relative to vertex a, exactly up to the
  // last division and addition (each rounding by at most an ulp of values below 2^53 units: 3
  // units in all); a triangle too large for that keeps the whole line.
  bool line_extent(const ScanVertex& a, const ScanVertex& b, const ScanVertex& c, int outer,
                   std::int64_t line, std::int64_t& first, std::int64_t& last) const {
    constexpr std::int64_t kExact = std::int64_t{1} << 52, kSlack = 16;
    const ScanVertex* p[3] = {&a, &b, &c};
    std::int64_t o[3], in[3];  // relative to a
    for (int k = 0; k < 3; ++k) {
      o[k] = outer == 0 ? p[k]->u - a.u : p[k]->v - a.v;
      in[k] = outer == 0 ? p[k]->v - a.v : p[k]->u - a.u;
      if (o[k] <= -kExact || o[k] >= kExact || in[k] <= -kExact || in[k] >= kExact) return true;
    }
    const std::int64_t origin_o = outer == 0 ? a.u : a.v, origin_in = outer == 0 ? a.v : a.u;
    const auto x = static_cast<double>((line << bits_) - origin_o);
    double lo = std::numeric_limits<double>::infinity(), hi = -lo;
    for (int e = 0; e < 3; ++e) {
      const double p_o = double(o[e]), q_o = double(o[(e + 1) % 3]);
      const double p_in = double(in[e]), q_in = double(in[(e + 1) % 3]);
      if (x < std::min(p_o, q_o) || x > std::max(p_o, q_o)) continue;
      if (p_o == q_o) {
        lo = std::min({lo, p_in, q_in}), hi = std::max({hi, p_in, q_in});
      } else {
        const double at = p_in + (x - p_o) * (q_in - p_in) / (q_o - p_o);
        lo = std::min(lo, at), hi = std::max(hi, at);
      }
    }
    if (!(lo <= hi)) return false;
    const auto lo_units = static_cast<std::int64_t>(std::floor(lo)) - kSlack + origin_in;
    const auto hi_units = static_cast<std::int64_t>(std::ceil(hi)) + kSlack + origin_in;
    first = std::max(first, ceil_units(lo_units));
    last = std::min(last, hi_units >> bits_);
    return first <= last;
  }

  static int perturbed_sign_wide(ScanWide value, std::int64_t du, std::int64_t dv) {
    if (value != 0) return value > 0 ? 1 : -1;
    return perturbed_sign(0, du, dv);
  }

  const ZMap& map_;
  const ZMapGrid& grid_;
  const DexelLattice& lattice_;
  int axis_, u_ = 0, v_ = 0, nu_ = 0, nv_ = 0;
  const DexelGrid* mask_;
  double bottom_ = 0;
  int bits_ = 0;
  std::int64_t q0_[2]{}, qx_[2]{}, qy_[2]{};
  double qz_[2]{};
  double t0_ = 0, tx_ = 0, ty_ = 0, tz_ = 0;
  double low_ = 0, high_ = 0;      // the top's lowest and highest vertex heights
  std::vector<int> live_columns_;  // the cell columns whose vertices can reach a ray
};

// The highest of a map's heights, on `threads` threads: found once per map, not per family.
inline float highest_height(const ZMap& map, unsigned threads) {
  constexpr std::size_t kChunk = std::size_t{1} << 20, kPartials = 16;
  const std::size_t n = map.heights.size(), chunks = (n + kChunk - 1) / kChunk;
  std::vector<float> part(chunks, -std::numeric_limits<float>::infinity());
  for_each_chunk(chunks, threads, [&](std::size_t c) {
    const float* h = map.heights.data() + c * kChunk;
    const std::size_t count = std::min(kChunk, n - c * kChunk);
    float lane[kPartials];  // independent maxima, so that the loop vectorises
    std::fill_n(lane, kPartials, -std::numeric_limits<float>::infinity());
    std::size_t k = 0;
    for (; k + kPartials <= count; k += kPartials)
      for (std::size_t l = 0; l < kPartials; ++l) lane[l] = h[k + l] > lane[l] ? h[k + l] : lane[l];
    for (; k < count; ++k) lane[0] = h[k] > lane[0] ? h[k] : lane[0];
    part[c] = *std::max_element(lane, lane + kPartials);
  });
  return *std::max_element(part.begin(), part.end());
}

// One family of rays: scan on `threads` threads, then the grid from the crossings
// (grid_from_hits), each ray's spans handed to emit(r, spans, out) (grid_from_hits).
// `highest` is highest_height(map).
template <class Emit>
DexelGrid scan_family(const ZMap& map, const DexelLattice& lattice, int axis, unsigned threads,
                      const DexelGrid* mask, float highest, Emit&& emit) {
  const ZMapScanner scanner(map, lattice, axis, mask, highest);
  threads = resolve_threads(threads);
  const int rows = map.grid.ny - 1;
  const int rows_per_item = 16;
  // The first two items: the bottom and the walls. The bottom crosses every ray along the spindle,
  // far more work than a band of rows: handed out last (as it was), it ran on one thread while
  // the others had finished (bench/README.md, issue 37). The crossings' order does not matter
  // (grid_from_hits).
  const int items = (rows + rows_per_item - 1) / rows_per_item + 2;
  std::vector<std::vector<MeshHit>> found(threads);
  for_each_chunk_indexed(
      static_cast<std::size_t>(items), threads, [&](std::size_t chunk, unsigned id) {
        const int item = static_cast<int>(chunk) - 2;
        if (item == -2)
          scanner.scan_bottom(found[id]);
        else if (item == -1)
          scanner.scan_walls(found[id]);
        else
          scanner.scan_rows(item * rows_per_item, std::min(rows, (item + 1) * rows_per_item),
                            found[id]);
      });
  const std::size_t nu = static_cast<std::size_t>(lattice.n[TripleDexel::u_axis(axis)]);
  return grid_from_hits(
      lattice, axis, threads, found,
      [&](std::size_t r, float t) {
        fail("scan dexelize: unbalanced crossings on ray ", r % nu, ", ", r / nu, " along axis ",
             "xyz"[axis], " at ", t, " (an internal error: please report the Z-map and lattice)");
      },
      emit);
}

}  // namespace detail

// The polyhedron of a Z-map (polyhedron.hpp) on `lattice`, by scan conversion. Throws
// tridex::Error for an invalid lattice, a Z-map with fewer than 2 × 2 points, or one reaching
// too far beyond the lattice for exact arithmetic (over ~10^13 spacings).
inline TripleDexel scan_dexelize(const ZMap& map, const DexelLattice& lattice,
                                 unsigned threads = 0) {
  detail::require_lattice(lattice, "scan dexelize");
  detail::require_solid_zmap(map, "scan dexelize");
  TripleDexel result;
  result.origin = lattice.origin, result.spacing = lattice.spacing, result.n = lattice.n;
  const float highest = detail::highest_height(map, threads);
  for (int axis = 0; axis < 3; ++axis)
    result.grids[axis] = detail::scan_family(
        map, lattice, axis, threads, nullptr, highest,
        [](std::size_t, std::span<const DexelInterval> spans, std::vector<DexelInterval>& out) {
          out.insert(out.end(), spans.begin(), spans.end());
        });
  return result;
}

// W0 ∩ M1 ∩ … ∩ MN on the stock's lattice, each Mi scan-converted; rays already empty are not
// scanned again. Throws tridex::Error for a malformed stock or a Z-map as scan_dexelize does.
inline TripleDexel scan_intersect_milled(const TripleDexel& stock, std::span<const ZMap> milled,
                                         unsigned threads = 0) {
  validate(stock);
  for (const ZMap& map : milled) detail::require_solid_zmap(map, "scan machine");
  const DexelLattice lattice = stock.lattice();
  if (milled.empty()) return stock;
  // The first map cuts the stock's rays themselves: no copy of the stock to start from (a serial
  // copy into fresh pages, bench/README.md, issue 37).
  TripleDexel result;
  result.origin = stock.origin, result.spacing = stock.spacing, result.n = stock.n;
  for (const ZMap& map : milled) {
    const float highest = detail::highest_height(map, threads);
    const bool first = &map == milled.data();
    // Each ray's cut is intersected with the ray as it stands as soon as its spans are known:
    // the cut is never stored as a grid of its own.
    for (int axis = 0; axis < 3; ++axis) {
      const DexelGrid& current = first ? stock.grids[axis] : result.grids[axis];
      result.grids[axis] = detail::scan_family(
          map, lattice, axis, threads, &current, highest,
          [&](std::size_t r, std::span<const DexelInterval> cut, std::vector<DexelInterval>& out) {
            detail::intersect_ray(current.ray(r), cut, out);
          });
    }
  }
  return result;
}

}  // namespace tridex
