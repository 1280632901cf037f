// tridex::gcode — the interpreter's state: the modal machine, the tool and the program context,
// shared by the stage files (modal.cpp: one block's codes; motion.cpp: lines, arcs, cycles,
// returns; interpreter.cpp: reading and program flow). What one stage alone keeps between blocks
// is a part of its own, named for it: ToolTable (modal.cpp), Splines (spline.cpp), TiltedPlane
// (tilted_plane_codes.cpp), CannedCycle (motion.cpp), CallRequest (modal.cpp, read by flow.cpp),
// Parameters (parameters.cpp), WarnedOnce and CutterComp (comp.cpp). What every stage reads is
// a part too, its comment naming who changes it: BlockContext (flow.cpp), Modal (modal.cpp),
// ToolState (modal.cpp and the motions), ProgramFrame (modal.cpp, rotary.cpp, update_frame).
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <functional>
#include <map>
#include <numbers>
#include <optional>
#include <set>
#include <string>
#include <unordered_map>
#include <vector>

#include "codes.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "tridex/gcode/lexer.hpp"

namespace tridex::gcode {

inline constexpr double kPi = std::numbers::pi;
inline constexpr double kAxisEps = 1e-9;  // a frame axis "has a component" along the tool axis
inline constexpr double kSameDirection = 1e-12;  // 1 − cos of the angle below which axes are equal
inline constexpr long long kMaxArcPieces = 10'000'000;
inline constexpr long long kMaxNurbsOrder = 100;  // G5.2 L: far above any CAM output

// ---- the interpreter's state ----------------------------------------------------------------
struct Interpreter::State : ParameterReader {
  InterpreterOptions options;
  MachineConfig machine;

  // The words lenient mode skipped, or the blocks it read in a stated way, of one cause.
  struct Skipped {
    long long count = 0;
    std::vector<int> lines;  // the first few
    int last_line = 0;
  };
  // What the run tells its caller besides the moves (Interpreter::warnings, tools_used, ...; the
  // lenient-mode counts in its summary warnings), gathered as the blocks execute.
  struct RunSummary {
    std::vector<Diagnostic> warnings;
    std::set<int> tools_used;
    std::map<int, int> tool_first_line;
    // The tool of the last move emitted, in tools_used already: the next moves of the same tool
    // skip the set (a look-up per move on the hot path of plain programs).
    std::optional<int> last_tool_used;
    bool selects_tool = false;  // a T word or M61 Q ran (a program with none: CAMotics' tool 1)
    long long blocks = 0;
    std::map<std::string, Skipped> skipped;  // by cause (unsupported)
    std::map<std::string, Skipped> read_as;  // by cause (lenient_read)
  };
  RunSummary summary;

  // Where the block being executed stands (flow.cpp sets the file and line of each block,
  // modal.cpp the column of its motion code): what diagnostics and moves name.
  struct BlockContext {
    const std::string* file = nullptr;
    int file_index = 0;  // of `file` in `files` (Move::file)
    int line = 0;
    int motion_column = 1;
  };
  BlockContext context;
  std::vector<std::string> files;  // every file of the run, in the order first read
  // Where a program fed in pieces (Interpreter::feed) stands between pieces: the flow's own state
  // that must outlive one piece. Control structures (calls, loops) stay within one piece.
  struct Continuation {
    bool begun = false;  // the machine state is set up (the first piece ran)
    int line = 0;        // lines read so far: the next piece's first line is line + 1
    bool started = false, percent_seen = false, ended = false;
    bool warned_after_end = false;
  };
  Continuation continuation;
  const std::function<void(const Move&)>* sink = nullptr;
  const std::function<void(const Dwell&)>* dwell_sink = nullptr;  // may hold no function

