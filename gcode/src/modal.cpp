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
  tool = number;
  pos += (before - loaded_length()) * axis;
  update_frame();
}

// Tool length offsets (RS274/NGC, NIST IR 6556 §3.6.3; LinuxCNC's G43, G43.1, G49): G43 H n
// takes tool n's length (no H: the loaded tool's, as LinuxCNC does; H0: none), Fanuc's G44 H n
// its negative, LinuxCNC's G43.1 Z the length written, G49 none. G43.4/G43.5 H n (TCP) take it as
// G43 does. With no tool lengths in the machine, they all leave the path alone.
void Interpreter::State::tool_length_codes() {
  int code = 0, column = 0;
  for (int c : {430, 431, 434, 435, 440, 490})
    if (int at = w.find_g(c)) {
      code = c;
      column = at;
    }
  if (!code) return;
  double next = 0;
  if (code == 431) {
    if (machine.dialect != Dialect::linuxcnc)
      unsupported(column, "G43.1 (LinuxCNC's dynamic tool length offset) needs --machine linuxcnc", "G43.1", false);
    for (char c : {'X', 'Y'})
      if (w.has(c)) error(w.col(c), std::string("G43.1 ") + c + ": a sideways tool offset is not simulated");
    if (!w.has('Z')) error(column, "G43.1 needs Z (the tool length offset)");
    next = length('Z');
    w.present &= ~(1u << letter_index('Z'));  // an offset here, not a coordinate
  } else if (code != 490) {
    int number = tool;
    if (w.has('H')) number = static_cast<int>(integer('H', "tool length offset number", 0, 99'999'999));
    if (std::optional<double> table = table_length(number)) {
      next = code == 440 ? -*table : *table;
    } else if (number != 0 && !machine.tool_lengths.empty()) {
      error(w.has('H') ? w.col('H') : column,
            "H" + std::to_string(number) + ": tool " + std::to_string(number) +
                " has no length in the tool table (\"tool-length\", or Z in a LinuxCNC .tbl)");
    }
  }
  if (machine.tool_lengths.empty()) next = 0;  // no lengths known: the programmed point is the tip
  if (next != length_offset) comp_forbid(column, "changing the tool length offset");
  length_offset = next;
  update_frame();
}

// The feed mode, F and S, in RS274/NGC's order (feed mode first). LinuxCNC's G94 and G95 set the
// feed rate to 0 (interp_convert.cc convert_feed_mode), so a feed move after them needs a new F;
// the other dialects clear it when the mode changes. Under G93, F is the block's 1/min (read in
// require_feed, only from the block itself, as LinuxCNC does); under G95 the rate is F × S.
void Interpreter::State::feed_mode_codes() {
  for (int code : {930, 940, 950}) {
    if (!w.find_g(code)) continue;
    FeedMode next = code == 930 ? FeedMode::inverse_time
                    : code == 940 ? FeedMode::per_minute
                                  : FeedMode::per_revolution;
    bool clears = machine.dialect == Dialect::linuxcnc ? code != 930 : next != feed_mode;
    if (clears) feed = feed_per_rev = 0;
    feed_mode = next;
  }
  if (w.has('F')) {
    if (w.value[static_cast<std::size_t>(letter_index('F'))] < 0)
      error(w.col('F'), "feed rate F must not be negative");
    if (feed_mode == FeedMode::inverse_time) inverse_time = w.take('F');
    else if (feed_mode == FeedMode::per_revolution) feed_per_rev = length('F');
    else feed = length('F');
  }
  if (w.has('S')) {
    double s = w.take('S');
    if (s < 0) error(w.col('S'), "spindle speed S must not be negative");
    speed = s;
  }
  if (feed_mode == FeedMode::per_revolution) feed = feed_per_rev * speed;
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
      error(w.col(c), name + " " + c + ": a tool offset along " + c + " is not simulated (tridex offsets tools along their axis only)");
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
    set_lengths[number] = length('Z');
    return;
  }
  if (far) error(column, name + " with the tool retracted far along its axis: its position is unknown");
  if (tilted || machine.kinematics || glm::dot(axis, Vec3(0, 0, 1)) < 1 - kSameDirection)
    error(column, name + " with a tilted frame or rotary axes is not simulated");
  // linear_axes(): the controlled point in machine coordinates; the control puts the gauge point
  // the active offset above it.
  double gauge = linear_axes().z + length_offset;
  double system = 0;
  if (l == 10) {
    system = work_offset.z + local_offset.z;
  } else if (auto it = offsets.find(9); it != offsets.end()) {  // G59.3 (never set by tridex: 0)
    system = it->second.z;
  }
  set_lengths[number] = gauge - system - length('Z');
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
  const std::string name = "G10 L" + std::to_string(l), offset = radius ? "cutter radius" : "tool length";
  if (!w.has('P')) error(column, name + " needs P (the " + offset + " offset number)");
  if (!w.has('R')) error(column, name + " needs R (the offset's value)");
  const int number = static_cast<int>(integer('P', (name + " P (a " + offset + " offset number)").c_str(), 0, 99'999'999));
  if (radius) {
    d_set_at[number] = name + " at line " + std::to_string(line);
    double& value = (l == 12 ? d_geometry : d_wear)[number];
    value = (incremental ? value : 0) + length('R');
    return;
  }
  for (char c : {'X', 'Y', 'Z', 'A', 'B', 'C'})
    if (w.has(c)) error(w.col(c), name + " " + c + ": a tool length offset takes R only");
  double value = length('R');
  if (l == 10) {
    set_lengths[number] = (incremental ? length_geometry(number).value_or(0) : 0) + value;
  } else {
    double& wear = length_wear[number];
    wear = (incremental ? wear : 0) + value;
  }
}

