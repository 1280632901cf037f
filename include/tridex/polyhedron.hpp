// tridex — polyhedrization of a Z-map (Step 2 of Inui, Chen and Umezu, CAD&A 19(4) 2022, §4.1).
//
// The milled Z-map is closed into a solid: the top is the height field, two triangles per cell
// split along the diagonal (i, j)–(i+1, j+1); empty points sit at the map's empty height; four
// vertical walls drop from the grid's border to a bottom rectangle one cell below the empty
// height, so that even a fully cut map encloses a slab of positive thickness. The solid is
//     { (x, y, z) local : (x, y) in the grid's rectangle, bottom ≤ z ≤ H(x, y) }
// with H the piecewise-linear interpolant on that triangulation (zmap_height below); the grid
// tree (grid_tree.hpp) intersects rays with exactly this solid without building the mesh.
// Output is in WORLD coordinates (frame.to_world), counter-clockwise from outside.
#pragma once

#include <algorithm>
#include <cstdint>
#include <vector>

#include "tridex/error.hpp"
#include "tridex/mesh.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

namespace detail {

inline void require_solid_zmap(const ZMap& map, const char* who) {
  if (map.grid.nx < 2 || map.grid.ny < 2)
    fail(who, ": a Z-map of ", map.grid.nx, " x ", map.grid.ny, " points has no cell to enclose a solid");
  if (map.heights.size() != map.grid.size())
    fail(who, ": Z-map holds ", map.heights.size(), " heights for ", map.grid.size(), " grid points");
  if (!std::isfinite(map.empty_height)) fail(who, ": Z-map empty height is not finite");
}

// The height of the solid's top at point (i, j): empty points (and any below) at the empty height.
inline double zmap_top(const ZMap& map, std::size_t index) {
  return std::max(double(map.heights[index]), double(map.empty_height));
}

// The bottom of the closed solid, one cell below the empty height.
inline double zmap_bottom(const ZMap& map) { return double(map.empty_height) - map.grid.cell; }

}  // namespace detail

// The piecewise-linear top H(x, y) of the polyhedron at frame-local (x, y) inside the grid.
inline double zmap_height(const ZMap& map, double x, double y) {
  const ZMapGrid& g = map.grid;
  double fx = (x - g.x0) / g.cell, fy = (y - g.y0) / g.cell;
  int i = std::clamp(static_cast<int>(std::floor(fx)), 0, g.nx - 2);
  int j = std::clamp(static_cast<int>(std::floor(fy)), 0, g.ny - 2);
  fx -= i, fy -= j;
  double h00 = detail::zmap_top(map, g.index(i, j)), h10 = detail::zmap_top(map, g.index(i + 1, j));
  double h01 = detail::zmap_top(map, g.index(i, j + 1)), h11 = detail::zmap_top(map, g.index(i + 1, j + 1));
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
    mesh.positions.emplace_back(static_cast<float>(w.x), static_cast<float>(w.y), static_cast<float>(w.z));
    return static_cast<std::uint32_t>(mesh.positions.size() - 1);
  };
  std::size_t top_count = g.size(), border_count = 2 * static_cast<std::size_t>(nx + ny) - 4;
  mesh.positions.reserve(top_count + border_count + 1);
  mesh.triangles.reserve(2 * static_cast<std::size_t>(nx - 1) * static_cast<std::size_t>(ny - 1) + 3 * border_count);
  for (int j = 0; j < ny; ++j)
    for (int i = 0; i < nx; ++i) add(g.x(i), g.y(j), detail::zmap_top(map, g.index(i, j)));
  auto top = [&](int i, int j) { return static_cast<std::uint32_t>(g.index(i, j)); };
  for (int j = 0; j + 1 < ny; ++j)
    for (int i = 0; i + 1 < nx; ++i) {
      mesh.triangles.emplace_back(top(i, j), top(i + 1, j), top(i + 1, j + 1));
      mesh.triangles.emplace_back(top(i, j), top(i + 1, j + 1), top(i, j + 1));
    }
  // The border, counter-clockwise seen from above: along y = y0, then x = x_end, y = y_end, x = x0.
  std::vector<glm::ivec2> border;
  border.reserve(border_count);
  for (int i = 0; i + 1 < nx; ++i) border.emplace_back(i, 0);
  for (int j = 0; j + 1 < ny; ++j) border.emplace_back(nx - 1, j);
  for (int i = nx - 1; i > 0; --i) border.emplace_back(i, ny - 1);
  for (int j = ny - 1; j > 0; --j) border.emplace_back(0, j);
  std::vector<std::uint32_t> below(border.size());
  for (std::size_t k = 0; k < border.size(); ++k) below[k] = add(g.x(border[k].x), g.y(border[k].y), bottom);
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
