// tridex backends — Z-map milling in a depth buffer (Step 1 of Inui, Chen and Umezu, CAD&A
// 19(4) 2022, §3.1, done the way their Z-map simulator does it, refs [9, 10]: Inui, "Fast
// inverse offset computation using polygon rendering hardware", CAD 35(2) 2003, and Inui &
// Ohta, "Using a GPU to accelerate die and mold fabrication", IEEE CG&A 27(1) 2007).
//
// Each grid point is a pixel centre of an orthographic view looking up the frame's z axis; the
// depth of a pixel is (z − z_lo)/(z_hi − z_lo) in a 32-bit float depth renderbuffer (FBO,
// GL_DEPTH_COMPONENT32F) and the depth test keeps the smallest, so drawing every move's swept
// cutter leaves the lowest swept surface above each point. The result is read back and the
// map takes the minimum with it. Grids larger than the largest viewport are drawn tile by tile.
// The context is OSMesa's (Mesa's software rasteriser, always available).
//
// The swept cutter of a move a → b is the Minkowski sum of the cutter and the segment. The
// cutter's lower surface is tessellated into a polyhedral cap P (profile vertices on the true
// curve, rings of S vertices on the true radius); for a convex polyhedron the lower boundary of
// P ⊕ [a, b] consists of P's faces at a (normal·(b − a) < 0) or at b (> 0) and the
// parallelograms swept by its silhouette edges, which is what is drawn (plus the rim's edges,
// which bound the cap). Everything drawn lies inside the swept solid, so the depth test yields
// exactly the milling of P.
//
// Tolerance. P is inscribed in the cutter C, and every profile chord and every ring chord has
// sagitta ≤ ε/2, so C ⊖ B_ε ⊂ P ⊂ C (B_ε the ball of radius ε = `tolerance`). GL heights are
// therefore bracketed by the exact milling with C (below) and with its erosion C ⊖ B_ε (above),
// up to the float depth resolution (2^−23·(z_hi − z_lo)) and sub-pixel float rounding of the
// vertices (~1e-4 cell) — which tests/backends checks for every cutter kind. In flat regions the
// height error is at most ε; on walls steeper than the tessellation it is the wall's offset by ε.
#pragma once

#include <span>

#include "tridex/cutter.hpp"
#include "tridex/mill.hpp"
#include "tridex/zmap.hpp"

namespace tridex::backends {

struct GlMillOptions {
  double tolerance = 0;  // ε above (model units); 0: a quarter of the map's cell
  int max_tile = 0;      // largest tile side in pixels; 0: the context's limit, at most 4096
};

// Lowers `map` by every move (tips in the map's frame). Throws tridex::Error for a move naming a
// missing cutter, coordinates that are not finite, a non-positive tolerance, or when OSMesa
// cannot make a context with a float depth framebuffer.
void gl_mill(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves,
             const GlMillOptions& options = {});

// Whether an OSMesa context with a 32-bit float depth framebuffer can be made here.
bool gl_available();

}  // namespace tridex::backends
