// tridex::gcode — the modal interpreter: a milling program in, a stream of tool-tip moves out.
//
// Codes: G0 G1 G2 G3 (I/J/K and R, full circles, helices) in G17/G18/G19, G20/G21, G90/G91,
// G90.1/G91.1, G54–G59 and G54.1 Pn, G10 L2/L20 (P0 the active system), LinuxCNC's G10 L1/L10/L11 (tool table entries), G52, G92/G92.1/G92.2/
// G92.3, G43/G44/G49 H and G43.1 (MachineConfig::tool_lengths), T, M6, M61 Q, F, S, M3/M4/M5, M0/M1/M2/M30, G93/G94/G95, G28/G30/G53, canned cycles
// G73 G81 G82 G83 G85 G86 G89 with G98/G99 and repeats (L or K), cutter radius compensation
// G41/G42 D (MachineConfig::tool_diameters), G41.1/G42.1 D and G40 as LinuxCNC computes it, M98 P L / M99 with O (or ':')
// numbers, G65 macro calls, G4; tilted planes Fanuc G68.2 (Euler Z-X-Z), G53.1, G53.6, G69 and
// Haas G268 (Q123), G253, G269; with MachineConfig::kinematics, A/B/C words on G0/G1 (raw
// machine coordinates), Haas DWO G254/G255 and Fanuc TCP G43.4/G43.5 I J K (part coordinates),
// rotary limits and G53.1 reachability (gcode/README.md, "Rotary words, DWO and TCP"); Fanuc
// Macro B and LinuxCNC parameters, expressions and o-word control flow (lexer.hpp). Accepted without effect on the tool path: G15 G61 G64 (P Q)
// G80 G97, look-ahead/smoothing G5.1 (Q R), G8 (P), G187 (P E), M7 M8 M9 and any other
// M-code (one warning per code unless the MachineConfig declares it). Anything else is an error
// naming file, line, column and word (a warning in lenient mode, which then skips the word).
//
// Conventions (docs/design.md): the programmed point is the tool tip after work offsets;
// G20 values are converted to mm; G68.2 R = Rz(I)·Rx(J)·Rz(K) and the tool axis is R·(0,0,1)
// once G53.1/G53.6 orient the tool; G268 R = Rz(K)·Ry(J)·Rx(I), oriented by G253. A home return
// (G28, G30 — but X/Y alone with the tool along +Z is a rapid at the current height — and G53
// Z), a tool change and a change of spindle direction leave the tip "far" along the tool axis; moves that leave the coordinate along the tool axis unset stay far
// and emit nothing; the first move that sets it comes straight back along the axis to its end.
// The program starts far along +Z (unless InterpreterOptions::start_position says otherwise).
//
// Emitted points are in the work frame: machine coordinates minus the G54 offset configured in
// MachineConfig (the machine frame itself when none is configured).
#pragma once

#include <functional>
#include <iosfwd>
#include <map>
#include <memory>
#include <optional>
#include <set>
#include <string>
#include <vector>

#include "tridex/gcode/diagnostic.hpp"
#include "tridex/gcode/kinematics.hpp"
#include "tridex/gcode/move.hpp"
#include "tridex/geometry.hpp"

