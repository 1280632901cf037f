// tridex command — rapids that cut: a finding to report (docs/design.md: every move removes
// material, rapid or feed, and a rapid that touches the stock is a finding).
//
// Material removal does not depend on the order of moves, so the simulation cannot know what a
// rapid met at its moment in the program. What it can say exactly is which rapids remove material
// that no feed move of their direction removes: those are checked against the direction's Z-map
// milled by its feed (non-rapid) moves alone, before the rapids are milled into it. A rapid
// through material that a later feed move cuts away is not caught.
#pragma once

#include <span>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/mill.hpp"
#include "tridex/zmap.hpp"

namespace tridex::cli {

struct RapidCut {
  std::size_t index = 0;  // into the rapids given
  double depth_mm = 0;    // deepest cut below the feed-only surface, along the spindle
};

// Rapids (tool-tip segments in the map's frame) that go deeper than `tolerance` below the
// surface of `feed_map` at some grid point holding material.
std::vector<RapidCut> rapid_cuts(const ZMap& feed_map, std::span<const Cutter> cutters,
                                 std::span<const CutMove> rapids, double tolerance);

}  // namespace tridex::cli