  // Feed modes (RS274/NGC group 5, NIST IR 6556 §3.5.19; LinuxCNC interp_inverse.cc): G94 F in
  // units per minute; G93 inverse time, F in 1/min, every feed block takes 1/F minutes (its rate
  // is its programmed length × F, set per move); G95 F in units per spindle revolution (× S).
  enum class FeedMode { per_minute, inverse_time, per_revolution };
  // The modal state the block's codes set (modal.cpp; motion.cpp works out the G93 feed per move).
  struct Modal {
    double unit = 1.0;  // mm per program unit
    bool incremental = false;
    bool arc_absolute = false;
    int plane = kG17;
    int motion = -1;  // -1: none yet
    // Fanuc and Haas: the group-01 code (G0-G3, a spline) the canned cycles, group 09 there,
    // leave in force; G80 returns to it (docs/gcode.md, "Canned cycles"). -1: none yet.
    int group01 = -1;
    bool retract_to_r = false;
    double feed = 0;  // mm/min of the next feed move (under G93 and G95, worked out per move)
    FeedMode feed_mode = FeedMode::per_minute;
    double inverse_time = 0;  // G93: the block's F (1/min)
    double feed_per_rev = 0;  // G95: mm per revolution
    double speed = 0;
    int spindle_direction = 0;
  };
  Modal modal;
  // The feed rate as LinuxCNC's #<_feed> reads it, in program units: per revolution under G95,
  // under G93 the rate of the last feed move.
  double programmed_feed() const {
    return (modal.feed_mode == FeedMode::per_revolution ? modal.feed_per_rev : modal.feed) /
           modal.unit;
  }
  void feed_mode_codes();                 // G93, G94, G95, F and S (modal.cpp)
  void inverse_time_rate(double length);  // G93: feed for a block `length` mm long (motion.cpp)
  // LinuxCNC's splines and NURBS between blocks (spline.cpp).
  struct NurbsPoint {
    Vec2 p{0.0};
    double weight = 1;
  };
  struct Splines {
    Vec2 mirror{0.0};  // G5 without I J: P1 − P0, program units (−P, −Q of the last G5)
    // G5.2 control points gathered for G5.3 (program units, XY) and the curve's order (L).
    std::vector<NurbsPoint> nurbs_points;
    int nurbs_order = 3;
  };
  Splines splines;
  // The tool (modal.cpp: T, M6, M61, G43/G49; motion.cpp, comp.cpp, spline.cpp and rotary.cpp
  // move it; update_frame says whether its direction is ambiguous): the tool selected and the one
  // loaded, its spindle direction, its tip position (the part frame as it sits with every rotary
  // at 0, which is machine coordinates without kinematics) and the far flag.
  struct ToolState {
    int selected = 0;
    int number = 0;
    // Tool length offset (G43 H, G43.1 Z, G44 H; 0 under G49), mm. The program names the point
    // this far below the spindle's gauge point, and the loaded tool's tip lies its own length
    // below it: the tip is length_shift() from the programmed point (rs274ngc's tool_offset,
    // interp_convert.cc convert_tool_length_offset). Without tool lengths both stay 0.
    double length_offset = 0;
    Vec3 axis{0.0, 0.0, 1.0};
    Vec3 pos{0.0};
    bool far = true;
    // Where the far tool lies when not along its axis (0: along it): a table turned under TCP
    // kinematics while the tool is far keeps it far where it was (rotary.cpp).
    Vec3 far_axis{0.0};
    bool ambiguous = false;
    Vec3 uvw_position{0.0};  // mm, where the U/V/W words put those axes (rotary.cpp)
  };
  ToolState tool;
  double loaded_length() const {
    auto it = machine.tool_lengths.find(tool.number);
    return it == machine.tool_lengths.end() ? 0.0 : it->second;
  }
  Vec3 length_shift() const { return (tool.length_offset - loaded_length()) * tool.axis; }
  // The control's tool table as LinuxCNC's G10 L1/L10/L11 or Fanuc's G10 L10/L11 rewrite it
  // (modal.cpp): the lengths G43 H reads (mm), geometry plus Fanuc's wear. The tool itself keeps
  // the machine's length (loaded_length): a program that sets a wrong length moves the tip as the
  // real machine would.
  struct ToolTable {
    std::map<int, double> lengths, wear;
  };
  ToolTable tool_table;
  std::optional<double> length_geometry(int number) const {
    if (auto it = tool_table.lengths.find(number); it != tool_table.lengths.end())
      return it->second;
    if (auto it = machine.tool_lengths.find(number); it != machine.tool_lengths.end())
      return it->second;
    return std::nullopt;
  }
  double wear_of(int number) const {
    auto it = tool_table.wear.find(number);
    return it == tool_table.wear.end() ? 0.0 : it->second;
  }
  std::optional<double> table_length(int number) const {
    std::optional<double> geometry = length_geometry(number);
    if (geometry) return *geometry + wear_of(number);
    return geometry;
  }
  void tool_table_entry(long long l, int column);   // LinuxCNC's G10 L1, L10, L11 (modal.cpp)
  void tool_length_entry(long long l, int column);  // Fanuc's G10 L10-L13 (modal.cpp)
  // A machine position names the gauge point (G53, G28/G30, the tool-change position, with the
  // tool along +Z): the tip lies the loaded tool's length below it.
  Vec3 tip_below(const Vec3& gauge) const { return gauge - Vec3(0, 0, loaded_length()); }

