// tridex::gcode — the modal machine: one block's codes applied in RS274/NGC's order of execution
// (NIST IR 6556 §3.8): units, feed, speed, tool, dwell, plane, distance modes, offsets, tilted
// planes, motion, program flow.
#include <cmath>

#include "state.hpp"

namespace tridex::gcode {

// A tool goes into the spindle: the gauge point stays, so the tip moves by the difference of
// the two tools' lengths (no move: the tool changed, rs274's CHANGE_TOOL keeps the position).
void Interpreter::State::load_tool(int number) {
  double before = loaded_length();
  tool.number = number;
  tool.pos += (before - loaded_length()) * tool.axis;
  update_frame();
}

// Tool length offsets (RS274/NGC, NIST IR 6556 §3.6.3; LinuxCNC's G43, G43.1, G49): G43 H n
// takes tool n's length (no H: the loaded tool's, as LinuxCNC does; H0: none), Fanuc's G44 H n
// its negative, LinuxCNC's G43.1 Z the length written, G49 none. G43.4/G43.5 H n (TCP), and
// Haas's G234 H n (its TCPC), take it as G43 does. With no tool lengths in the machine, they all
// leave the path alone.
void Interpreter::State::tool_length_codes() {
  int code = 0, column = 0;
  for (int c : {kG43, kG43_1, kG43_4, kG43_5, kG234, kG44, kG49})
    if (int at = w.find_g(c)) {
      code = c;
      column = at;
    }
  if (!code) return;
  double next = 0;
  if (code == kG43_1) {
    if (machine.dialect != Dialect::linuxcnc)
      unsupported(column, "G43.1 (LinuxCNC's dynamic tool length offset) needs --machine linuxcnc",
                  "G43.1", false);
    for (char c : {'X', 'Y'})
      if (w.has(c))
        error(w.col(c), std::string("G43.1 ") + c + ": a sideways tool offset is not simulated");
    if (!w.has('Z')) error(column, "G43.1 needs Z (the tool length offset)");
    next = length('Z');
    w.present &= ~(1u << letter_index('Z'));  // an offset here, not a coordinate
  } else if (code != kG49) {
    int number = tool.number;
    if (w.has('H'))
      number = static_cast<int>(integer('H', "tool length offset number", 0, 99'999'999));
    if (std::optional<double> table = table_length(number)) {
      next = code == kG44 ? -*table : *table;
    } else if (number != 0 && !machine.tool_lengths.empty()) {
      error(w.has('H') ? w.col('H') : column,
            "H" + std::to_string(number) + ": tool " + std::to_string(number) +
                " has no length in the tool table (\"tool-length\", or Z in a LinuxCNC .tbl)");
    }
  }
  if (machine.tool_lengths.empty()) next = 0;  // no lengths known: the programmed point is the tip
  if (next != tool.length_offset) comp_forbid(column, "changing the tool length offset");
  tool.length_offset = next;
  update_frame();
}

// The feed mode, F and S, in RS274/NGC's order (feed mode first). LinuxCNC's G94 and G95 set the
// feed rate to 0 (interp_convert.cc convert_feed_mode), so a feed move after them needs a new F;
// the other dialects clear it when the mode changes. Under G93, F is the block's 1/min (read in
// require_feed, only from the block itself, as LinuxCNC does); under G95 the rate is F × S.
void Interpreter::State::feed_mode_codes() {
  for (int code : {kG93, kG94, kG95}) {
    if (!w.find_g(code)) continue;
    FeedMode next = code == kG93   ? FeedMode::inverse_time
                    : code == kG94 ? FeedMode::per_minute
                                   : FeedMode::per_revolution;
    bool clears = machine.dialect == Dialect::linuxcnc ? code != kG93 : next != modal.feed_mode;
    if (clears) modal.feed = modal.feed_per_rev = 0;
    modal.feed_mode = next;
  }
  if (w.has('F')) {
    if (w.value[static_cast<std::size_t>(letter_index('F'))] < 0)
      error(w.col('F'), "feed rate F must not be negative");
    if (modal.feed_mode == FeedMode::inverse_time)
      modal.inverse_time = w.take('F');
    else if (modal.feed_mode == FeedMode::per_revolution)
      modal.feed_per_rev = length('F');
    else
      modal.feed = length('F');
  }
  if (w.has('S')) {
    double s = w.take('S');
    if (s < 0) error(w.col('S'), "spindle speed S must not be negative");
    modal.speed = s;
  }
  if (modal.feed_mode == FeedMode::per_revolution) modal.feed = modal.feed_per_rev * modal.speed;
}

// LinuxCNC's G10 L1 / L10 / L11 P<tool> (interp_convert.cc convert_setup_tool): set the tool
// table entry of tool P. L1: Z is its length and R its radius. L10: the length that makes the
// current position read Z under G43 of that tool (the gauge point as the control knows it, in
// the active work system, G52/G92 included, minus Z); L11: the same in G59.3 without G52/G92.
// A later G43 H / G41 D reads the entry; nothing moves now. X/Y (sideways and lathe offsets) and
// the other axes' offsets are not simulated: an error. I, J (lathe angles) and Q (orientation)
// are read and leave the mill alone.
void Interpreter::State::tool_table_entry(long long l, int column) {
  const std::string name = "G10 L" + std::to_string(l);
  if (!w.has('P')) error(column, name + " needs P (the tool number)");
  int number = static_cast<int>(integer('P', (name + " P (a tool number)").c_str(), 0, 99'999'999));
  bool any = false;
  for (char c : {'X', 'Y', 'Z', 'A', 'B', 'C', 'U', 'V', 'W', 'R', 'Q', 'I', 'J'}) any |= w.has(c);
  if (!any) error(column, name + " without offsets has no effect");
  for (char c : {'X', 'Y', 'A', 'B', 'C', 'U', 'V', 'W'})
    if (w.has(c))
      error(w.col(c), name + " " + c + ": a tool offset along " + c +
                          " is not simulated (tridex offsets tools along their axis only)");
  if (w.has('Q')) {
    double q = w.take('Q');
    if (std::abs(q - std::round(q)) > 1e-9) error(w.col('Q'), "Q number in G10 is not an integer");
    if (q > 9) error(w.col('Q'), "invalid tool orientation Q" + format_number(q));
  }
  for (char c : {'I', 'J'})
    if (w.has(c)) w.take(c);
  // The radius of compensation already on stays (LinuxCNC reads it at G41/G42).
  if (w.has('R')) machine.tool_diameters[number] = 2 * length('R');
  if (!w.has('Z')) return;
  if (l == 1) {
    tool_table.lengths[number] = length('Z');
    return;
  }
  if (tool.far)
    error(column, name + " with the tool retracted far along its axis: its position is unknown");
  if (frame.tilted || machine.kinematics || glm::dot(tool.axis, Vec3(0, 0, 1)) < 1 - kSameDirection)
    error(column, name + " with a tilted frame or rotary axes is not simulated");
  // linear_axes(): the controlled point in machine coordinates; the control puts the gauge point
  // the active offset above it.
  double gauge = linear_axes().z + tool.length_offset;
  double system = 0;
  if (l == 10) {
    system = frame.work_offset.z + frame.local_offset.z;
  } else if (auto it = frame.offsets.find(9);
             it != frame.offsets.end()) {  // G59.3 (never set by tridex: 0)
    system = it->second.z;
  }
  tool_table.lengths[number] = gauge - system - length('Z');
}

// Fanuc's and Haas's G10 L10 / L11 P<offset> R<value> (Fanuc 0i-MF operator's manual, "Tool
// compensation values input by program", memory C; Haas's G10, where L1 is L11): the tool length
// geometry (L10) or wear (L11) of H offset P, set to R under G90 and changed by R under G91. G43 H
// reads geometry plus wear; a geometry never set is the machine's length of tool P. Their cutter
// radius offsets (L12, L13) hold a radius on Fanuc and a diameter or a radius on Haas (its setting
// 40, the machine file's "d_offsets"): G41/G42 D and the macro variables read them (comp.cpp,
// parameters.cpp).
void Interpreter::State::tool_length_entry(long long l, int column) {
  const bool radius = l == 12 || l == 13;
  const std::string name = "G10 L" + std::to_string(l),
                    offset = radius ? "cutter radius" : "tool length";
  if (!w.has('P')) error(column, name + " needs P (the " + offset + " offset number)");
  if (!w.has('R')) error(column, name + " needs R (the offset's value)");
  const int number = static_cast<int>(
      integer('P', (name + " P (a " + offset + " offset number)").c_str(), 0, 99'999'999));
  if (radius) {
    comp.d_set_at[number] = name + " at line " + std::to_string(context.line);
    double& value = (l == 12 ? comp.d_geometry : comp.d_wear)[number];
    value = (modal.incremental ? value : 0) + length('R');
    return;
  }
  for (char c : {'X', 'Y', 'Z', 'A', 'B', 'C'})
    if (w.has(c)) error(w.col(c), name + " " + c + ": a tool length offset takes R only");
  double value = length('R');
  if (l == 10) {
    tool_table.lengths[number] =
        (modal.incremental ? length_geometry(number).value_or(0) : 0) + value;
  } else {
    double& wear = tool_table.wear[number];
    wear = (modal.incremental ? wear : 0) + value;
  }
}

// One block, in RS274/NGC's order of execution (NIST IR 6556 §3.8, table 8; LinuxCNC's
// execute_block and convert_g): the codes that change how later words read come before the ones
// that read them, and the move comes after every mode it depends on.
//   1. G65 (a macro call takes the whole block)      9. tool length G43/G44/G49, TCP, DWO
//   2. units G20/G21                                10. look-ahead and smoothing (no effect)
//   3. feed mode G93/G94/G95, F, S                   11. cycle return G98/G99
//   4. tool: T, M6, M61                              12. work system G54-G59.3, G54.1, G154
//   5. spindle M3/M4/M5, kinematics switches         13. G52/G92 offsets and G10 tables
//   6. dwell G4                                      14. tilted plane G68.x and its orienting
//   7. plane G17/G18/G19                             15. motion mode, then the axis words' moves
//   8. cutter compensation, distance modes           16. program flow M2/M30/M97/M98/M99
// Last, every word of the block must have been read by some code.
Flow Interpreter::State::execute(const Block& block) {
  gather(block);
  // A G68.2 P2/P3 plane under way takes the next blocks.
  if (tilt.plane_blocks.code && !w.find_g(tilt.plane_blocks.code))
    error(block.words.front().column, incomplete_plane());
  if (int column = w.find_g(kG65)) return macro_call(column);
  BlockCodes codes = block_codes();
  // Most blocks of a CAM program hold no G code but G0/G1 (`X.. Y.. Z..`): the stages marked
  // below look only for their own G codes, so such a block skips them (the hot path of plain
  // programs stays free of compensation's, kinematics' and the modal groups' look-ups).
  if (codes.modal_g) units_codes();
  feed_mode_codes();
  tool_change_codes();
  spindle_codes();
  kinematics_switch_code();  // M428-style switches, as LinuxCNC's user M-codes (rotary.cpp)
  if (codes.nonmodal == kG4) dwell_code(codes);
  if (codes.modal_g) {
    plane_codes();
    // Cutter radius compensation (comp.cpp): after the plane, before motion (NIST IR 6556 §3.8).
    for (int code : {kG40, kG41, kG42, kG41_1, kG42_1})
      if (int column = w.find_g(code)) cutter_comp_codes(code, column);
    distance_mode_codes();
    tool_length_codes();
    tool_center_codes();  // G43.4/G43.5/G234 TCP, G254/G255 DWO (rotary.cpp)
    smoothing_codes(codes);
    return_mode_codes();
    work_system_codes();
  }
  offset_codes(codes);
  tilted_plane_group(codes);  // tilted_plane_codes.cpp
  motion_mode_codes(codes);
  axis_words(codes);
  block_move(codes);
  Flow flow = flow_codes();
  check_words_used();
  return flow;
}

// The codes that decide the later stages, and the column a move's diagnostics point at: its
// motion or non-modal code, else its first coordinate, else the block's start.
Interpreter::State::BlockCodes Interpreter::State::block_codes() {
  BlockCodes codes;
  context.motion_column = 0;
  for (int i = 0; i < w.g_count; ++i) {
    const Code& g = w.g[static_cast<std::size_t>(i)];
    if (g.code != kG0 && g.code != kG1) codes.modal_g = true;
    int group = block_g_group(g.code);
    if (group == kMotion) {
      codes.motion = g.code;
      context.motion_column = g.column;
    } else if (group == kNonModal) {
      codes.nonmodal = g.code;
      if (g.code != kG4) context.motion_column = g.column;
    } else if (group == kTilt) {
      codes.tilt = g.code;
    } else if (group == kOrient) {
      codes.orient = g.code;
    }
  }
  if (context.motion_column == 0) {
    context.motion_column = 1;
    for (char c : {'X', 'Y', 'Z'})
      if (w.has(c)) {
        context.motion_column = w.col(c);
        break;
      }
  }
  return codes;
}

// Units first, so that every length in this block is read in them.
void Interpreter::State::units_codes() {
  for (int code : {kG20, kG21}) {
    int column = w.find_g(code);
    if (!column) continue;
    double next = code == kG20 ? 25.4 : 1.0;
    if (next != modal.unit) comp_forbid(column, "changing units");
    modal.unit = next;
  }
}

// T selects a tool; M6 (or T alone, on a machine whose T loads the tool) loads it, LinuxCNC's
// M61 Q says which tool the spindle holds.
void Interpreter::State::tool_change_codes() {
  if (w.has('T')) {
    tool.selected = static_cast<int>(integer('T', "tool number", 0, 99'999'999));
    summary.selects_tool = true;
  }

  if (w.find_m(kM6) || (w.has('T') && machine.tool_loads_on_t)) {
    comp_forbid(w.find_m(kM6) ? w.find_m(kM6) : w.col('T'), "a tool change");
    comp.programmed_current = false;  // LinuxCNC resynchronises with where the tool really is
    load_tool(tool.selected);
    summary.tool_first_line.emplace(tool.number, context.line);
    if (machine.tool_change == ToolChange::retract_far) go_far();
    if (machine.tool_change == ToolChange::to_position) {
      if (glm::dot(tool.axis, Vec3(0, 0, 1)) < 1 - kSameDirection)
        error(w.find_m(kM6) ? w.find_m(kM6) : w.col('T'),
              "a tool change to the machine's tool-change position with a tilted tool depends on "
              "the kinematics; retract (G28 or G53 Z) and cancel the tilt first");
      Vec3 tip = tip_below(machine.tool_change_position);
      if (!tool.far) emit(MoveKind::rapid, tool.pos, tip, 0.0);
      tool.pos = tip;
    }
  }
  if (int column = w.find_m(kM61)) {  // LinuxCNC: the tool in the spindle is Q (nothing moves)
    if (!w.has('Q')) error(column, "M61 needs Q (the tool number)");
    tool.selected = static_cast<int>(integer('Q', "M61 tool number", 0, 99'999'999));
    summary.selects_tool = true;
    load_tool(tool.selected);
  }
}

void Interpreter::State::spindle_codes() {
  if (w.find_m(kM3)) modal.spindle_direction = 1;
  if (w.find_m(kM4)) modal.spindle_direction = -1;
  if (w.find_m(kM5)) modal.spindle_direction = 0;
}

// G4: dwell P (seconds or ms) or, on Fanuc, X.
void Interpreter::State::dwell_code(const BlockCodes& codes) {
  // Fanuc's `G4 X2.` dwells; beside P, or with a motion code in the block, X is a coordinate.
  bool x_dwell = !w.has('P') && w.has('X') && codes.motion < 0;
  char c = w.has('P') ? 'P' : x_dwell ? 'X' : 0;
  if (!c) error(w.find_g(kG4), "G4 needs a dwell time P");
  double time = w.take(c);
  if (time < 0) error(w.col(c), "dwell time must not be negative");
  if (c == 'X') w.present &= ~(1u << letter_index('X'));  // a time here, not a coordinate
  emit_dwell(c == 'X' ? time : dwell_seconds(time));
}

void Interpreter::State::plane_codes() {
  for (int code : {kG17, kG18, kG19})
    if (int column = w.find_g(code)) {
      if (code != modal.plane) comp_forbid(column, "changing the plane");
      modal.plane = code;
    }
}

// G90/G91 (coordinates), G90.1/G91.1 (arc centres).
void Interpreter::State::distance_mode_codes() {
  if (w.find_g(kG90)) modal.incremental = false;
  if (w.find_g(kG91)) modal.incremental = true;
  if (w.find_g(kG90_1)) modal.arc_absolute = true;
  if (w.find_g(kG91_1)) modal.arc_absolute = false;
}

// Look-ahead and smoothing modes change how the control follows the path, not the path: their
// words are read and dropped.
void Interpreter::State::smoothing_codes(const BlockCodes& codes) {
  if (w.find_g(kG5_1) && codes.motion != kG5_1) {  // Fanuc's G5.1 Q (a spline G5.1 is a motion)
    for (char c : {'Q', 'R'})
      if (w.has(c)) w.take(c);
  }
  if (w.find_g(kG8) && w.has('P')) w.take('P');
  if (w.find_g(kG187)) {
    for (char c : {'P', 'E'})
      if (w.has(c)) w.take(c);
  }
  if (w.find_g(kG103) && w.has('P')) w.take('P');  // Haas: blocks of look-ahead
  if (w.find_g(kG64)) {  // path blending tolerances (LinuxCNC G64 P Q): no effect on the path
    if (w.has('P')) w.take('P');
    if (w.has('Q')) w.take('Q');
  }
}

void Interpreter::State::return_mode_codes() {
  if (w.find_g(kG98)) modal.retract_to_r = false;
  if (w.find_g(kG99)) modal.retract_to_r = true;
}

// The work coordinate system: G54-G59, G54.1 P, Haas's G154 P.
void Interpreter::State::work_system_codes() {
  for (int code : {kG54, kG55, kG56, kG57, kG58, kG59, kG54_1, kG154}) {
    int column = w.find_g(code);
    if (!column) continue;
    int key = (code - kG54) / 10 + 1;
    if (code == kG54_1) {
      if (!w.has('P')) error(column, "G54.1 needs P (1-300)");
      key = MachineConfig::g54_1_key(static_cast<int>(integer('P', "G54.1 number", 1, 300)));
    } else if (code == kG154) {  // Haas: the same extra offsets as G54.1 P1-P99
      if (!w.has('P')) error(column, "G154 needs P (1-99)");
      key = MachineConfig::g54_1_key(static_cast<int>(integer('P', "G154 number", 1, 99)));
    }
    if (frame.tilted && key != frame.work_key)
      error(column, "work coordinates change while a tilted plane is active (cancel it first)");
    if (key != frame.work_key) comp_forbid(column, "changing the work coordinate system");
    frame.work_key = key;
    auto it = frame.offsets.find(key);
    frame.work_offset = it == frame.offsets.end() ? Vec3(0.0) : it->second;
    update_frame();
  }
}

// G52 and G92 (local offsets) and G10 (offset tables): non-modal codes whose X/Y/Z are theirs.
void Interpreter::State::offset_codes(BlockCodes& codes) {
  const int nonmodal = codes.nonmodal;
  if (nonmodal == kG52 || (nonmodal >= kG92 && nonmodal <= kG92_3)) {
    codes.axis_consumer = true;
    comp_forbid(w.find_g(nonmodal), code_name('G', nonmodal));
    local_offsets(nonmodal, w.find_g(nonmodal));
  }
  if (nonmodal == kG10) {
    codes.axis_consumer = true;
    int column = w.find_g(kG10);
    bool linuxcnc_tools = machine.dialect == Dialect::linuxcnc;
    if (!w.has('L'))
      error(column, linuxcnc_tools                     ? "G10 needs L1, L2, L10, L11 or L20"
                    : machine.dialect == Dialect::haas ? "G10 needs L1, L2, L10-L13 or L20"
                                                       : "G10 needs L2, L10-L13 or L20");
    long long l = integer('L', "G10 L", 0, 99);
    if (linuxcnc_tools && (l == 1 || l == 10 || l == 11)) {
      tool_table_entry(l, column);
    } else if (!linuxcnc_tools &&
               ((l >= 10 && l <= 13) || (l == 1 && machine.dialect == Dialect::haas))) {
      tool_length_entry(l, column);
    } else if (l != 2 && l != 20) {
      unsupported(column,
                  "G10 L" + std::to_string(l) + " is not supported (only L2 and L20" +
                      (linuxcnc_tools ? ", and L1, L10, L11" : ", and L10-L13 for tool offsets") +
                      ")",
                  "G10 L");
    } else {
      work_offset_entry(l, column);
    }
  }
}

// G10 L2 / L20 P: a work offset. Fanuc: L2 P1-6 sets G54-G59, L20 Pn sets G54.1 Pn. LinuxCNC:
// P1-6 are G54-G59 for both, and L20 sets the offset that makes the current position read X Y Z.
// P0: the active one.
void Interpreter::State::work_offset_entry(long long l, int column) {
  if (!w.has('P')) error(column, "G10 L" + std::to_string(l) + " needs P");
  bool linuxcnc = machine.dialect == Dialect::linuxcnc;
  int key = 0;
  if (l == 2 || linuxcnc) {
    if (w.has('R'))
      unsupported(w.col('R'),
                  "G10 L" + std::to_string(l) + " R (a rotated coordinate system) is not supported",
                  "G10 R", false);
    key = static_cast<int>(integer('P', linuxcnc ? "G10 P" : "G10 L2 P", 0, 6));
  } else {
    key = MachineConfig::g54_1_key(static_cast<int>(integer('P', "G10 L20 P", 0, 300)));
    if (key == MachineConfig::g54_1_key(0)) key = 0;
  }
  if (key == 0) key = frame.work_key;
  if (modal.incremental)
    error(column, "G10 under G91 is read differently by different controls; use G90");
  Vec3 value = frame.offsets.count(key) ? frame.offsets[key] : Vec3(0.0);
  bool relative_to_position = linuxcnc && l == 20;
  if (relative_to_position && tool.far)
    error(column, "G10 L20 with the tool retracted far along its axis: its position is unknown");
  for (int i = 0; i < 3; ++i)
    if (w.has(kAxisLetter[i]))
      value[i] = relative_to_position
                     ? linear_axes()[i] - frame.local_offset[i] - length(kAxisLetter[i])
                     : length(kAxisLetter[i]);
  // A rotary offset of 0 changes nothing, nor do LinuxCNC's plain A/B/C (no kinematics). On a
  // machine whose kinematics has the axis it shifts that axis's zero, as X Y Z's (Fanuc's work
  // offsets hold every axis: an HMC's `G10 L2 P1 X… Y… Z… B…` sets G54's B). Elsewhere it would
  // turn the part under the program: an error.
  RotaryPositions rotary =
      frame.rotary_offsets.count(key) ? frame.rotary_offsets[key] : RotaryPositions{};
  for (char c : {'A', 'B', 'C'}) {
    if (!w.has(c)) continue;
    const int col = w.col(c);
    const double angle = w.take(c);
    if (machine.kinematics && machine.kinematics->find(c) && !linuxcnc) {
      rotary[static_cast<std::size_t>(rotary_index(c))] = angle;
    } else if (angle != 0 && !(linuxcnc && !machine.kinematics)) {
      error(col, std::string("G10 ") + c + format_number(angle) +
                     ": a rotary work offset other than 0 is simulated only on a machine whose "
                     "kinematics has that axis");
    }
  }
  if (rotary != RotaryPositions{} || frame.rotary_offsets.count(key))
    frame.rotary_offsets[key] = rotary;
  if (key == frame.work_key) comp_forbid(column, "G10 on the active work offset");
  frame.offsets[key] = value;
  if (key == frame.work_key) {
    if (frame.tilted) error(column, "G10 changes the active work offset under a tilted plane");
    frame.work_offset = value;
    update_frame();
  }
}

// The tilted working plane (G68.x, G268, G69; tilted_plane_codes.cpp) and its orienting codes.
void Interpreter::State::tilted_plane_group(BlockCodes& codes) {
  if (codes.tilt >= 0) {
    comp_forbid(w.find_g(codes.tilt), code_name('G', codes.tilt));
    if (codes.tilt != kG69 && codes.tilt != kG269) codes.axis_consumer = true;
    tilted_plane(codes.tilt);
  }
  if (codes.orient >= 0) orient_to_plane(codes.orient);
}

// The motion mode (group 1): a new code ends a canned cycle of another kind, and G5.2 control
// points not ended by G5.3.
void Interpreter::State::motion_mode_codes(const BlockCodes& codes) {
  const int motion_code = codes.motion;
  if (motion_code < 0) return;
  if (codes.axis_consumer && motion_code != kG80)
    error(context.motion_column,
          code_name('G', motion_code) + " in a block whose X/Y/Z belong to another code");
  if (motion_code == kG80 || !is_cycle(motion_code)) canned.active = false;
  if (is_cycle(motion_code) && modal.motion != motion_code) canned.active = false;
  if (modal.motion == kG5_2 && motion_code != kG5_2 && !splines.nurbs_points.empty())
    warn(context.motion_column, "the G5.2 control points before this " +
                                    code_name('G', motion_code) +
                                    " are dropped: no G5.3 ended them (LinuxCNC drops them too)");
  if (motion_code == kG5_2 && modal.motion != kG5_2)
    splines.nurbs_points.clear();  // a new curve starts
  if (motion_code != kG80 && !is_cycle(motion_code)) modal.group01 = motion_code;
  // Fanuc and Haas keep the canned cycles in group 09 and G0-G3 in group 01 (FANUC 0i-MF
  // operator's manual B-64604EN, "G code list": G80-G89 group 09; Haas mill operator's manual,
  // "G80 Canned Cycle Cancel (Group 09)"): G80 ends the cycle and leaves the group-01 mode that
  // was in force, so a bare `Z0.5` after it moves in that mode. LinuxCNC's cycles are motion
  // modes: G80 leaves none, and rs274 refuses axis words until one is given.
  modal.motion =
      motion_code == kG80 && machine.dialect != Dialect::linuxcnc ? modal.group01 : motion_code;
}

// The words beside X Y Z that a move reads: LinuxCNC's polar @ ^, the rotary A B C, U V W.
void Interpreter::State::axis_words(const BlockCodes& codes) {
  const int nonmodal = codes.nonmodal;
  if (w.has('@') || w.has('^')) polar_words(codes.axis_consumer, nonmodal);
  if (w.has('A') || w.has('B') || w.has('C'))
    comp_forbid(w.col(w.has('A') ? 'A' : w.has('B') ? 'B' : 'C'), "a rotary axis word");
  if (!codes.axis_consumer && nonmodal != kG28 && nonmodal != kG30) rotary_words();
  extra_linear_words(!codes.axis_consumer && nonmodal < 0);
}

// The block's move: a return (G28/G30), a machine-coordinate move (G53), the end of a NURBS
// (G5.3), or the motion mode's move along the axis words.
void Interpreter::State::block_move(const BlockCodes& codes) {
  const int nonmodal = codes.nonmodal;
  if (nonmodal == kG28 || nonmodal == kG30) {
    if (codes.motion >= 0 && codes.motion != kG80)
      error(context.motion_column, "G28/G30 with a motion code in the same block");
    comp_forbid(w.find_g(nonmodal), code_name('G', nonmodal));
    home_return(nonmodal == kG30);
  } else if (nonmodal == kG53) {
    machine_coordinate_move();
  } else if (nonmodal == kG5_3) {  // G5.3: the NURBS of the G5.2 blocks before it (spline.cpp)
    if (codes.motion >= 0 || has_axis_words())
      error(context.motion_column,
            "G5.3 ends a G5.2 NURBS: no motion code or coordinates in its block");
    nurbs_end(context.motion_column);
  } else if (!codes.axis_consumer) {
    motion_mode_move(codes.motion >= 0 && codes.motion != kG80);  // G80 starts no move
  }
}

// G53 X Y Z: a move in machine coordinates. LinuxCNC moves under G0 or G1 and refuses any other
// mode (rs274: "Must use G0 or G1 with G53"). Fanuc's and Haas's G53 is a one-shot positioning
// at rapid traverse whatever the group-01 mode (FANUC 0i-MF operator's manual B-64604EN,
// "Machine coordinate system": "the tool moves to the specified position at rapid traverse";
// Haas mill operator's manual, "G53 Non-Modal Machine Coordinate Selection (Group 00)").
void Interpreter::State::machine_coordinate_move() {
  comp_forbid(w.find_g(kG53), "G53");
  const bool fanuc = machine.dialect != Dialect::linuxcnc;
  if (!fanuc && modal.motion != kG0 && modal.motion != kG1)
    error(context.motion_column, "G53 needs G0 or G1 modal");
  const bool rapid = fanuc || modal.motion == kG0;
  if (!rapid) require_feed();
  Vec3 target(0.0);
  unsigned mask = 0;
  for (int i = 0; i < 3; ++i)
    if (w.has(kAxisLetter[i])) {
      target[i] = length(kAxisLetter[i]);
      mask |= 1u << i;
    }
  if (mask)
    machine_move(target, mask, rapid ? MoveKind::rapid : MoveKind::feed, rapid ? 0.0 : modal.feed);
}

// The active motion mode's move, where the block gives it something to do: axis words, or a
// motion code (`new_code`) or the words its mode reads without coordinates.
void Interpreter::State::motion_mode_move(bool new_code) {
  bool axes = has_axis_words();
  if (modal.motion == kG0 || modal.motion == kG1) {
    // A G1 that only turns the rotaries is a move too: the table turns under the tool.
    if (axes || simultaneous.active) {
      if (modal.motion == kG1) require_feed();
      linear(modal.motion == kG0 ? MoveKind::rapid : MoveKind::feed,
             modal.motion == kG0 ? 0.0 : modal.feed);
    }
    simultaneous.active = false;
  } else if (modal.motion == kG2 || modal.motion == kG3) {
    char cu = kCenterLetter[plane_axes(modal.plane)[0]],
         cv = kCenterLetter[plane_axes(modal.plane)[1]];
    if (axes || new_code || w.has(cu) || w.has(cv) || w.has('R')) arc(modal.motion == kG3);
  } else if (modal.motion >= kG38_2 && modal.motion <= kG38_5) {
    if (axes || new_code) probe(modal.motion);
  } else if (modal.motion == kG5 || modal.motion == kG5_1) {
    if (axes || new_code || w.has('I') || w.has('J') || w.has('P') || w.has('Q'))
      spline(modal.motion == kG5_1);
  } else if (modal.motion == kG5_2) {
    if (axes || new_code || w.has('P') || w.has('L')) nurbs_point();
  } else if (is_cycle(modal.motion)) {
    if (axes || new_code || w.has('R')) {
      comp_forbid(context.motion_column, "a canned cycle");
      cycle(modal.motion);
    }
  } else if (axes) {
    error(context.motion_column,
          "X/Y/Z without an active motion mode (G0, G1, G2, G3, G5, G5.1, G5.2 or a cycle)");
  }
}

// Program flow last: the end (M2, M30), a subprogram call (M98, Haas's M97) or return (M99).
Flow Interpreter::State::flow_codes() {
  Flow flow = Flow::next;
  if (w.find_m(kM2) || w.find_m(kM30)) {
    comp_finish();
    flow = Flow::end;
  }
  for (int m : {kM98, kM97}) {  // M97 P: Haas, a local subprogram at block N P of this program
    const int column = w.find_m(m);
    if (!column) continue;
    const std::string name = m == kM98 ? "M98" : "M97";
    if (!w.has('P'))
      error(column, name + (m == kM98 ? " needs P (the O number to call)"
                                      : " needs P (the N number to call)"));
    call_request.label = static_cast<int>(integer('P', (name + " P").c_str(), 0, 999'999'999));
    if (w.has('L') && w.has('K')) error(w.col('K'), "repeat count given twice (L and K)");
    call_request.repeats = 1;
    if (w.has('L')) call_request.repeats = integer('L', (name + " repeat count").c_str(), 0, 9999);
    if (w.has('K')) call_request.repeats = integer('K', (name + " repeat count").c_str(), 0, 9999);
    flow = Flow::call;
  }
  if (w.find_m(kM99)) flow = Flow::ret;
  return flow;
}

// Every word must have been used by some code of the block: never a silent misreading.
void Interpreter::State::check_words_used() {
  // Fanuc keeps a D word for the next G41/G42 (`T4 D04 M06`); LinuxCNC refuses it, as rs274.
  if (machine.dialect != Dialect::linuxcnc && w.has('D') && !((w.used >> letter_index('D')) & 1u))
    comp.offset_d =
        static_cast<int>(integer('D', "D (a cutter radius offset number)", 0, 99'999'999));
  std::uint32_t free_words = w.present & ~w.used;
  for (char c : {'F', 'S', 'T', 'O'}) free_words &= ~(1u << letter_index(c));
  if (w.m_arguments)
    for (char c : {'P', 'Q', 'E', 'L', 'R'}) free_words &= ~(1u << letter_index(c));
  if (!free_words) return;
  for (int i = 0; i < 26; ++i) {
    if (!((free_words >> i) & 1u)) continue;
    char c = static_cast<char>('A' + i);
    std::size_t k = static_cast<std::size_t>(i);
    bool axis_letter = c == 'X' || c == 'Y' || c == 'Z';
    if (axis_letter) continue;  // axis words are consumed by construction or rejected above
    if ((c == 'A' || c == 'B' || c == 'C') && !machine.kinematics) {
      // A 4-axis post writes A0. at every tool start: with the tool along +Z (no G53.1 has
      // turned the axes) an axis that stays at zero turns nothing, whatever the machine. Any
      // other angle is never dropped, even lenient.
      if (w.value[k] == 0 && glm::dot(tool.axis, Vec3(0, 0, 1)) >= 1 - kSameDirection) {
        if (warned_once.rotary_at_zero.insert(c).second)
          warn(w.column[k],
               std::string("rotary word ") + c +
                   "0 read as the axis staying at zero (the "
                   "tool stays along +Z); a machine file with \"kinematics\" models the axis");
        continue;
      }
      error(w.column[k],
            std::string("rotary word ") + c + format_number(w.value[k]) +
                ": reading A/B/C needs a machine file with \"kinematics\" (--machine)");
    }
    // Only words that never carry geometry may be dropped: E (an extruder), D and H (offset
    // numbers, which tridex does not apply).
    bool skippable = c == 'E' || c == 'D' || c == 'H';
    unsupported(w.column[k],
                std::string("word ") + c + format_number(w.value[k]) +
                    " is not used by any code in this block",
                std::string("unused word ") + c, skippable);
  }
}

// G65 P<program> L<repeats> <arguments>: a macro call. Argument words become the callee's locals
// by Fanuc's argument specification I: A B C I J K D E F H M Q R S T U V W X Y Z are #1 #2 #3 #4
// #5 #6 #7 #8 #9 #11 #13 #17 #18 #19 #20 #21 #22 #23 #24 #25 #26 (G, L, N, O, P are not arguments).
//
// Fanuc wants G65 before its arguments (FANUC Series 0i-MF operator's manual B-64604EN, "Custom
// macro", "Argument specification": "G65 must be specified before any argument"), and G is no
// argument. A code written before G65 is a code of the block, which a Fanuc control reads before
// it calls (the programs of a Fanuc HMC start their macro calls with `G54 G65 P…`): the modal
// codes that only set a mode (plane, units, distance, work system, cycle return) are read so;
// any other code beside G65 (one that moves, or reads the words G65 takes as arguments) stays an
// error, even lenient.
Flow Interpreter::State::macro_call(int column) {
  static constexpr int kSettings[] = {kG17, kG18, kG19, kG20, kG21, kG54, kG55, kG56,
                                      kG57, kG58, kG59, kG90, kG91, kG98, kG99};
  for (int i = 0; i < w.g_count; ++i) {
    const Code& g = w.g[static_cast<std::size_t>(i)];
    if (g.code == kG65) continue;
    if (machine.dialect == Dialect::linuxcnc || g.column > column ||
        std::find(std::begin(kSettings), std::end(kSettings), g.code) == std::end(kSettings))
      error(g.column, code_name('G', g.code) +
                          " beside G65: only codes that set a mode (G17-G19, G20/G21, G54-G59, "
                          "G90/G91, G98/G99) may stand in a G65 block, before G65");
  }
  if (w.m_count > 0) error(column, "G65 must be the only G or M code of its block");
  units_codes();
  plane_codes();
  distance_mode_codes();
  return_mode_codes();
  work_system_codes();
  if (!w.has('P')) error(column, "G65 needs P (the O number of the macro)");
  call_request.label = static_cast<int>(integer('P', "G65 P", 0, 999'999'999));
  call_request.repeats = w.has('L') ? integer('L', "G65 repeat count", 0, 9999) : 1;
  static constexpr int kArgument[26] = {1, 2, 3, 7,  8,  9,  0,  11, 4,  5,  6,  0,  13,
                                        0, 0, 0, 17, 18, 19, 20, 21, 22, 23, 24, 25, 26};
  call_request.arguments.fill(Value{0, true});
  for (int i = 0; i < 26; ++i) {
    char c = static_cast<char>('A' + i);
    if (!w.has(c) || c == 'L' || c == 'P') continue;
    if (kArgument[i] == 0) error(w.col(c), std::string("G65: ") + c + " is not an argument word");
    call_request.arguments[static_cast<std::size_t>(kArgument[i])] = Value{w.take(c), false};
  }
  w.used = w.present;
  return Flow::macro;
}

// G52 X Y Z sets the local offset (from the work zero); G92 X Y Z sets it so that the current
// position reads X Y Z; G92.1 clears it, G92.2 suspends it, G92.3 restores it. LinuxCNC keeps G52
// and G92 in one register; Fanuc's G52 and G92 change the same program origin.
void Interpreter::State::local_offsets(int code, int column) {
  const Vec3 before = frame.local_offset;
  if (code == kG92_1 || code == kG92_2) {
    frame.saved_local_offset = code == kG92_2 ? frame.local_offset : Vec3(0.0);
    frame.local_offset = Vec3(0.0);
  } else if (code == kG92_3) {
    frame.local_offset = frame.saved_local_offset;
  } else {
    bool any = false;
    for (int i = 0; i < 3; ++i) {
      char c = kAxisLetter[i];
      if (!w.has(c)) continue;
      any = true;
      double v = length(c);
      if (code == kG52) {
        frame.local_offset[i] = v;
      } else {
        // In raw rotary form "far" is along the turned tool, which any linear axis may follow.
        bool along_axis = std::abs(tool.axis[i]) > kAxisEps || raw_rotary();
        if (tool.far && along_axis)
          error(w.col(c),
                std::string("G92 ") +=
                c + std::string(" with the tool retracted far along its axis: its position is "
                                "unknown (a machine file can set the start position)"));
        frame.local_offset[i] = linear_axes()[i] - frame.work_offset[i] - v;
      }
    }
    if (!any) error(column, code_name('G', code) + " needs X, Y or Z");
    frame.saved_local_offset = frame.local_offset;
  }
  // Under a tilted plane only a code that leaves the offset as it is (LinuxCNC's tilted-plane
  // demos clear G52 to zero in a subroutine) is read: a shift there has no agreed meaning.
  if (frame.tilted && frame.local_offset != before)
    error(column, code_name('G', code) +
                      " changes the local offset under a tilted plane (cancel it first)");
  update_frame();
}

}  // namespace tridex::gcode
