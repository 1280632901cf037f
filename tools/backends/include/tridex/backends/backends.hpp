// tridex backends — interchangeable implementations of Step 1 (Z-map milling) and Steps 2–3
// (Z-maps → W0 ∩ M1 ∩ … ∩ MN on a triple dexel) of Inui, Chen and Umezu, CAD&A 19(4) 2022.
//
//   Z-map:  cpu    the kernel's exact milling (mill.hpp)
//           gl     the swept cutters drawn into a 32-bit float depth buffer (OSMesa), the way
//                  the paper's Z-map simulator does (its refs [9, 10]); see gl_mill.hpp
//   dexel:  tree   the paper's grid AABB tree (intersect_milled.hpp)
//           embree Embree 3 ray casting of each Z-map's polyhedron, every hit of each ray
//           scan   scan conversion of the Z-map's implicit triangles onto the ray grids
//                  (scan_dexelize.hpp), no mesh and no BVH
//
// Every backend computes the same solid: dexel backends agree up to float rounding of the end
// points (tests/backends), and gl heights agree with cpu within the cutter tessellation bound
// stated in gl_mill.hpp. The defaults are the fastest correct ones on the reference machine
// (bench/backends.md): cpu and scan.
#pragma once

#include <span>
#include <string_view>

#include "tridex/cutter.hpp"
#include "tridex/dexel.hpp"
#include "tridex/mill.hpp"
#include "tridex/zmap.hpp"

namespace tridex::backends {

enum class ZMapBackend { cpu, gl };
enum class DexelBackend { tree, embree, scan };

inline constexpr ZMapBackend default_zmap_backend = ZMapBackend::cpu;
inline constexpr DexelBackend default_dexel_backend = DexelBackend::scan;

// Names as the command line spells them; parse_* throw tridex::Error naming the valid ones.
const char* to_string(ZMapBackend backend);
const char* to_string(DexelBackend backend);
ZMapBackend parse_zmap_backend(std::string_view name);
DexelBackend parse_dexel_backend(std::string_view name);

// Whether a backend can run in this process (gl needs an OSMesa context; embree a device).
bool available(ZMapBackend backend);
bool available(DexelBackend backend);

// Step 1: lowers `map` by every move (tips in the map's frame, move.cutter indexing `cutters`).
// threads = 0: every hardware thread (the gl backend draws on one context and ignores it).
void mill_with(ZMapBackend backend, ZMap& map, std::span<const Cutter> cutters,
               std::span<const CutMove> moves, unsigned threads = 0);

// Steps 2–3: W0 ∩ M1 ∩ … ∩ MN on the stock's lattice, Mi the polyhedron of milled[i].
TripleDexel machine_with(DexelBackend backend, const TripleDexel& stock,
                         std::span<const ZMap> milled, unsigned threads = 0);

}  // namespace tridex::backends
