// tridex — polyhedrization of a Z-map (Step 2 of Inui, Chen and Umezu, CAD&A 19(4) 2022, §4.1).
//
// The milled Z-map is closed into a solid: the top is the height field, two triangles per cell
// split along the diagonal (i, j)–(i+1, j+1); empty points sit at the map's empty height; four
// vertical walls drop from the grid's border to a bottom rectangle one cell below the empty
// height, so that even a fully cut map encloses a slab of positive thickness. The solid is
//     { (x, y, z) local : (x, y) in the grid's rectangle, bottom ≤ z ≤ H(x, y) }
// with H the piecewise-linear interpolant on that triangulation (zmap_height below), finer on
// the map's fine cells (ZMapFineCells, zmap.hpp; their steps to plain neighbours are vertical
// faces of the solid); the grid tree (grid_tree.hpp) intersects rays with exactly this solid
// without building the mesh.
// Output is in WORLD coordinates (frame.to_world), counter-clockwise from outside.
#pragma once

#include <algorithm>
#include <array>
#include <cstdint>
#include <unordered_map>
#include <vector>

#include "tridex/error.hpp"
#include "tridex/mesh.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

namespace detail {

inline void require_solid_zmap(const ZMap& map, const char* who) {
  if (map.grid.nx < 2 || map.grid.ny < 2)
    fail(who, ": a Z-map of ", map.grid.nx, " x ", map.grid.ny,
         " points has no cell to enclose a solid");
  if (map.heights.size() != map.grid.size())
    fail(who, ": Z-map holds ", map.heights.size(), " heights for ", map.grid.size(),
         " grid points");
  if (!std::isfinite(map.empty_height)) fail(who, ": Z-map empty height is not finite");
}

// The height of the solid's top at point (i, j): empty points (and any below) at the empty height.
inline double zmap_top(const ZMap& map, std::size_t index) {
  return std::max(double(map.heights[index]), double(map.empty_height));
}

// The bottom of the closed solid, one cell below the empty height.
inline double zmap_bottom(const ZMap& map) { return double(map.empty_height) - map.grid.cell; }

// The vertical step along the edge of fine cell (i, j) from corner ca to corner cb (counter-
// clockwise round the cell seen from above), where the cell's sub-points p[0] = ca, p[1], …,
// p[kSteps] = cb meet a plain neighbour's straight edge cb → ca (or a border wall): the
// vertical polygon ca → cb → p[kSteps−1] → … → p[1], fanned from ca. Each of its edges is
// traversed opposite to the cell's or the neighbour's, so the surface stays closed wherever the
// sub-points lie above or below the straight edge. `emit(a, b, c)` takes counter-clockwise
// corners seen from outside.
template <class P, class Emit>
void fine_cell_step(const P* p, const Emit& emit) {
  constexpr int kSteps = ZMapFineCells::kSteps;
  emit(p[0], p[kSteps], p[kSteps - 1]);
  for (int m = kSteps - 1; m > 1; --m) emit(p[0], p[m], p[m - 1]);
}

// The sub-point indices (a + kSide·b) along each side of a fine cell, counter-clockwise seen
// from above, and the neighbouring cell across that side.
struct FineSide {
  int point[ZMapFineCells::kSide];
  int di, dj;
};
inline const std::array<FineSide, 4>& fine_sides() {
  constexpr int k = ZMapFineCells::kSteps, s = ZMapFineCells::kSide;
  static const std::array<FineSide, 4> sides = [] {
    std::array<FineSide, 4> out{};
    for (int m = 0; m <= k; ++m) {
      out[0].point[m] = m;                // y = y(j), +x
      out[1].point[m] = k + s * m;        // x = x(i + 1), +y
      out[2].point[m] = (k - m) + s * k;  // y = y(j + 1), −x
      out[3].point[m] = s * (k - m);      // x = x(i), −y
    }
    out[0].di = 0, out[0].dj = -1, out[1].di = 1, out[1].dj = 0;
    out[2].di = 0, out[2].dj = 1, out[3].di = -1, out[3].dj = 0;
    return out;
  }();
  return sides;
}

// Whether cell (i, j) is fine; false for cells outside the grid.
inline bool is_fine_cell(const ZMap& map, int i, int j) {
  return i >= 0 && j >= 0 && i + 1 < map.grid.nx && j + 1 < map.grid.ny &&
         map.fine_cell(i, j) != nullptr;
}

// The top triangles of the fine cells and their steps to plain neighbours, appended to `mesh`.
// Sub-points on an edge two fine cells share are one vertex; corners are the grid's top
// vertices (index g.index(i, j)).
template <class Add>
void polyhedrize_fine_cells(const ZMap& map, Mesh& mesh, const Add& add) {
  if (map.fine.empty()) return;
  constexpr int kSteps = ZMapFineCells::kSteps, kSide = ZMapFineCells::kSide;
  const ZMapGrid& g = map.grid;
  const double step = g.cell / kSteps;
  const std::uint64_t row = static_cast<std::uint64_t>(kSteps) * static_cast<std::uint64_t>(g.nx);
  std::unordered_map<std::uint64_t, std::uint32_t> shared;  // by global sub-point (I + row·J)
  for (std::size_t c = 0; c < map.fine.cells.size(); ++c) {
    const int i = static_cast<int>(map.fine.cells[c] % static_cast<std::uint32_t>(g.nx));
    const int j = static_cast<int>(map.fine.cells[c] / static_cast<std::uint32_t>(g.nx));
    const float* f = map.fine.heights.data() + c * ZMapFineCells::kPoints;
    std::uint32_t v[ZMapFineCells::kPoints];
    for (int b = 0; b < kSide; ++b)
      for (int a = 0; a < kSide; ++a) {
        const int I = kSteps * i + a, J = kSteps * j + b;
        std::uint32_t& to = v[a + kSide * b];
        if ((a == 0 || a == kSteps) && (b == 0 || b == kSteps)) {
          to = static_cast<std::uint32_t>(g.index(i + a / kSteps, j + b / kSteps));
          continue;
        }
        const double x = g.x0 + I * step, y = g.y0 + J * step, h = f[a + kSide * b];
        if (a == 0 || a == kSteps || b == 0 || b == kSteps) {  // on the cell's edge: maybe shared
          const auto key = static_cast<std::uint64_t>(I) + row * static_cast<std::uint64_t>(J);
          auto [at, fresh] = shared.try_emplace(key, 0u);
          if (fresh) at->second = add(x, y, h);
          to = at->second;
        } else {
          to = add(x, y, h);
        }
      }
    for (int b = 0; b < kSteps; ++b)
      for (int a = 0; a < kSteps; ++a) {
        const std::uint32_t p00 = v[a + kSide * b], p10 = v[a + 1 + kSide * b];
        const std::uint32_t p01 = v[a + kSide * (b + 1)], p11 = v[a + 1 + kSide * (b + 1)];
        mesh.triangles.emplace_back(p00, p10, p11);
        mesh.triangles.emplace_back(p00, p11, p01);
      }
    for (const FineSide& side : fine_sides()) {
      if (is_fine_cell(map, i + side.di, j + side.dj)) continue;
      std::uint32_t p[kSide];
      for (int m = 0; m < kSide; ++m) p[m] = v[side.point[m]];
      fine_cell_step(p, [&](std::uint32_t a, std::uint32_t b, std::uint32_t c3) {
        mesh.triangles.emplace_back(a, b, c3);
      });
    }
  }
}

}  // namespace detail

