// tridex::gcode — the bundled machines: one registry of names and how each is built, from which
// MachineConfig::bundled, the list of names (the command's --help and messages) and the
// "kinematics" key's profiles all come; and that key of the machine file, a profile's name or an
// object in the profiles' terms (machine.hpp). The rest of the machine file: machine_file.cpp.
#include "tridex/gcode/machine.hpp"

#include <algorithm>
#include <array>
#include <cctype>
#include <cmath>
#include <initializer_list>
#include <memory>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "tridex/collide.hpp"
#include <utility>

namespace tridex::gcode {
namespace {

using Limits = std::optional<std::array<double, 2>>;

RotaryAxis make_axis(char letter, bool on_head, Vec3 direction, Vec3 pivot,
                     std::optional<std::array<double, 2>> limits) {
  RotaryAxis axis;
  axis.letter = letter;
  axis.on_head = on_head;
  axis.direction = direction;
  axis.pivot = pivot;
  axis.limits = limits;
  return axis;
}

// The default machine with rotary axes: a bundled kinematics profile is a machine too, so that
// `--machine bc-trunnion` reads rotary words as `{"kinematics": "bc-trunnion"}` does.
MachineConfig rotary_machine(MachineType type, std::vector<RotaryAxis> axes) {
  Kinematics kin;
  kin.type = type;
  kin.axes = std::move(axes);
  MachineConfig machine;
  machine.kinematics = std::move(kin);
  return machine;
}

// The far rule of docs/design.md.
MachineConfig default_machine() { return MachineConfig{}; }

// The default machine, reading Haas's tool offset registers.
MachineConfig haas_machine() {
  MachineConfig m;
  m.dialect = Dialect::haas;
  return m;
}

// rs274 run standalone (its default configuration): start at the origin, M6 in place, G28/G30
// at the origin, G53 literal, G99, LinuxCNC's dialect. The differential tests compare with it
// (tests/gcode/test_linuxcnc_diff.cpp).
MachineConfig rs274_machine() {
  MachineConfig m;
  m.dialect = Dialect::linuxcnc;
  m.start_position = Vec3(0.0);
  m.tool_change = ToolChange::in_place;
  m.set_home(Vec3(0.0));
  m.set_reference2(Vec3(0.0));
  m.g53_literal = true;
  m.g99_at_start = true;
  return m;
}

// LinuxCNC as a user runs it: LinuxCNC's dialect and G99 at start as rs274, but the machine is
// homed, Z at the top of its travel (the LinuxCNC User Manual, "Homing": HOME usually 0 at the
// top of Z), far above a work offset touched off on the part, so the tip starts far along +Z;
// M6 lifts the quill to Z's home first (the [EMCIO] TOOL_CHANGE_QUILL_UP or
// TOOL_CHANGE_POSITION of the sample configurations), and G28/G30 and G53 go to machine
// positions above the work whose place tridex cannot know: far along the tool, as the default
// machine's. Tool length offsets are applied from G43 on, as in LinuxCNC.
MachineConfig linuxcnc_machine() {
  MachineConfig m;
  m.dialect = Dialect::linuxcnc;
  m.g99_at_start = true;
  return m;
}

// The kinematics profiles. Machine coordinates are tool-tip coordinates with every rotary at 0;
// the pivots put the table-face centre (or the tip, for head axes) at the origin, as a machine
// file written against a machine's own zero would after subtracting it.

// ---- the profiles' parts (issue 33) -------------------------------------------------------------
// Boxes and cylinders of a plausible size (a 200-400 mm table, a 90 mm spindle nose), placed as
// the machine stands with every axis at zero, so that a profile checks its table and head without
// the builder's CAD; a machine file's "components" (docs/machine-files.md) replaces them. The
// table face is z = 0, the bed well below what the table's turns sweep.

MachineComponent built_part(std::string name, std::string on, Mesh mesh) {
  MachineComponent c;
  c.name = std::move(name), c.on = std::move(on);
  c.built = std::make_shared<const Mesh>(std::move(mesh));
  return c;
}

MachineConfig with_parts(MachineConfig m, std::vector<MachineComponent> parts) {
  parts.push_back(built_part("spindle nose", "spindle", make_frustum_mesh(45, 45, 0, 150)));
  m.components = std::move(parts);
  return m;
}

// A trunnion's cradle as a UMC-style table stands (tilt axis along X, axis 0, or Y, axis 1, at
// height `pivot`): the C drive's housing under the platter, no wider than it (so that a head that
// clears the platter at a high tilt clears the housing); a floor plate under it; the side plates
// at the tilt axis's ends, 180-210 mm out, well clear of the 200 mm platter and of what stands on
// it, rising to the bearings 30 mm above the tilt axis (still below the table face).
Mesh trunnion_cradle(int along, double pivot) {
  auto box = [&](Vec3 lo, Vec3 hi) {  // given with the tilt axis along X
    if (along == 1) std::swap(lo.x, lo.y), std::swap(hi.x, hi.y);
    return make_box_mesh(lo, hi);
  };
  const double bottom = pivot - 60;
  return merge_meshes({make_frustum_mesh(100, 100, bottom, -30),
                       box({-210, -90, bottom}, {210, 90, bottom + 25}),
                       box({-210, -110, bottom}, {-180, 110, pivot + 30}),
                       box({180, -110, bottom}, {210, 110, pivot + 30})});
}

// LinuxCNC's switchable kinematics in its sample configurations (docs/src/motion/switchkins.adoc
// in LinuxCNC; configs/sim/axis/vismach/5axis): REMAP M428 selects the TCP kinematics
// (xyzac-trt-kins, xyzbc-trt-kins, xyzab_tdr_kins), M429 identity kinematics (the start, with
// sparm=identityfirst), M430 a user's own ("userk", type 2), which tridex cannot know: refused.
MachineConfig with_linuxcnc_switches(MachineConfig m, bool userk) {
  m.kinematics_switches = {{428, KinematicsSwitch::tcp}, {429, KinematicsSwitch::identity}};
  if (userk) m.kinematics_switches[430] = KinematicsSwitch::refuse;
  return m;
}

// Table-table: A tilts the trunnion about X through (0, 0, −75) (the C face 75 mm above the tilt
// axis), −120°…120°; C turns the platter on it about Z through the origin, endless. LinuxCNC's
// xyzac-trt kinematics with its default directions (part_to_machine = Rx(A)·Rz(C) about the
// pivots; trtfuncs.c with conventional-directions 0), and its M428/M429/M430 switches. Its sample
// configuration's pivots differ (docs/machine-files.md, "Kinematics switches").
MachineConfig ac_trunnion() {
  return with_linuxcnc_switches(
      with_parts(rotary_machine(MachineType::table_table,
                                {make_axis('A', false, {1, 0, 0}, {0, 0, -75},
                                           std::array<double, 2>{-120, 120}),
                                 make_axis('C', false, {0, 0, 1}, {0, 0, 0}, Limits{})}),
                 {built_part("platter", "C", make_frustum_mesh(100, 100, -30, 0)),
                  built_part("trunnion", "A", trunnion_cradle(0, -75)),
                  built_part("bed", "bed", make_box_mesh({-600, -400, -500}, {600, 400, -420}))}),
      true);
}

// Table-table, Haas UMC-style: B tilts about Y through (0, 0, −50), −35°…110° (a UMC-750's
// published tilt range); C turns about Z through the origin, endless. The directions of
// LinuxCNC's xyzbc-trt kinematics, and its M428/M429/M430 switches.
MachineConfig bc_trunnion() {
  return with_linuxcnc_switches(
      with_parts(rotary_machine(MachineType::table_table,
                                {make_axis('B', false, {0, 1, 0}, {0, 0, -50},
                                           std::array<double, 2>{-35, 110}),
                                 make_axis('C', false, {0, 0, 1}, {0, 0, 0}, Limits{})}),
                 {built_part("platter", "C", make_frustum_mesh(100, 100, -30, 0)),
                  built_part("trunnion", "B", trunnion_cradle(1, -50)),
                  built_part("bed", "bed", make_box_mesh({-600, -400, -500}, {600, 400, -420}))}),
      true);
}

// ---- LinuxCNC's 5-axis sample configurations (configs/sim/axis/vismach/5axis) -----------------
// Each as its INI sets it up: LinuxCNC's dialect, tool tables in mm ([TRAJ]LINEAR_UNITS), the
// rotary limits of its [AXIS_*] sections, the pivots its HALCMD lines give the kinematics
// component, those HAL pins' values (for #<_hal[...]>), and its REMAP M-codes. Pivots are in
// tip coordinates: the kinematics add the tool offset (motion.tooloffset.z) to the z offset,
// which the tool length offset cancels. G53 goes where it says (every joint's HOME is 0). No
// parts, no travel (its limits are joint positions).
MachineConfig linuxcnc_sample(std::vector<RotaryAxis> axes, bool userk, const std::string& pins,
                              std::initializer_list<std::pair<const char*, double>> values) {
  MachineConfig m = with_linuxcnc_switches(linuxcnc_machine(), userk);
  m.kinematics = rotary_machine(MachineType::table_table, std::move(axes)).kinematics;
  m.tool_table_in_inches = false;
  m.linear_units_stated = true;
  m.g53_literal = true;
  for (const auto& [name, value] : values)
    m.named_variables["_hal[" + pins + "." + name + "]"] = value;
  return m;
}

// xyzac-trt.ini: xyzac-trt-kins (trtfuncs.c, conventional-directions 0: part_to_machine =
// Rx(A)·Rz(C)) with y-offset 20, z-offset 10 and the rotation point at the origin: A about X
// through (0, 20, 10), −100°…50°, carrying C about Z through the origin, ±36000°.
MachineConfig xyzac_trt() {
  return linuxcnc_sample({make_axis('A', false, {1, 0, 0}, {0, 20, 10}, Limits{{-100, 50}}),
                          make_axis('C', false, {0, 0, 1}, {0, 0, 0}, Limits{{-36000, 36000}})},
                         true, "xyzac-trt-kins",
                         {{"x-rot-point", 0},
                          {"y-rot-point", 0},
                          {"z-rot-point", 0},
                          {"y-offset", 20},
                          {"z-offset", 10}});
}

// xyzbc-trt.ini: xyzbc-trt-kins (part_to_machine = Ry(B)·Rz(C)) with x-offset −20, z-offset −15:
// B about Y through (−20, 0, −15), ±36000°, carrying C about Z through the origin, ±36000°.
MachineConfig xyzbc_trt() {
  return linuxcnc_sample({make_axis('B', false, {0, 1, 0}, {-20, 0, -15}, Limits{{-36000, 36000}}),
                          make_axis('C', false, {0, 0, 1}, {0, 0, 0}, Limits{{-36000, 36000}})},
                         true, "xyzbc-trt-kins",
                         {{"x-rot-point", 0},
                          {"y-rot-point", 0},
                          {"z-rot-point", 0},
                          {"x-offset", -20},
                          {"z-offset", -15}});
}

// xyzab-tdr.ini (table-dual-rotary): xyzab_tdr_kins.comp, whose inverse is joints =
// Ry(−B)·Rx(−A) about the pivots (the conventional directions): B about Y through the origin,
// −180°…180°, carrying A about X through (−20, 0, −10) (x-offset −20, z-offset −10), ±3600°. Its
// demo reads the pins; M428 selects the TCP kinematics, M429 identity (the start); no M430.
MachineConfig xyzab_tdr() {
  return linuxcnc_sample({make_axis('B', false, {0, -1, 0}, {0, 0, 0}, Limits{{-180, 180}}),
                          make_axis('A', false, {-1, 0, 0}, {-20, 0, -10}, Limits{{-3600, 3600}})},
                         false, "xyzab_tdr_kins",
                         {{"x-rot-point", 0},
                          {"y-rot-point", 0},
                          {"z-rot-point", 0},
                          {"x-offset", -20},
                          {"z-offset", -10}});
}

// Head-table: B turns the head about Y through (0, 0, 150) (pivot 150 mm above the tip),
// −110°…110°; C turns the table about Z through the origin, endless.
MachineConfig b_head_c_table() {
  return with_parts(
      rotary_machine(
          MachineType::head_table,
          {make_axis('B', true, {0, 1, 0}, {0, 0, 150}, std::array<double, 2>{-110, 110}),
           make_axis('C', false, {0, 0, 1}, {0, 0, 0}, Limits{})}),
      {built_part("head", "B", make_box_mesh({-80, -80, 200}, {80, 80, 450})),
       built_part("table", "C", make_frustum_mesh(200, 200, -40, 0)),
       built_part("bed", "bed", make_box_mesh({-600, -400, -500}, {600, 400, -420}))});
}

// Head-head: C turns the head about Z through the spindle line, −360°…360°; A, carried by C,
// tilts the spindle about X through (0, 0, 150), −100°…100°.
MachineConfig head_head() {
  return with_parts(
      rotary_machine(
          MachineType::head_head,
          {make_axis('C', true, {0, 0, 1}, {0, 0, 0}, std::array<double, 2>{-360, 360}),
           make_axis('A', true, {1, 0, 0}, {0, 0, 150}, std::array<double, 2>{-100, 100})}),
      {built_part("fork", "C", make_box_mesh({-150, -60, 330}, {150, 60, 450})),
       built_part("head", "A", make_box_mesh({-70, -70, 200}, {70, 70, 250})),
       built_part("table", "bed", make_box_mesh({-500, -300, -60}, {500, 300, 0}))});
}

// Horizontal machining centre: the spindle along machine Z (horizontal, Y vertical, as on any
// HMC), a B table (the pallet's rotary) turning about Y through the origin, endless (indexing and
// full rotary tables turn past 360°), Fanuc's dialect. Its pallet changer (M60 change, M71 a
// pallet code an HMC's programs write) and B table clamp (M10 clamp, M11 unclamp) move no axis
// tridex simulates: declared, so that they pass without a warning.
MachineConfig hmc_b_table() {
  MachineConfig m = rotary_machine(MachineType::table_table,
                                   {make_axis('B', false, {0, 1, 0}, {0, 0, 0}, Limits{})});
  m.m_codes = {10, 11, 60, 71};
  return m;
}

// The registry, in the order the names are listed.
struct BundledMachine {
  std::string_view name;
  MachineConfig (*build)();
};
constexpr std::array<BundledMachine, 12> kBundled{{
    {"default", default_machine},
    {"haas", haas_machine},
    {"linuxcnc", linuxcnc_machine},
    {"rs274", rs274_machine},
    {"ac-trunnion", ac_trunnion},
    {"bc-trunnion", bc_trunnion},
    {"b-head-c-table", b_head_c_table},
    {"head-head", head_head},
    {"hmc-b-table", hmc_b_table},
    {"xyzac-trt", xyzac_trt},
    {"xyzbc-trt", xyzbc_trt},
    {"xyzab-tdr", xyzab_tdr},
}};

// ---- the machine file's "kinematics" key -------------------------------------------------

[[noreturn]] void json_fail(const std::string& path, const std::string& what,
                            const nlohmann::json& value) {
  detail::fail(path, ": ", what, ", got ", value.dump());
}

double json_number(const nlohmann::json& j, const std::string& path) {
  if (!j.is_number()) json_fail(path, "must be a number", j);
  double v = j.get<double>();
  // Within ±1e9 (mm, degrees): far past any machine, and far from overflow once squared.
  if (!(std::abs(v) <= 1e9)) json_fail(path, "must be a finite number within ±1e9", j);
  return v;
}

Vec3 json_vec3(const nlohmann::json& j, const std::string& path) {
  if (!j.is_array() || j.size() != 3) json_fail(path, "must be an array of 3 numbers", j);
  Vec3 v;
  for (int i = 0; i < 3; ++i)
    v[i] = json_number(j[std::size_t(i)], path + "[" + std::to_string(i) + "]");
  return v;
}

const nlohmann::json& json_key(const nlohmann::json& object, const char* key,
                               const std::string& path) {
  auto it = object.find(key);
  if (it == object.end()) detail::fail(path, ": the key \"", key, "\" is missing");
  return *it;
}

void json_known_keys(const nlohmann::json& object, std::initializer_list<const char*> keys,
                     const std::string& path) {
  for (auto it = object.begin(); it != object.end(); ++it)
    if (std::none_of(keys.begin(), keys.end(), [&](const char* k) { return it.key() == k; }))
      detail::fail(
          path, ".", it.key(), ": unknown key (known: ",
          [&] {
            std::string list;
            for (const char* k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
            return list;
          }(),
          ")");
}

// "travel": {"X": [min, max], ...}, each letter optional.
std::array<std::optional<std::array<double, 2>>, 3> travel_from_json(const nlohmann::json& j,
                                                                     const std::string& path) {
  if (!j.is_object()) json_fail(path, "must be an object such as {\"X\": [-300, 300]}", j);
  json_known_keys(j, {"X", "Y", "Z"}, path);
  std::array<std::optional<std::array<double, 2>>, 3> travel;
  for (int i = 0; i < 3; ++i) {
    std::string letter(1, char('X' + i));
    if (!j.contains(letter)) continue;
    const nlohmann::json& range = j[letter];
    std::string at = path + "." + letter;
    if (!range.is_array() || range.size() != 2) json_fail(at, "must be [min, max] in mm", range);
    double lo = json_number(range[0], at + "[0]"), hi = json_number(range[1], at + "[1]");
    if (!(lo < hi)) json_fail(at, "min must be less than max", range);
    travel[std::size_t(i)] = std::array<double, 2>{lo, hi};
  }
  return travel;
}

RotaryAxis axis_from_json(const nlohmann::json& j, const std::string& path) {
  if (!j.is_object()) json_fail(path, "must be an object", j);
  json_known_keys(j, {"letter", "on", "direction", "sense", "pivot", "limits"}, path);
  RotaryAxis axis;
  const nlohmann::json& letter = json_key(j, "letter", path);
  if (!letter.is_string() || letter.get<std::string>().size() != 1 ||
      rotary_index(letter.get<std::string>()[0]) < 0)
    json_fail(path + ".letter", "must be \"A\", \"B\" or \"C\"", letter);
  axis.letter = char(std::toupper(static_cast<unsigned char>(letter.get<std::string>()[0])));
  const nlohmann::json& on = json_key(j, "on", path);
  if (on != "table" && on != "head") json_fail(path + ".on", "must be \"table\" or \"head\"", on);
  axis.on_head = on == "head";
  Vec3 direction = json_vec3(json_key(j, "direction", path), path + ".direction");
  if (!(glm::length(direction) > 1e-12))
    json_fail(path + ".direction", "must not be the zero vector", j["direction"]);
  double sense = 1;
  if (j.contains("sense")) {
    sense = json_number(j["sense"], path + ".sense");
    if (sense != 1 && sense != -1) json_fail(path + ".sense", "must be 1 or -1", j["sense"]);
  }
  axis.direction = sense * glm::normalize(direction);
  axis.pivot = json_vec3(json_key(j, "pivot", path), path + ".pivot");
  if (j.contains("limits")) {
    const nlohmann::json& limits = j["limits"];
    if (!limits.is_array() || limits.size() != 2)
      json_fail(path + ".limits", "must be [min, max] in degrees", limits);
    double lo = json_number(limits[0], path + ".limits[0]");
    double hi = json_number(limits[1], path + ".limits[1]");
    if (!(lo < hi)) json_fail(path + ".limits", "min must be less than max", limits);
    axis.limits = std::array<double, 2>{lo, hi};
  }
  return axis;
}

}  // namespace

std::optional<MachineConfig> MachineConfig::bundled(std::string_view name) {
  for (const BundledMachine& machine : kBundled)
    if (machine.name == name) return machine.build();
  return std::nullopt;
}

std::string bundled_machine_names() {
  std::string names;
  for (const BundledMachine& machine : kBundled)
    names += (names.empty() ? "" : ", ") + std::string(machine.name);
  return names;
}

std::optional<Kinematics> kinematics_profile(std::string_view name) {
  std::optional<MachineConfig> machine = MachineConfig::bundled(name);
  if (!machine) return std::nullopt;
  return std::move(machine->kinematics);
}

std::vector<std::string> kinematics_profile_names() {
  std::vector<std::string> names;
  for (const BundledMachine& machine : kBundled)
    if (machine.build().kinematics) names.emplace_back(machine.name);
  return names;
}

Kinematics kinematics_from_json(const nlohmann::json& value, const std::string& path) {
  if (value.is_string()) {
    std::optional<Kinematics> profile = kinematics_profile(value.get<std::string>());
    if (!profile) {
      std::string names;
      for (const std::string& n : kinematics_profile_names())
        names += (names.empty() ? "" : ", ") + n;
      json_fail(path, "is not a bundled profile (" + names + ")", value);
    }
    return *profile;
  }
  if (!value.is_object()) json_fail(path, "must be a profile name or an object", value);
  if (value.contains("profile")) {  // a bundled profile with the machine's own travel
    json_known_keys(value, {"profile", "travel"}, path);
    Kinematics kin = kinematics_from_json(value["profile"], path + ".profile");
    if (value.contains("travel")) kin.travel = travel_from_json(value["travel"], path + ".travel");
    return kin;
  }
  json_known_keys(value, {"type", "axes", "travel"}, path);
  Kinematics kin;
  if (value.contains("travel")) kin.travel = travel_from_json(value["travel"], path + ".travel");
  const nlohmann::json& type = json_key(value, "type", path);
  if (type == "table-table")
    kin.type = MachineType::table_table;
  else if (type == "head-table")
    kin.type = MachineType::head_table;
  else if (type == "head-head")
    kin.type = MachineType::head_head;
  else
    json_fail(path + ".type", "must be \"table-table\", \"head-table\" or \"head-head\"", type);
  const nlohmann::json& axes = json_key(value, "axes", path);
  if (!axes.is_array() || axes.empty() || axes.size() > 2)
    json_fail(path + ".axes", "must be an array of one or two axes", axes);
  for (std::size_t i = 0; i < axes.size(); ++i)
    kin.axes.push_back(axis_from_json(axes[i], path + ".axes[" + std::to_string(i) + "]"));
  try {
    kin.validate();
  } catch (const Error& e) {
    // validate() speaks of "kinematics"; name the machine file's path and the axes instead.
    std::string message = e.what();
    if (message.rfind("kinematics: ", 0) == 0) message = message.substr(12);
    detail::fail(path, ": ", message, " (", value.dump(), ")");
  }
  return kin;
}

}  // namespace tridex::gcode