  // The active program frame (program point p -> machine origin + rotation·p, worked out by
  // update_frame) and what makes it: the work offsets (modal.cpp: G54-G59, G10 L2/L20, G52, G92),
  // whether a tilted plane is on (tilted_plane_codes.cpp) and the rotary axes (rotary.cpp; only
  // with MachineConfig::kinematics): their positions and how X Y Z are read. raw: machine
  // coordinates (the part frame is machine_to_part of the rotaries); dwo (Haas G254) and tcp
  // (Fanuc G43.4/G43.5): the part frame, as the control computes it.
  struct ProgramFrame {
    Mat3 rotation{1.0};
    Vec3 origin{0.0};
    bool tilted = false;
    int work_key = 1;
    Vec3 work_offset{0.0};
    std::map<int, Vec3> offsets;
    Vec3 local_offset{0.0};        // G52 / G92 (one register, as LinuxCNC keeps it), machine axes
    Vec3 saved_local_offset{0.0};  // G92.2 suspends, G92.3 restores
    Vec3 world_origin{0.0};
    RotaryPositions rotary_position{};
    // Rotary work offsets (G10 L2/L20 A/B/C on a machine whose kinematics has the axis), keyed as
    // `offsets`: the machine's angle is the program's plus the active one, as for X Y Z; the
    // fixture sits turned by it on the table, so the part turns by the program's angle
    // (rotary_position) and the axis limits meet the machine's (rotary.cpp).
    std::map<int, RotaryPositions> rotary_offsets;
    RotaryPositions rotary_offset() const {
      auto it = rotary_offsets.find(work_key);
      return it == rotary_offsets.end() ? RotaryPositions{} : it->second;
    }
    bool tcp = false;
    bool dwo = false;
    // The machine's TCP kinematics, switched on by an M-code ("kinematics_switches", rotary.cpp):
    // X Y Z read as under G43.4, which G43/G49 do not cancel (LinuxCNC's switchkins).
    bool tcp_kinematics = false;
    bool tcp_on() const { return tcp || tcp_kinematics; }
  };
  ProgramFrame frame;
  // G68.2 / G68.4 P2 (three points) and P3 (two vectors) are written over consecutive blocks,
  // one Q each (tilted_plane_codes.cpp); their words are gathered here until the last one
  // completes the plane.
  struct PlaneBlocks {
    int code = 0;  // kG68_2 or kG68_4 while a plane is under way; 0 otherwise
    int p = 0;
    int first_line = 0;
    unsigned given = 0;  // bit q: the Q block has been read
    std::array<Vec3, 4> xyz{}, ijk{};
    double r = 0;
  };
  // The tilted plane (tilted_plane_codes.cpp): its frame, the line that set it, and a
  // several-block form under way.
  struct TiltedPlane {
    Mat3 rotation{1.0};
    Vec3 origin{0.0};
    int line = 0;
    PlaneBlocks plane_blocks;
  };
  TiltedPlane tilt;

  // The warnings given once a run (each stage's own).
  struct WarnedOnce {
    bool home = false;
    bool reference2 = false;
    std::set<int> m_codes;
    std::set<char> rotary_at_zero;  // A/B/C words of 0 read on a machine without kinematics
    bool probe = false;             // G38.x read as rs274 standalone does
    bool comp_without_d = false;    // Fanuc/Haas G41/G42 with no D yet: D0
    bool plain_rotary = false;      // A/B/C on a LinuxCNC machine without kinematics (rotary.cpp)
    bool uvw = false;               // U/V/W on a LinuxCNC machine (rotary.cpp)
  };
  WarnedOnce warned_once;

  // Canned cycle state (motion.cpp; sticky values, program units converted to mm, as written).
  struct CannedCycle {
    bool active = false;
    bool initial_far = false;
    double initial = 0;
    double r = 0, z = 0, q = 0;
    double dwell = 0;  // seconds at the hole's bottom (G82, G86, G89)
    bool has_r = false, has_z = false, has_q = false;
  };
  CannedCycle canned;

  // Subprogram calls requested by the block just executed (modal.cpp; flow.cpp carries them out).
  struct CallRequest {
    int label = 0;
    long long repeats = 0;
    std::array<Value, 34> arguments{};  // G65: #1..#33 from the argument words
  };
  CallRequest call_request;

  // Parameters (parameters.cpp): #1..#33 of each call level (Fanuc locals; LinuxCNC's #1..#30),
  // named locals of each o-word call, and the globals. Fanuc's vacant is the default.
  struct Parameters {
    struct Scope {
      std::array<Value, 34> locals;
      std::unordered_map<std::string, Value> named;
      Scope() { locals.fill(Value{0, true}); }
    };
    std::vector<Scope> scopes = std::vector<Scope>(1);
    std::unordered_map<int, Value> globals;
    std::unordered_map<std::string, Value> named_globals;
  };
  Parameters parameters;

  Value numbered(int n) override;
  std::optional<Value> named(std::string_view name) override;
  bool vacant_words_omitted() const override { return machine.dialect != Dialect::linuxcnc; }
  void assign(const Assignment& a);  // #n = v or #<name> = v, system variables included
  void preset(int n, double value);  // the machine file's "variables"

  Words w;

  // ---- diagnostics ----
  [[noreturn]] void error(int column, std::string message) const {
    throw GcodeError(Diagnostic{*context.file, context.line, column, std::move(message)});
  }
  void warn(int column, std::string message) {
    // Bounded: a warning per block of a long program would grow memory with its length.
    if (summary.warnings.size() < 1000)
      summary.warnings.push_back(
          Diagnostic{*context.file, context.line, column, std::move(message)});
  }
  // Lenient mode may skip a word only where skipping cannot change the tool path; `cause` names
  // the kind of word (counted for the run's summary, however many there are).
  void unsupported(int column, const std::string& message, const std::string& cause,
                   bool skippable = true) {
    if (!options.lenient) error(column, message);
    if (!skippable)
      error(column, message + " (cannot be skipped in lenient mode: it changes the tool path)");
    warn(column, message + " (skipped: lenient mode)");
    Skipped& s = summary.skipped[cause];
    if (s.count++ < 5) s.lines.push_back(context.line);
  }
  // Lenient mode reads a block it cannot take as written in a stated way (`cause`, which names
  // the direction it was read along): a warning for the line, and a count per cause for the
  // run's summary, however many (the warnings themselves stop at 1000).
  void lenient_read(int column, const std::string& message, const std::string& cause) {
    Skipped& s = summary.read_as[cause];
    if (s.count > 0 && s.last_line == context.line) return;  // one per line: an arc's chords
    s.last_line = context.line;
    warn(column, message);
    if (s.count++ < 5) s.lines.push_back(context.line);
  }
  static std::string direction_text(const Vec3& d) {
    char text[112];  // snprintf: GCC 12 warns falsely on "literal" + std::string chains
    std::snprintf(text, sizeof text, "(%.10g, %.10g, %.10g)", d.x, d.y, d.z);
    return text;
  }

