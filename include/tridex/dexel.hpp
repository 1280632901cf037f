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
//
// A DexelLattice is the lattice alone (origin, spacing, node counts); Booleans require both
// operands on the same lattice.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <span>
#include <vector>

#include <glm/glm.hpp>

#include "tridex/geometry.hpp"

namespace tridex {

struct DexelLattice {
  Vec3 origin{0};      // world position of node (0, 0, 0)
  double spacing = 1;  // the same along x, y and z
  glm::ivec3 n{0};     // nodes along x, y, z

  Vec3 node(int i, int j, int k) const { return origin + spacing * Vec3(i, j, k); }
  // The box spanned by the nodes.
  Aabb bounds() const {
    return Aabb{origin, origin + spacing * Vec3(glm::max(n - 1, glm::ivec3(0)))};
  }
  bool operator==(const DexelLattice&) const = default;

  // Nodes covering `box` with the given spacing, centred on it, with the outermost nodes more
  // than spacing/2 outside it on every side, so that a solid inside `box` never touches the
  // lattice's outer rays or nodes (surface extraction needs outside nodes all around).
  static DexelLattice covering(const Aabb& box, double spacing);
  // The same with `cells_on_longest_side` spacings across the box's longest side.
  static DexelLattice covering_resolution(const Aabb& box, int cells_on_longest_side);
};

struct DexelInterval {
  float enter;
  float exit;
};

struct DexelGrid {
  int axis = 0;
  int nu = 0, nv = 0;                    // rays along the u and v axes
  std::vector<std::uint32_t> offsets;    // nu·nv + 1 entries; offsets[0] == 0
  std::vector<DexelInterval> intervals;  // all rays' intervals, ray after ray

  std::size_t ray_count() const {
    return static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
  }
  std::size_t ray_index(int iu, int iv) const {
    return static_cast<std::size_t>(iu) +
           static_cast<std::size_t>(nu) * static_cast<std::size_t>(iv);
  }
  std::span<const DexelInterval> ray(std::size_t r) const {
    return {intervals.data() + offsets[r], intervals.data() + offsets[r + 1]};
  }
  std::span<const DexelInterval> ray(int iu, int iv) const { return ray(ray_index(iu, iv)); }
};

struct TripleDexel {
  Vec3 origin{0};      // world position of lattice node (0, 0, 0)
  double spacing = 1;  // lattice spacing, the same along x, y and z
  glm::ivec3 n{0};     // lattice nodes along x, y, z
  DexelGrid grids[3];  // grids[a]: rays parallel to axis a

  static int u_axis(int a) { return (a + 1) % 3; }
  static int v_axis(int a) { return (a + 2) % 3; }
  Vec3 node(int i, int j, int k) const { return origin + spacing * Vec3(i, j, k); }
  DexelLattice lattice() const { return DexelLattice{origin, spacing, n}; }

