// tridex backends — Step 2–3 with Embree 3 (Wald et al., "Embree: a kernel framework for
// efficient CPU ray tracing", ACM ToG 33(4), 2014) in place of the paper's grid AABB tree
// (Inui, Chen and Umezu, CAD&A 19(4) 2022, §4.2).
//
// One scene per Z-map: its polyhedron (polyhedron.hpp) as a triangle mesh in world coordinates,
// built in robust (watertight) mode. Every hit of each lattice ray is collected by an
// intersection filter that records the hit and rejects it, so traversal goes on to the next.
// Hits are sorted; each is entering or leaving by the sign of its triangle's normal along the
// ray. A ray through a shared edge or vertex can be reported by several triangles (or none):
// hits within a float-rounding distance of each other are merged, their directions summed, so
// a doubled crossing counts once and a graze cancels. The spans between entering and leaving
// are intersected with the stock ray by ray.
#pragma once

#include <span>

#include "tridex/dexel.hpp"
#include "tridex/zmap.hpp"

namespace tridex::backends {

// The polyhedron of `map` on `lattice`. Throws tridex::Error for a Z-map with fewer than
// 2 × 2 points, an invalid lattice, or when Embree cannot create a device or build the scene.
TripleDexel embree_dexelize(const ZMap& map, const DexelLattice& lattice, unsigned threads = 0);

// W0 ∩ M1 ∩ … ∩ MN on the stock's lattice; one Embree scene alive at a time.
TripleDexel embree_machine(const TripleDexel& stock, std::span<const ZMap> milled,
                           unsigned threads = 0);

}  // namespace tridex::backends