  // ---- words ----
  // G5 and G5.1 are LinuxCNC's splines (motions). On Fanuc they are modes: G5 P10000 / G5 P0
  // high-speed machining, G5.1 Q1 AI contour control (smoothing). So they are splines under the
  // LinuxCNC dialect, and elsewhere where the block has a spline's words: G5 with X, Y, I, J or
  // Q, G5.1 with I or J.
  bool g5_spline = false, g5_1_spline = false;  // of the block being gathered
  void find_splines(const Block& block) {
    g5_spline = g5_1_spline = machine.dialect == Dialect::linuxcnc;
    for (const Word& word : block.words) {
      bool ij = word.letter == 'I' || word.letter == 'J';
      g5_spline |= ij || word.letter == 'X' || word.letter == 'Y' || word.letter == 'Q';
      g5_1_spline |= ij;
    }
  }
  // The modal group of a G code in this block: g_group, the motions of the LinuxCNC dialect
  // (G5 and G5.1 splines, G5.2 NURBS and its G5.3 end, G38.2–G38.5 straight probes) and Haas's
  // G234.
  int block_g_group(int code) const {
    if ((code == kG5 && g5_spline) || (code == kG5_1 && g5_1_spline)) return kMotion;
    if (machine.dialect == Dialect::linuxcnc && (code == kG5_2 || code == kG5_3))
      return code == kG5_2 ? kMotion : kNonModal;
    if (code >= kG38_2 && code <= kG38_5 && machine.dialect == Dialect::linuxcnc) return kMotion;
    if (code == kG68 && machine.dialect == Dialect::linuxcnc) return -1;  // no G68 in LinuxCNC
    // Haas's G234 (TCPC, group 08, cancelled by G49: Haas mill operator's manual) is Fanuc's G43.4.
    if (code == kG234 && machine.dialect == Dialect::haas) return kToolLength;
    return g_group(code);
  }

  // A kinematics switch of the machine (LinuxCNC's remapped M428..., modal group 10; rotary.cpp
  // runs it): one a block.
  bool gather_switch(int m, int column) {
    if (!machine.kinematics_switches.count(m)) return false;
    if (w.kinematics_switch >= 0) {
      std::string message = code_name('M', m * 10);  // (one string: GCC 12's -Wrestrict)
      message += " and ";
      message += code_name('M', w.kinematics_switch * 10);
      message += " both switch the kinematics (one a block)";
      error(column, message);
    }
    w.kinematics_switch = m;
    w.kinematics_switch_column = column;
    return true;
  }

