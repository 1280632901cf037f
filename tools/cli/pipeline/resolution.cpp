#include "pipeline/resolution.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>

namespace tridex::cli {

double missable_depth(const Cutter& cutter, double s) {
  const double radius = cutter.radius();
  if (!(s < radius)) return std::numeric_limits<double>::infinity();
  const double side = radius - std::sqrt(radius * radius - s * s);  // the side's arc
  return std::max(cutter.lower_height(s), side);
}

ResolutionBound resolution_bound(const std::vector<gcode::MoveGroup>& groups,
                                 const std::vector<gcode::Move>& simultaneous,
                                 std::span<const Cutter> cutters,
                                 const std::map<int, std::uint32_t>& cutter_of_tool, double spacing,
                                 double zmap_cell) {
  ResolutionBound bound;
  auto consider = [&](int tool, double s) {
    const auto found = cutter_of_tool.find(tool);
    if (found == cutter_of_tool.end()) return;
    const double depth = missable_depth(cutters[found->second], s);
    if (bound.tool == 0 || depth > bound.missable) bound = {depth, tool, s};
  };
  for (const gcode::MoveGroup& group : groups) {
    const double cos_theta =
        std::max({std::abs(group.axis.x), std::abs(group.axis.y), std::abs(group.axis.z)}) /
        std::max(1e-300, glm::length(group.axis));
    const double s_ray = 0.5 * spacing * std::sqrt(1 + 1 / (cos_theta * cos_theta));
    for (int tool : group.tools) consider(tool, s_ray + std::sqrt(2.0) * zmap_cell);
  }
  for (const gcode::Move& m : simultaneous) consider(m.tool, spacing);
  return bound;
}

double spacing_for_tolerance(const std::function<double(double spacing)>& bound_at, double coarsest,
                             double tolerance) {
  if (bound_at(coarsest) <= tolerance) return coarsest;
  // The bound grows with the spacing: bisect on [0, coarsest] for the largest one within it.
  double fine = 0, coarse = coarsest;
  for (int k = 0; k < 60; ++k) {
    const double mid = 0.5 * (fine + coarse);
    (bound_at(mid) <= tolerance ? fine : coarse) = mid;
  }
  return fine > 0 && bound_at(fine) <= tolerance ? fine : 0.0;
}

std::string missable_text(const ResolutionBound& bound, std::span<const Cutter> cutters,
                          const std::map<int, std::uint32_t>& cutter_of_tool) {
  const auto found = cutter_of_tool.find(bound.tool);
  if (found == cutter_of_tool.end()) return "0 mm (no tool cuts)";
  const Cutter& c = cutters[found->second];
  char tool_name[96];
  std::snprintf(tool_name, sizeof tool_name, "%g mm %s", 2 * c.radius(), c.name().c_str());
  char text[256];
  if (std::isfinite(bound.missable))
    std::snprintf(text, sizeof text, "%.3g mm (tool %d, %s)", bound.missable, bound.tool,
                  tool_name);
  else
    std::snprintf(text, sizeof text,
                  "any depth (tool %d, %s: a sample can lie %.3g mm from its tip, beyond its "
                  "radius)",
                  bound.tool, tool_name, bound.distance);
  return text;
}

}  // namespace tridex::cli
