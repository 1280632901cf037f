// tridex::gcode — one tool-tip move, the unit the interpreter streams to the simulator.
#pragma once

#include <array>

#include "tridex/geometry.hpp"

namespace tridex::gcode {

// rapid: G0 (and the returns of G28/G30/G53); feed: G1; arc: one chord of a linearised G2/G3;
// cycle: one straight piece of an expanded canned cycle (feed == 0 marks its rapid pieces).
enum class MoveKind { rapid, feed, arc, cycle };

inline const char* to_string(MoveKind kind) {
  switch (kind) {
    case MoveKind::rapid:
      return "rapid";
    case MoveKind::feed:
      return "feed";
    case MoveKind::arc:
      return "arc";
    case MoveKind::cycle:
      return "cycle";
  }
  return "?";
}

// How the tool moves along a move (docs/gcode.md, "Simultaneous 5-axis"). fixed: the tool axis
// stays `axis` and the tip runs straight from `start` to `end` (every move of a 3+2 program).
// joints: rotary words on a cut without TCP: every joint (the linear axes' machine coordinates
// and the rotary positions) runs linearly in time from its start to its end value, so the tip
// curves on the part. tcp: under G43.4/G43.5 the tip runs straight on the part while
// the rotaries run linearly in angle. Only joints and tcp moves turn the tool.
enum class PoseLaw : unsigned char { fixed, joints, tcp };

struct Move {
  int line = 0;  // 1-based source line of the block that made the move
  MoveKind kind = MoveKind::rapid;
  int tool = 0;              // the tool in the spindle (last M6); 0 before any tool change
  int file = 0;              // the file of `line`: an index into Interpreter::files() (0: the
                             //   program run() read; then the subprogram files it called)
  Vec3 start{0.0};           // tool tip, mm, in the work frame (the simulation's world frame:
  Vec3 end{0.0};             //   machine table frame after the G54 offset, no tilted plane)
  Vec3 axis{0.0, 0.0, 1.0};  // unit spindle direction (tip towards holder), work frame
  double feed = 0;           // mm/min; 0 for rapids and the rapid pieces of cycles
  double spindle = 0;        // rpm, signed: + for M3, − for M4, 0 while stopped (M5)
  bool from_far = false;     // the approach from "far along the tool axis": `start` is a
                             //   stand-in for where the machine put the tool, not a point
                             //   of the program (docs/design.md, the far rule)
  // With a kinematic model (MachineConfig::kinematics) only: the machine's rotary axes (bit 0
  // A, 1 B, 2 C), their positions in degrees (A, B, C) and the machine coordinates of the linear
  // axes at `end` (work offset included: where the machine's axes stand).
  unsigned char rotary_axes = 0;
  PoseLaw pose = PoseLaw::fixed;
  std::array<double, 3> rotary{};
  Vec3 machine{0.0};
  // A simultaneous move (pose ≠ fixed) only: the rotary positions at `start`; `axis`, `rotary`
  // and `machine` are the end's. The start's machine coordinates follow from `start` and these
  // (gcode/simultaneous.hpp).
  std::array<double, 3> rotary_start{};
};

// A pause with the tool standing still: G4, and the pause at a hole's bottom in G82, G86 and
// G89. Not a move (it removes nothing); it counts for the machining time only.
struct Dwell {
  int line = 0;              // 1-based source line of the block that dwells
  int tool = 0;              // the tool in the spindle
  Vec3 axis{0.0, 0.0, 1.0};  // the spindle direction, work frame
  double seconds = 0;        // as programmed, converted to seconds (see Interpreter::run)
};

}  // namespace tridex::gcode
