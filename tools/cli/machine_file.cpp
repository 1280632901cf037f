#include "machine_file.hpp"

#include <array>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <sstream>

#include <nlohmann/json.hpp>

#include "errors.hpp"
#include "json_input.hpp"

namespace tridex::cli {

namespace {

namespace fs = std::filesystem;
using nlohmann::json;

// Concatenation through a stream (GCC 12 warns falsely on "literal" + std::string chains).
template <class... Parts>
std::string cat(const Parts&... parts) {
  std::ostringstream out;
  (out << ... << parts);
  return out.str();
}

Vec3 point(const json& value, const std::string& where) {
  if (!value.is_array() || value.size() != 3)
    input_error(where, ": must be [x, y, z] in mm, got ", value.dump());
  Vec3 p;
  for (int i = 0; i < 3; ++i) {
    const json& c = value[static_cast<std::size_t>(i)];
    if (!c.is_number() || !std::isfinite(c.get<double>()))
      input_error(where, ": must be [x, y, z] of finite numbers, got ", value.dump());
    p[i] = c.get<double>();
  }
  return p;
}

std::set<int> m_code_list(const json& value, const std::string& where) {
  if (!value.is_array()) input_error(where, ": must be a list of M-code numbers, got ", value.dump());
  std::set<int> codes;
  for (const json& c : value) {
    if (!c.is_number_integer() || c.get<long long>() < 0 || c.get<long long>() > 9999)
      input_error(where, ": M-code numbers are integers in [0, 9999], got ", c.dump());
    codes.insert(static_cast<int>(c.get<long long>()));
  }
  return codes;
}

const json& string_value(const json& value, const std::string& where) {
  if (!value.is_string()) input_error(where, ": must be a string, got ", value.dump());
  return value;
}

// "G54".."G59" -> 1..6; "G54.1 P<n>" -> 100 + n.
int work_offset_key(const std::string& name, const std::string& where) {
  for (int n = 1; n <= 6; ++n)
    if (name == cat("G", 53 + n)) return gcode::MachineConfig::g54_key(n);
  if (name.rfind("G54.1 P", 0) == 0) {
    std::string number = name.substr(7);
    if (!number.empty() && number.size() <= 3 &&
        number.find_first_not_of("0123456789") == std::string::npos) {
      int p = std::stoi(number);
      if (p >= 1 && p <= 300) return gcode::MachineConfig::g54_1_key(p);
    }
  }
  input_error(where, ": unknown work offset \"", name, "\" (G54..G59 or \"G54.1 P1\"..\"G54.1 P300\")");
}

// A positive, finite number of `unit` (mm, mm/min).
double positive(const json& value, const std::string& where, const char* unit) {
  if (!value.is_number() || !(value.get<double>() > 0) || !std::isfinite(value.get<double>()))
    input_error(where, ": must be a positive number of ", unit, ", got ", value.dump());
  return value.get<double>();
}
double rate(const json& value, const std::string& where) { return positive(value, where, "mm/min"); }

// Rotary rapid rates, degrees per minute, indexed A, B, C (0 where not given): one number for
// every rotary axis, or {"A": …, "B": …, "C": …}.
std::array<double, 3> rotary_rates(const json& value, const std::string& where) {
  std::array<double, 3> rates{};
  if (value.is_object()) {
    for (const auto& [letter, r] : value.items()) {
      if (letter != "A" && letter != "B" && letter != "C")
        input_error(where, ": \"", letter, "\" is not a rotary axis (A, B or C)");
      if (!r.is_number() || !(r.get<double>() > 0) || !std::isfinite(r.get<double>()))
        input_error(where, ": \"", letter, "\" must be a positive number of degrees per minute, got ", r.dump());
      rates[static_cast<std::size_t>(letter[0] - 'A')] = r.get<double>();
    }
  } else if (value.is_number() && value.get<double>() > 0 && std::isfinite(value.get<double>())) {
    rates.fill(value.get<double>());
  } else {
    input_error(where, ": one rate for every rotary axis, or {\"A\": …, \"C\": …}, in degrees per minute, got ",
                value.dump());
  }
  return rates;
}

// A bundled machine: MachineConfig's own ("default", "haas", "linuxcnc"), or a bundled kinematics
// profile by name (the default machine with that profile's rotary axes), so that
// `--machine bc-trunnion` reads rotary words as `{"kinematics": "bc-trunnion"}` does.
std::optional<gcode::MachineConfig> bundled_machine(const std::string& name) {
  if (auto machine = gcode::MachineConfig::bundled(name)) return machine;
  auto profile = gcode::kinematics_profile(name);
  if (!profile) return std::nullopt;
  gcode::MachineConfig machine = *gcode::MachineConfig::bundled("default");
  machine.kinematics = std::move(profile);
  return machine;
}

gcode::MachineConfig parse(const json& doc, const std::string& file, MachineRates* rates) {
  if (!doc.is_object()) input_error(file, ": a machine file is a JSON object");
  gcode::MachineConfig m;
  if (auto base = doc.find("base"); base != doc.end()) {
    std::string name = string_value(*base, cat(file, ": \"base\"")).get<std::string>();
    auto bundled = bundled_machine(name);
    if (!bundled) input_error(file, ": \"base\": no bundled machine \"", name, "\" (", kBundledMachines, ")");
    m = *bundled;
  }
  for (const auto& [key, value] : doc.items()) {
    std::string where = cat(file, ": \"", key, "\"");
    if (key == "name" || key == "description" || key == "base") {
      string_value(value, where);
    } else if (key == "dialect") {
      std::string d = string_value(value, where).get<std::string>();
      if (d == "fanuc") m.dialect = gcode::Dialect::fanuc;
      else if (d == "haas") m.dialect = gcode::Dialect::haas;
      else if (d == "linuxcnc") m.dialect = gcode::Dialect::linuxcnc;
      else input_error(where, ": \"fanuc\", \"haas\" or \"linuxcnc\", got \"", d, "\"");
    } else if (key == "units") {
      std::string u = string_value(value, where).get<std::string>();
      if (u != "mm" && u != "inch") input_error(where, ": \"mm\" or \"inch\", got \"", u, "\"");
      m.inch_at_start = u == "inch";
    } else if (key == "linear_units") {  // LinuxCNC's [TRAJ]LINEAR_UNITS: a .tbl's units
      std::string u = string_value(value, where).get<std::string>();
      if (u != "mm" && u != "inch") input_error(where, ": \"mm\" or \"inch\", got \"", u, "\"");
      m.tool_table_in_inches = u == "inch";
    } else if (key == "start") {
      if (value.is_string() && value.get<std::string>() == "far")
        m.start_position.reset();
      else
        m.start_position = point(value, where);
    } else if (key == "tool_change") {
      if (value.is_string() && value.get<std::string>() == "far") {
        m.tool_change = gcode::ToolChange::retract_far;
      } else if (value.is_string() && value.get<std::string>() == "in_place") {
        m.tool_change = gcode::ToolChange::in_place;
      } else if (value.is_array()) {
        m.tool_change = gcode::ToolChange::to_position;
        m.tool_change_position = point(value, where);
      } else {
        input_error(where, ": \"far\", \"in_place\" or [x, y, z], got ", value.dump());
      }
    } else if (key == "tool_loads_on_t") {
      if (!value.is_boolean()) input_error(where, ": must be true or false, got ", value.dump());
      m.tool_loads_on_t = value.get<bool>();
    } else if (key == "arc_radius_tolerance_mm") {  // Fanuc's parameter 3410
      m.arc_radius_tolerance = positive(value, where, "mm");
    } else if (key == "d_offsets") {  // what the D registers hold (Haas: its setting 40)
      std::string d = string_value(value, where).get<std::string>();
      if (d != "radius" && d != "diameter") input_error(where, ": \"radius\" or \"diameter\", got \"", d, "\"");
      m.d_offsets = d == "radius" ? gcode::DOffsets::radius : gcode::DOffsets::diameter;
    } else if (key == "g53") {
      std::string g = string_value(value, where).get<std::string>();
      if (g != "far" && g != "literal") input_error(where, ": \"far\" or \"literal\", got \"", g, "\"");
      m.g53_literal = g == "literal";
    } else if (key == "home") {
      m.set_home(point(value, where));
    } else if (key == "reference2") {
      m.set_reference2(point(value, where));
    } else if (key == "work_offsets") {
      if (!value.is_object()) input_error(where, ": must be an object such as {\"G54\": [x, y, z]}");
      for (const auto& [name, offset] : value.items())
        m.work_offsets[work_offset_key(name, where)] = point(offset, cat(where, ": \"", name, "\""));
    } else if (key == "m_codes") {
      m.m_codes = m_code_list(value, where);
    } else if (key == "forbidden_m_codes") {
      m.forbidden_m_codes = m_code_list(value, where);
    } else if (key == "variables") {  // {"#650": 2000, "#1000": 0}: what the control holds
      if (!value.is_object()) input_error(where, ": must be an object such as {\"#650\": 2000}");
      for (const auto& [name, number] : value.items()) {
        if (!number.is_number() || !std::isfinite(number.get<double>()))
          input_error(where, ": \"", name, "\": must be a number, got ", number.dump());
        if (name.starts_with("#<")) {  // LinuxCNC's named global, case and spaces as it reads them
          std::string global;
          for (char c : name.substr(2, name.size() > 3 ? name.size() - 3 : 0))
            if (c != ' ' && c != '\t') global.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(c))));
          if (!name.ends_with(">") || global.size() < 2 || global[0] != '_')
            input_error(where, ": \"", name, "\" is not a global named parameter (#<_name>)");
          m.named_variables[global] = number.get<double>();
          continue;
        }
        std::string digits = name.starts_with("#") ? name.substr(1) : name;
        char* end = nullptr;
        const long n = digits.empty() ? -1 : std::strtol(digits.c_str(), &end, 10);
        if (n < 1 || n > 999999 || *end != '\0')
          input_error(where, ": \"", name, "\" is not a variable number (#1 to #999999) or #<_name>");
        m.variables[static_cast<int>(n)] = number.get<double>();
      }
    } else if (key == "kinematics") {
      try {
        m.kinematics = gcode::kinematics_from_json(value, cat(file, ": kinematics"));
      } catch (const InputError&) {
        throw;
      } catch (const Error& e) {
        input_error(e.what());
      }
    } else if (key == "far_distance") {
      m.far_distance = positive(value, where, "mm");
    } else if (key == "rapid_rate_mm_per_min") {
      MachineRates r;
      if (value.is_array()) {
        if (value.size() != 3) input_error(where, ": one rate, or [x, y, z] in mm/min, got ", value.dump());
        for (int a = 0; a < 3; ++a) r.rapid_mm_per_min[a] = rate(value[static_cast<std::size_t>(a)], where);
        r.rapid_per_axis = true;
      } else {
        r.rapid_mm_per_min = Vec3(rate(value, where));
      }
      if (rates) {
        rates->rapid_mm_per_min = r.rapid_mm_per_min;
        rates->rapid_per_axis = r.rapid_per_axis;
        rates->source = file;
      }
    } else if (key == "rapid_rate_deg_per_min") {
      std::array<double, 3> turn = rotary_rates(value, where);
      if (rates) rates->rapid_deg_per_min = turn;
    } else if (key == "max_feed_mm_per_min") {
      double max_feed = rate(value, where);
      if (rates) rates->max_feed_mm_per_min = max_feed;
    } else if (key == "subprograms") {
      if (!value.is_array()) input_error(where, ": must be a list of folders");
      fs::path base = fs::path(file).parent_path();
      for (const json& dir : value)
        m.subprogram_dirs.push_back((base / string_value(dir, where).get<std::string>()).string());
    } else {
      input_error(where, ": unknown key (known: name, description, base, dialect, units, start, "
                         "tool_change, tool_loads_on_t, arc_radius_tolerance_mm, d_offsets, home, reference2, work_offsets, m_codes, "
                         "forbidden_m_codes, variables, far_distance, subprograms, kinematics, "
                         "rapid_rate_mm_per_min, rapid_rate_deg_per_min, max_feed_mm_per_min)");
    }
  }
  for (int code : m.m_codes)
    if (m.forbidden_m_codes.count(code))
      input_error(file, ": M", code, " is both in \"m_codes\" and in \"forbidden_m_codes\"");
  return m;
}

}  // namespace

gcode::MachineConfig machine_from_json(const json& doc, const std::string& file, MachineRates* rates) {
  try {
    return parse(doc, file, rates);
  } catch (const json::exception& e) {
    input_error(file, ": ", e.what());
  }
}

gcode::MachineConfig load_machine(const std::string& name_or_file,
                                  const std::vector<std::string>& subprogram_dirs, MachineRates* rates) {
  gcode::MachineConfig machine;
  if (name_or_file.empty()) {
    machine = *gcode::MachineConfig::bundled("default");
  } else if (auto bundled = bundled_machine(name_or_file)) {
    machine = *bundled;
  } else {
    std::error_code error;
    if (!fs::is_regular_file(name_or_file, error))
      input_error("--machine ", name_or_file, ": neither a bundled machine (", kBundledMachines,
                  ") nor a machine file");
    machine = machine_from_json(read_json_file(name_or_file), name_or_file, rates);
  }
  for (const std::string& dir : subprogram_dirs) {
    std::error_code error;
    if (!fs::is_directory(dir, error)) input_error("--subprograms ", dir, ": not a folder");
    machine.subprogram_dirs.insert(machine.subprogram_dirs.begin(), dir);
  }
  return machine;
}

}  // namespace tridex::cli