namespace tridex::gcode {

// The controller dialect: where Fanuc (and Haas, Mazak, most Fanuc-like controls) and LinuxCNC
// read the same program differently. Fanuc: a word whose value is vacant (#0, an unset local) is
// left out, FIX/FUP round toward/away from zero. LinuxCNC: unset numbered parameters read 0, FIX
// and FUP are floor and ceiling. Haas: Fanuc's, with Haas's tool offset registers (macro
// variables #2001–#2800, G10 L1 as wear; parameters.cpp, modal.cpp).
enum class Dialect { fanuc, haas, linuxcnc };

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

// What the interpreter needs to know of the machine (tridex's machine file, tools/cli/machine.*,
// fills it; the defaults are the "far along the tool axis" rule of docs/design.md).
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
  // Fanuc and Haas: how far an I/J/K arc's end may lie off its circle (mm; Fanuc's parameter
  // 3410) before the control alarms; within it the arc is cut as a spiral. The default passes a
  // program posted to 4 decimals of an inch (0.0001 in = 0.00254 mm off). LinuxCNC's own rule
  // replaces it under its dialect.
  double arc_radius_tolerance = 0.02;
  DOffsets d_offsets = DOffsets::dialect;
  bool inch_at_start = false;      // units before any G20/G21: inch (true) or mm
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
  // tip); with some, G43 H / G43.1 / G44 H / G49 shift which point the program names (gcode/README.md,
  // "Tool length offsets").
  std::map<int, double> tool_lengths;
  // The units of a LinuxCNC tool table (.tbl) for this machine: LinuxCNC reads it in machine
  // units, its INI's [TRAJ]LINEAR_UNITS; rs274 run standalone, with no INI, in inches.
  bool tool_table_in_inches = true;

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

  // The bundled machines: "default" (the far rule), "haas" (the default with Haas's dialect) and
  // "linuxcnc" (rs274 run standalone: start at the origin, M6 in place, G28/G30 at the origin,
  // G53 literal, G99, LinuxCNC's dialect); nullopt otherwise.
  static std::optional<MachineConfig> bundled(const std::string& name);
};

struct InterpreterOptions {
  double arc_tolerance = 0.001;         // mm, largest chord error of a linearised arc
  bool lenient = false;        // unsupported words become warnings and are skipped
  bool block_delete = true;    // skip blocks that start with '/' (the switch on)
  int max_call_depth = 16;     // nested M98 / G65 / o-word calls
  double peck_clearance = 0.254;  // mm, G73 back-off and G83 re-entry gap (LinuxCNC's 0.010 in)
  // Error once this many blocks ran: bounds endless loops (M98 L, WHILE, GOTO); 0 = no bound.
  long long max_blocks = 100'000'000;
};

class Interpreter {
 public:
  explicit Interpreter(InterpreterOptions options = {}, MachineConfig machine = {});
  ~Interpreter();
  Interpreter(Interpreter&&) noexcept;
  Interpreter& operator=(Interpreter&&) noexcept;

  // Streams every move of the program to `sink` in program order; throws GcodeError (or its
  // SyntaxError) on bad input. Memory does not grow with the program's length. Each call starts
  // from a fresh machine state. M98 needs a seekable stream (files and string streams are).
  void run(std::istream& program, const std::string& file_name,
           const std::function<void(const Move&)>& sink);
  // The same, streaming every dwell to `dwell_sink` as well. The time word follows the dialect:
  // LinuxCNC reads G4 P and a cycle's P in seconds; Fanuc reads P in milliseconds and G4 X in
  // seconds (Haas's `P1.`, seconds for its decimal point, reads as 1 ms). A cycle's P is sticky,
  // as its Q is.
  void run(std::istream& program, const std::string& file_name,
           const std::function<void(const Move&)>& sink,
           const std::function<void(const Dwell&)>& dwell_sink);

  const std::vector<Diagnostic>& warnings() const;
  const std::set<int>& tools_used() const;              // tools of the emitted moves
  const std::map<int, int>& tool_first_line() const;    // tool -> line of the M6 that loaded it
                                                        // (its first move's line if none)
  long long blocks() const;                             // blocks executed by the last run
  // The files of the current (or last) run, Move::file's table: the program given to run(), then
  // each subprogram file in the order it was first called (its path as found). Grows during a run.
  const std::vector<std::string>& files() const;

  struct State;  // the implementation (gcode/src/state.hpp)

 private:
  std::unique_ptr<State> state_;
};

// Reads a whole program file into memory as moves (convenient for small programs and tests).
std::vector<Move> read_moves(const std::string& path, InterpreterOptions options = {},
                             MachineConfig machine = {});

}  // namespace tridex::gcode
