// tridex::gcode — the machine, in one module: the model (MachineConfig: what the interpreter needs
// to know of the machine, its rotary kinematics, kinematics.hpp, and its speeds, MachineRates),
// the bundled machines (one registry, machine.cpp: their names and how each is built; the
// command's --help list, its messages and the "kinematics" key's profiles all come from it) and
// the machine file that describes a machine in JSON (machine_file.cpp; README "Machine files").
//
// The machine file is a JSON object; every key is optional: "name", "description", "base" (a
// bundled machine to start from), "dialect", "units", "linear_units", "start", "tool_change",
// "tool_loads_on_t", "decimal_point_input", "initial_tool", "arc_radius_tolerance_mm", "d_offsets",
// "g53", "home", "reference2", "work_offsets", "m_codes", "forbidden_m_codes",
// "kinematics_switches", "kinematics_at_start", "variables",
// "far_distance", "subprograms" (folders relative to the file), "kinematics", the speeds
// "rapid_rate_mm_per_min", "rapid_rate_deg_per_min", "max_feed_mm_per_min", and the collision
// check's "components", "collision" and "linear_axes" (machine_parts below).
//
// Key "kinematics" (issue 11's machine file; see gcode/README.md, "Machine kinematics"): either
// the name of a bundled machine that has rotary axes (a profile), or an object:
//   "kinematics": {
//     "type": "table-table",              // or "head-table", "head-head"
//     "axes": [                           // chain order, each side from the machine outward
//       {"letter": "A",                   // A, B or C; each at most once
//        "on": "table",                   // "table" or "head"
//        "direction": [1, 0, 0],          // the axis line's direction (any length but zero)
//        "sense": 1,                      // optional, 1 or -1: which way a positive angle turns
//        "pivot": [0, 0, -75],            // a point on the line, mm, every rotary at 0
//        "limits": [-110, 110]},          // optional, degrees; absent: turns without end
//       {"letter": "C", "on": "table", "direction": [0, 0, 1], "pivot": [0, 0, 0]}],
//     "travel": {"X": [-300, 300], "Y": [-250, 250], "Z": [-400, 0]}}  // optional, see below
// or a profile with the machine's travel: {"profile": NAME, "travel": {...}}. One or two axes;
// "table-table" has them all on the table, "head-head" all on the head, "head-table" one of
// each. "travel" bounds the linear axes in machine coordinates (Kinematics::travel). Errors name
// the key path and the value (`kinematics.axes[1].direction: ...`).
#pragma once

#include <array>
#include <map>
#include <memory>
#include <nlohmann/json_fwd.hpp>
#include <optional>
#include <set>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "tridex/error.hpp"
#include "tridex/gcode/kinematics.hpp"
#include "tridex/geometry.hpp"
#include "tridex/mesh.hpp"

namespace tridex::gcode {

// The machine file's speeds (README "Machine files"), for the machining time:
// "rapid_rate_mm_per_min" (a number, or [x, y, z]), "rapid_rate_deg_per_min" (a number for every
// rotary axis, or {"A": …, "C": …}) and "max_feed_mm_per_min" (feeds above it run at it).
struct MachineRates {
  static constexpr double kDefaultRapid = 10000;  // mm/min, when the machine file gives none

