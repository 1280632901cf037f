#include "tool_table.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <map>
#include <vector>

#include <nlohmann/json.hpp>

#include "errors.hpp"
#include "json_input.hpp"

namespace tridex::cli {

namespace {

std::string lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

double number_field(const nlohmann::json& tool, const std::string& where,
                    std::initializer_list<const char*> keys, bool required) {
  for (const char* key : keys) {
    auto it = tool.find(key);
    if (it == tool.end()) continue;
    if (!it->is_number())
      input_error(where, ": \"", key, "\" must be a number, got ", json_type_name(*it));
    double value = it->get<double>();
    if (!std::isfinite(value) || value < 0)
      input_error(where, ": \"", key, "\" must be a finite non-negative number, got ", value);
    return value;
  }
  if (required) input_error(where, ": missing \"", *keys.begin(), "\"");
  return 0;
}

// The lower half of an ellipsoid with semi-axes a (radial) and b (axial) as a convex polyline of
// (ρ, h) points from the tip, evenly spaced in the ellipse's parameter so the pieces are short
// where the curvature is high.
std::vector<Vec2> spheroid_profile(double a, double b) {
  std::vector<Vec2> points;
  const int pieces = 64;
  for (int k = 0; k <= pieces; ++k) {
    double theta = (M_PI / 2) * k / pieces;
    points.emplace_back(a * std::sin(theta), b - b * std::cos(theta));
  }
  points.front() = Vec2(0, 0);
  return points;
}

}  // namespace

Cutter make_cutter(const ToolSpec& spec, const std::string& where) {
  double radius = spec.diameter_mm / 2;
  if (!(radius > 0)) input_error(where, ": \"diameter\" must be positive, got ", spec.diameter_mm);
  auto need_length = [&] {
    if (!(spec.length_mm > 0))
      input_error(where, ": shape \"", spec.shape, "\" needs a positive \"length\"");
  };
  try {
    if (spec.shape == "cylindrical") return Cutter::flat(radius);
    if (spec.shape == "ballnose") return Cutter::ball(radius);
    if (spec.shape == "bullnose") {
      if (!(spec.corner_radius_mm > 0))
        input_error(where, ": shape \"bullnose\" needs a positive \"corner-radius\"");
      return Cutter::bull_nose(radius, spec.corner_radius_mm);
    }
    if (spec.shape == "conical") {
      need_length();
      return Cutter::cone(radius, glm::degrees(std::atan(radius / spec.length_mm)));
    }
    if (spec.shape == "snubnose") {
      need_length();
      double tip = spec.snub_diameter_mm / 2;
      if (tip >= radius)
        input_error(where, ": \"snub_diameter\" ", spec.snub_diameter_mm,
                    " must be smaller than \"diameter\" ", spec.diameter_mm);
      return Cutter::chamfer(radius, tip, glm::degrees(std::atan((radius - tip) / spec.length_mm)));
    }
    if (spec.shape == "spheroid") {
      need_length();
      return Cutter::from_profile(spheroid_profile(radius, spec.length_mm / 2));
    }
  } catch (const InputError&) {
    throw;
  } catch (const tridex::Error& e) {
    input_error(where, ": ", e.what());
  }
  input_error(where, ": unknown shape \"", spec.shape,
              "\" (expected cylindrical, ballnose, bullnose, conical, snubnose or spheroid)");
}

ToolTable ToolTable::from_json(const nlohmann::json& table, const std::string& source) {
  if (!table.is_object())
    input_error(source, ": a tool table must be a JSON object keyed by tool number");
  ToolTable result;
  std::map<int, std::string> key_of;  // tool number -> its key, to name both of a duplicate
  for (auto it = table.begin(); it != table.end(); ++it) {
    const std::string& key = it.key();
    std::string where = source + ": tool \"" + key + "\"";
    // Digits only: std::stoi would also take " 1" and "+1", and "01" is the same tool as "1".
    int number = -1;
    auto [end, error] = std::from_chars(key.data(), key.data() + key.size(), number);
    if (key.empty() || !std::isdigit(static_cast<unsigned char>(key[0])) || error != std::errc() ||
        end != key.data() + key.size())
      input_error(where, ": the key must be a non-negative tool number (digits only)");
    if (auto [previous, inserted] = key_of.emplace(number, key); !inserted)
      input_error(source, ": keys \"", previous->second, "\" and \"", key, "\" are both tool ", number);
    where = source + ": tool " + std::to_string(number);
    const nlohmann::json& tool = it.value();
    if (!tool.is_object()) input_error(where, ": must be a JSON object, got ", json_type_name(tool));

    double scale = 1;
    if (auto units = tool.find("units"); units != tool.end()) {
      if (!units->is_string()) input_error(where, ": \"units\" must be a string, got ", json_type_name(*units));
      std::string u = lower(units->get<std::string>());
      if (u == "mm" || u == "metric") scale = 1;
      else if (u == "inch" || u == "in" || u == "imperial") scale = 25.4;
      else input_error(where, ": unknown \"units\" \"", u, "\" (expected mm, metric, inch or imperial)");
    }
    ToolSpec spec;
    spec.number = number;
    auto shape = tool.find("shape");
    if (shape == tool.end() || !shape->is_string()) input_error(where, ": missing \"shape\" (a string)");
    spec.shape = lower(shape->get<std::string>());
    spec.diameter_mm = scale * number_field(tool, where, {"diameter"}, true);
    spec.length_mm = scale * number_field(tool, where, {"length"}, false);
    spec.corner_radius_mm =
        scale * number_field(tool, where, {"corner-radius", "corner_radius"}, false);
    spec.snub_diameter_mm =
        scale * number_field(tool, where, {"snub_diameter", "snub-diameter"}, false);
    if (auto d = tool.find("description"); d != tool.end() && d->is_string())
      spec.description = d->get<std::string>();
    spec.cutter = make_cutter(spec, where);
    result.tools_.emplace(number, std::move(spec));
  }
  return result;
}

ToolTable ToolTable::read(const std::filesystem::path& path) {
  return from_json(read_json_file(path), path.string());
}

}  // namespace tridex::cli
