// tridex::gcode — rotary axes on moves, Haas DWO and Fanuc TCP: 3+2 programs that index the
// machine with A/B/C words instead of a tilted plane. The kinematic model (kinematics.hpp) says
// where the tool points on the part and, without DWO or TCP, where machine coordinates put the
// tip (the raw form simple posts write). Haas DWO (G254/G255, Haas mill operator's manual,
// "Dynamic Work Offset") and Fanuc TCP (G43.4, G43.5 I J K; Fanuc B-64484EN, "tool center point
// control") make X Y Z positions of the part frame (the work coordinates as measured with every
// rotary at 0), which the control turns into machine coordinates itself.
#include <cmath>

#include "state.hpp"

namespace tridex::gcode {

// G43.4 / G43.5 switch TCP on (G43, G44 and G49 off: the same modal group), as Haas's G234
// (TCPC, read on the Haas dialect only: block_g_group) does; G254 / G255 switch DWO on and off.
// G43.5 I J K gives the tool direction on the part directly.
void Interpreter::State::tool_center_codes() {
  bool was_tcp = frame.tcp, was_dwo = frame.dwo;
  if (w.find_g(kG43) || w.find_g(kG44) || w.find_g(kG49)) frame.tcp = false;
  if (w.find_g(kG43_4) || w.find_g(kG234)) frame.tcp = true;
  if (int column = w.find_g(kG43_5)) {
    frame.tcp = true;
    if (w.has('I') || w.has('J') || w.has('K')) {
      Vec3 direction(w.has('I') ? w.take('I') : 0.0, w.has('J') ? w.take('J') : 0.0,
                     w.has('K') ? w.take('K') : 0.0);
      if (!(glm::length(direction) > 1e-9) || !is_finite(direction))
        error(column, "G43.5 I J K: the tool direction must not be the zero vector");
      direction = glm::normalize(direction);
      if (machine.kinematics) {
        try {
          frame.rotary_position =
              orient_tool(*machine.kinematics, direction, frame.rotary_position);
        } catch (const Error& e) {
          error(column, std::string("G43.5: ") + e.what());
        }
      }
      if (glm::dot(direction, tool.axis) < 1 - kSameDirection) go_far();
      tool.axis = direction;
    }
  }
  if (w.find_g(kG254)) frame.dwo = true;
  if (w.find_g(kG255)) frame.dwo = false;
  if (frame.tcp != was_tcp || frame.dwo != was_dwo)
    update_frame();  // the tip stays where it is on the part
}

// A kinematics switch of the machine file (LinuxCNC's switchkins, docs/src/motion/switchkins.adoc
// in LinuxCNC: the sample configs' M428 selects the TCP kinematics, M429 identity, M430 a user's
// own): the joints stay where they are, so the tip keeps its place on the part and later X Y Z
// read in the new kinematics. Run with the user-defined M-codes, before the block's motion
// (LinuxCNC's order of execution; a remap of modal group 10).
void Interpreter::State::kinematics_switch_code() {
  if (w.kinematics_switch < 0) return;
  const int code = w.kinematics_switch, column = w.kinematics_switch_column;
  const KinematicsSwitch kind = machine.kinematics_switches.at(code);
  if (kind == KinematicsSwitch::refuse) {
    std::string message = code_name('M', code * 10);  // (one string: GCC 12's -Wrestrict)
    message +=
        " switches to kinematics of this machine's own (LinuxCNC's user kinematics, "
        "switchkins type 2), which tridex cannot know: use the machine's TCP or identity "
        "switch, or give the machine file's \"kinematics_switches\" another meaning for it";
    error(column, message);
  }
  const bool next = kind == KinematicsSwitch::tcp;
  if (next == frame.tcp_kinematics) return;
  comp_forbid(column, "switching the kinematics");
  frame.tcp_kinematics = next;
  update_frame();  // the tip stays where it is on the part
}

// A B C on a G0/G1 block (or alone under G0/G1 modal): each letter an axis of the machine, within
// its limits; the tool direction becomes the kinematics'. An indexing move (G0) leaves the tool
// far along its axis, except in raw form where the machine coordinates keep the tip known (the
// sweep of the rotation itself is not simulated). Rotary motion during G1 is simultaneous
// 5-axis (simultaneous_start).
// LinuxCNC's U/V/W: linear axes of their own (a quill, a second carriage) that a LinuxCNC
// machine may have and reads as plain axes (rs274 run standalone, with no INI, has none and
// refuses them). They do not move the tool tridex simulates: read under the LinuxCNC dialect
// with one warning, their positions kept (`track`: on moves) for #5426–#5428 and #<_u> #<_v>
// #<_w>; on other machines an unused word, as before.
void Interpreter::State::extra_linear_words(bool track) {
  if (machine.dialect != Dialect::linuxcnc) return;
  int first = 0;
  for (char c : {'U', 'V', 'W'})
    if (w.has(c) && (!first || w.col(c) < first)) first = w.col(c);
  if (!first) return;
  for (int i = 0; i < 3; ++i) {
    char c = "UVW"[i];
    if (!w.has(c)) continue;
    double v = length(c);
    if (track) tool.uvw_position[i] = modal.incremental ? tool.uvw_position[i] + v : v;
  }
  if (!warned_once.uvw) {
    warned_once.uvw = true;
    warn(first,
         "U/V/W read as plain axes, as LinuxCNC does on a machine that has them: they do not move "
         "the tool tridex simulates");
  }
}

void Interpreter::State::rotary_words() {
  int first = 0;
  for (char c : {'A', 'B', 'C'}) {
    bool unused = w.has(c) && !((w.used >> letter_index(c)) & 1u);
    if (unused && (!first || w.col(c) < first)) first = w.col(c);
  }
  if (!first) return;
  if (!machine.kinematics) {
    // The unused-word check refuses them, naming the machine file, except on LinuxCNC: without
    // kinematics (trivkins) A/B/C are axes of their own, as rs274 reads them, that turn nothing.
    if (machine.dialect != Dialect::linuxcnc) return;
    for (char c : {'A', 'B', 'C'})
      if (w.has(c) && !((w.used >> letter_index(c)) & 1u)) w.take(c);
    if (!warned_once.plain_rotary) {
      warned_once.plain_rotary = true;
      warn(first,
           "A/B/C read as plain axes, as LinuxCNC does on a machine without kinematics: the "
           "tool does not tilt (give the machine file \"kinematics\" to simulate them)");
    }
    return;
  }
  const Kinematics& kin = *machine.kinematics;
  if (modal.motion != kG0 && modal.motion != kG1)
    error(first, "A/B/C words need G0 or G1 (a rotary word on an arc or a cycle is a 5-axis move)");
  RotaryPositions next = frame.rotary_position;
  for (char c : {'A', 'B', 'C'}) {
    if (!w.has(c) || ((w.used >> letter_index(c)) & 1u)) continue;
    const RotaryAxis* a = kin.find(c);
    if (!a) {
      std::string letters;
      for (const RotaryAxis& x : kin.axes)
        letters += (letters.empty() ? "" : ", ") + std::string(1, x.letter);
      error(w.col(c), std::string("rotary word ") + c +
                          format_number(w.value[static_cast<std::size_t>(letter_index(c))]) +
                          ": the machine has no " + c + " axis (its rotary axes: " + letters + ")");
    }
    double v = w.take(c);
    std::size_t i = static_cast<std::size_t>(rotary_index(c));
    next[i] = modal.incremental ? frame.rotary_position[i] + v : v;
    // A rotary work offset (G10 … B) says how far the fixture sits turned on the table: the
    // program's angle turns the part (the kinematics), the machine's, offset added, meets the
    // axis's limits.
    const double machine_angle = next[i] + frame.rotary_offset()[i];
    if (a->limits && (machine_angle < (*a->limits)[0] || machine_angle > (*a->limits)[1]))
      error(w.col(c), std::string("rotary position ") + c + format_number(machine_angle) +
                          " is outside the " + c + " axis's limits [" +
                          format_number((*a->limits)[0]) + ", " + format_number((*a->limits)[1]) +
                          "] (machine file)");
  }
  if (next == frame.rotary_position) return;
  // LinuxCNC plans every move, G0 too, in world coordinates and its TCP kinematics turn them into
  // joints: under a kinematics switch's TCP a rapid that turns the rotaries moves the tip straight
  // on the part as G1 does (a simultaneous move); Fanuc's G43.4 rapids are the machine's own.
  const bool tcp_kinematics = frame.tcp_kinematics && !frame.tcp && !frame.tilted && !frame.dwo;
  if (modal.motion == kG1 || (tcp_kinematics && !tool.far)) {
    simultaneous_start(first);
  } else if (tcp_kinematics) {
    // Far (after a tool change): X Y Z are the part's, so the tool stays far where it was, not
    // along its turned axis; the next Z brings it back.
    if (tool.far_axis == Vec3(0.0)) tool.far_axis = tool.axis;
  } else if (frame.tilted || frame.tcp_on() || frame.dwo) {
    go_far();
  }
  set_rotary(next);
}

// G1 turning A/B/C: simultaneous 5-axis (docs/gcode.md, "Simultaneous 5-axis"). The block's move
// carries its start (the tip on the part, the rotary positions now) and its pose law: every joint
// linear in time (raw rotary words), or under TCP the tip straight on the part with the rotaries
// linear in angle. G43.5 is read as G43.4 (the rotaries, not the tool vector, are interpolated).
// DWO (G254) and tilted planes are 3+2 frames: a turn within one is refused, even lenient (no
// reading of it would be the machine's).
void Interpreter::State::simultaneous_start(int column) {
  if (frame.tilted || frame.dwo)
    error(column, std::string("rotary motion during a cut under ") +
                      (frame.dwo ? "DWO (G254)" : "a tilted plane") +
                      " is not simultaneous 5-axis on any control: cancel it and use TCP "
                      "(G43.4), or raw rotary words");
  if (tool.far)
    error(column,
          "rotary motion during a cut while the tool is retracted far along its axis: the "
          "cut's start is unknown; position the tool (X Y Z) before turning it");
  simultaneous.active = true;
  simultaneous.pose = frame.tcp_on() ? PoseLaw::tcp : PoseLaw::joints;
  simultaneous.tip = tool.pos;
  simultaneous.rotary = frame.rotary_position;
}

// New rotary positions: the tool direction and the raw frame follow; the tip keeps its machine
// coordinates in raw form and its place on the part under TCP/DWO (the caller decides on far).
void Interpreter::State::set_rotary(const RotaryPositions& next) {
  Vec3 program_point = to_program(tool.pos);
  frame.rotary_position = next;
  tool.axis = tool_direction(*machine.kinematics, frame.rotary_position);
  update_frame();
  tool.pos = to_machine(program_point);
}

}  // namespace tridex::gcode