  Vec3 rapid_mm_per_min{kDefaultRapid};
  bool rapid_per_axis = false;
  std::array<double, 3> rapid_deg_per_min{};  // A, B, C; 0: not given (such turns are not timed)
  std::optional<double> max_feed_mm_per_min;
  std::string source = "default";  // where the rapid rate came from: "default" or the file
};

// The machine's parts for the collision check (issue 33; docs/machine-files.md, "Components"):
// each a mesh attached to a link of the chain, placed as it is with every axis at zero. `on` is
// "bed", "spindle" (the mesh relative to the spindle's gauge point, +Z up the tool), a rotary
// axis letter ("A", "B", "C") or a linear axis letter ("X", "Y", "Z": that axis's carriage).
struct MachineComponent {
  std::string name;
  std::string on;
  std::string mesh;  // the STL's path, resolved against the machine file's folder
  // A bundled machine's part, made in code (machine.cpp): used when `mesh` is empty.
  std::shared_ptr<const Mesh> built;
};

// The machine file's "collision": bodies closer than `clearance` (mm) collide, closer than
// `near_miss` come near; `ignore` lists pairs of component names never tested.
struct CollisionSettings {
  double clearance = 0;
  double near_miss = 0;
  std::vector<std::pair<std::string, std::string>> ignore;
};

// The controller dialect: where Fanuc (and Haas, Mazak, most Fanuc-like controls) and LinuxCNC
// read the same program differently. Fanuc: a word whose value is vacant (#0, an unset local) is
// left out, FIX/FUP round toward/away from zero. LinuxCNC: unset numbered parameters read 0, FIX
// and FUP are floor and ceiling. Haas: Fanuc's, with Haas's tool offset registers (macro
// variables #2001–#2800, G10 L1 as wear; parameters.cpp, modal.cpp).
enum class Dialect { fanuc, haas, linuxcnc };

// What an M-code of the machine file's "kinematics_switches" does (LinuxCNC's switchable
// kinematics, docs/src/motion/switchkins.adoc: a remapped M-code sets motion.switchkins-type).
enum class KinematicsSwitch {
  tcp,       // the kinematics with tool centre point control: X Y Z are the tip on the part, as
             // under G43.4 (LinuxCNC's xyzac-trt-kins, xyzbc-trt-kins, xyzab_tdr_kins type)
  identity,  // identity kinematics: every word is a joint (raw rotary words)
  refuse,    // kinematics of the machine's own (LinuxCNC's "userk"): an error, no guess
};

// What M6 does with the tool tip.
enum class ToolChange {
  retract_far,  // leaves it far along the tool axis (the default: where it goes is the machine's)
  in_place,     // leaves it where it is (LinuxCNC's rs274 standalone)
  to_position,  // moves it (a rapid, machine coordinates) to tool_change_position
};

// What a Fanuc/Haas control's D (cutter compensation) offset registers hold, where a program or
// the machine file writes them (G10 L12/L13, #13001… or #2401…): Fanuc's a radius; Haas's a
// diameter or a radius after its setting 40. `dialect`: a radius on Fanuc, unknown on Haas.
enum class DOffsets { dialect, radius, diameter };

// The machine: what the interpreter needs to know of it (the defaults are the "far along the tool
// axis" rule of docs/design.md), its rotary axes and its speeds. machine_from_json fills it from a
// machine file, MachineConfig::bundled from the registry.
struct MachineConfig {
  static constexpr double kDefaultFar = 1e4;  // mm

  Dialect dialect = Dialect::fanuc;

  // G28 and G30 P2 positions in machine coordinates. The defaults lie far above the work along
  // +Z, so that the usual `G28 G91 Z0` retract cuts nothing; using them raises a warning.
  Vec3 home{0.0, 0.0, kDefaultFar};
  Vec3 reference2{0.0, 0.0, kDefaultFar};
  bool home_is_default = true;
  bool reference2_is_default = true;

  // Work offsets (machine coordinates of each work zero), keyed as G10 numbers them:
  // 1..6 = G54..G59 (G10 L2 P1..P6), 100 + n = G54.1 Pn (G10 L20 Pn, n = 1..300). Absent = 0.
  std::map<int, Vec3> work_offsets;

  // How far "far along the tool axis" is: the start of the approach move that brings the tool
  // back from a retract. Must exceed the size of the work.
  double far_distance = kDefaultFar;

  // Tip at program start, machine coordinates; unset: far along +Z.
  std::optional<Vec3> start_position;
  ToolChange tool_change = ToolChange::retract_far;
  Vec3 tool_change_position{0.0};  // machine coordinates, for ToolChange::to_position
  bool tool_loads_on_t = false;    // the control loads a tool on T alone (no M6 needed)
  // Fanuc's decimal-point input (parameter 3401 bit 0): true, X102 is 102 mm (calculator input);
  // false, X102 is 102 least increments (0.102 mm). Unset: not known. The interpreter reads an
  // integer as whole units either way; `tridex lint` and `diff` flag integers (issue 39).
  std::optional<bool> decimal_point_input;
  // How far an I/J/K arc's end may lie off its circle (mm) before the control alarms; within it
  // the arc is cut as a spiral. Unset: the dialect's rule (docs/gcode.md, "Arcs"): Fanuc and
  // Haas 0.020 mm under G21 and 0.0020 in under G20 (Fanuc's parameter 3410, in the input unit,
  // at 20 increments of IS-B), LinuxCNC its interpreter's (interp_arc.cc). Set (the machine
  // file's "arc_radius_tolerance_mm", this machine's parameter 3410): that, in every dialect.
  std::optional<double> arc_radius_tolerance;
  DOffsets d_offsets = DOffsets::dialect;
  bool inch_at_start = false;  // units before any G20/G21: inch (true) or mm
  bool units_stated = false;   // a machine file's "units" said so (no warning about G20/G21)
  // G53 with the tool along +Z: false, a G53 Z is a retract (the tip goes far along the tool, as
  // G28 with the default position); true, G53 goes to the machine coordinates it names, because
  // this machine's zero is known (the work offsets and G28/G30 positions are measured from it).
  bool g53_literal = false;
  // Canned cycles retract to the R plane (G99) until the program says G98; false: to the
  // initial level (G98). rs274 standalone starts in G99.
  bool g99_at_start = false;