  void gather(const Block& block) {
    w.present = w.used = 0;
    find_splines(block);
    w.g_count = w.m_count = 0;
    w.m_arguments = false;
    w.kinematics_switch = -1;
    w.vacant_words = &block.vacant_words;
    std::array<int, kGroupCount> g_seen{};
    std::array<int, kMGroupCount> m_seen{};
    // In a G65 block M is an argument (#13), not an M-code (Fanuc's argument specification I).
    const bool macro_call =
        machine.dialect != Dialect::linuxcnc &&
        std::any_of(block.words.begin(), block.words.end(),
                    [](const Word& word) { return word.letter == 'G' && word.value == 65; });
    for (const Word& word : block.words) {
      if (word.letter == 'G' || (word.letter == 'M' && !macro_call)) {
        // Codes are small; anything else is unsupported before it reaches an int (fuzz finding).
        double scaled = word.value * 10;
        double rounded = std::round(scaled);
        bool integral = std::abs(scaled - rounded) < 1e-6 && word.value >= 0 && word.value < 10000;
        int code = integral ? static_cast<int>(rounded) : -1;
        if (word.letter == 'M' && code % 10) integral = false;
        int group = !integral ? -1 : word.letter == 'G' ? block_g_group(code) : m_group(code / 10);
        // A machine may forbid any M-code, the ones tridex acts on (M0-M9, M30, M98, M99)
        // included: the machine file's "forbidden_m_codes".
        if (integral && word.letter == 'M' && machine.forbidden_m_codes.count(code / 10))
          error(word.column,
                code_name('M', code) + " is not allowed on this machine (machine file)");
        if (group < 0 && integral && word.letter == 'M') {
          if (gather_switch(code / 10, word.column)) continue;  // a kinematics switch
          // An M-code moves no axis: accepted (once a warning per code unless the machine
          // declares it).
          int m = code / 10;
          if (!machine.m_codes.count(m) && warned_once.m_codes.insert(m).second)
            warn(word.column,
                 code_name('M', code) +
                     " has no effect on the tool path here (accepted; declare it in the "
                     "machine file's m_codes to silence this)");
          // Spindle orientation (M19 R Q P), LinuxCNC's override switches (M50-M53 P), I/O
          // codes (M62-M65 P, M66 P E L Q, M67/M68 E Q) and user codes (M100-M199 P Q) take
          // arguments of their own.
          w.m_arguments |=
              m == 19 || (m >= 50 && m <= 53) || (m >= 62 && m <= 68) || (m >= 100 && m <= 199);
          continue;
        }
        if (group < 0) {
          // Codes known to leave the path alone (feed and speed modes, exact stop, cancels of
          // modes tridex never enters) may be skipped in a block without coordinates; any other
          // unknown code could move the tool or change how later coordinates read.
          static constexpr int kHarmless[] = {kG5,    kG9,  kG13_1, kG50, kG50_1,
                                              kG61_1, kG62, kG63,   kG67, kG96};
          bool harmless =
              word.letter == 'G' && integral &&
              std::find(std::begin(kHarmless), std::end(kHarmless), code) != std::end(kHarmless);
          bool coordinates = false;
          for (const Word& other : block.words)
            coordinates |= other.letter == 'X' || other.letter == 'Y' || other.letter == 'Z';
          std::string name = integral ? code_name(word.letter, code)
                                      : std::string(1, word.letter) + format_number(word.value);
          if (word.letter == 'G' &&
              ((code >= kG38_2 && code <= kG38_5) || code == kG31))  // never skipped: it moves
            error(word.column, name +
                                   " (probing) is not simulated: where the probe touches, and so "
                                   "where the tool goes next, is known only on the machine; "
                                   "leave the probing cycle out of the program tridex reads (or, "
                                   "with --machine linuxcnc, read it as rs274 does)");
          if (word.letter == 'G' && (code == kG5_2 || code == kG5_3))
            error(word.column, name + " (LinuxCNC's NURBS) is read with --machine linuxcnc only");
          if (word.letter == 'G' && integral && machine.dialect == Dialect::linuxcnc) {
            // Never skipped, even lenient: each moves the tool or sets how it moves. LinuxCNC's
            // lathe codes (G7 diameter mode, G33 threading, G70-G72 turning cycles, G76 threading
            // cycle, G96 constant surface speed) have no meaning on a mill.
            static constexpr int kLathe[] = {kG7,  kG33,   kG70,   kG71, kG71_1, kG71_2,
                                             kG72, kG72_1, kG72_2, kG76, kG96};
            if (std::find(std::begin(kLathe), std::end(kLathe), code) != std::end(kLathe))
              error(word.column, name + " is a lathe code: tridex simulates milling machines");
          }
          unsupported(word.column, "unsupported code " + name, "code " + name,
                      harmless && !coordinates);
          continue;
        }
        if (word.letter == 'G') {
          int& seen = g_seen[static_cast<std::size_t>(group)];
          if (seen && group == kMotion &&
              (code == kG80 || w.g[static_cast<std::size_t>(seen - 1)].code == kG80)) {
            // G80 beside another motion code (the safe-start line `G0 G17 G40 G49 G80 G90`):
            // rs274, Fanuc and Haas read it as the other code, which ends any cycle anyway.
            if (code != kG80) w.g[static_cast<std::size_t>(seen - 1)] = Code{code, word.column};
            continue;
          }
          if (seen)
            error(word.column, code_name('G', code) + " conflicts with " +
                                   code_name('G', w.g[static_cast<std::size_t>(seen - 1)].code) +
                                   " in the same block (same modal group)");
          if (w.g_count == static_cast<int>(w.g.size())) error(word.column, "too many G codes");
          w.g[static_cast<std::size_t>(w.g_count++)] = Code{code, word.column};
          seen = w.g_count;
        } else {
          int& seen = m_seen[static_cast<std::size_t>(group)];
          if (seen)
            error(word.column, code_name('M', code) + " conflicts with " +
                                   code_name('M', w.m[static_cast<std::size_t>(seen - 1)].code) +
                                   " in the same block (same modal group)");
          w.m[static_cast<std::size_t>(w.m_count++)] = Code{code / 10, word.column};
          seen = w.m_count;
        }
        continue;
      }
      if (word.letter == 'N') continue;  // sequence numbers carry no meaning here
      std::size_t i = static_cast<std::size_t>(letter_index(word.letter));
      if (w.has(word.letter))
        error(word.column, std::string("repeated word ") + word.letter + " (first at column " +
                               std::to_string(w.column[i]) + ")");
      w.present |= 1u << i;
      w.value[i] = word.value;
      w.column[i] = word.column;
    }
  }

  double length(char c) { return w.take(c) * modal.unit; }

  long long integer(char c, const char* what, long long low, long long high) {
    double v = w.take(c);
    if (std::abs(v - std::round(v)) > 1e-9 || v < static_cast<double>(low) ||
        v > static_cast<double>(high))
      error(w.col(c), std::string(what) + ": " + c + format_number(v) + " must be an integer in [" +
                          std::to_string(low) + ", " + std::to_string(high) + "]");
    return static_cast<long long>(std::llround(v));
  }

