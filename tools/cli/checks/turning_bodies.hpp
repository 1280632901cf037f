// tridex check — the shank, the holder and the spindle's parts of every simultaneous 5-axis move
// (Move::pose ≠ fixed: the tool axis turns; issue 34) and of every raw-form rapid turn of the
// rotaries between moves, against the stock as a triple dexel, as collision_check.hpp tests them
// for the 3+2 moves against the Z-maps.
//
// The poses along a move come from the machine's interpolation (gcode/simultaneous.hpp), sampled
// so finely that no point of the body moves more than half a dexel spacing between two samples:
// the tip's speed plus the farthest body point's distance from the tip times the axis's turn rate
// (MovePath::bounds) bounds each point's speed, so a collision deeper than a quarter spacing at
// any pose is deeper than 0 at the nearest sample. Spans of samples whose body, grown by how far
// it can move within them, meets no tile holding material (SweepMaterial) are skipped by halves.
//
// At each pose each part (a frustum about the tool axis; a shank of no given length runs up to
// where it can no longer reach the stock's box) is tested against the final result (after every
// 3+2 and simultaneous cut): removal only takes material away, so what the result holds was there
// at every moment of the program, and a part in it is a real collision, never a false one. What
// it misses: material that a later move removed (a holder that plunges into stock a later pass
// clears), as the 3+2 check across directions misses nothing but reports more
// (collision_check.hpp). The depth is the distance from the deepest material point in the part to
// the part's surface (Euclidean, where a 3+2 move's is along the spindle); material is read on the
// Z rays, each ray's material searched for its least signed distance to the part (convex along the
// ray). The findings join SimulationResult::body's lists (no direction: group = the groups' count);
// they add no stick-out (BodyFindings::holder_depth is along one spindle direction).
#pragma once

#include <span>

#include "pipeline/pipeline.hpp"
#include "tridex/tool_body.hpp"

namespace tridex::cli {

// Tests r.simultaneous's moves, then r.turning_rapids's (a raw-form G0 turning the rotaries
// between two moves, at the line of the move after it), against r.result with `bodies`
// (bodies_against_stock: parallel to r.cutters) and records collisions and near misses (within
// `clearance` mm) in r.body.
void check_turning_bodies(SimulationResult& r, std::span<const ToolBody> bodies, double clearance,
                          unsigned threads);

}  // namespace tridex::cli