Flow Interpreter::State::execute(const Block& block) {
  gather(block);
  if (plane_blocks.code && !w.find_g(plane_blocks.code))  // a G68.2 P2/P3 plane is under way
    error(block.words.front().column, incomplete_plane());
  if (int column = w.find_g(650)) return macro_call(column);
  motion_column = 0;
  int motion_code = -1, nonmodal = -1, tilt = -1, orient = -1;
  for (int i = 0; i < w.g_count; ++i) {
    const Code& g = w.g[static_cast<std::size_t>(i)];
    int group = block_g_group(g.code);
    if (group == kMotion) {
      motion_code = g.code;
      motion_column = g.column;
    } else if (group == kNonModal) {
      nonmodal = g.code;
      if (g.code != 40) motion_column = g.column;
    } else if (group == kTilt) {
      tilt = g.code;
    } else if (group == kOrient) {
      orient = g.code;
    }
  }
  if (motion_column == 0) {
    motion_column = 1;
    for (char c : {'X', 'Y', 'Z'})
      if (w.has(c)) {
        motion_column = w.col(c);
        break;
      }
  }

  // Units first, so that every length in this block is read in them.
  for (int code : {200, 210}) {
    int column = w.find_g(code);
    if (!column) continue;
    double next = code == 200 ? 25.4 : 1.0;
    if (next != unit) comp_forbid(column, "changing units");
    unit = next;
  }

  feed_mode_codes();
  if (w.has('T')) tool_selected = static_cast<int>(integer('T', "tool number", 0, 99'999'999));

  if (w.find_m(6) || (w.has('T') && machine.tool_loads_on_t)) {
    comp_forbid(w.find_m(6) ? w.find_m(6) : w.col('T'), "a tool change");
    comp_programmed_current = false;  // LinuxCNC resynchronises with where the tool really is
    load_tool(tool_selected);
    tool_first_line.emplace(tool, line);
    if (machine.tool_change == ToolChange::retract_far) go_far();
    if (machine.tool_change == ToolChange::to_position) {
      if (glm::dot(axis, Vec3(0, 0, 1)) < 1 - kSameDirection)
        error(w.find_m(6) ? w.find_m(6) : w.col('T'),
              "a tool change to the machine's tool-change position with a tilted tool depends on "
              "the kinematics; retract (G28 or G53 Z) and cancel the tilt first");
      Vec3 tip = tip_below(machine.tool_change_position);
      if (!far) emit(MoveKind::rapid, pos, tip, 0.0);
      pos = tip;
    }
  }
  if (int column = w.find_m(61)) {  // LinuxCNC: the tool in the spindle is Q (nothing moves)
    if (!w.has('Q')) error(column, "M61 needs Q (the tool number)");
    tool_selected = static_cast<int>(integer('Q', "M61 tool number", 0, 99'999'999));
    load_tool(tool_selected);
  }
  if (w.find_m(3)) spindle_direction = 1;
  if (w.find_m(4)) spindle_direction = -1;
  if (w.find_m(5)) spindle_direction = 0;

  if (nonmodal == 40) {  // dwell: P (seconds or ms) or, on Fanuc, X
    // Fanuc's `G4 X2.` dwells; beside P, or with a motion code in the block, X is a coordinate.
    bool x_dwell = !w.has('P') && w.has('X') && motion_code < 0;
    char c = w.has('P') ? 'P' : x_dwell ? 'X' : 0;
    if (!c) error(w.find_g(40), "G4 needs a dwell time P");
    double time = w.take(c);
    if (time < 0) error(w.col(c), "dwell time must not be negative");
    if (c == 'X') w.present &= ~(1u << letter_index('X'));  // a time here, not a coordinate
    emit_dwell(c == 'X' ? time : dwell_seconds(time));
  }

  for (int code : {170, 180, 190})
    if (int column = w.find_g(code)) {
      if (code != plane) comp_forbid(column, "changing the plane");
      plane = code;
    }
  // Cutter radius compensation (comp.cpp): after the plane, before motion (NIST IR 6556 §3.8).
  for (int code : {400, 410, 420, 411, 421})
    if (int column = w.find_g(code)) cutter_comp_codes(code, column);
  if (w.find_g(900)) incremental = false;
  if (w.find_g(910)) incremental = true;
  if (w.find_g(901)) arc_absolute = true;
  if (w.find_g(911)) arc_absolute = false;
  tool_length_codes();
  tool_center_codes();  // G43.4/G43.5 TCP, G254/G255 DWO (rotary.cpp)
  // Look-ahead and smoothing modes change how the control follows the path, not the path.
  if (w.find_g(51) && motion_code != 51) {  // Fanuc's G5.1 Q (a spline G5.1 is a motion)
    for (char c : {'Q', 'R'})
      if (w.has(c)) w.take(c);
  }
  if (w.find_g(80) && w.has('P')) w.take('P');
  if (w.find_g(1870)) {
    for (char c : {'P', 'E'})
      if (w.has(c)) w.take(c);
  }
  if (w.find_g(1030) && w.has('P')) w.take('P');  // Haas: blocks of look-ahead
  if (w.find_g(640)) {  // path blending tolerances (LinuxCNC G64 P Q): no effect on the path
    if (w.has('P')) w.take('P');
    if (w.has('Q')) w.take('Q');
  }
  if (w.find_g(980)) retract_to_r = false;
  if (w.find_g(990)) retract_to_r = true;

  // Work coordinate system.
  for (int code : {540, 550, 560, 570, 580, 590, 541, 1540}) {
    int column = w.find_g(code);
    if (!column) continue;
    int key = (code - 540) / 10 + 1;
    if (code == 541) {
      if (!w.has('P')) error(column, "G54.1 needs P (1-300)");
      key = MachineConfig::g54_1_key(static_cast<int>(integer('P', "G54.1 number", 1, 300)));
    } else if (code == 1540) {  // Haas: the same extra offsets as G54.1 P1-P99
      if (!w.has('P')) error(column, "G154 needs P (1-99)");
      key = MachineConfig::g54_1_key(static_cast<int>(integer('P', "G154 number", 1, 99)));
    }
    if (tilted && key != work_key)
      error(column, "work coordinates change while a tilted plane is active (cancel it first)");
    if (key != work_key) comp_forbid(column, "changing the work coordinate system");
    work_key = key;
    auto it = offsets.find(key);
    work_offset = it == offsets.end() ? Vec3(0.0) : it->second;
    update_frame();
  }

  bool axis_consumer = false;  // a code other than motion that takes X/Y/Z
  if (nonmodal == 520 || (nonmodal >= 920 && nonmodal <= 923)) {
    axis_consumer = true;
    comp_forbid(w.find_g(nonmodal), code_name('G', nonmodal));
    local_offsets(nonmodal, w.find_g(nonmodal));
  }
  if (nonmodal == 100) {
    axis_consumer = true;
    int column = w.find_g(100);
    bool linuxcnc_tools = machine.dialect == Dialect::linuxcnc;
    if (!w.has('L'))
      error(column, linuxcnc_tools ? "G10 needs L1, L2, L10, L11 or L20"
                                   : machine.dialect == Dialect::haas ? "G10 needs L1, L2, L10-L13 or L20"
                                                                      : "G10 needs L2, L10-L13 or L20");
    long long l = integer('L', "G10 L", 0, 99);
    if (linuxcnc_tools && (l == 1 || l == 10 || l == 11)) {
      tool_table_entry(l, column);
    } else if (!linuxcnc_tools && ((l >= 10 && l <= 13) || (l == 1 && machine.dialect == Dialect::haas))) {
      tool_length_entry(l, column);
    } else if (l != 2 && l != 20) {
      unsupported(column, "G10 L" + std::to_string(l) + " is not supported (only L2 and L20" +
                              (linuxcnc_tools ? ", and L1, L10, L11" : ", and L10-L13 for tool offsets") + ")",
                  "G10 L");
    } else {
      if (!w.has('P')) error(column, "G10 L" + std::to_string(l) + " needs P");
      // Fanuc: L2 P1-6 sets G54-G59, L20 Pn sets G54.1 Pn. LinuxCNC: P1-6 are G54-G59 for both,
      // and L20 sets the offset that makes the current position read X Y Z. P0: the active one.
      bool linuxcnc = machine.dialect == Dialect::linuxcnc;
      int key = 0;
      if (l == 2 || linuxcnc) {
        if (w.has('R'))
          unsupported(w.col('R'), "G10 L" + std::to_string(l) + " R (a rotated coordinate system) is not supported",
                      "G10 R", false);
        key = static_cast<int>(integer('P', linuxcnc ? "G10 P" : "G10 L2 P", 0, 6));
      } else {
        key = MachineConfig::g54_1_key(static_cast<int>(integer('P', "G10 L20 P", 0, 300)));
        if (key == MachineConfig::g54_1_key(0)) key = 0;
      }
      if (key == 0) key = work_key;
      if (incremental)
        error(column, "G10 under G91 is read differently by different controls; use G90");
      Vec3 value = offsets.count(key) ? offsets[key] : Vec3(0.0);
      bool relative_to_position = linuxcnc && l == 20;
      if (relative_to_position && far)
        error(column, "G10 L20 with the tool retracted far along its axis: its position is unknown");
      for (int i = 0; i < 3; ++i)
        if (w.has(kAxisLetter[i]))
          value[i] = relative_to_position ? linear_axes()[i] - local_offset[i] - length(kAxisLetter[i])
                                          : length(kAxisLetter[i]);
      // A rotary offset of 0 changes nothing, nor do LinuxCNC's plain A/B/C (no kinematics);
      // any other would turn the part under the program, which tridex does not model.
      for (char c : {'A', 'B', 'C'})
        if (w.has(c) && w.take(c) != 0 && !(linuxcnc && !machine.kinematics))
          error(w.col(c), std::string("G10 ") + c + format_number(w.value[static_cast<std::size_t>(letter_index(c))]) +
                              ": a rotary work offset other than 0 is not simulated");
      if (key == work_key) comp_forbid(column, "G10 on the active work offset");
      offsets[key] = value;
      if (key == work_key) {
        if (tilted) error(column, "G10 changes the active work offset under a tilted plane");
        work_offset = value;
        update_frame();
      }
    }
  }

  // Tilted working plane (tilt.cpp).
  if (tilt >= 0) {
    comp_forbid(w.find_g(tilt), code_name('G', tilt));
    if (tilt != 690 && tilt != 2690) axis_consumer = true;
    tilted_plane(tilt);
  }
  if (orient >= 0) orient_to_plane(orient);

  // Motion.
  if (motion_code >= 0) {
    if (axis_consumer && motion_code != 800)
      error(motion_column, code_name('G', motion_code) +
                               " in a block whose X/Y/Z belong to another code");
    if (motion_code == 800 || !is_cycle(motion_code)) cycle_active = false;
    if (is_cycle(motion_code) && motion != motion_code) cycle_active = false;
    if (motion == 52 && motion_code != 52 && !nurbs_points.empty())
      warn(motion_column, "the G5.2 control points before this " + code_name('G', motion_code) +
                              " are dropped: no G5.3 ended them (LinuxCNC drops them too)");
    if (motion_code == 52 && motion != 52) nurbs_points.clear();  // a new curve starts
    motion = motion_code;
  }
  if (w.has('@') || w.has('^')) polar_words(axis_consumer, nonmodal);
  if (w.has('A') || w.has('B') || w.has('C'))
    comp_forbid(w.col(w.has('A') ? 'A' : w.has('B') ? 'B' : 'C'), "a rotary axis word");
  if (!axis_consumer && nonmodal != 280 && nonmodal != 300) rotary_words();
  extra_linear_words(!axis_consumer && nonmodal < 0);
  if (nonmodal == 280 || nonmodal == 300) {
    if (motion_code >= 0 && motion_code != 800)
      error(motion_column, "G28/G30 with a motion code in the same block");
    comp_forbid(w.find_g(nonmodal), code_name('G', nonmodal));
    home_return(nonmodal == 300);
  } else if (nonmodal == 530) {
    comp_forbid(w.find_g(530), "G53");
    if (motion != 0 && motion != 10)
      error(motion_column, "G53 needs G0 or G1 modal");
    if (motion == 10) require_feed();
    Vec3 target(0.0);
    unsigned mask = 0;
    for (int i = 0; i < 3; ++i)
      if (w.has(kAxisLetter[i])) {
        target[i] = length(kAxisLetter[i]);
        mask |= 1u << i;
      }
    if (mask)
      machine_move(target, mask, motion == 0 ? MoveKind::rapid : MoveKind::feed,
                   motion == 0 ? 0.0 : feed);
  } else if (nonmodal == 53) {  // G5.3: the NURBS of the G5.2 blocks before it (spline.cpp)
    if (motion_code >= 0 || has_axis_words())
      error(motion_column, "G5.3 ends a G5.2 NURBS: no motion code or coordinates in its block");
    nurbs_end(motion_column);
  } else if (!axis_consumer) {
    bool axes = has_axis_words();
    if (motion == 0 || motion == 10) {
      if (axes) {
        if (motion == 10) require_feed();
        linear(motion == 0 ? MoveKind::rapid : MoveKind::feed, motion == 0 ? 0.0 : feed);
      }
    } else if (motion == 20 || motion == 30) {
      char cu = kCenterLetter[plane_axes(plane)[0]], cv = kCenterLetter[plane_axes(plane)[1]];
      if (axes || motion_code >= 0 || w.has(cu) || w.has(cv) || w.has('R')) arc(motion == 30);
    } else if (motion >= 382 && motion <= 385) {
      if (axes || motion_code >= 0) probe(motion);
    } else if (motion == 50 || motion == 51) {
      if (axes || motion_code >= 0 || w.has('I') || w.has('J') || w.has('P') || w.has('Q'))
        spline(motion == 51);
    } else if (motion == 52) {
      if (axes || motion_code >= 0 || w.has('P') || w.has('L')) nurbs_point();
    } else if (is_cycle(motion)) {
      if (axes || motion_code >= 0 || w.has('R')) {
        comp_forbid(motion_column, "a canned cycle");
        cycle(motion);
      }
    } else if (axes) {
      error(motion_column, "X/Y/Z without an active motion mode (G0, G1, G2, G3, G5, G5.1, G5.2 or a cycle)");
    }
  }

  // Program flow last.
  Flow flow = Flow::next;
  if (w.find_m(2) || w.find_m(30)) {
    comp_finish();
    flow = Flow::end;
  }
  for (int m : {98, 97}) {  // M97 P: Haas, a local subprogram at block N P of this program
    const int column = w.find_m(m);
    if (!column) continue;
    const std::string name = m == 98 ? "M98" : "M97";
    if (!w.has('P')) error(column, name + (m == 98 ? " needs P (the O number to call)" : " needs P (the N number to call)"));
    call_label = static_cast<int>(integer('P', (name + " P").c_str(), 0, 999'999'999));
    if (w.has('L') && w.has('K')) error(w.col('K'), "repeat count given twice (L and K)");
    call_repeats = 1;
    if (w.has('L')) call_repeats = integer('L', (name + " repeat count").c_str(), 0, 9999);
    if (w.has('K')) call_repeats = integer('K', (name + " repeat count").c_str(), 0, 9999);
    flow = Flow::call;
  }
  if (w.find_m(99)) flow = Flow::ret;

  // Fanuc keeps a D word for the next G41/G42 (`T4 D04 M06`); LinuxCNC refuses it, as rs274.
  if (machine.dialect != Dialect::linuxcnc && w.has('D') && !((w.used >> letter_index('D')) & 1u))
    offset_d = static_cast<int>(integer('D', "D (a cutter radius offset number)", 0, 99'999'999));
  // Every word must have been used by some code of the block: never a silent misreading.
  std::uint32_t free_words = w.present & ~w.used;
  for (char c : {'F', 'S', 'T', 'O'}) free_words &= ~(1u << letter_index(c));
  if (w.m_arguments)
    for (char c : {'P', 'Q', 'E', 'L', 'R'}) free_words &= ~(1u << letter_index(c));
  if (free_words) {
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
        if (w.value[k] == 0 && glm::dot(axis, Vec3(0, 0, 1)) >= 1 - kSameDirection) {
          if (warned_rotary_at_zero.insert(c).second)
            warn(w.column[k], std::string("rotary word ") + c + "0 read as the axis staying at zero (the "
                              "tool stays along +Z); a machine file with \"kinematics\" models the axis");
          continue;
        }
        error(w.column[k], std::string("rotary word ") + c + format_number(w.value[k]) +
                               ": reading A/B/C needs a machine file with \"kinematics\" (--machine)");
      }
      // Only words that never carry geometry may be dropped: E (an extruder), D and H (offset
      // numbers, which tridex does not apply).
      bool skippable = c == 'E' || c == 'D' || c == 'H';
      unsupported(w.column[k], std::string("word ") + c + format_number(w.value[k]) +
                                   " is not used by any code in this block",
                  std::string("unused word ") + c, skippable);
    }
  }
  return flow;
}

}  // namespace tridex::gcode