  // How far an arc's end may lie off its circle, mm: the machine's, else Fanuc's parameter 3410
  // as tridex assumes it, 20 least input increments of IS-B (0.020 mm, or 0.0020 in under G20).
  // LinuxCNC's own rule (motion.cpp) replaces it for I/J/K arcs under its dialect.
  double arc_radius_tolerance() const {
    if (machine.arc_radius_tolerance) return *machine.arc_radius_tolerance;
    if (machine.dialect == Dialect::linuxcnc) return 0.02;  // R-form arcs only (as before)
    return modal.unit == 1.0 ? 0.02 : 0.002 * 25.4;
  }
  std::string arc_tolerance_source() const {
    return machine.arc_radius_tolerance ? "the machine file's arc_radius_tolerance_mm"
                                        : "Fanuc's parameter 3410 as tridex assumes it; a machine "
                                          "file's arc_radius_tolerance_mm sets this machine's";
  }

  bool has_axis_words() const {
    return w.has('X') || w.has('Y') || w.has('Z') || w.has('@') || w.has('^');
  }

  // ---- frames ----
  // Where the linear axes stand, in the coordinates offsets are added in (G92, G10 L20): the tip
  // on the part, or in raw rotary form (kinematics without TCP or DWO) the machine coordinates,
  // which differ from the tip's place on the part as soon as a table axis is turned.
  bool raw_rotary() const {
    return machine.kinematics && !frame.tcp_on() && !frame.dwo && !frame.tilted;
  }
  Vec3 linear_axes() const {
    return raw_rotary() ? machine_from_part(*machine.kinematics, tool.pos, frame.rotary_position)
                        : tool.pos - length_shift();
  }
  Vec3 to_machine(const Vec3& p) const { return frame.origin + frame.rotation * p; }
  Vec3 to_program(const Vec3& m) const {
    return glm::transpose(frame.rotation) * (m - frame.origin);
  }

  void update_frame() {
    if (frame.tilted) {
      frame.rotation = tilt.rotation;
      frame.origin = tilt.origin + length_shift();
    } else if (raw_rotary()) {
      // Raw rotary programs: X Y Z (after the work offset) are the machine's linear axes.
      Frame m = machine_to_part(*machine.kinematics, frame.rotary_position);
      frame.rotation = m.rotation;
      frame.origin = m.to_world(frame.work_offset + frame.local_offset);
    } else {
      frame.rotation = Mat3(1.0);
      frame.origin = frame.work_offset + frame.local_offset + length_shift();
    }
    tool.ambiguous = frame.tilted && glm::dot(tilt.rotation[2], tool.axis) < 1 - kSameDirection;
  }

  // ---- emitting ----
  void emit(MoveKind kind, const Vec3& a, const Vec3& b, double move_feed, bool from_far = false) {
    if (tool.ambiguous) {
      std::string message = "spindle direction is ambiguous: the plane tilted at line " +
                            std::to_string(tilt.line) +
                            " is not normal to the tool and no G53.1/G53.6/G253 has oriented it";
      if (!options.lenient) error(context.motion_column, message);
      lenient_read(context.motion_column,
                   message + "; read along the current direction " + direction_text(tool.axis) +
                       " (lenient mode)",
                   "move under an ambiguous tilted plane along the current direction " +
                       direction_text(tool.axis));
    }
    if (machine.kinematics && length_shift() != Vec3(0.0))
      error(context.motion_column,
            "the tool length offset (" + format_number(tool.length_offset) +
                " mm) differs from the loaded tool " + std::to_string(tool.number) + "'s length (" +
                format_number(loaded_length()) +
                " mm) on a machine with rotary axes, which tridex does not simulate: "
                "use G43 H" +
                std::to_string(tool.number) + " (or G43.4), or a tool table without tool lengths");
    Move move;
    move.line = context.line;
    move.file = context.file_index;
    move.kind = kind;
    move.tool = tool.number;
    move.start = a - frame.world_origin;
    move.end = b - frame.world_origin;
    move.axis = tool.axis;
    move.feed = move_feed;
    move.from_far = from_far;
    move.spindle = modal.speed * modal.spindle_direction;
    if (simultaneous.active) {  // a cut that turns the rotaries: its true start (rotary.cpp)
      simultaneous.active = false;
      move.start = simultaneous.tip - frame.world_origin;
      move.pose = simultaneous.pose;
      move.rotary_start = simultaneous.rotary;
    }
    if (machine.kinematics) {
      for (const RotaryAxis& rotary_axis : machine.kinematics->axes)
        move.rotary_axes |= static_cast<unsigned char>(1u << rotary_index(rotary_axis.letter));
      move.rotary = frame.rotary_position;
      move.machine = machine_from_part(*machine.kinematics, b, frame.rotary_position);
    }
    if (summary.last_tool_used != tool.number) {
      summary.last_tool_used = tool.number;
      if (summary.tools_used.insert(tool.number).second)
        summary.tool_first_line.emplace(tool.number, context.line);
    }
    (*sink)(move);
  }

