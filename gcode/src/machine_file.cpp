// tridex::gcode — the machine file: a machine described in JSON (machine.hpp lists the keys,
// README "Machine files" documents them), read into a MachineConfig, its kinematics and its
// speeds. Every fault is a MachineError naming the file, the key and the value.
#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <nlohmann/json.hpp>
#include <optional>
#include <sstream>
#include <utility>
#include <vector>

#include "tridex/error.hpp"
#include "tridex/gcode/machine.hpp"
#include "codes.hpp"

namespace tridex::gcode {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

template <class... Parts>
[[noreturn]] void machine_error(const Parts&... parts) {
  std::ostringstream message;
  (message << ... << parts);
  throw MachineError(message.str());
}

// Concatenation through a stream (GCC 12 warns falsely on "literal" + std::string chains).
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

// Every number of a machine file lies within ±kMaxValue (mm, mm/min, a variable's value): a
// kilometre-scale machine is far inside, and positions, distances and times computed from such
// values stay finite (a home at 1e308 made every machining time null).
constexpr double kMaxValue = 1e9;

bool in_range(const json& c) { return c.is_number() && std::abs(c.get<double>()) <= kMaxValue; }

Vec3 point(const json& value, const std::string& where) {
  if (!value.is_array() || value.size() != 3)
    machine_error(where, ": must be [x, y, z] in mm, got ", value.dump());
  Vec3 p;
  for (int i = 0; i < 3; ++i) {
    const json& c = value[static_cast<std::size_t>(i)];
    if (!in_range(c))
      machine_error(where, ": must be [x, y, z] of numbers within ±", kMaxValue, " mm, got ",
                    value.dump());
    p[i] = c.get<double>();
  }
  return p;
}

std::set<int> m_code_list(const json& value, const std::string& where) {
  if (!value.is_array())
    machine_error(where, ": must be a list of M-code numbers, got ", value.dump());
  std::set<int> codes;
  for (const json& c : value) {
    if (!c.is_number_integer() || c.get<long long>() < 0 || c.get<long long>() > 9999)
      machine_error(where, ": M-code numbers are integers in [0, 9999], got ", c.dump());
    codes.insert(static_cast<int>(c.get<long long>()));
  }
  return codes;
}

const json& string_value(const json& value, const std::string& where) {
  if (!value.is_string()) machine_error(where, ": must be a string, got ", value.dump());
  return value;
}

// "G54".."G59" -> 1..6; "G54.1 P<n>" -> 100 + n.
int work_offset_key(const std::string& name, const std::string& where) {
  for (int n = 1; n <= 6; ++n)
    if (name == cat("G", 53 + n)) return MachineConfig::g54_key(n);
  if (name.rfind("G54.1 P", 0) == 0) {
    std::string number = name.substr(7);
    if (!number.empty() && number.size() <= 3 &&
        number.find_first_not_of("0123456789") == std::string::npos) {
      int p = std::stoi(number);
      if (p >= 1 && p <= 300) return MachineConfig::g54_1_key(p);
    }
  }
  machine_error(where, ": unknown work offset \"", name,
                "\" (G54..G59 or \"G54.1 P1\"..\"G54.1 P300\")");
}

// A positive, finite number of `unit` (mm, mm/min).
double positive(const json& value, const std::string& where, const char* unit) {
  if (!in_range(value) || !(value.get<double>() > 0))
    machine_error(where, ": must be a positive number of ", unit, " up to ", kMaxValue, ", got ",
                  value.dump());
  return value.get<double>();
}
double rate(const json& value, const std::string& where) {
  return positive(value, where, "mm/min");
}

// "rapid_rate_mm_per_min": one rate for every linear axis, or [x, y, z].
void linear_rates(const json& value, const std::string& where, const std::string& file,
                  MachineRates& rates) {
  MachineRates r;
  if (value.is_array()) {
    if (value.size() != 3)
      machine_error(where, ": one rate, or [x, y, z] in mm/min, got ", value.dump());
    for (int a = 0; a < 3; ++a)
      r.rapid_mm_per_min[a] = rate(value[static_cast<std::size_t>(a)], where);
    r.rapid_per_axis = true;
  } else {
    r.rapid_mm_per_min = Vec3(rate(value, where));
  }
  rates.rapid_mm_per_min = r.rapid_mm_per_min;
  rates.rapid_per_axis = r.rapid_per_axis;
  rates.source = file;
}

// Rotary rapid rates, degrees per minute, indexed A, B, C (0 where not given): one number for
// every rotary axis, or {"A": …, "B": …, "C": …}.
std::array<double, 3> rotary_rates(const json& value, const std::string& where) {
  std::array<double, 3> rates{};
  if (value.is_object()) {
    for (const auto& [letter, r] : value.items()) {
      if (letter != "A" && letter != "B" && letter != "C")
        machine_error(where, ": \"", letter, "\" is not a rotary axis (A, B or C)");
      if (!in_range(r) || !(r.get<double>() > 0))
        machine_error(where, ": \"", letter,
                      "\" must be a positive number of degrees per minute, got ", r.dump());
      rates[static_cast<std::size_t>(letter[0] - 'A')] = r.get<double>();
    }
  } else if (in_range(value) && value.get<double>() > 0) {
    rates.fill(value.get<double>());
  } else {
    machine_error(
        where,
        ": one rate for every rotary axis, or {\"A\": …, \"C\": …}, in degrees per minute, got ",
        value.dump());
  }
  return rates;
}

// "variables": {"#650": 2000, "#<_name>": 1}: what the control holds when the program starts.
void read_variables(const json& value, const std::string& where, MachineConfig& m) {
  if (!value.is_object()) machine_error(where, ": must be an object such as {\"#650\": 2000}");
  std::set<long> seen;  // this file's keys, normalised (a base machine's may be overridden)
  std::set<std::string> named_seen;
  for (const auto& [name, number] : value.items()) {
    if (!in_range(number))
      machine_error(where, ": \"", name, "\": must be a number within ±", kMaxValue, ", got ",
                    number.dump());
    if (name.starts_with("#<")) {  // LinuxCNC's named global, case and spaces as it reads them
      std::string global;
      for (char c : name.substr(2, name.size() > 3 ? name.size() - 3 : 0))
        if (c != ' ' && c != '\t')
          global.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
      if (!name.ends_with(">") || global.size() < 2 || global[0] != '_')
        machine_error(where, ": \"", name, "\" is not a global named parameter (#<_name>)");
      // "#<_a>" and "#<_A>" are one parameter to the control: given twice, one would win silently.
      m.named_variables[global] = number.get<double>();
      if (!named_seen.insert(global).second)
        machine_error(where, ": \"", name, "\" names #<", global,
                      ">, as another key does (one variable given twice)");
      continue;
    }
    std::string digits = name.starts_with("#") ? name.substr(1) : name;
    const bool all_digits = !digits.empty() && digits.size() <= 9 &&
                            digits.find_first_not_of("0123456789") == std::string::npos;
    const long n = all_digits ? std::strtol(digits.c_str(), nullptr, 10) : -1;
    if (n < 1 || n > 999999)
      machine_error(where, ": \"", name,
                    "\" is not a variable number (#1 to #999999, digits only) or #<_name>");
    // "#5" and "#05" are one variable.
    m.variables[static_cast<int>(n)] = number.get<double>();
    if (!seen.insert(n).second)
      machine_error(where, ": \"", name, "\" names #", n,
                    ", as another key does (one variable given twice)");
  }
}

// "mm" or "inch": true for inch.
bool is_inch(const json& value, const std::string& where) {
  std::string u = string_value(value, where).get<std::string>();
  if (u != "mm" && u != "inch") machine_error(where, ": \"mm\" or \"inch\", got \"", u, "\"");
  return u == "inch";
}

int tool_number(const json& value, const std::string& where) {
  if (!value.is_number_integer() || value.get<long long>() < 0 ||
      value.get<long long>() > 1'000'000'000)
    machine_error(where, ": must be a tool number (0: none), got ", value.dump());
  return static_cast<int>(value.get<long long>());
}

// ---- the collision check's keys (issue 33): "components", "collision", "linear_axes" --------

double parts_distance(const json& value, const std::string& where) {
  if (!in_range(value) || value.get<double>() < 0)
    machine_error(where, ": must be a distance >= 0 in mm, got ", value.dump());
  return value.get<double>();
}

void read_components(const json& value, const std::string& where, const std::string& file,
                     MachineConfig& m) {
  if (!value.is_array())
    machine_error(where, ": must be a list of {\"name\", \"on\", \"mesh\"} objects");
  m.components.clear();
  for (std::size_t k = 0; k < value.size(); ++k) {
    const json& c = value[k];
    const std::string at = cat(where, "[", k, "]");
    if (!c.is_object()) machine_error(at, ": must be an object {\"name\", \"on\", \"mesh\"}");
    MachineComponent part;
    for (const auto& [key, v] : c.items()) {
      const std::string key_at = cat(at, ".", key);
      if (key == "name")
        part.name = string_value(v, key_at).get<std::string>();
      else if (key == "on")
        part.on = string_value(v, key_at).get<std::string>();
      else if (key == "mesh")
        part.mesh =
            (fs::path(file).parent_path() / string_value(v, key_at).get<std::string>()).string();
      else
        machine_error(key_at, ": unknown key (known: name, on, mesh)");
    }
    if (part.name.empty() || part.on.empty() || part.mesh.empty())
      machine_error(at, ": needs \"name\", \"on\" and \"mesh\", got ", c.dump());
    for (const MachineComponent& other : m.components)
      if (other.name == part.name) machine_error(at, ": a second component \"", part.name, "\"");
    m.components.push_back(std::move(part));
  }
}

void read_collision(const json& value, const std::string& where, MachineConfig& m) {
  if (!value.is_object())
    machine_error(where, ": must be an object {\"clearance\", \"near_miss\", \"ignore\"}");
  for (const auto& [key, v] : value.items()) {
    const std::string at = cat(where, ".", key);
    if (key == "clearance") {
      m.collision.clearance = parts_distance(v, at);
    } else if (key == "near_miss") {
      m.collision.near_miss = parts_distance(v, at);
    } else if (key == "ignore") {
      if (!v.is_array()) machine_error(at, ": must be a list of [name, name] pairs");
      m.collision.ignore.clear();
      for (const json& pair : v) {
        if (!pair.is_array() || pair.size() != 2 || !pair[0].is_string() || !pair[1].is_string())
          machine_error(at, ": each entry is a pair of component names, got ", pair.dump());
        m.collision.ignore.emplace_back(pair[0].get<std::string>(), pair[1].get<std::string>());
      }
    } else {
      machine_error(at, ": unknown key (known: clearance, near_miss, ignore)");
    }
  }
}

void read_linear_axes(const json& value, const std::string& where, MachineConfig& m) {
  if (!value.is_object())
    machine_error(where, ": must be an object such as {\"X\": \"head\", \"Y\": \"table\"}");
  for (const auto& [key, v] : value.items()) {
    const std::string at = cat(where, ".", key);
    if (key != "X" && key != "Y" && key != "Z") machine_error(at, ": the linear axes are X, Y, Z");
    const std::string side = string_value(v, at).get<std::string>();
    if (side != "head" && side != "table")
      machine_error(at, ": \"head\" or \"table\", got \"", side, "\"");
    m.linear_on_head[static_cast<std::size_t>(key[0] - 'X')] = side == "head";
  }
}

// Reads one of the collision check's keys; false for another key.
bool read_parts_key(const std::string& key, const json& value, const std::string& file,
                    MachineConfig& m) {
  const std::string where = cat(file, ": \"", key, "\"");
  if (key == "components")
    read_components(value, where, file, m);
  else if (key == "collision")
    read_collision(value, where, m);
  else if (key == "linear_axes")
    read_linear_axes(value, where, m);
  else
    return false;
  return true;
}

// After every key is read (the kinematics may come later in the file): each component's link
// exists, and each ignored pair names components.
void check_component_links(const std::string& file, const MachineConfig& m) {
  for (std::size_t k = 0; k < m.components.size(); ++k) {
    const MachineComponent& c = m.components[k];
    const std::string& on = c.on;
    const bool rotary =
        (on == "A" || on == "B" || on == "C") && m.kinematics && m.kinematics->find(on[0]);
    const bool linear = on == "X" || on == "Y" || on == "Z";
    if (on != "bed" && on != "spindle" && !rotary && !linear)
      machine_error(file, ": \"components\"[", k, "].on: \"", on,
                    "\" is no link of this machine (bed, spindle, X, Y, Z",
                    m.kinematics ? " or one of its rotary axes" : "", ")");
  }
  for (const auto& [a, b] : m.collision.ignore)
    for (const std::string& name : {a, b})
      if (std::none_of(m.components.begin(), m.components.end(),
                       [&](const MachineComponent& c) { return c.name == name; }))
        machine_error(file, ": \"collision\".ignore: no component \"", name, "\"");
}

// ---- LinuxCNC's switchable kinematics: "kinematics_switches", "kinematics_at_start" ----------
// (docs/src/motion/switchkins.adoc in LinuxCNC: the sample configs remap M428/M429/M430 to set
// motion.switchkins-type; docs/machine-files.md, "Kinematics switches").

KinematicsSwitch switch_kind(const json& value, const std::string& where) {
  const std::string kind = value.is_string() ? value.get<std::string>() : std::string();
  if (kind == "tcp") return KinematicsSwitch::tcp;
  if (kind == "identity") return KinematicsSwitch::identity;
  if (kind != "refuse")
    machine_error(where, ": \"tcp\", \"identity\" or \"refuse\", got ", value.dump());
  return KinematicsSwitch::refuse;
}

bool read_switch_key(const std::string& key, const json& value, const std::string& file,
                     MachineConfig& m) {
  const std::string where = cat(file, ": \"", key, "\"");
  if (key == "kinematics_at_start") {
    const KinematicsSwitch kind = switch_kind(value, where);
    if (kind == KinematicsSwitch::refuse)
      machine_error(where, ": \"tcp\" or \"identity\", got ", value.dump());
    m.tcp_kinematics_at_start = kind == KinematicsSwitch::tcp;
    return true;
  }
  if (key != "kinematics_switches") return false;
  if (!value.is_object())
    machine_error(where, ": must be an object such as {\"M428\": \"tcp\", \"M429\": \"identity\"}");
  m.kinematics_switches.clear();  // this file's list replaces a base machine's
  for (const auto& [name, kind] : value.items()) {
    const std::string at = cat(where, ": \"", name, "\"");
    const std::string digits = name.starts_with("M") || name.starts_with("m") ? name.substr(1) : "";
    if (digits.empty() || digits.size() > 4 ||
        digits.find_first_not_of("0123456789") != std::string::npos)
      machine_error(at, ": not an M-code (\"M428\")");
    const int code = std::stoi(digits);
    // The codes the interpreter acts on (M0-M9, M30, M61, M97-M99) keep their meaning.
    if (m_group(code) >= 0)
      machine_error(at, ": M", code, " already has a meaning; a switch needs a code of its own");
    if (!m.kinematics_switches.emplace(code, switch_kind(kind, at)).second)
      machine_error(at, ": M", code, " given twice");
  }
  return true;
}

void check_switches(const std::string& file, const MachineConfig& m) {
  if ((!m.kinematics_switches.empty() || m.tcp_kinematics_at_start) && !m.kinematics)
    machine_error(file,
                  ": \"kinematics_switches\" and \"kinematics_at_start\" need \"kinematics\"");
  for (const auto& [code, kind] : m.kinematics_switches)
    if (m.m_codes.count(code) || m.forbidden_m_codes.count(code))
      machine_error(file, ": M", code,
                    " is a kinematics switch and in \"m_codes\" or \"forbidden_m_codes\"");
}

constexpr const char* kMachineFileKeys =
    "name, description, base, dialect, units, start, tool_change, tool_loads_on_t, "
    "decimal_point_input, initial_tool, "
    "arc_radius_tolerance_mm, d_offsets, home, reference2, work_offsets, m_codes, "
    "forbidden_m_codes, kinematics_switches, kinematics_at_start, variables, far_distance, "
    "subprograms, kinematics, rapid_rate_mm_per_min, "
    "rapid_rate_deg_per_min, max_feed_mm_per_min, components, collision, linear_axes";

MachineConfig parse(const json& doc, const std::string& file) {
  if (!doc.is_object()) machine_error(file, ": a machine file is a JSON object");
  MachineConfig m;
  if (auto base = doc.find("base"); base != doc.end()) {
    std::string name = string_value(*base, cat(file, ": \"base\"")).get<std::string>();
    auto bundled = MachineConfig::bundled(name);
    if (!bundled)
      machine_error(file, ": \"base\": no bundled machine \"", name, "\" (",
                    bundled_machine_names(), ")");
    m = *bundled;
  }
  for (const auto& [key, value] : doc.items()) {
    std::string where = cat(file, ": \"", key, "\"");
    if (key == "name" || key == "description" || key == "base") {
      string_value(value, where);
    } else if (key == "dialect") {
      std::string d = string_value(value, where).get<std::string>();
      if (d == "fanuc")
        m.dialect = Dialect::fanuc;
      else if (d == "haas")
        m.dialect = Dialect::haas;
      else if (d == "linuxcnc")
        m.dialect = Dialect::linuxcnc;
      else
        machine_error(where, ": \"fanuc\", \"haas\" or \"linuxcnc\", got \"", d, "\"");
    } else if (key == "units") {
      m.inch_at_start = is_inch(value, where);
      m.units_stated = true;
    } else if (key == "linear_units") {  // LinuxCNC's [TRAJ]LINEAR_UNITS: a .tbl's units
      m.tool_table_in_inches = is_inch(value, where);
      m.linear_units_stated = true;
    } else if (key == "start") {
      if (value.is_string() && value.get<std::string>() == "far")
        m.start_position.reset();
      else
        m.start_position = point(value, where);
    } else if (key == "tool_change") {
      if (value.is_string() && value.get<std::string>() == "far") {
        m.tool_change = ToolChange::retract_far;
      } else if (value.is_string() && value.get<std::string>() == "in_place") {
        m.tool_change = ToolChange::in_place;
      } else if (value.is_array()) {
        m.tool_change = ToolChange::to_position;
        m.tool_change_position = point(value, where);
      } else {
        machine_error(where, ": \"far\", \"in_place\" or [x, y, z], got ", value.dump());
      }
    } else if (key == "tool_loads_on_t" || key == "decimal_point_input") {  // DPI: param. 3401
      if (!value.is_boolean()) machine_error(where, ": must be true or false, got ", value.dump());
      (key == "tool_loads_on_t" ? m.tool_loads_on_t : m.decimal_point_input.emplace()) =
          value.get<bool>();
    } else if (key == "initial_tool") {  // the tool in the spindle at start (CAMotics: 1)
      m.initial_tool = tool_number(value, where);
      m.initial_tool_stated = true;
    } else if (key == "arc_radius_tolerance_mm") {  // Fanuc's parameter 3410
      m.arc_radius_tolerance = positive(value, where, "mm");
    } else if (key == "d_offsets") {  // what the D registers hold (Haas: its setting 40)
      std::string d = string_value(value, where).get<std::string>();
      if (d != "radius" && d != "diameter")
        machine_error(where, ": \"radius\" or \"diameter\", got \"", d, "\"");
      m.d_offsets = d == "radius" ? DOffsets::radius : DOffsets::diameter;
    } else if (key == "g53") {
      std::string g = string_value(value, where).get<std::string>();
      if (g != "far" && g != "literal")
        machine_error(where, ": \"far\" or \"literal\", got \"", g, "\"");
      m.g53_literal = g == "literal";
    } else if (key == "home") {
      m.set_home(point(value, where));
    } else if (key == "reference2") {
      m.set_reference2(point(value, where));
    } else if (key == "work_offsets") {
      if (!value.is_object())
        machine_error(where, ": must be an object such as {\"G54\": [x, y, z]}");
      for (const auto& [name, offset] : value.items())
        m.work_offsets[work_offset_key(name, where)] =
            point(offset, cat(where, ": \"", name, "\""));
    } else if (key == "m_codes") {
      m.m_codes = m_code_list(value, where);
    } else if (key == "forbidden_m_codes") {
      m.forbidden_m_codes = m_code_list(value, where);
    } else if (key == "variables") {  // {"#650": 2000, "#1000": 0}: what the control holds
      read_variables(value, where, m);
    } else if (key == "kinematics") {
      try {
        m.kinematics = kinematics_from_json(value, cat(file, ": kinematics"));
      } catch (const MachineError&) {
        throw;
      } catch (const Error& e) {
        machine_error(e.what());
      }
    } else if (key == "far_distance") {
      m.far_distance = positive(value, where, "mm");
    } else if (key == "rapid_rate_mm_per_min") {
      linear_rates(value, where, file, m.rates);
    } else if (key == "rapid_rate_deg_per_min") {
      m.rates.rapid_deg_per_min = rotary_rates(value, where);
    } else if (key == "max_feed_mm_per_min") {
      m.rates.max_feed_mm_per_min = rate(value, where);
    } else if (key == "subprograms") {
      if (!value.is_array()) machine_error(where, ": must be a list of folders");
      fs::path base = fs::path(file).parent_path();
      for (const json& dir : value)
        m.subprogram_dirs.push_back((base / string_value(dir, where).get<std::string>()).string());
    } else if (!read_parts_key(key, value, file, m) && !read_switch_key(key, value, file, m)) {
      machine_error(where, ": unknown key (known: ", kMachineFileKeys, ")");
    }
  }
  for (int code : m.m_codes)
    if (m.forbidden_m_codes.count(code))
      machine_error(file, ": M", code, " is both in \"m_codes\" and in \"forbidden_m_codes\"");
  check_component_links(file, m);
  check_switches(file, m);
  return m;
}

}  // namespace

MachineConfig machine_from_json(const json& doc, const std::string& file) {
  // The reader of "kinematics" recurses into "profile" objects: a bound on the nesting keeps a
  // hostile file from exhausting the stack (the command's JSON reader refuses deeper files first).
  constexpr std::size_t kMaxDepth = 64;
  std::vector<std::pair<const json*, std::size_t>> pending{{&doc, 1}};
  while (!pending.empty()) {
    auto [value, depth] = pending.back();
    pending.pop_back();
    if (!value->is_structured()) continue;
    if (depth > kMaxDepth)
      machine_error(file, ": objects and arrays nested more than ", kMaxDepth, " deep");
    for (const json& child : *value) pending.emplace_back(&child, depth + 1);
  }
  try {
    return parse(doc, file);
  } catch (const json::exception& e) {
    machine_error(file, ": ", e.what());
  }
}

}  // namespace tridex::gcode
