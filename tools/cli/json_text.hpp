// tridex command — small helpers for the JSON it writes.
#pragma once

#include <charconv>
#include <cmath>
#include <string>

#include <nlohmann/json.hpp>

#include "tridex/geometry.hpp"

namespace tridex::cli {

// Rounding noise of rotations (6.1e-17 for a zero) printed as 0; other values as they are.
inline double clean(double v) { return std::abs(v) < 1e-12 ? 0.0 : v; }

using Json = nlohmann::ordered_json;  // keys in the order written

inline Json to_json(const Vec3& v) { return Json::array({clean(v.x), clean(v.y), clean(v.z)}); }

// Appends the shortest text that reads back as `v` (std::to_chars), for the JSON Lines of
// `moves`, which can run to millions of records.
inline void append_number(std::string& out, double v) {
  char buffer[32];
  auto result = std::to_chars(buffer, buffer + sizeof buffer, clean(v));
  out.append(buffer, result.ptr);
}

inline void append_vec3(std::string& out, const Vec3& v) {
  out += '[';
  append_number(out, v.x);
  out += ',';
  append_number(out, v.y);
  out += ',';
  append_number(out, v.z);
  out += ']';
}

}  // namespace tridex::cli