  // A G4 or cycle P word's time in seconds: LinuxCNC reads seconds, Fanuc milliseconds.
  double dwell_seconds(double p) const {
    return machine.dialect == Dialect::linuxcnc ? p : p / 1000.0;
  }
  void emit_dwell(double seconds) {
    if (seconds > 0 && dwell_sink && *dwell_sink)
      (*dwell_sink)(Dwell{context.line, tool.number, tool.axis, seconds});
  }

  // ---- cutter radius compensation (comp.cpp) ----
  // Side: +1 left (G41), −1 right (G42), 0 off. Compensated moves wait in comp.queue until the
  // next move tells where they end (LinuxCNC's queue of canonical moves, interp_queue.cc).
  struct CompMove {
    enum Kind { straight, arc } kind = straight;
    MoveKind move_kind = MoveKind::feed;
    int line = 0;
    double feed = 0;
    Vec2 direction{0.0};        // straight: the direction it was programmed in, for the gouge check
    Vec3 end{0.0};              // program frame
    Vec2 centre{0.0};           // arc
    int turn = 0;               // arc: +1 counter-clockwise, −1 clockwise
    int extra_turns = 0;        // arc: full circles before its end (LinuxCNC's P − 1)
    double original_sweep = 0;  // arc: signed radians when queued (0: never checked)
  };
  // Cutter radius compensation (comp.cpp).
  struct CutterComp {
    int side = 0;
    double radius = 0;  // mm, ≥ 0
    int offset_d = -1;  // Fanuc: the last D word, modal (#4107); -1: none yet
    // Fanuc/Haas: the D offsets a program wrote (G10 L12/L13, or a macro variable such as #13001)
    // and what wrote them ("G10 L12 at line 3"), and their geometry and wear as written (mm).
    std::map<int, std::string> d_set_at;
    std::map<int, double> d_geometry, d_wear;
    bool first = true;  // the next compensated move is the entry move
    // Fanuc/Haas: the entry move's end waits for the next move's start direction (comp.cpp).
    bool entry_pending = false;
    bool arc_forbidden = false;       // just after G40: the next move must be straight
    bool programmed_current = false;  // coordinates count from programmed, not the tip
    Vec3 programmed{0.0};             // the last programmed point (program frame)
    Vec3 current{0.0};                // where the queued moves end (program frame)
    std::vector<CompMove> queue;
    Vec2 endpoint{0.0};  // where the queued moves start (program frame)
    bool endpoint_valid = false;
  };
  CutterComp comp;
  // Radius per unit of a D register: 1 (it holds a radius), 0.5 (a diameter), none where the
  // machine does not say (Haas, whose setting 40 decides).
  std::optional<double> d_register_scale() const {
    if (machine.d_offsets == DOffsets::diameter) return 0.5;
    if (machine.d_offsets == DOffsets::radius || machine.dialect != Dialect::haas) return 1.0;
    return std::nullopt;
  }
  double d_offset_radius(int number, int column, const std::string& code);  // comp.cpp
  void comp_resolve_entry(const Vec2& next_direction);
  bool comp_active() const { return comp.side != 0 && comp.radius > 0; }
  // A program point's coordinates in the active plane, (u, v) of plane_axes (G17: X Y; G18: Z X,
  // LinuxCNC's order for compensation), and a point with those replaced.
  Vec2 plane_uv(const Vec3& p) const {
    const std::array<int, 3> a = plane_axes(modal.plane);
    return Vec2(p[a[0]], p[a[1]]);
  }
  Vec3 with_plane_uv(Vec3 p, const Vec2& q) const {
    const std::array<int, 3> a = plane_axes(modal.plane);
    p[a[0]] = q.x;
    p[a[1]] = q.y;
    return p;
  }
  void cutter_comp_codes(int code, int column);  // G40, G41, G42, G41.1, G42.1
  void comp_forbid(int column, const std::string& what) const;
  void comp_straight(MoveKind kind, const Vec3& target, double move_feed);
  void comp_straight_entry(CompMove& move, const Vec3& target);
  void comp_arc(bool ccw);
  void comp_arc_entry(CompMove& move, bool ccw, bool inside, const std::string& too_small);
  void comp_move_endpoint_and_flush(const Vec2& to);
  void comp_dequeue();
  void comp_finish() {  // at the end of the program: emit what waits
    if (!comp.queue.empty()) comp_move_endpoint_and_flush(plane_uv(comp.current));
  }

