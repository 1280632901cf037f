// tridex — dexels and triple dexels (data layout).
//
// A triple dexel (Hook 1986; Benouamer & Michelucci 1997; used by Inui, Chen and Umezu 2022,
// §3.2) samples a solid along three families of axis-parallel rays through the nodes of one
// cubic lattice. Lattice node (i, j, k) lies at origin + spacing·(i, j, k), 0 ≤ i < n.x,
// 0 ≤ j < n.y, 0 ≤ k < n.z. Grid `a` (a = 0, 1, 2 for x, y, z) holds the rays parallel to axis
// a: one per node of the other two axes u = (a+1) % 3, v = (a+2) % 3, so ray (iu, iv) passes
// through origin + spacing·(iu·e_u + iv·e_v) and is stored at index iu + n[u]·iv.
//
// Storage is flat (no heap allocation per ray): the intervals of ray r are
// intervals[offsets[r] .. offsets[r+1]), each a solid span [enter, exit] of world coordinate
// along the axis, sorted, disjoint and non-empty (enter < exit).
#pragma once

#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "tridex/geometry.hpp"

namespace tridex {

struct DexelInterval {
  float enter;
  float exit;
};

struct DexelGrid {
  int axis = 0;
  int nu = 0, nv = 0;                   // rays along the u and v axes
  std::vector<std::uint32_t> offsets;   // nu·nv + 1 entries; offsets[0] == 0
  std::vector<DexelInterval> intervals;  // all rays' intervals, ray after ray

  std::size_t ray_count() const { return static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv); }
  std::size_t ray_index(int iu, int iv) const {
    return static_cast<std::size_t>(iu) + static_cast<std::size_t>(nu) * static_cast<std::size_t>(iv);
  }
  std::span<const DexelInterval> ray(std::size_t r) const {
    return {intervals.data() + offsets[r], intervals.data() + offsets[r + 1]};
  }
  std::span<const DexelInterval> ray(int iu, int iv) const { return ray(ray_index(iu, iv)); }
};

struct TripleDexel {
  Vec3 origin{0};        // world position of lattice node (0, 0, 0)
  double spacing = 1;    // lattice spacing, the same along x, y and z
  glm::ivec3 n{0};       // lattice nodes along x, y, z
  DexelGrid grids[3];    // grids[a]: rays parallel to axis a

  static int u_axis(int a) { return (a + 1) % 3; }
  static int v_axis(int a) { return (a + 2) % 3; }
  Vec3 node(int i, int j, int k) const { return origin + spacing * Vec3(i, j, k); }
};

}  // namespace tridex
