#include "inputs/tool_table.hpp"

#include <algorithm>
#include <cctype>
#include <charconv>
#include <cmath>
#include <limits>
#include <map>
#include <vector>

#include <nlohmann/json.hpp>

#include "errors.hpp"
#include "inputs/json_input.hpp"

namespace tridex::cli {

std::string ascii_lower(std::string text) {
  std::transform(text.begin(), text.end(), text.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return text;
}

namespace {

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

// The holder's sections in the CAMotics-style table: [{"bottom-diameter", "top-diameter",
// "length"}].
std::vector<BodySection> holder_sections(const nlohmann::json& tool, const std::string& where,
                                         double scale) {
  std::vector<BodySection> sections;
  auto holder = tool.find("holder");
  if (holder == tool.end()) return sections;
  if (!holder->is_array() || holder->empty())
    input_error(where, ": \"holder\" must be a non-empty list of sections, got ",
                json_type_name(*holder));
  for (std::size_t k = 0; k < holder->size(); ++k) {
    const nlohmann::json& section = (*holder)[k];
    std::string at = where + ": \"holder\" section " + std::to_string(k + 1);
    if (!section.is_object())
      input_error(at, ": must be a JSON object, got ", json_type_name(section));
    sections.push_back(BodySection{scale * number_field(section, at, {"bottom-diameter"}, true) / 2,
                                   scale * number_field(section, at, {"top-diameter"}, true) / 2,
                                   scale * number_field(section, at, {"length"}, true)});
  }
  return sections;
}

// Fusion's tool types (its library's "type"), by the solid tridex mills for them.
enum class FusionKind { flat, ball, bull_nose, drill, chamfer, countersink, tapered, unusable };

FusionKind fusion_kind(const std::string& type) {
  static const std::map<std::string, FusionKind> kKinds = {
      {"flat end mill", FusionKind::flat},
      {"face mill", FusionKind::flat},
      {"slot mill", FusionKind::flat},
      {"dovetail mill", FusionKind::flat},
      {"thread mill", FusionKind::flat},
      {"tap right hand", FusionKind::flat},
      {"tap left hand", FusionKind::flat},
      {"reamer", FusionKind::flat},
      {"counter bore", FusionKind::flat},
      {"boring bar", FusionKind::flat},
      {"ball end mill", FusionKind::ball},
      {"lollipop mill", FusionKind::ball},
      {"bull nose end mill", FusionKind::bull_nose},
      {"drill", FusionKind::drill},
      {"spot drill", FusionKind::drill},
      {"center drill", FusionKind::drill},
      {"chamfer mill", FusionKind::chamfer},
      {"counter sink", FusionKind::countersink},
      {"countersink", FusionKind::countersink},
      {"tapered mill", FusionKind::tapered},
  };
  auto it = kKinds.find(type);
  return it == kKinds.end() ? FusionKind::unusable : it->second;
}

std::string fusion_unusable_reason(const std::string& type) {
  if (type == "radius mill" || type == "form mill")
    return "whose profile is concave: tridex mills convex cutters only (tridex/cutter.hpp)";
  if (type == "probe" || type.find("holder") != std::string::npos) return "not a cutter";
  return "not a milling cutter tridex knows (docs/tool-tables.md lists the Fusion types)";
}

// An angle field in degrees within (0, 180) (a point angle) or (0, 90) (a half angle).
double angle_field(const nlohmann::json& geometry, const std::string& at, const char* key,
                   double below) {
  const double angle = number_field(geometry, at, {key}, true);
  if (!(angle > 0 && angle < below))
    input_error(at, ": \"", key, "\" ", angle, " must lie in (0, ", below, ") degrees");
  return angle;
}

// A bull nose or tapered profile's corner: the arc of radius `corner` from the flat tip of radius
// `flat` up to where its tangent makes `half_angle_deg` with the axis, as a fine polyline, then
// the taper up to `radius` (ρ, h from the tip).
std::vector<Vec2> tapered_corner_profile(double radius, double flat, double corner,
                                         double half_angle_deg) {
  std::vector<Vec2> points{Vec2(0, 0)};
  if (flat > 0) points.emplace_back(flat, 0);
  const double end = M_PI / 2 - glm::radians(half_angle_deg);  // the arc's turn from the tip
  const int pieces = 32;
  for (int k = 1; k <= pieces; ++k) {
    const double theta = end * k / pieces;
    points.emplace_back(flat + corner * std::sin(theta), corner - corner * std::cos(theta));
  }
  const Vec2 last = points.back();
  points.emplace_back(radius, last.y + (radius - last.x) / std::tan(glm::radians(half_angle_deg)));
  return points;
}

// The cutter of a Fusion tool (docs/tool-tables.md): what a tool of the kind sweeps, as a convex
// solid of revolution continued upward at full radius (the Z-map model, tridex/cutter.hpp).
Cutter fusion_cutter(FusionKind kind, const nlohmann::json& geometry, double scale,
                     const std::string& at, ToolSpec& spec) {
  const double radius = spec.diameter_mm / 2;
  if (!(radius > 0)) input_error(at, ": \"DC\" must be positive, got ", spec.diameter_mm);
  try {
    switch (kind) {
      case FusionKind::flat:
        return Cutter::flat(radius);
      case FusionKind::ball:
        return Cutter::ball(radius);
      case FusionKind::bull_nose: {
        spec.corner_radius_mm = scale * number_field(geometry, at, {"RE"}, true);
        // Fusion keeps "bull nose" with RE equal to the radius for what is a ball; a larger RE is
        // no tool (docs/tool-tables.md).
        if (spec.corner_radius_mm > radius * (1 + 1e-9))
          input_error(at, ": \"RE\" ", spec.corner_radius_mm, " mm is larger than the radius ",
                      radius, " mm");
        if (spec.corner_radius_mm >= radius) return Cutter::ball(radius);
        if (!(spec.corner_radius_mm > 0)) return Cutter::flat(radius);
        return Cutter::bull_nose(radius, spec.corner_radius_mm);
      }
      case FusionKind::drill:  // SIG: the point angle, 118° on a jobber drill
        return Cutter::cone(radius, angle_field(geometry, at, "SIG", 180) / 2);
      case FusionKind::chamfer:
      case FusionKind::countersink: {
        // A chamfer mill's TA is its half angle (45 for a 90° tool); a countersink's SIG its
        // included angle. Either key is read for either type.
        const bool half =
            geometry.contains("TA") && (kind == FusionKind::chamfer || !geometry.contains("SIG"));
        const double angle =
            half ? angle_field(geometry, at, "TA", 90) : angle_field(geometry, at, "SIG", 180) / 2;
        const double tip = scale * number_field(geometry, at, {"tip-diameter"}, false) / 2;
        return Cutter::chamfer(radius, tip, angle);
      }
      case FusionKind::tapered: {
        // DC is the tip's diameter, TA the taper's half angle, RE the tip's corner radius; the
        // flutes widen to DC + 2·LCF·tan(TA) at their top.
        const double angle = angle_field(geometry, at, "TA", 90);
        const double corner = scale * number_field(geometry, at, {"RE"}, false);
        const double top = radius + spec.flute_length_mm * std::tan(glm::radians(angle));
        spec.corner_radius_mm = corner;
        if (corner >= radius) return Cutter::tapered_ball(top, radius, angle);
        if (corner > 0)
          return Cutter::from_profile(tapered_corner_profile(top, radius - corner, corner, angle));
        return Cutter::chamfer(top, radius, angle);
      }
      case FusionKind::unusable:
        break;
    }
  } catch (const InputError&) {
    throw;
  } catch (const tridex::Error& e) {
    input_error(at, ": ", e.what());
  }
  input_error(at, ": not a cutter");
}

}  // namespace

ToolBody make_body(const ToolSpec& spec, const std::string& where) {
  ToolBody body;
  if (spec.flute_length_mm > 0) {
    double shank = spec.shank_diameter_mm > 0 ? spec.shank_diameter_mm : spec.diameter_mm;
    if (spec.stick_out_mm > 0 && spec.flute_length_mm > spec.stick_out_mm)
      input_error(where, ": \"flute-length\" ", spec.flute_length_mm,
                  " mm is longer than \"stick-out\" ", spec.stick_out_mm, " mm");
    double length = spec.stick_out_mm > 0 ? spec.stick_out_mm - spec.flute_length_mm
                                          : std::numeric_limits<double>::infinity();
    if (length > 0)
      body.parts.push_back(
          BodyPart{"shank", spec.flute_length_mm, BodySection{shank / 2, shank / 2, length}});
  } else if (spec.shank_diameter_mm > 0) {
    input_error(where, ": \"shank-diameter\" needs \"flute-length\" (where the shank begins)");
  }
  if (spec.holder.empty()) return body;
  if (!(spec.stick_out_mm > 0)) input_error(where, ": \"holder\" needs a positive \"stick-out\"");
  body.stick_out = spec.stick_out_mm;
  double bottom = spec.stick_out_mm;
  for (std::size_t k = 0; k < spec.holder.size(); ++k) {
    const BodySection& s = spec.holder[k];
    std::string name = "holder section " + std::to_string(k + 1);
    if (!(s.length > 0)) input_error(where, ": ", name, ": the length must be positive");
    if (!(s.bottom_radius > 0))
      input_error(where, ": ", name,
                  ": the bottom diameter must be positive (a holder has a face)");
    body.parts.push_back(BodyPart{name, bottom, s});
    bottom += s.length;
  }
  return body;
}

namespace {

// Every length of a tool, after its unit is applied (a value that passes in inches may overflow
// in mm), must be finite and below this: 100 m is past any machine, and the lengths stay far from
// overflow when the kernel squares and sums them.
constexpr double kMaxToolLengthMm = 1e5;
// A holder of more sections than this is no real holder; each costs a part checked per move.
constexpr std::size_t kMaxHolderSections = 1000;

void check_length(const std::string& where, const char* key, double mm) {
  if (!(std::abs(mm) <= kMaxToolLengthMm))
    input_error(where, ": \"", key, "\" is ", mm, " mm after unit conversion, beyond ",
                kMaxToolLengthMm, " mm");
}

void check_tool_ranges(const ToolSpec& spec, const std::string& where) {
  check_length(where, "diameter", spec.diameter_mm);
  check_length(where, "length", spec.length_mm);
  check_length(where, "corner-radius", spec.corner_radius_mm);
  check_length(where, "snub-diameter", spec.snub_diameter_mm);
  check_length(where, "flute-length", spec.flute_length_mm);
  check_length(where, "shank-diameter", spec.shank_diameter_mm);
  check_length(where, "stick-out", spec.stick_out_mm);
  if (spec.holder.size() > kMaxHolderSections)
    input_error(where, ": the holder has ", spec.holder.size(), " sections, more than ",
                kMaxHolderSections);
  double total = 0;
  for (std::size_t k = 0; k < spec.holder.size(); ++k) {
    const std::string at = where + ": holder section " + std::to_string(k + 1);
    check_length(at, "bottom diameter", 2 * spec.holder[k].bottom_radius);
    check_length(at, "top diameter", 2 * spec.holder[k].top_radius);
    check_length(at, "length", spec.holder[k].length);
    total += spec.holder[k].length;
  }
  check_length(where, "holder length", total);
}

double tool_length_mm(double mm, const std::string& where, const char* key) {
  check_length(where, key, mm);
  return mm;
}

}  // namespace

Cutter make_cutter(const ToolSpec& spec, const std::string& where) {
  check_tool_ranges(spec, where);
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
      input_error(source, ": keys \"", previous->second, "\" and \"", key, "\" are both tool ",
                  number);
    where = source + ": tool " + std::to_string(number);
    const nlohmann::json& tool = it.value();
    if (!tool.is_object())
      input_error(where, ": must be a JSON object, got ", json_type_name(tool));

    double scale = 1;
    if (auto units = tool.find("units"); units != tool.end()) {
      if (!units->is_string())
        input_error(where, ": \"units\" must be a string, got ", json_type_name(*units));
      std::string u = ascii_lower(units->get<std::string>());
      if (u == "mm" || u == "metric")
        scale = 1;
      else if (u == "inch" || u == "in" || u == "imperial")
        scale = 25.4;
      else
        input_error(where, ": unknown \"units\" \"", u,
                    "\" (expected mm, metric, inch or imperial)");
    }
    ToolSpec spec;
    spec.number = number;
    auto shape = tool.find("shape");
    if (shape == tool.end() || !shape->is_string())
      input_error(where, ": missing \"shape\" (a string)");
    spec.shape = ascii_lower(shape->get<std::string>());
    spec.diameter_mm = scale * number_field(tool, where, {"diameter"}, true);
    spec.length_mm = scale * number_field(tool, where, {"length"}, false);
    spec.corner_radius_mm =
        scale * number_field(tool, where, {"corner-radius", "corner_radius"}, false);
    spec.snub_diameter_mm =
        scale * number_field(tool, where, {"snub_diameter", "snub-diameter"}, false);
    if (auto d = tool.find("description"); d != tool.end() && d->is_string())
      spec.description = d->get<std::string>();
    spec.flute_length_mm =
        scale * number_field(tool, where, {"flute-length", "flute_length"}, false);
    spec.shank_diameter_mm =
        scale * number_field(tool, where, {"shank-diameter", "shank_diameter"}, false);
    spec.stick_out_mm = scale * number_field(tool, where, {"stick-out", "stick_out"}, false);
    spec.holder = holder_sections(tool, where, scale);
    for (const char* name : {"tool-length", "tool_length"})
      if (auto length = tool.find(name); length != tool.end()) {
        if (!length->is_number() || !std::isfinite(length->get<double>()))
          input_error(where, ": \"", name, "\" must be a finite number, got ", length->dump());
        result.tool_lengths_[number] = tool_length_mm(scale * length->get<double>(), where, name);
      }
    spec.cutter = make_cutter(spec, where);
    spec.body = make_body(spec, where);
    result.tools_.emplace(number, std::move(spec));
  }
  return result;
}

ToolTable ToolTable::from_tbl(const std::string& text, const std::string& source, double unit_mm) {
  ToolTable result;
  std::map<int, int> line_of;  // tool number -> its line, to name both of a duplicate
  int line = 0;
  for (std::size_t at = 0; at < text.size();) {
    // LF, CR LF and a lone CR (old Mac editors) each end a line.
    std::size_t end = text.find_first_of("\r\n", at);
    if (end == std::string::npos) end = text.size();
    std::string row = text.substr(at, end - at);
    at = end + (text.compare(end, 2, "\r\n") == 0 ? 2 : 1);
    ++line;
    std::string description;
    if (std::size_t semicolon = row.find(';'); semicolon != std::string::npos) {
      description = row.substr(semicolon + 1);
      row.resize(semicolon);
    }
    std::map<char, std::pair<double, int>> words;  // letter -> value, column
    for (std::size_t i = 0; i < row.size();) {
      if (std::isspace(static_cast<unsigned char>(row[i]))) {
        ++i;
        continue;
      }
      const int column = static_cast<int>(i) + 1;
      const char letter = static_cast<char>(std::toupper(static_cast<unsigned char>(row[i])));
      std::size_t stop = row.find_first_of(" \t\r", i);
      if (stop == std::string::npos) stop = row.size();
      const std::string word = row.substr(i, stop - i);
      i = stop;
      double value = 0;
      const char* first = word.data() + 1;
      if (*first == '+') ++first;  // LinuxCNC writes Z+0.511000
      auto [rest, error] = std::from_chars(first, word.data() + word.size(), value);
      if (!std::isalpha(static_cast<unsigned char>(letter)) || word.size() < 2 ||
          error != std::errc() || rest != word.data() + word.size() || !std::isfinite(value))
        input_error(source, ":", line, ":", column, ": \"", word,
                    "\" is not a tool table word (a letter and a number)");
      if (words.count(letter))
        input_error(source, ":", line, ":", column, ": repeated word ", letter);
      words[letter] = {value, column};
    }
    if (words.empty()) continue;
    auto t = words.find('T');
    if (t == words.end()) input_error(source, ":", line, ": no tool number T");
    const auto [tool_value, tool_column] = t->second;
    if (tool_value < 0 || tool_value > 1e9 || tool_value != std::floor(tool_value))
      input_error(source, ":", line, ":", tool_column, ": T", tool_value, " is not a tool number");
    const int number = static_cast<int>(tool_value);
    if (auto [previous, inserted] = line_of.emplace(number, line); !inserted)
      input_error(source, ":", line, ": tool ", number, " again (first at line ", previous->second,
                  ")");
    for (char c : {'X', 'Y'})
      if (auto it = words.find(c); it != words.end() && it->second.first != 0)
        input_error(source, ":", line, ":", it->second.second, ": tool ", number,
                    " has a sideways offset ", c, it->second.first,
                    ", which tridex does not simulate");
    // An entry without Z has length 0, as LinuxCNC reads it (tooldata_common.cc,
    // tooldata_read_entry: the offset starts zeroed and only a Z word sets its z).
    if (auto z = words.find('Z'); z != words.end())
      result.tool_lengths_[number] = tool_length_mm(
          unit_mm * z->second.first,
          source + ":" + std::to_string(line) + ": tool " + std::to_string(number), "Z");
    else
      result.tool_lengths_[number] = 0;
    auto d = words.find('D');
    if (d == words.end() || d->second.first == 0) {
      // D0 or no D (LinuxCNC's diameter then is 0): a probe, an engraver or a tool not measured
      // yet. It cuts nothing, but it is in the table: G41/G42 with it offset by 0, as LinuxCNC.
      result.zero_diameter_.insert(number);
      continue;
    }
    std::string where = source + ":" + std::to_string(line) + ": tool " + std::to_string(number);
    if (d->second.first < 0)
      input_error(where, ": the diameter D must not be negative, got ", d->second.first);
    ToolSpec spec;
    spec.number = number;
    spec.shape = "cylindrical";
    spec.diameter_mm = unit_mm * d->second.first;
    spec.description = description;
    spec.cutter = make_cutter(spec, where);
    spec.body = make_body(spec, where);
    result.tools_.emplace(number, std::move(spec));
  }
  return result;
}

ToolTable ToolTable::from_fusion_json(const nlohmann::json& library, const std::string& source) {
  auto data = library.is_object() ? library.find("data") : library.end();
  if (data == library.end() || !data->is_array())
    input_error(source, ": a Fusion tool library must be a JSON object with a \"data\" list");
  ToolTable result;
  std::map<int, std::size_t> entry_of;  // tool number -> its index in "data"
  for (std::size_t k = 0; k < data->size(); ++k) {
    const nlohmann::json& tool = (*data)[k];
    std::string where = source + ": \"data\"[" + std::to_string(k) + "]";
    if (!tool.is_object())
      input_error(where, ": must be a JSON object, got ", json_type_name(tool));
    auto type = tool.find("type");
    if (type == tool.end() || !type->is_string())
      input_error(where, ": missing \"type\" (a string)");
    const std::string type_name = ascii_lower(type->get<std::string>());
    std::string description;
    if (auto d = tool.find("description"); d != tool.end() && d->is_string())
      description = d->get<std::string>();
    if (!description.empty()) where += " (\"" + description + "\")";
    // The number the program calls it by.
    auto post = tool.find("post-process");
    // An entry that cannot cut and that no program can call (a lone holder) is not a tool.
    if (fusion_kind(type_name) == FusionKind::unusable &&
        (post == tool.end() || !post->is_object() || !post->contains("number")))
      continue;
    if (post == tool.end() || !post->is_object())
      input_error(where, ": missing \"post-process\" (an object)");
    auto number_key = post->find("number");
    if (number_key == post->end() || !number_key->is_number_integer() ||
        number_key->get<long long>() < 0 || number_key->get<long long>() > 1'000'000'000)
      input_error(where,
                  ": \"post-process\".\"number\" must be a non-negative integer tool number");
    const int number = static_cast<int>(number_key->get<long long>());
    if (auto [previous, inserted] = entry_of.emplace(number, k); !inserted)
      input_error(source, ": \"data\"[", previous->second, "] and \"data\"[", k, "] are both tool ",
                  number);
    where = source + ": tool " + std::to_string(number) +
            (description.empty() ? "" : " (\"" + description + "\")");
    const FusionKind kind = fusion_kind(type_name);
    if (kind == FusionKind::unusable) {
      // Kept, so that a program that uses it is told what it is (pipeline.cpp, load_cutters).
      result.unusable_[number] =
          where + " is a Fusion \"" + type_name + "\", " + fusion_unusable_reason(type_name);
      continue;
    }

    auto unit_scale = [&](const nlohmann::json& object, const std::string& at, double fallback) {
      auto unit = object.find("unit");
      if (unit == object.end()) return fallback;
      if (!unit->is_string())
        input_error(at, ": \"unit\" must be a string, got ", json_type_name(*unit));
      std::string u = ascii_lower(unit->get<std::string>());
      if (u == "millimeters" || u == "mm") return 1.0;
      if (u == "inches" || u == "inch" || u == "in") return 25.4;
      input_error(at, ": unknown \"unit\" \"", u, "\" (expected millimeters or inches)");
    };
    auto unit = tool.find("unit");
    if (unit == tool.end()) input_error(where, ": missing \"unit\"");
    const double scale = unit_scale(tool, where, 1.0);
    auto geometry = tool.find("geometry");
    if (geometry == tool.end() || !geometry->is_object())
      input_error(where, ": missing \"geometry\" (an object)");
    const std::string at = where + ": \"geometry\"";
    ToolSpec spec;
    spec.number = number;
    spec.shape = type_name;
    spec.description = description;
    spec.diameter_mm = scale * number_field(*geometry, at, {"DC"}, true);
    spec.flute_length_mm = scale * number_field(*geometry, at, {"LCF"}, true);
    spec.stick_out_mm = scale * number_field(*geometry, at, {"LB"}, true);
    const double overall = scale * number_field(*geometry, at, {"OAL"}, true);
    spec.shank_diameter_mm = scale * number_field(*geometry, at, {"SFDM"}, true);
    if (spec.stick_out_mm > overall)
      input_error(at, ": \"LB\" ", spec.stick_out_mm, " mm is longer than \"OAL\" ", overall,
                  " mm");
    if (!(spec.flute_length_mm > 0)) input_error(at, ": \"LCF\" must be positive");
    if (spec.flute_length_mm > spec.stick_out_mm)
      input_error(at, ": \"LCF\" ", spec.flute_length_mm, " mm is longer than \"LB\" ",
                  spec.stick_out_mm, " mm");
    if (!(spec.shank_diameter_mm > 0)) input_error(at, ": \"SFDM\" must be positive");
    if (auto holder = tool.find("holder"); holder != tool.end()) {
      const std::string hat = where + ": \"holder\"";
      if (!holder->is_object())
        input_error(hat, ": must be a JSON object, got ", json_type_name(*holder));
      const double holder_scale = unit_scale(*holder, hat, scale);
      auto segments = holder->find("segments");
      if (segments == holder->end() || !segments->is_array())
        input_error(hat, ": missing \"segments\" (a list)");
      for (std::size_t s = 0; s < segments->size(); ++s) {
        const nlohmann::json& segment = (*segments)[s];
        std::string sat = hat + ": \"segments\"[" + std::to_string(s) + "]";
        if (!segment.is_object())
          input_error(sat, ": must be a JSON object, got ", json_type_name(segment));
        spec.holder.push_back(
            BodySection{holder_scale * number_field(segment, sat, {"lower-diameter"}, true) / 2,
                        holder_scale * number_field(segment, sat, {"upper-diameter"}, true) / 2,
                        holder_scale * number_field(segment, sat, {"height"}, true)});
      }
    }
    check_tool_ranges(spec, where);  // as make_cutter does for the other formats
    spec.cutter = fusion_cutter(kind, *geometry, scale, at, spec);
    spec.body = make_body(spec, where);
    result.tools_.emplace(number, std::move(spec));
  }
  return result;
}

ToolTable ToolTable::read(const std::filesystem::path& path, double tbl_unit_mm) {
  if (ascii_lower(path.extension().string()) == ".tbl")
    return from_tbl(read_text_file(path, "a tool table"), path.string(), tbl_unit_mm);
  nlohmann::json json = read_json_file(path);
  if (json.is_object() && json.contains("data") && json["data"].is_array())
    return from_fusion_json(json, path.string());
  return from_json(json, path.string());
}

}  // namespace tridex::cli