// The piecewise-linear top H(x, y) of the polyhedron at frame-local (x, y) inside the grid: on
// a fine cell (ZMapFineCells), interpolated on its sub-grid.
inline double zmap_height(const ZMap& map, double x, double y) {
  const ZMapGrid& g = map.grid;
  double fx = (x - g.x0) / g.cell, fy = (y - g.y0) / g.cell;
  int i = std::clamp(static_cast<int>(std::floor(fx)), 0, g.nx - 2);
  int j = std::clamp(static_cast<int>(std::floor(fy)), 0, g.ny - 2);
  fx -= i, fy -= j;
  double h00, h10, h01, h11;
  if (const float* f = map.fine_cell(i, j)) {
    constexpr int kSteps = ZMapFineCells::kSteps, kSide = ZMapFineCells::kSide;
    fx *= kSteps, fy *= kSteps;
    const int a = std::clamp(static_cast<int>(std::floor(fx)), 0, kSteps - 1);
    const int b = std::clamp(static_cast<int>(std::floor(fy)), 0, kSteps - 1);
    fx -= a, fy -= b;
    h00 = f[a + kSide * b], h10 = f[a + 1 + kSide * b], h01 = f[a + kSide * (b + 1)],
    h11 = f[a + 1 + kSide * (b + 1)];
  } else {
    h00 = detail::zmap_top(map, g.index(i, j)), h10 = detail::zmap_top(map, g.index(i + 1, j));
    h01 = detail::zmap_top(map, g.index(i, j + 1)),
    h11 = detail::zmap_top(map, g.index(i + 1, j + 1));
  }
  if (fx >= fy) return h00 + fx * (h10 - h00) + fy * (h11 - h10);
  return h00 + fx * (h11 - h01) + fy * (h01 - h00);
}

