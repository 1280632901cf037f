// tridex — the parts of a tool that do not cut: the shank above the flutes and the holder's
// sections, as CAM tool libraries describe them (a stack of cylinders and cone frusta around the
// tool axis, measured from the tool tip).
//
// A Z-map (zmap.hpp) holds material below its height at every grid point, so a solid of
// revolution moving along a segment meets the material exactly where some grid point's height lies
// above the lowest point of the swept solid there: the test of cut_depth (mill.hpp) with the
// part's *lower surface* in place of a cutter's. A part's top does not matter (all the material
// below the height counts), so a section is described to the Z-map by its bottom height above
// the tip and the cutter that has its lower surface:
//   cylinder, or a frustum narrowing upward   flat disc of the bottom radius;
//   frustum widening upward                     chamfer (flat bottom disc, then the cone).
// Near misses: the part grown by a distance δ is its Minkowski sum with a ball of radius δ, whose
// lower surface is that of the profile offset by δ in the (ρ, h) plane (a solid of revolution's
// nearest point to any point lies in the same meridian half-plane): a bull nose of radius r + δ
// and corner δ for a flat disc, the offset chamfer (flat, arc, line, arc) for a widening frustum,
// its arcs as fine polylines inside the true ones (distances err by under 0.2 % of δ, long).
#pragma once

#include <algorithm>
#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "tridex/cutter.hpp"
#include "tridex/error.hpp"
#include "tridex/geometry.hpp"

namespace tridex {

// One stacked section: radii at its bottom and top and its length along the axis, in mm.
struct BodySection {
  double bottom_radius = 0, top_radius = 0, length = 0;
};

struct BodyPart {
  std::string name;   // "shank", "holder section 1" (the bottom one), ...
  double bottom = 0;  // height of its bottom above the tool tip
  BodySection shape;
};

// The non-cutting parts of one tool, bottom to top; empty when the table describes none.
struct ToolBody {
  std::vector<BodyPart> parts;
  double stick_out = 0;  // length out of the holder (0: no holder given)
  bool has_holder() const { return stick_out > 0; }
};

// The lower surface of `part` grown by `grow` ≥ 0 (its Minkowski sum with a ball), as a cutter
// whose tip lies `grow` below the part's bottom.
inline Cutter part_surface(const BodyPart& part, double grow) {
  const BodySection& s = part.shape;
  detail::require_positive(s.bottom_radius, "body section bottom radius");
  if (!(s.top_radius > s.bottom_radius) || !(s.length < std::numeric_limits<double>::infinity()) ||
      !(s.length > 0)) {
    // The bottom disc is the widest part seen from below.
    return grow > 0 ? Cutter::bull_nose(s.bottom_radius + grow, grow)
                    : Cutter::flat(s.bottom_radius);
  }
  const double rise = s.top_radius - s.bottom_radius;
  const double half_angle_deg = glm::degrees(std::atan2(rise, s.length));
  if (!(grow > 0)) return Cutter::chamfer(s.top_radius, s.bottom_radius, half_angle_deg);
  // Offset profile in (ρ, h), h from the grown tip: the bottom edge (r0, δ) and the top edge
  // (r1, δ + L) rounded by arcs of radius δ, joined by the cone's side moved out by δ.
  const double normal_angle = std::atan2(-rise, s.length);  // outward normal of the cone's side
  constexpr int kArcPieces = 16;
  std::vector<Vec2> points{Vec2(0, 0)};
  auto arc = [&](double centre_rho, double centre_h, double from, double to) {
    for (int k = 0; k <= kArcPieces; ++k) {
      double a = from + (to - from) * k / kArcPieces;
      Vec2 p(centre_rho + grow * std::cos(a), centre_h + grow * std::sin(a));
      if (p.x > points.back().x + 1e-12 * (1 + p.x))
        points.push_back(Vec2(p.x, std::max(p.y, points.back().y)));
    }
  };
  arc(s.bottom_radius, grow, -M_PI / 2, normal_angle);
  arc(s.top_radius, grow + s.length, normal_angle, 0);
  return Cutter::from_profile(points);
}

}  // namespace tridex