namespace tridex::gcode {

// G65 P<program> L<repeats> <arguments>: a macro call. Argument words become the callee's locals
// by Fanuc's argument specification I: A B C I J K D E F H M Q R S T U V W X Y Z are #1 #2 #3 #4
// #5 #6 #7 #8 #9 #11 #13 #17 #18 #19 #20 #21 #22 #23 #24 #25 #26 (G, L, N, O, P are not arguments).
Flow Interpreter::State::macro_call(int column) {
  if (w.g_count > 1 || w.m_count > 0)
    error(column, "G65 must be the only G or M code of its block");
  if (!w.has('P')) error(column, "G65 needs P (the O number of the macro)");
  call_label = static_cast<int>(integer('P', "G65 P", 0, 999'999'999));
  call_repeats = w.has('L') ? integer('L', "G65 repeat count", 0, 9999) : 1;
  static constexpr int kArgument[26] = {1,  2,  3,  7,  8,  9,  0,  11, 4,  5,  6,  0,  13,
                                        0,  0,  0,  17, 18, 19, 20, 21, 22, 23, 24, 25, 26};
  call_arguments.fill(Value{0, true});
  for (int i = 0; i < 26; ++i) {
    char c = static_cast<char>('A' + i);
    if (!w.has(c) || c == 'L' || c == 'P') continue;
    if (kArgument[i] == 0)
      error(w.col(c), std::string("G65: ") + c + " is not an argument word");
    call_arguments[static_cast<std::size_t>(kArgument[i])] = Value{w.take(c), false};
  }
  w.used = w.present;
  return Flow::macro;
}

// G52 X Y Z sets the local offset (from the work zero); G92 X Y Z sets it so that the current
// position reads X Y Z; G92.1 clears it, G92.2 suspends it, G92.3 restores it. LinuxCNC keeps G52
// and G92 in one register; Fanuc's G52 and G92 change the same program origin.
void Interpreter::State::local_offsets(int code, int column) {
  const Vec3 before = local_offset;
  if (code == 921 || code == 922) {
    saved_local_offset = code == 922 ? local_offset : Vec3(0.0);
    local_offset = Vec3(0.0);
  } else if (code == 923) {
    local_offset = saved_local_offset;
  } else {
    bool any = false;
    for (int i = 0; i < 3; ++i) {
      char c = kAxisLetter[i];
      if (!w.has(c)) continue;
      any = true;
      double v = length(c);
      if (code == 520) {
        local_offset[i] = v;
      } else {
        // In raw rotary form "far" is along the turned tool, which any linear axis may follow.
        bool along_axis = std::abs(axis[i]) > kAxisEps || raw_rotary();
        if (far && along_axis)
          error(w.col(c), std::string("G92 ") += c + std::string(
                              " with the tool retracted far along its axis: its position is "
                              "unknown (a machine file can set the start position)"));
        local_offset[i] = linear_axes()[i] - work_offset[i] - v;
      }
    }
    if (!any) error(column, code_name('G', code) + " needs X, Y or Z");
    saved_local_offset = local_offset;
  }
  // Under a tilted plane only a code that leaves the offset as it is (LinuxCNC's tilted-plane
  // demos clear G52 to zero in a subroutine) is read: a shift there has no agreed meaning.
  if (tilted && local_offset != before)
    error(column, code_name('G', code) + " changes the local offset under a tilted plane (cancel it first)");
  update_frame();
}

}  // namespace tridex::gcode