  // No material: every ray without intervals.
  static TripleDexel empty(const DexelLattice& lattice);
  // The box `box`: a ray gets [box.min, box.max] along its axis when its transverse position
  // (pu, pv) satisfies min ≤ p < max on both axes — half-open, the same rule the mesh
  // dexelizer's perturbation applies to a ray on a face, so that a box whose faces lie on
  // lattice rays counts exactly size/spacing rays across.
  static TripleDexel box(const DexelLattice& lattice, const Aabb& box);
};

namespace detail {

inline void require_lattice(const DexelLattice& l, const char* who) {
  if (!is_finite(l.origin)) fail(who, ": lattice origin is not finite");
  require_positive(l.spacing, "dexel lattice spacing");
  if (l.n.x < 1 || l.n.y < 1 || l.n.z < 1)
    fail(who, ": lattice of ", l.n.x, " x ", l.n.y, " x ", l.n.z, " nodes is empty");
  // Offsets are 32-bit and ray indices must fit in memory: 2^31 nodes per face is far beyond use.
  double face = std::max({double(l.n.x) * l.n.y, double(l.n.y) * l.n.z, double(l.n.z) * l.n.x});
  if (face > 2e9)
    fail(who, ": lattice of ", l.n.x, " x ", l.n.y, " x ", l.n.z, " nodes is too large");
}

inline int lattice_count(double extent, double spacing) {
  double n = std::floor(extent / spacing) + 3;  // > spacing/2 of margin on each side
  if (!(n < 1e6))
    fail("dexel lattice: ", n, " nodes along one side is too many (extent ", extent, ", spacing ",
         spacing, ")");
  return static_cast<int>(n);
}

}  // namespace detail

inline DexelLattice DexelLattice::covering(const Aabb& box, double spacing) {
  detail::require_positive(spacing, "dexel lattice spacing");
  if (box.empty() || !is_finite(box.min) || !is_finite(box.max))
    detail::fail("dexel lattice: box is empty or not finite");
  DexelLattice l;
  // A hair less than asked (1e-7 relative): a box a whole number of spacings wide would
  // otherwise have its faces exactly on rows of rays, where the half-open intervals keep the
  // rows on the min faces and drop those on the max faces, and with them the crossings the
  // surface needs to rebuild the edges there (the top edge came out bevelled by up to a spacing
  // along the max faces). With the nodes drawn together about the box's centre, the rows
  // nearest the faces fall just inside both (by about 1e-7 of the box's size).
  l.spacing = spacing * (1 - 1e-7);
  Vec3 size = box.size();
  for (int a = 0; a < 3; ++a) {
    l.n[a] = detail::lattice_count(size[a], spacing);
    l.origin[a] = box.center()[a] - 0.5 * l.spacing * (l.n[a] - 1);
  }
  return l;
}

inline DexelLattice DexelLattice::covering_resolution(const Aabb& box, int cells_on_longest_side) {
  if (cells_on_longest_side < 1)
    detail::fail("dexel lattice: cells on the longest side must be at least 1, got ",
                 cells_on_longest_side);
  if (box.empty() || !is_finite(box.min) || !is_finite(box.max))
    detail::fail("dexel lattice: box is empty or not finite");
  Vec3 size = box.size();
  double longest = std::max({size.x, size.y, size.z});
  if (!(longest > 0)) detail::fail("dexel lattice: box has zero size");
  return covering(box, longest / cells_on_longest_side);
}

inline TripleDexel TripleDexel::empty(const DexelLattice& lattice) {
  detail::require_lattice(lattice, "triple dexel");
  TripleDexel d;
  d.origin = lattice.origin, d.spacing = lattice.spacing, d.n = lattice.n;
  for (int a = 0; a < 3; ++a) {
    DexelGrid& g = d.grids[a];
    g.axis = a, g.nu = lattice.n[u_axis(a)], g.nv = lattice.n[v_axis(a)];
    g.offsets.assign(g.ray_count() + 1, 0);
  }
  return d;
}

inline TripleDexel TripleDexel::box(const DexelLattice& lattice, const Aabb& solid) {
  if (!is_finite(solid.min) || !is_finite(solid.max))
    detail::fail("triple dexel: box is not finite");
  TripleDexel d = empty(lattice);
  if (solid.empty()) return d;
  for (int a = 0; a < 3; ++a) {
    if (!(solid.min[a] < solid.max[a])) return empty(lattice);  // flat: no volume
    DexelGrid& g = d.grids[a];
    int u = u_axis(a), v = v_axis(a);
    DexelInterval span{static_cast<float>(solid.min[a]), static_cast<float>(solid.max[a])};
    // In lattice units, with faces within 1e-9 spacings of a node snapped onto it (so that a face
    // meant to lie on a ray is not lost to rounding of origin + spacing·i).
    auto first_index = [&](int axis_, double x) {
      double c = (x - lattice.origin[axis_]) / lattice.spacing, r = std::round(c);
      return std::ceil(std::abs(c - r) < 1e-9 ? r : c);
    };
    double u0 = first_index(u, solid.min[u]), u1 = first_index(u, solid.max[u]);
    double v0 = first_index(v, solid.min[v]), v1 = first_index(v, solid.max[v]);
    for (int iv = 0; iv < g.nv; ++iv)
      for (int iu = 0; iu < g.nu; ++iu) {
        bool inside = iu >= u0 && iu < u1 && iv >= v0 && iv < v1;
        if (inside) g.intervals.push_back(span);
        g.offsets[g.ray_index(iu, iv) + 1] = static_cast<std::uint32_t>(g.intervals.size());
      }
  }
  return d;
}

}  // namespace tridex