// Closed, outward-oriented mesh of the Z-map's solid in world coordinates: nx·ny top vertices,
// one bottom vertex under each border point and one at the bottom's centre; 2·(nx−1)·(ny−1) top
// triangles, two per border edge on the walls, and a fan of the bottom rectangle around its
// centre (its border is subdivided by the wall vertices, and the fan keeps every triangle
// non-degenerate). Throws tridex::Error for a map with fewer than 2 × 2 points.
inline Mesh polyhedrize(const ZMap& map) {
  detail::require_solid_zmap(map, "polyhedrize");
  const ZMapGrid& g = map.grid;
  const int nx = g.nx, ny = g.ny;
  const double bottom = detail::zmap_bottom(map);
  Mesh mesh;
  auto add = [&](double x, double y, double z) {
    Vec3 w = g.frame.to_world(Vec3(x, y, z));
    mesh.positions.emplace_back(static_cast<float>(w.x), static_cast<float>(w.y),
                                static_cast<float>(w.z));
    return static_cast<std::uint32_t>(mesh.positions.size() - 1);
  };
  std::size_t top_count = g.size(), border_count = 2 * static_cast<std::size_t>(nx + ny) - 4;
  mesh.positions.reserve(top_count + border_count + 1);
  mesh.triangles.reserve(2 * static_cast<std::size_t>(nx - 1) * static_cast<std::size_t>(ny - 1) +
                         3 * border_count);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) add(g.x(i), g.y(j), detail::zmap_top(map, g.index(i, j)));
  auto top = [&](int i, int j) { return static_cast<std::uint32_t>(g.index(i, j)); };
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i)
      if (!map.fine_cell(i, j)) {
        mesh.triangles.emplace_back(top(i, j), top(i + 1, j), top(i + 1, j + 1));
        mesh.triangles.emplace_back(top(i, j), top(i + 1, j + 1), top(i, j + 1));
      }
  detail::polyhedrize_fine_cells(map, mesh, add);
  // The border, counter-clockwise seen from above: along y = y0, then x = x_end, y = y_end, x = x0.
  std::vector<glm::ivec2> border;
  border.reserve(border_count);
  for (int i = 0; i + 1 < nx; ++i) border.emplace_back(i, 0);
  for (int j = 0; j + 1 < ny; ++j) border.emplace_back(nx - 1, j);
  for (int i = nx - 1; i > 0; --i) border.emplace_back(i, ny - 1);
  for (int j = ny - 1; j > 0; --j) border.emplace_back(0, j);
  std::vector<std::uint32_t> below(border.size());
  for (std::size_t k = 0; k < border.size(); ++k)
    below[k] = add(g.x(border[k].x), g.y(border[k].y), bottom);
  std::uint32_t centre = add(0.5 * (g.x(0) + g.x(nx - 1)), 0.5 * (g.y(0) + g.y(ny - 1)), bottom);
  for (std::size_t k = 0; k < border.size(); ++k) {
    std::size_t next = (k + 1) % border.size();
    std::uint32_t t0 = top(border[k].x, border[k].y), t1 = top(border[next].x, border[next].y);
    // Going counter-clockwise around the border, the outside is to the right: wall quad
    // below[k] → below[next] → t1 → t0 faces outward.
    mesh.triangles.emplace_back(below[k], below[next], t1);
    mesh.triangles.emplace_back(below[k], t1, t0);
    mesh.triangles.emplace_back(centre, below[next], below[k]);  // bottom, facing down
  }
  return mesh;
}

}  // namespace tridex
