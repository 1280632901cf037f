// tridex — surface extraction: triple dexel → closed, outward-oriented triangle mesh (Step 4 of
// the method in docs/design.md): the contract.
//
// Marching cubes on the triple-dexel lattice, with crossings at the dexel end points (exact, not
// interpolated) and sharp edges and corners kept as in Extended Marching Cubes. The machinery
// lives in detail/: surface_extractor.hpp (the method, node states, slabs on threads and their
// join) and surface_cells.hpp (one cell's vertices and triangles).
#pragma once

#include "tridex/dexel.hpp"
#include "tridex/error.hpp"
#include "tridex/mesh.hpp"

namespace tridex {

struct SurfaceOptions {
  unsigned threads = 0;         // 0: one per hardware thread; the output does not depend on it
  bool sharp_features = true;   // Extended Marching Cubes feature points and edge flips
  double feature_angle = 35.0;  // degrees; normals spreading more than this mark a feature
};

// The boundary of the solid sampled by `dexel` (clipped to the lattice box) as a closed,
// outward-oriented triangle mesh — every edge shared by exactly two triangles in opposite
// directions (check_mesh(...).closed()) — without degenerate triangles. Vertices are dexel end
// points (kept at least 1e-4 of a spacing off the nodes), lattice nodes where the solid reaches
// the lattice boundary, and per-cell feature or centre points. Node states follow the z rays
// (half-open [enter, exit)); parts thinner than the spacing between nodes may be lost (as in
// any marching-cubes method). Throws tridex::Error for a malformed triple dexel (see validate) or
// a feature_angle outside (0, 180) degrees.
inline Mesh extract_surface(const TripleDexel& dexel, SurfaceOptions options = {});

// The volume of extract_surface(TripleDexel::box(lattice, box)) without extracting it: the box
// with each face where the extractor puts that face's crossings, which it keeps a margin off the
// nodes (a few float steps: about 3e-4 mm on a 100 mm lattice). A removal measured as the uncut
// stock's surface less the result's (tools/cli/pipeline) cancels that offset. `box` lies inside
// the lattice's nodes, as DexelLattice::covering places it.
inline double box_surface_volume(const DexelLattice& lattice, const Aabb& box);

}  // namespace tridex

#include "tridex/detail/surface_cells.hpp"
#include "tridex/detail/surface_extractor.hpp"

namespace tridex {

inline Mesh extract_surface(const TripleDexel& dexel, SurfaceOptions options) {
  validate(dexel);
  if (!(options.feature_angle > 0 && options.feature_angle < 180))
    detail::fail("extract_surface: feature_angle must be in (0, 180) degrees, got ",
                 options.feature_angle);
  if (dexel.n.x < 2 || dexel.n.y < 2 || dexel.n.z < 2)
    return Mesh{};  // a flat lattice holds no volume
  detail::surface::Extractor extractor(dexel, options);
  return extractor.run(options.threads);
}

inline double box_surface_volume(const DexelLattice& lattice, const Aabb& box) {
  const double margin = detail::surface::crossing_margin(lattice), h = lattice.spacing;
  // The crossing of the face at c: its float end point's place in its cell, clamped as
  // surface_cells.hpp's crossing() clamps it.
  auto face = [&](int a, double c) {
    const double x = double(static_cast<float>(c));
    const double x0 = lattice.origin[a] + h * std::floor((x - lattice.origin[a]) / h);
    return x0 + std::clamp((x - x0) / h, margin, 1 - margin) * h;
  };
  double volume = 1;
  for (int a = 0; a < 3; ++a) volume *= face(a, box.max[a]) - face(a, box.min[a]);
  return volume;
}

}  // namespace tridex
