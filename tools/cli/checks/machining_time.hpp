// tridex command — the machining time: each move's time from its feed or the machine's rapid
// rate, and the dwells as programmed, summed per tool, per spindle direction and in total.
//
// A feed move (line, arc chord, cycle piece) takes length / feed: the interpreter gives the feed
// in mm/min (G20 feeds converted), an arc as its chords (their summed length is the arc's to the
// arc tolerance), a canned cycle as its pieces (feed 0 marks the rapid ones). A rapid moves every
// linear axis at most at its rate: with one rate for all, length / rate; with one per axis, the
// longest of |Δx|/x, |Δy|/y, |Δz|/z (a straight rapid as LinuxCNC plans it), along the work frame's
// axes. Acceleration, tool changes and the approach from "far along the tool axis" (whose start
// is a stand-in, docs/design.md) are not timed; the approaches are counted. The interpreter
// gives every feed in mm/min: under G93 inverse time a block's moves run at its length × F, so
// the block takes 1/F minutes; under G95 at F × S.
#pragma once

#include <array>
#include <map>
#include <optional>
#include <string>
#include <vector>

#include "json_text.hpp"
#include "tridex/gcode/machine.hpp"
#include "tridex/gcode/move.hpp"
#include "tridex/geometry.hpp"

namespace tridex::cli {

struct MachiningTime {
  double feed_s = 0, rapid_s = 0, dwell_s = 0;
  std::map<int, double> by_tool;                      // tool number -> seconds
  std::vector<std::pair<Vec3, double>> by_direction;  // in order of first appearance
  // Moves whose tool axis turns (Move::pose ≠ fixed): in no direction (each ends at its own
  // axis: a 5-axis program would list one per move), counted apart.
  double simultaneous_s = 0;
  long long simultaneous_moves = 0;
  long long untimed_approaches = 0;  // moves back from "far": where they start is not known
  long long capped_feeds = 0;        // feed moves run at max_feed_mm_per_min instead
  long long untimed_turns = 0;       // rapids turning a rotary axis that has no rate
  double total_s() const { return feed_s + rapid_s + dwell_s; }
};

class MachiningTimer {
 public:
  MachiningTimer() = default;
  // The machine's speeds and, where it has them, its rotary axes.
  explicit MachiningTimer(const gcode::MachineConfig& machine);
  void add(const gcode::Move& move);
  void add(const gcode::Dwell& dwell);
  const MachiningTime& time() const { return time_; }
  const gcode::MachineRates& rates() const { return rates_; }

 private:
  void charge(int tool, const Vec3& axis, double seconds);
  double rapid_minutes(const gcode::Move& move);

  gcode::MachineRates rates_;
  std::optional<gcode::Kinematics> kinematics_;
  MachiningTime time_;
  std::size_t last_direction_ = 0;
  // Where the machine's axes stood after the previous move (kinematic model only): a rotary
  // turn between moves shows as this move's start differing from it.
  bool have_last_ = false;
  Vec3 last_machine_{0.0};
  gcode::RotaryPositions last_rotary_{};
};

// The report's "machining_time" object.
Json machining_time_json(const MachiningTimer& timer);
// "1 h 02 min 05 s" style, for the summary lines.
std::string duration_text(double seconds);
// "machining time 12 min 03 s (feed …, rapid …, dwell …) with rapids at 10000 mm/min (the
// default)": no ';', which ends the summary line's timing.
std::string machining_time_text(const MachiningTimer& timer);

}  // namespace tridex::cli
