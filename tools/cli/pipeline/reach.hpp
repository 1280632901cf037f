// tridex command — a lattice over the part of a box stock the tools can reach (issue 36, row 15).
//
// A box stock much larger than the toolpath (a 10 m plate around a 10 mm pocket) would spread the
// lattice's resolution over material no tool touches. In the Z-map model a move removes what lies
// above its cutter in its direction's frame, within the cutter's radius across the spindle, so
// the stock's part any move can change lies in the box of those prisms (every move's segment
// grown by the largest radius of the direction's tools across the spindle and up to the stock's
// top along it), clipped to the stock. The lattice covers that box, grown by a margin of a few
// lattice cells so that no cut reaches its faces inside the stock; what lies outside it is the
// stock, uncut. The removed volume is measured on the lattice, exactly as for a normal stock.
//
// The surface: the solid on the reach box R is a closed mesh M. R's faces inside the stock are
// uncut (the margin) and flat; they are dropped from M, leaving one open rim on the stock face P
// that R touches. The stock's other five faces are two triangles each; P less R's rectangle is
// closed by four fans, each from a corner of P over the rim's vertices along one side of R's
// rectangle: watertight, with no vertex added on the rim. Used only when R touches exactly one
// face of the stock (the +Z pocket in a plate; a program reaching several faces keeps the lattice
// over the whole stock) and is at most a quarter of the stock along its longest side.
#pragma once

#include <cstdint>
#include <map>
#include <optional>
#include <span>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/gcode/grouping.hpp"
#include "tridex/mesh.hpp"

namespace tridex::cli {

// Lattice cells the reach box is grown by on each side.
inline constexpr double kReachMarginCells = 3;

// Each group's tool tips, start and end of every move, in the group's frame: the box of each
// (empty for a group without moves), on `threads` threads (0: every hardware thread). A bound
// is a minimum or maximum, so the boxes do not depend on the thread count. Several checks read
// them; a pass over every move of a 5-million-move program on one thread left the other core
// idle between the parse and the milling (bench/README.md, issue 37).
std::vector<Aabb> local_paths(const std::vector<gcode::MoveGroup>& groups, unsigned threads);

// The box of the stock the moves can cut (before the margin); nullopt when a move turns the tool
// (those are cut on the dexels, not by a direction's Z-map) or nothing reaches. `paths`: the
// groups' local_paths.
std::optional<Aabb> reach_of_moves(const std::vector<gcode::MoveGroup>& groups,
                                   std::span<const Aabb> paths,
                                   const std::vector<gcode::Move>& simultaneous,
                                   std::span<const Cutter> cutters,
                                   const std::map<int, std::uint32_t>& cutter_of_tool,
                                   const Aabb& stock);

// `reach` grown by kReachMarginCells cells of `spacing` and clipped to `stock`, then each side
// made a whole number of cells and a half (grown on its sides inside the stock), when it touches
// exactly one face of the stock and is at most a quarter of it along the stock's longest side;
// nullopt otherwise.
std::optional<Aabb> clipped_reach(const Aabb& reach, const Aabb& stock, double spacing);

// The whole stock's surface from M, the closed surface of the solid on `reach` (clipped_reach's):
// see above. `spacing`: the lattice's, for telling the faces' vertices. Throws tridex::Error when
// M's faces inside the stock are not as the margin makes them (no single rim).
Mesh stitch_into_stock(const Mesh& clipped, const Aabb& reach, const Aabb& stock, double spacing);

}  // namespace tridex::cli
