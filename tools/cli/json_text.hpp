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
// A value that is not finite is written as null (as nlohmann::json writes it): JSON has no NaN or
// infinity, and a line of `moves` must parse. The readers of the inputs keep such values out.
inline void append_number(std::string& out, double v) {
  if (!std::isfinite(v)) {
    out += "null";
    return;
  }
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

// Text that is not valid UTF-8 read as ISO 8859-1 (Latin-1) and transcoded to UTF-8: the
// European posts that write "(Fräser Ø6)" in Latin-1, a file name with a byte 0xFF. JSON is
// UTF-8, so the report holds the characters meant (in all likelihood) instead of failing.
inline std::string latin1_to_utf8(const std::string& text) {
  std::string out;
  out.reserve(text.size() + text.size() / 4);
  for (char c : text) {
    const auto byte = static_cast<unsigned char>(c);
    if (byte < 0x80) {
      out += c;
    } else {
      out += static_cast<char>(0xc0 | (byte >> 6));
      out += static_cast<char>(0x80 | (byte & 0x3f));
    }
  }
  return out;
}

namespace json_detail {

inline bool valid_utf8(const std::string& text) {
  try {
    (void)nlohmann::json(text).dump();
    return true;
  } catch (const nlohmann::json::type_error&) {
    return false;
  }
}

// Every string and key of `value` that is not UTF-8, transcoded from Latin-1.
inline Json transcoded(const Json& value) {
  if (value.is_string()) {
    const std::string& text = value.get_ref<const std::string&>();
    return valid_utf8(text) ? value : Json(latin1_to_utf8(text));
  }
  if (value.is_array()) {
    Json out = Json::array();
    for (const Json& item : value) out.push_back(transcoded(item));
    return out;
  }
  if (value.is_object()) {
    Json out = Json::object();
    for (const auto& [key, item] : value.items())
      out[valid_utf8(key) ? key : latin1_to_utf8(key)] = transcoded(item);
    return out;
  }
  return value;
}

}  // namespace json_detail

// `value` as JSON text; strings that are not UTF-8 (a Latin-1 comment, a file name) are transcoded
// from Latin-1 (latin1_to_utf8) rather than failing the run after its other outputs were written.
inline std::string dump_json(const Json& value, int indent = -1) {
  try {
    return value.dump(indent);
  } catch (const nlohmann::json::type_error&) {
    return json_detail::transcoded(value).dump(indent);
  }
}

}  // namespace tridex::cli
