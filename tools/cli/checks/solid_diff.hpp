// Two triple dexels on one lattice compared ray by ray (tridex diff and tridex regress, issue 39):
// where one solid has material and the other not for longer than a tolerance along a ray, the span
// is a difference; spans whose lattice nodes touch (26-neighbours, one kind) form a region, its
// volume the largest of the three ray directions' sums (each direction alone misses walls parallel
// to it), its deepest point the middle of its longest span.
#pragma once

#include <set>
#include <string>
#include <vector>

#include "tridex/dexel.hpp"

namespace tridex::cli {

// A span along one ray where the two solids differ.
constexpr std::size_t kDiffProbes = 16;

struct DiffSpan {
  int axis = 0, iu = 0, iv = 0;
  float from = 0, to = 0;
  bool removed = false;  // material in A that B removed (else material B left that A removed)
  Vec3 point(const TripleDexel& d, double t) const {
    Vec3 p = d.node(0, 0, 0);
    p[TripleDexel::u_axis(axis)] += d.spacing * iu;
    p[TripleDexel::v_axis(axis)] += d.spacing * iv;
    p[axis] = t;
    return p;
  }
};

struct DiffRegion {
  bool removed = false;
  std::vector<std::size_t> spans;  // into the span list
  double volume = 0, depth = 0;
  Vec3 deepest{0};
  Aabb box;
  std::vector<Vec3> probes;
  std::set<int> lines_a, lines_b, changed_a, changed_b, tools_a, tools_b;
  std::set<std::string> sub_a, sub_b;  // diff: "file:line" of moves in subprogram files
};

// The spans where exactly one of `a` and `b` (one lattice) holds material, longer than `tolerance`.
std::vector<DiffSpan> solid_differences(const TripleDexel& a, const TripleDexel& b,
                                        double tolerance);
// Spans joined into regions through the lattice nodes they cover (26-neighbours, one kind).
std::vector<DiffRegion> connect_spans(const std::vector<DiffSpan>& spans, const TripleDexel& d);
// Volume, deepest point, box and probes (the middles of the longest spans, at most kDiffProbes) of
// each region; the regions largest first.
void measure_regions(std::vector<DiffRegion>& regions, const std::vector<DiffSpan>& spans,
                     const TripleDexel& d);

}  // namespace tridex::cli