  // ---- motion (motion.cpp) ----
  void move_to(Vec3 target, const std::array<bool, 3>& set_absolute, const Mat3& rot,
               const Vec3& org, MoveKind kind, double move_feed);
  // The point the block's X Y Z words name, in the program frame, from `current`; set[i] says
  // coordinate i was given absolutely (motion.cpp).
  struct Target {
    Vec3 point{0.0};
    std::array<bool, 3> set{};
  };
  Target axis_word_target(const Vec3& current);  // takes the words
  void linear(MoveKind kind, double move_feed);
  void require_feed();
  void arc(bool ccw);
  struct ArcData {
    Vec3 end{0.0};                 // program frame
    Vec2 centre{0.0};              // in the plane's (u, v)
    double programmed_radius = 0;  // R arcs: |R|; 0 for I/J/K
  };
  ArcData arc_data(const Vec3& start, bool ccw);
  double arc_sweep(const Vec3& start, const Vec3& end, const Vec2& c, bool ccw) const;
  double arc_length(const Vec3& start, const ArcData& a, bool ccw, int extra_turns = 0) const;
  int arc_extra_turns();
  void arc_chords(const Vec3& start, const Vec3& end, const Vec2& c, bool ccw, double sweep,
                  double move_feed);
  void cycle(int code);
  // A canned cycle's levels along its axis (program frame), and whether it clears far.
  struct CycleLevels {
    double r_level = 0, bottom = 0, clear = 0;
    bool clear_far = false;
  };
  long long cycle_words(int code, char depth_letter);
  CycleLevels cycle_levels(int code, double current);
  Vec3 cycle_point(double u_coordinate, double v_coordinate, double depth) const;
  void cycle_rapid(const Vec3& to);
  void cycle_cut(const Vec3& to);
  void cycle_hole(int code, double hole_u, double hole_v, const CycleLevels& levels);
  // LinuxCNC's G5 / G5.1 splines as biarcs (spline.cpp).
  void spline(bool quadratic);
  void biarc(const Vec2& p0, const Vec2& t0, const Vec2& p4, const Vec2& t4, double z);
  void spline_piece(const Vec2& from, const Vec2& to, const Vec2& tangent, double z);
  // LinuxCNC's G5.2/G5.3 NURBS (spline.cpp): a control point per G5.2 block, the cut at G5.3.
  void nurbs_point();
  void nurbs_end(int column);
  void nurbs_feed(std::vector<NurbsPoint> control, int order, const Vec2& end, double z);
  void probe(int code);  // LinuxCNC's G38.2–G38.5 (motion.cpp)
  void machine_move(const Vec3& target, unsigned mask, MoveKind kind, double move_feed);
  void polar_words(bool axis_consumer,
                   int nonmodal);  // LinuxCNC @ and ^ become X and Y (motion.cpp)
  void home_return(bool second);
  void tool_length_codes();    // G43 H, G43.1, G44 H, G49 (modal.cpp)
  void load_tool(int number);  // the tip moves with the tool's length (modal.cpp)
  void go_far() {
    tool.far = true;
    tool.far_axis = Vec3(0.0);
  }
  Flow macro_call(int column);               // G65 (modal.cpp)
  void local_offsets(int code, int column);  // G52, G92, G92.1, G92.2, G92.3 (modal.cpp)

  // ---- rotary axes, DWO and TCP (rotary.cpp) ----
  void tool_center_codes();
  void kinematics_switch_code();
  void rotary_words();
  void simultaneous_start(int column);
  void extra_linear_words(bool track);  // LinuxCNC's U/V/W
  void set_rotary(const RotaryPositions& next);
  // A cut that turns the rotaries (rotary.cpp): where its tool started (the tip on the part and
  // the rotary positions before the block's words), for the move the block emits next.
  struct SimultaneousStart {
    bool active = false;
    PoseLaw pose = PoseLaw::joints;
    Vec3 tip{0.0};
    RotaryPositions rotary{};
  };
  SimultaneousStart simultaneous;

  // ---- tilted planes (tilted_plane_codes.cpp) ----
  std::optional<Frame> plane_words(int code);  // nullopt: a several-block form awaits more blocks
  std::optional<Frame> several_block_plane(int code, int p);
  std::string incomplete_plane() const;
  void tilted_plane(int code);
  void orient_to_plane(int code);

  // ---- one block (modal.cpp): execute calls a stage per modal group, in RS274/NGC's order ----
  Flow execute(const Block& block);
  // The block's codes that decide the later stages (-1: none), and whether a code other than the
  // motion takes its X/Y/Z (G10, G52, G92, a tilted plane).
  struct BlockCodes {
    int motion = -1;
    int nonmodal = -1;
    int tilt = -1;
    int orient = -1;
    bool axis_consumer = false;
    bool modal_g = false;  // a G code other than G0 and G1 (execute's modal stages look for one)
  };
  BlockCodes block_codes();
  void units_codes();
  void tool_change_codes();  // T, M6, M61
  void spindle_codes();
  void dwell_code(const BlockCodes& codes);
  void plane_codes();
  void distance_mode_codes();
  void smoothing_codes(const BlockCodes& codes);
  void return_mode_codes();
  void work_system_codes();
  void offset_codes(BlockCodes& codes);             // G52, G92, G10
  void work_offset_entry(long long l, int column);  // G10 L2, L20
  void tilted_plane_group(BlockCodes& codes);
  void motion_mode_codes(const BlockCodes& codes);
  void axis_words(const BlockCodes& codes);
  void block_move(const BlockCodes& codes);
  void machine_coordinate_move();  // G53
  void motion_mode_move(bool new_code);
  Flow flow_codes();
  void check_words_used();
};

// Runs a whole program through `state` (flow.cpp).
void run_program(Interpreter::State& state, std::istream& program, const std::string& file_name);
// One piece of a program fed in pieces: continues from state.continuation, updates it, and leaves
// the end-of-program checks to Interpreter::finish().
void run_program_piece(Interpreter::State& state, std::istream& piece,
                       const std::string& file_name);

}  // namespace tridex::gcode
