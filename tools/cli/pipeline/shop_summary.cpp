#include "pipeline/shop_summary.hpp"

#include <cmath>
#include <cstdio>
#include <optional>

namespace tridex::cli {

namespace {

// -0 and rounding noise as 0, to 3 decimals.
std::string number(double v) {
  char text[32];
  if (std::abs(v) < 5e-4) v = 0;
  std::snprintf(text, sizeof text, "%.3f", v);
  std::string s = text;
  while (s.back() == '0') s.pop_back();
  if (s.back() == '.') s.pop_back();
  return s;
}

}  // namespace

Vec3 g68_2_angles(const Vec3& axis) {
  const double j = glm::degrees(std::acos(std::clamp(axis.z, -1.0, 1.0)));
  const double i =
      std::hypot(axis.x, axis.y) < 1e-12 ? 0 : glm::degrees(std::atan2(axis.x, -axis.y));
  return {i, j, 0};
}

std::string tools_text(const SimulationResult& r) {
  std::string text;
  const ToolTable* table = r.input.tools ? &*r.input.tools : nullptr;
  for (const auto& [tool, index] : r.cutter_of_tool) {
    const Cutter& c = r.cutters[index];
    text += text.empty() ? "tools: T" : ", T";
    text += std::to_string(tool);
    text += ' ';
    text += number(2 * c.radius());
    text += " mm ";
    text += c.name();
    const ToolSpec* spec = table ? table->find(tool) : nullptr;
    if (spec && !spec->description.empty()) {
      text += " (\"";
      text += spec->description;
      text += "\")";
    }
  }
  return text.empty() ? "tools: none" : text;
}

std::string directions_text(const SimulationResult& r) {
  std::string text;
  for (const gcode::MoveGroup& group : r.groups) {
    std::string one = axis_label(group.axis);
    if (one.find('_') != std::string::npos) one = "tilted";
    const std::optional<gcode::Move> first =
        group.moves.empty() ? std::nullopt : std::optional<gcode::Move>(group.moves.front());
    if (r.input.machine.kinematics && first && first->rotary_axes) {
      std::string angles;
      for (int a = 0; a < 3; ++a)
        if (first->rotary_axes & (1u << a)) {
          if (!angles.empty()) angles += ' ';
          angles += "ABC"[a];
          angles += number(first->rotary[static_cast<std::size_t>(a)]);
        }
      one += " (";
      one += angles;
      one += ')';
    } else if (one == "tilted" || one[0] == '-' || one[1] != 'z') {
      const Vec3 g = g68_2_angles(group.axis);
      one += " (G68.2 I";
      one += number(g.x);
      one += " J";
      one += number(g.y);
      one += " K0)";
    }
    text += text.empty() ? "directions: " : ", ";
    text += one;
  }
  return text.empty() ? "directions: none" : text;
}

}  // namespace tridex::cli
