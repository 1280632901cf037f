// tridex command — what the lattice resolves (issue 31): the deepest gouge a cutter can leave
// between the samples of the Z-maps and the triple dexel without any sample seeing it, and the
// spacing `check` chooses so that this stays within its gouge tolerance.
//
// The bound (docs/reports.md, "What the lattice resolves"). In a direction's frame a cutter
// removes what lies above its lower surface tip.z + h(ρ) (cutter.hpp: h is the height of the
// profile at a distance ρ from the axis, convex and non-decreasing). Say a move leaves its tip,
// the deepest point of its imprint, at T. The result is sampled where the dexel rays cross the
// direction's Z-map polyhedron, and the polyhedron interpolates the map's nodes:
//  - the rays of the lattice family nearest the spindle (angle θ, cos θ = max |a_k|) cross the
//    plane of the imprint on a rectangular lattice of h by h / cos θ, so one of them, at Q,
//    passes within s_ray = (h / 2)·√(1 + 1 / cos²θ) of T across the spindle (h/√2 when the
//    spindle is a lattice axis);
//  - the polyhedron at Q is a convex combination of the nodes of Q's triangle, each within
//    √2·c of Q (c the Z-map cell), and a node at a distance d from T is milled exactly, to at
//    most T.z + h(d), since the cutter passed over it there;
//  so the sample at Q lies at most h(s_ray + √2·c) above T: an imprint deeper than that is seen.
// A cutter's side leaves the same kind of imprint across the spindle (an arc of its radius R),
// whose sagitta R − √(R² − s²) counts too (for a flat end, whose lower surface is flat). Moves
// whose tool turns (simultaneous.cpp) are cut on the triple dexel directly: s = h, the worst θ.
// A cutter narrower than s can fit between the samples: the bound is then infinite.
// The bound says how much deeper than the samples show a gouge can be: every gouge deeper than
// the gouge tolerance plus the bound is found, and `check` keeps the bound within the tolerance.
#pragma once

#include <functional>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/gcode/grouping.hpp"

namespace tridex::cli {

// The depth a cutter's imprint can reach below samples at most `s` from its deepest point:
// max(h(s), R − √(R² − s²)); infinite when s reaches the cutter's radius.
double missable_depth(const Cutter& cutter, double s);

struct ResolutionBound {
  double missable = 0;  // mm, infinite when a cutter fits between the samples
  int tool = 0;         // the tool that sets it (0: no tool cuts)
  double distance = 0;  // s for that tool's direction, mm
};

// The bound for every tool of every group (and the simultaneous moves') on a lattice of
// `spacing` with Z-maps of `zmap_cell`.
ResolutionBound resolution_bound(const std::vector<gcode::MoveGroup>& groups,
                                 const std::vector<gcode::Move>& simultaneous,
                                 std::span<const Cutter> cutters,
                                 const std::map<int, std::uint32_t>& cutter_of_tool, double spacing,
                                 double zmap_cell);

// The largest spacing ≤ `coarsest` whose bound (with the Z-map cell that zmap_cell_for gives
// it) is within `tolerance`; 0 when none is (a Z-map cell given that is too coarse by itself).
double spacing_for_tolerance(const std::function<double(double spacing)>& bound_at, double coarsest,
                             double tolerance);

// "0.0123 mm (tool 4, 2 mm ball end)" or "any depth (tool 4, 2 mm ball end: a sample can lie
// 1.3 mm from its tip, beyond its radius)"; `cutters`/`cutter_of_tool` as resolution_bound's.
std::string missable_text(const ResolutionBound& bound, std::span<const Cutter> cutters,
                          const std::map<int, std::uint32_t>& cutter_of_tool);

}  // namespace tridex::cli