  // M-codes beyond the ones the interpreter acts on (M0-M9, M30, M98, M99): declared ones are
  // accepted quietly, forbidden ones are errors, any other is accepted with one warning per code
  // (an M-code moves no axis; the machine file says which ones exist).
  std::set<int> m_codes;
  std::set<int> forbidden_m_codes;
  // M-codes that switch the kinematics ("kinematics_switches": {"M428": "tcp", ...}), and the
  // kinematics at start ("kinematics_at_start": false, identity, as LinuxCNC's sample configs
  // with sparm=identityfirst; true, TCP, as xyzac-trt-kins without it). Only with `kinematics`.
  std::map<int, KinematicsSwitch> kinematics_switches;
  bool tcp_kinematics_at_start = false;

  // Numbered variables as the program finds them when it starts: the control's persistent
  // commons (Fanuc #500-#999, kept across power-off) and the inputs a program reads (#1000...),
  // which the program alone cannot know. Any other starts vacant (0 under LinuxCNC).
  std::map<int, double> variables;
  // LinuxCNC's global named parameters the same way (#<_name>, the name lower case without its
  // #< >), such as a value the operator sets by MDI before running the program.
  std::map<std::string, double> named_variables;

  // Where M98 / G65 / o<name> call look for programs the file does not contain: O1234.nc-style
  // files (and name.ngc for LinuxCNC) in these folders, in order.
  std::vector<std::string> subprogram_dirs;

  // The rotary axes (kinematics.hpp): with them, A/B/C words on G0/G1 index the tool, and Haas
  // DWO (G254/G255) and Fanuc TCP (G43.4/G43.5) are read; without them a rotary word is an error.
  std::optional<Kinematics> kinematics;
  // Tool diameters (mm) by tool number, from the tool table: G41/G42 D<n> (or the loaded tool)
  // offsets by half of it. A tool that is not here cannot be compensated.
  std::map<int, double> tool_diameters;
  // Tool lengths (mm) by tool number, from the tool table: the gauge point of the spindle to the
  // tip. With none, every tool length code leaves the path alone (the programmed point is the
  // tip); with some, G43 H / G43.1 / G44 H / G49 shift which point the program names
  // (gcode/README.md, "Tool length offsets").
  std::map<int, double> tool_lengths;
  // The units of a LinuxCNC tool table (.tbl) for this machine: LinuxCNC reads it in machine
  // units, its INI's [TRAJ]LINEAR_UNITS; rs274 run standalone, with no INI, in inches.
  bool tool_table_in_inches = true;
  bool linear_units_stated = false;  // a machine file's "linear_units" said so
  // The tool in the spindle when the program starts ("initial_tool"; 0: none, the default):
  // CAMotics runs a program with no tool change with tool 1. Moves before the first tool change
  // are cut with it (the command warns when it does).
  int initial_tool = 0;
  bool initial_tool_stated = false;

  void set_home(const Vec3& p) {
    home = p;
    home_is_default = false;
  }
  void set_reference2(const Vec3& p) {
    reference2 = p;
    reference2_is_default = false;
  }
  static int g54_key(int n) { return n; }          // n = 1..6 for G54..G59
  static int g54_1_key(int p) { return 100 + p; }  // G54.1 Pp

  // The speeds, for the machining time (the interpreter does not read them).
  MachineRates rates;

  // The collision check's machine (issue 33): its parts, which side each linear axis moves
  // ("linear_axes": true = the head, false = the table; default the head, as kinematics.hpp's
  // model has it) and the distances.
  std::vector<MachineComponent> components;
  std::array<bool, 3> linear_on_head{true, true, true};
  CollisionSettings collision;

  // A bundled machine by name (the registry in machine.cpp); nullopt for another name.
  static std::optional<MachineConfig> bundled(std::string_view name);
};

// ---- the bundled machines -----------------------------------------------------------------------

// Their names in the registry's order, joined by ", " (the command's --help and its messages).
std::string bundled_machine_names();

// The bundled machines that have rotary axes are the "kinematics" key's profiles: the profile is
// that machine's kinematics; std::nullopt for another name.
std::optional<Kinematics> kinematics_profile(std::string_view name);
std::vector<std::string> kinematics_profile_names();

// ---- the machine file --------------------------------------------------------------------------

// Bad input in a machine description: the message names the file, the key and the value.
class MachineError : public tridex::Error {
 public:
  using tridex::Error::Error;
};

// The machine a parsed machine file describes; `file` names it in messages and is where its
// "subprograms" folders are found from. Throws MachineError.
MachineConfig machine_from_json(const nlohmann::json& doc, const std::string& file);

// The "kinematics" value of a machine file (a profile name or an object, schema above); `path`
// prefixes the key paths in error messages. Throws tridex::Error.
Kinematics kinematics_from_json(const nlohmann::json& value,
                                const std::string& path = "kinematics");

}  // namespace tridex::gcode
