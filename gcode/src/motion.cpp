// tridex::gcode — motion: straight moves and the "far along the tool axis" rule, arcs linearised
// to a chord tolerance, canned cycles expanded into pieces, home returns and machine-coordinate
// moves. Geometry follows RS274/NGC (NIST IR 6556) as LinuxCNC implements it.
#include <algorithm>
#include <cmath>

#include "state.hpp"

namespace tridex::gcode {

// Moves the tip to program point `target` of the frame (rot, org); coordinate i was set
// absolutely when set_absolute[i]. Handles the far state (see interpreter.hpp).
void Interpreter::State::move_to(Vec3 target, const std::array<bool, 3>& set_absolute,
                                 const Mat3& rot, const Vec3& org, MoveKind kind,
                                 double move_feed) {
  auto to_frame_machine = [&](const Vec3& p) { return org + rot * p; };
  if (!tool.far) {
    Vec3 end = to_frame_machine(target);
    emit(kind, tool.pos, end, move_feed);
    tool.pos = end;
    return;
  }
  Vec3 current = glm::transpose(rot) * (tool.pos - org);
  const Vec3 far_axis = tool.far_axis == Vec3(0.0) ? tool.axis : tool.far_axis;
  Vec3 along = glm::transpose(rot) * far_axis;
  bool any = false, all = true;
  for (int i = 0; i < 3; ++i) {
    if (std::abs(along[i]) <= kAxisEps) continue;
    if (set_absolute[static_cast<std::size_t>(i)]) {
      any = true;
    } else {
      all = false;
      target[i] = current[i];
    }
  }
  if (!any) {  // still far: only the lateral position changes
    tool.pos = to_frame_machine(target);
    return;
  }
  if (!all)
    error(context.motion_column,
          "the tool is retracted far along its axis and this move sets only some of the "
          "coordinates along the tool axis; set all of X, Y and Z to bring it back");
  Vec3 end = to_frame_machine(target);
  emit(kind, end + machine.far_distance * far_axis, end, move_feed, true);
  tool.pos = end;
  tool.far = false;
  tool.far_axis = Vec3(0.0);
}

Interpreter::State::Target Interpreter::State::axis_word_target(const Vec3& current) {
  Target t{current, {}};
  for (int i = 0; i < 3; ++i) {
    char c = kAxisLetter[i];
    if (!w.has(c)) continue;
    double v = length(c);
    t.point[i] = modal.incremental ? current[i] + v : v;
    t.set[static_cast<std::size_t>(i)] = !modal.incremental;
  }
  return t;
}

void Interpreter::State::linear(MoveKind kind, double move_feed) {
  // Under cutter compensation the programmed point, not the offset tip, is where coordinates
  // count from (and, just after G40, until the next move).
  Vec3 current = comp.programmed_current ? comp.programmed : to_program(tool.pos);
  const auto [target, set] = axis_word_target(current);
  comp.programmed_current = false;
  if (kind == MoveKind::feed && modal.feed_mode == FeedMode::inverse_time) {
    inverse_time_rate(glm::length(target - current));
    move_feed = modal.feed;
  }
  if (comp_active()) {
    comp_straight(kind, target, move_feed);
    return;
  }
  comp.arc_forbidden = false;
  move_to(target, set, frame.rotation, frame.origin, kind, move_feed);
}

void Interpreter::State::require_feed() {
  if (modal.feed_mode == FeedMode::inverse_time) {  // LinuxCNC's checks (interp_convert.cc)
    if (!w.has('F'))
      error(context.motion_column,
            "F word missing with inverse time (G93) feed move: every G1, G2 and G3 "
            "block needs its own F");
    if (!(modal.inverse_time > 0))
      error(w.col('F'), "inverse time (G93) F0: the move would never end");
    return;
  }
  if (modal.feed_mode == FeedMode::per_revolution) {
    if (!(modal.feed_per_rev > 0))
      error(context.motion_column, "feed move with no feed per revolution (F) set (G95)");
    if (!(modal.speed > 0))
      error(context.motion_column,
            "cannot feed with zero spindle speed in feed per revolution mode (G95)");
    return;
  }
  if (!(modal.feed > 0)) {
    std::string left_out;
    if (w.vacant_words)
      for (const std::string& word : *w.vacant_words)
        if (word[0] == 'F')
          left_out = ": this block's " + word +
                     " was left out, its value vacant (a variable the control keeps, such "
                     "as #500-#999, is set at the start by the machine file's \"variables\")";
    error(context.motion_column, "feed move with no feed rate (F) set" + left_out);
  }
}

// G93: a block `length` mm long (its programmed path, as LinuxCNC's inverse_time_rate_straight
// and _arc measure it) takes 1/F minutes, so it runs at length × F mm/min. A block that does not
// move takes no time at any rate; LinuxCNC gives it 0.1 units/min.
void Interpreter::State::inverse_time_rate(double length) {
  modal.feed = length > 0 ? length * modal.inverse_time : 0.1 * modal.unit;
}

// The length of the arc (a helix along the plane normal) from `start` (program frame) that
// arc_data found, as LinuxCNC's find_arc_length: the start radius times the sweep, and the rise.
double Interpreter::State::arc_length(const Vec3& start, const ArcData& a, bool ccw,
                                      int extra_turns) const {
  const std::array<int, 3> axes = plane_axes(modal.plane);
  double radius = glm::length(a.centre - Vec2(start[axes[0]], start[axes[1]]));
  double sweep = arc_sweep(start, a.end, a.centre, ccw) + 2 * kPi * extra_turns;
  return std::hypot(radius * sweep, a.end[axes[2]] - start[axes[2]]);
}

// LinuxCNC's P on G2/G3, the number of turns (a helix that winds P times down a bore): the arc
// goes round P − 1 full circles before its end, the rise shared over all of them (rs274 prints
// `G3 … P3` as ARC_FEED(…, 3, …), the rotation that LinuxCNC 2.9 interp_find.cc find_turn turns
// into the arc plus (P − 1)·2π). P must be an integer of 1 or more, as rs274 requires ("P value
// not an integer with M19 G2 or G3", "P value should be 1 or greater with G2 or G3"). Returns
// P − 1; 0 without P. On Fanuc and Haas P stays a word no code of the block uses.
int Interpreter::State::arc_extra_turns() {
  if (machine.dialect != Dialect::linuxcnc || !w.has('P')) return 0;
  return static_cast<int>(integer('P', "G2/G3 P (the number of turns)", 1, 1'000'000)) - 1;
}

// ---- arcs ----
void Interpreter::State::arc(bool ccw) {
  if (comp.arc_forbidden)
    error(context.motion_column,
          "the move just after turning cutter compensation off (G40) must be straight, "
          "not an arc (as LinuxCNC requires)");
  if (comp_active()) {
    require_feed();
    comp_arc(ccw);
    return;
  }
  if (tool.far) {
    // The far rule: a move that leaves the coordinates along the tool axis unset stays far and
    // only changes the lateral position (a 2D program's arcs before any Z cut nothing).
    Vec3 along = glm::transpose(frame.rotation) * tool.axis;
    Vec3 target = to_program(tool.pos);
    for (int i = 0; i < 3; ++i) {
      char c = kAxisLetter[i];
      if (!w.has(c)) continue;
      if (std::abs(along[i]) > kAxisEps)
        error(w.col(c),
              "arc from a retracted position that also moves along the tool axis: the "
              "tool is far along its axis and its start is unknown; position it first");
      target[i] = modal.incremental ? target[i] + length(c) : length(c);
    }
    for (char c : {'I', 'J', 'K', 'R'})
      if (w.has(c)) w.take(c);
    arc_extra_turns();
    tool.pos = to_machine(target);
    return;
  }
  require_feed();
  Vec3 start = to_program(tool.pos);
  ArcData a = arc_data(start, ccw);
  const int extra_turns = arc_extra_turns();
  if (modal.feed_mode == FeedMode::inverse_time)
    inverse_time_rate(arc_length(start, a, ccw, extra_turns));
  arc_chords(start, a.end, a.centre, ccw,
             arc_sweep(start, a.end, a.centre, ccw) + 2 * kPi * extra_turns, modal.feed);
  tool.pos = to_machine(a.end);
}

// The end point and centre of the G2/G3 of this block from `start` (program frame), with
// RS274/NGC's checks: I/J/K or R, radii that agree, a radius long enough for its chord.
Interpreter::State::ArcData Interpreter::State::arc_data(const Vec3& start, bool ccw) {
  const std::array<int, 3> axes = plane_axes(modal.plane);
  const int u = axes[0], v = axes[1];
  Vec3 end = start;
  for (int i = 0; i < 3; ++i) {
    char c = kAxisLetter[i];
    if (w.has(c)) end[i] = modal.incremental ? start[i] + length(c) : length(c);
  }
  char cu = kCenterLetter[u], cv = kCenterLetter[v];
  bool has_center = w.has(cu) || w.has(cv);
  bool has_radius = w.has('R');
  if (has_center && has_radius)
    error(w.col('R'), "arc with both R and " + std::string(1, cu) + "/" + cv + " words");
  if (!has_center && !has_radius)
    error(context.motion_column, std::string("arc needs ") + cu + "/" + cv + " (in " +
                                     code_name('G', modal.plane) + ") or R");
  Vec2 s(start[u], start[v]), e(end[u], end[v]), c;
  ArcData result;
  result.end = end;
  if (has_center) {
    if (modal.arc_absolute) {
      if (!w.has(cu) || !w.has(cv))
        error(context.motion_column,
              std::string("arc centre under G90.1 needs both ") + cu + " and " + cv);
      c = Vec2(length(cu), length(cv));
    } else {
      c = s + Vec2(w.has(cu) ? length(cu) : 0.0, w.has(cv) ? length(cv) : 0.0);
    }
    double r0 = glm::length(s - c);
    double r1 = glm::length(e - c);
    if (!(r0 > 1e-9))
      error(context.motion_column, "zero-radius arc: the centre is the start point");
    if (!(r1 > 1e-9)) error(context.motion_column, "zero-radius arc: the centre is the end point");
    // LinuxCNC 2.9 (interp_arc.cc arc_data_ijk) cuts a spiral where the radii differ by up to
    // 0.002·√2 in (0.02·√2 mm under G21), or by 100 times that within 0.1 % of the radius.
    const bool linuxcnc = machine.dialect == Dialect::linuxcnc && !machine.arc_radius_tolerance;
    const double spiral = (modal.unit == 1.0 ? 0.02 : 0.002 * 25.4) * std::numbers::sqrt2;
    auto radii_disagree = [&](const Vec2& centre) {
      const double a = glm::length(s - centre), b = glm::length(e - centre);
      const double d = std::abs(b - a);
      return linuxcnc ? d > 100 * spiral || (d / std::max(a, b) > 0.001 && d > spiral)
                      : d > arc_radius_tolerance();
    };
    if (radii_disagree(c)) {
      // A post that writes absolute centres without G90.1 (or incremental ones under it) makes
      // the radii disagree; say so when the words fit as the other mode's centre (issue 39).
      std::string hint;
      if (!modal.arc_absolute && w.has(cu) && w.has(cv) &&
          !radii_disagree(Vec2(length(cu), length(cv))))
        hint = "; the " + std::string(1, cu) + "/" + cv +
               " words fit as absolute centres: is G90.1 missing?";
      if (modal.arc_absolute &&
          !radii_disagree(s + Vec2(w.has(cu) ? length(cu) : 0.0, w.has(cv) ? length(cv) : 0.0)))
        hint = "; the " + std::string(1, cu) + "/" + cv +
               " words fit as incremental centres: is G91.1 missing?";
      error(context.motion_column,
            "arc end radius " + format_number(r1) + " differs from start radius " +
                format_number(r0) + " by more than " +
                (linuxcnc ? "LinuxCNC's spiral tolerance (" + format_number(spiral) +
                                " mm, or 0.1 % of the radius)"
                          : format_number(arc_radius_tolerance()) + " mm (" +
                                arc_tolerance_source() + ")") +
                hint);
    }
  } else {
    double r = length('R');
    double d = glm::length(e - s);
    if (!(std::abs(r) > 1e-9)) error(w.col('R'), "zero-radius arc (R0)");
    if (!(d > 1e-9))
      error(w.col('R'), "R-form arc with the same start and end point (a full circle needs I/J/K)");
    if (d > 2 * std::abs(r) + arc_radius_tolerance())
      error(w.col('R'), "arc radius " + format_number(std::abs(r)) +
                            " is too small for its chord of " + format_number(d));
    result.programmed_radius = std::abs(r);
    double h = std::sqrt(std::max(0.0, r * r - d * d / 4));
    Vec2 dir = (e - s) / d;
    Vec2 left(-dir.y, dir.x);
    // The shorter arc (R > 0) turns around a centre on its inner side: left of the chord for
    // counter-clockwise motion.
    bool centre_left = ccw == (r > 0);
    c = 0.5 * (s + e) + (centre_left ? h : -h) * left;
  }
  result.centre = c;
  return result;
}

// How far an arc from `start` to `end` (program frame) turns about `c` in the active plane:
// (0, 2π], a full circle when the two points coincide.
double Interpreter::State::arc_sweep(const Vec3& start, const Vec3& end, const Vec2& c,
                                     bool ccw) const {
  const std::array<int, 3> axes = plane_axes(modal.plane);
  const int u = axes[0], v = axes[1];
  Vec2 s(start[u], start[v]), e(end[u], end[v]);
  double a0 = std::atan2(s.y - c.y, s.x - c.x);
  double a1 = std::atan2(e.y - c.y, e.x - c.x);
  double sweep = ccw ? a1 - a0 : a0 - a1;
  if (glm::length(e - s) <= 1e-9) return 2 * kPi;  // start == end: a full circle
  while (sweep <= 0) sweep += 2 * kPi;
  while (sweep > 2 * kPi) sweep -= 2 * kPi;
  return sweep;
}

// Emits the arc from the tip (at program point `start`) to `end` about `c`, turning `sweep`
// radians, as chords within the arc tolerance; the radius and the height along the plane normal
// change linearly (helices, and I/J/K arcs whose end radius differs slightly).
void Interpreter::State::arc_chords(const Vec3& start, const Vec3& end, const Vec2& c, bool ccw,
                                    double sweep, double move_feed) {
  const std::array<int, 3> axes = plane_axes(modal.plane);
  const int u = axes[0], v = axes[1], n = axes[2];
  Vec2 s(start[u], start[v]), e(end[u], end[v]);
  double r0 = glm::length(s - c), r1 = glm::length(e - c);
  double a0 = std::atan2(s.y - c.y, s.x - c.x);
  double r = std::max(r0, r1);
  long long pieces = 1;
  if (r > options.arc_tolerance) {
    double step = 2 * std::acos(1 - options.arc_tolerance / r);
    double count = std::ceil(sweep / step);
    if (!(count <= static_cast<double>(kMaxArcPieces)))
      error(context.motion_column, "arc of radius " + format_number(r) + " needs more than " +
                                       std::to_string(kMaxArcPieces) + " pieces at this tolerance");
    pieces = std::max(1LL, static_cast<long long>(count));
  }
  double sign = ccw ? 1.0 : -1.0;
  Vec3 previous = tool.pos;
  for (long long k = 1; k <= pieces; ++k) {
    Vec3 p = end;
    if (k < pieces) {
      double t = static_cast<double>(k) / static_cast<double>(pieces);
      double angle = a0 + sign * sweep * t;
      double radius = r0 + (r1 - r0) * t;
      p[u] = c.x + radius * std::cos(angle);
      p[v] = c.y + radius * std::sin(angle);
      p[n] = start[n] + (end[n] - start[n]) * t;
    }
    Vec3 m = to_machine(p);
    emit(MoveKind::arc, previous, m, move_feed);
    previous = m;
  }
  tool.pos = to_machine(end);
}

// ---- straight probes ----
// LinuxCNC's G38.2 / G38.3 (towards the part, G38.3 without error when nothing is touched) and
// G38.4 / G38.5 (away from it), as its rs274 run standalone reads them (interp_convert.cc
// convert_probe, the errors; sai/saicanon.cc STRAIGHT_PROBE, the position): the probe reaches the
// programmed point and stops 0.254 mm (0.01 in) back towards where it started, and the next
// block starts there. #5061–#5063 hold the programmed point, #5070 is 0 (standalone's "not
// tripped"). Where a real probe touches is known only on the machine: said once in the warnings.
void Interpreter::State::probe(int code) {
  const std::string name = code_name('G', code);
  if (comp.side != 0)
    error(context.motion_column, name + ": cannot probe with cutter radius compensation on");
  if (modal.feed_mode == FeedMode::per_revolution)
    error(context.motion_column, name + ": cannot probe in feed per revolution mode (G95)");
  if (!(modal.feed > 0)) error(context.motion_column, name + ": cannot probe with zero feed rate");
  Vec3 current = comp.programmed_current ? comp.programmed : to_program(tool.pos);
  const auto [target, set] = axis_word_target(current);
  comp.programmed_current = false;
  comp.arc_forbidden = false;
  const bool must_move = code == kG38_2 || code == kG38_4;  // G38.3/G38.5 may stand still
  if (must_move && target == current)
    error(context.motion_column,
          name + ": start point too close to probe point (the probe does not move)");
  if (!warned_once.probe) {
    warned_once.probe = true;
    warn(context.motion_column,
         name +
             " read as LinuxCNC's rs274 standalone does: the probe reaches the "
             "programmed point and backs off 0.254 mm; where it really touches is "
             "known only on the machine");
  }
  move_to(target, set, frame.rotation, frame.origin, MoveKind::feed, modal.feed);
  for (int i = 0; i < 3; ++i) parameters.globals[5061 + i] = Value{target[i] / modal.unit, false};
  parameters.globals[5070] = Value{0, false};
  double distance = glm::length(target - current);
  if (tool.far || !(distance > 0)) return;
  Vec3 back = to_machine(target + 0.254 * (current - target) / distance);
  emit(MoveKind::feed, tool.pos, back, modal.feed);
  tool.pos = back;
}

// ---- canned cycles ----
namespace {
// The cycles that dwell at the bottom of the hole.
bool cycle_dwells(int code) {
  return code == kG74 || code == kG82 || code == kG84 || code == kG86 || code == kG89;
}
}  // namespace

// A canned cycle's block: its sticky words, the levels along its axis, then each hole (L or K
// repeats) in turn.
void Interpreter::State::cycle(int code) {
  const std::array<int, 3> axes = plane_axes(modal.plane);
  const int u = axes[0], v = axes[1], n = axes[2];
  Vec3 drill = frame.rotation[n];  // cycle axis in machine coordinates
  if (glm::dot(drill, tool.axis) < 1 - 1e-9)
    error(context.motion_column, code_name('G', code) + " drills along the " +
                                     code_name('G', modal.plane) +
                                     " plane normal, which is not the spindle direction");
  const long long repeats = cycle_words(code, kAxisLetter[n]);

  Vec3 current = to_program(tool.pos);
  const CycleLevels levels = cycle_levels(code, current[n]);

  // Lateral target of the first hole; increments repeat under G91.
  double du = w.has(kAxisLetter[u]) ? length(kAxisLetter[u]) : 0.0;
  double dv = w.has(kAxisLetter[v]) ? length(kAxisLetter[v]) : 0.0;
  double hole_u = modal.incremental ? current[u] : (w.has(kAxisLetter[u]) ? du : current[u]);
  double hole_v = modal.incremental ? current[v] : (w.has(kAxisLetter[v]) ? dv : current[v]);
  // LinuxCNC's polar words under G91 (polar_words() left them): each repeat moves the hole out
  // by @ and turns it by ^ about the program origin (CYCLE_MACRO, interp_cycles.cc).
  double step_radius = w.has('@') ? length('@') : 0.0;
  double step_angle = w.has('^') ? glm::radians(w.take('^')) : 0.0;

  if (!tool.far && current[n] < levels.r_level - 1e-9)
    cycle_rapid(cycle_point(current[u], current[v], levels.r_level));
  for (long long k = 0; k < repeats; ++k) {
    if (modal.incremental) {
      hole_u += du;
      hole_v += dv;
    }
    if (step_radius != 0 || step_angle != 0) {
      if (hole_u == 0 && hole_v == 0)
        error(context.motion_column,
              "incremental (G91) polar coordinates at the origin: the direction is unknown");
      double radius = std::hypot(hole_u, hole_v) + step_radius;
      double angle = std::atan2(hole_v, hole_u) + step_angle;
      hole_u = radius * std::cos(angle);
      hole_v = radius * std::sin(angle);
    }
    cycle_hole(code, hole_u, hole_v, levels);
  }
}

// The cycle's words: R, the depth along the plane's normal and Q stay from block to block (the
// cycle's sticky data), P where the cycle reads it; the repeat count (L or K) is returned.
long long Interpreter::State::cycle_words(int code, char depth_letter) {
  if (w.has('R')) {
    canned.r = length('R');
    canned.has_r = true;
  }
  if (w.has(depth_letter)) {
    canned.z = length(depth_letter);
    canned.has_z = true;
  }
  if (code == kG73 || code == kG83) {
    if (w.has('Q')) {
      canned.q = length('Q');
      canned.has_q = true;
    }
    if (!canned.has_q || !(canned.q > 0))
      error(context.motion_column, code_name('G', code) + " needs a positive peck depth Q");
  }
  // The cycles that dwell at the bottom read P. Fanuc and Haas keep P as modal cycle data in any
  // cycle (a post writes it on G81 too), for a later one that dwells.
  if ((cycle_dwells(code) || machine.dialect != Dialect::linuxcnc) && w.has('P')) {
    double p = w.take('P');
    if (p < 0) error(w.col('P'), "dwell P must not be negative");
    canned.dwell = dwell_seconds(p);
  }
  if (modal.feed_mode == FeedMode::inverse_time)
    error(context.motion_column, code_name('G', code) +
                                     ": canned cycles cannot run in inverse time feed "
                                     "(G93), as LinuxCNC requires; G94 first");
  if (!canned.has_r)
    error(context.motion_column, code_name('G', code) + " needs R (retract plane)");
  if (!canned.has_z)
    error(context.motion_column,
          code_name('G', code) + " needs " + depth_letter + " (hole bottom)");
  require_feed();
  if (w.has('L') && w.has('K')) error(w.col('K'), "repeat count given twice (L and K)");
  if (w.has('L') && (code == kG74 || code == kG84) && machine.dialect == Dialect::linuxcnc)
    error(w.col('L'),
          code_name('G', code) + " L: LinuxCNC's rs274 takes no repeats on a tapping cycle");
  long long repeats = 1;
  if (w.has('L')) repeats = integer('L', "repeat count", 0, 9999);
  if (w.has('K')) repeats = integer('K', "repeat count", 0, 9999);
  return repeats;
}

// The R plane, the bottom and the clear level along the cycle's axis, from `current` (the tool's
// place along it); the cycle's initial level is kept while the cycle mode lasts.
Interpreter::State::CycleLevels Interpreter::State::cycle_levels(int code, double current) {
  if (!canned.active) {
    canned.active = true;
    canned.initial_far = tool.far;
    canned.initial = current;
  }
  if (tool.far && modal.incremental)
    error(context.motion_column, "incremental canned cycle from a retracted (far) position");
  // G91: R counts from the initial level of the cycle (kept while the cycle mode lasts, as
  // LinuxCNC's cycle_il and Fanuc's initial point), not from where the last hole left the tool.
  double incremental_base = canned.initial_far ? current : canned.initial;
  double r_level = modal.incremental ? incremental_base + canned.r : canned.r;
  double bottom = modal.incremental ? r_level + canned.z : canned.z;
  if (bottom > r_level)
    error(context.motion_column, "hole bottom " + format_number(bottom) + " is above the R plane " +
                                     format_number(r_level));
  if (code == kG73 || code == kG83) {
    // A real control pecks a hole a few hundred times at most; a tiny Q against a deep hole
    // (or a far R plane) would emit moves without end, and below one ulp would never finish.
    constexpr double kMaxPecks = 100000;
    double pecks = (r_level - bottom) / canned.q;
    if (!(pecks <= kMaxPecks))
      error(context.motion_column, code_name('G', code) + " would peck " + format_number(pecks) +
                                       " times (R " + format_number(r_level) + " to " +
                                       format_number(bottom) + " by Q " + format_number(canned.q) +
                                       "); at most 100000 per hole");
  }
  bool clear_far = !modal.retract_to_r && canned.initial_far;
  double clear = modal.retract_to_r ? r_level : std::max(canned.initial, r_level);
  if (clear_far) clear = r_level;
  return CycleLevels{r_level, bottom, clear, clear_far};
}

// A point of the cycle: (u, v) in the plane and `depth` along its normal, program frame.
Vec3 Interpreter::State::cycle_point(double u_coordinate, double v_coordinate, double depth) const {
  const std::array<int, 3> axes = plane_axes(modal.plane);
  Vec3 p;
  p[axes[0]] = u_coordinate;
  p[axes[1]] = v_coordinate;
  p[axes[2]] = depth;
  return to_machine(p);
}

void Interpreter::State::cycle_rapid(const Vec3& to) {
  emit(MoveKind::cycle, tool.pos, to, 0.0);
  tool.pos = to;
}

void Interpreter::State::cycle_cut(const Vec3& to) {
  emit(MoveKind::cycle, tool.pos, to, modal.feed);
  tool.pos = to;
}

// One hole: onto its R plane, down (pecking for G73 and G83), the dwell, and out to the clear
// level.
void Interpreter::State::cycle_hole(int code, double hole_u, double hole_v,
                                    const CycleLevels& levels) {
  const int n = plane_axes(modal.plane)[2];
  const double r_level = levels.r_level, bottom = levels.bottom, clear = levels.clear;
  const bool clear_far = levels.clear_far;
  auto at = [&](double uu, double vv, double depth) { return cycle_point(uu, vv, depth); };
  if (tool.far) {
    // Come back from far straight down the axis onto the R plane of the hole.
    Vec3 r_point = at(hole_u, hole_v, r_level);
    emit(MoveKind::cycle, r_point + machine.far_distance * tool.axis, r_point, 0.0, true);
    tool.pos = r_point;
    tool.far = false;
  } else {
    Vec3 level = to_program(tool.pos);
    cycle_rapid(at(hole_u, hole_v, level[n]));
    cycle_rapid(at(hole_u, hole_v, r_level));
  }
  double d = options.peck_clearance;
  switch (code) {
    case kG73:
      for (double depth = r_level - canned.q; depth > bottom; depth -= canned.q) {
        cycle_cut(at(hole_u, hole_v, depth));
        cycle_rapid(at(hole_u, hole_v, depth + d));
      }
      cycle_cut(at(hole_u, hole_v, bottom));
      break;
    case kG83:
      for (double depth = r_level - canned.q; depth > bottom; depth -= canned.q) {
        cycle_cut(at(hole_u, hole_v, depth));
        cycle_rapid(at(hole_u, hole_v, r_level));
        cycle_rapid(at(hole_u, hole_v, depth + d));
      }
      cycle_cut(at(hole_u, hole_v, bottom));
      break;
    default:  // the others go down at feed in one piece
      cycle_cut(at(hole_u, hole_v, bottom));
      break;
  }
  if (cycle_dwells(code)) emit_dwell(canned.dwell);  // at the bottom
  switch (code) {  // the way out: at feed for these, at rapid for the others (below)
    case kG74:     // tapping (G74 left hand, G84 right hand): the spindle reverses and the tap
    case kG84:  // backs out at feed: to R on Fanuc and Haas, as G85; LinuxCNC's to the clear level
      cycle_cut(
          at(hole_u, hole_v, machine.dialect == Dialect::linuxcnc && !clear_far ? clear : r_level));
      break;
    case kG85:  // to R (then rapid to the clear level)
      cycle_cut(at(hole_u, hole_v, r_level));
      break;
    case kG89:  // all the way to the clear level, as LinuxCNC does
      cycle_cut(at(hole_u, hole_v, clear_far ? r_level : clear));
      break;
    default:
      break;
  }
  Vec3 out = at(hole_u, hole_v, clear);
  if (out != tool.pos) cycle_rapid(out);
  if (clear_far) go_far();
}

// ---- LinuxCNC polar coordinates ----
// `@` is a radius and `^` an angle (degrees, from +X) about the program origin in the XY plane
// (LinuxCNC's find_ends and convert_cycle_xy, interp_find.cc and interp_cycles.cc). G90: a word
// left out keeps the current point's radius or angle. G91: `@` adds to the current radius, `^`
// turns the current point about the origin. The result is written back as the block's X and Y
// (in program units, incremental under G91), so lines, arcs, cycles and compensation read it;
// in a G91 cycle they are a step of each repeat instead (cycle()).
void Interpreter::State::polar_words(bool axis_consumer, int nonmodal) {
  int column = w.col(w.has('@') ? '@' : '^');
  if (machine.dialect != Dialect::linuxcnc)
    error(column, "'@' and '^' (polar coordinates) are LinuxCNC's words: use --machine linuxcnc");
  if (nonmodal == kG53) error(column, "polar coordinates cannot be used with G53");
  bool moving = modal.motion == kG0 || modal.motion == kG1 || modal.motion == kG2 ||
                modal.motion == kG3 || is_cycle(modal.motion);
  if (axis_consumer || nonmodal == kG28 || nonmodal == kG30 || !moving)
    error(column, "polar coordinates can only be used for motion (G0, G1, G2, G3 or a cycle)");
  if (modal.plane != kG17) error(column, "polar coordinates need the XY plane (G17)");
  for (char c : {'X', 'Y'})
    if (w.has(c))
      error(w.col(c), std::string("polar coordinates and an ") + c + " word in the same block");
  bool cycle_block = is_cycle(modal.motion);
  if (cycle_block && modal.incremental) return;  // a step of every repeat: cycle() reads the words
  Vec3 current = (comp.programmed_current ? comp.programmed : to_program(tool.pos)) / modal.unit;
  double x = current.x, y = current.y;
  bool has_radius = w.has('@'), has_angle = w.has('^');
  double radius = has_radius ? w.take('@') : 0, angle = has_angle ? glm::radians(w.take('^')) : 0;
  bool at_origin = x == 0 && y == 0;
  if (!modal.incremental) {
    if (!has_angle && at_origin && !cycle_block)
      error(column, "polar radius without an angle at the origin: the direction is unknown");
    if (!has_radius) radius = std::hypot(x, y);
    if (!has_angle) angle = std::atan2(y, x);
  } else {
    if (at_origin)
      error(column, "incremental (G91) polar coordinates at the origin: the direction is unknown");
    radius += std::hypot(x, y);
    angle += std::atan2(y, x);
  }
  w.present &= ~((1u << letter_index('@')) | (1u << letter_index('^')));  // read: now X and Y
  double new_x = radius * std::cos(angle), new_y = radius * std::sin(angle);
  for (char c : {'X', 'Y'}) {
    std::size_t i = static_cast<std::size_t>(letter_index(c));
    w.present |= 1u << i;
    w.value[i] = c == 'X' ? (modal.incremental ? new_x - x : new_x)
                          : (modal.incremental ? new_y - y : new_y);
    w.column[i] = column;
  }
}

// ---- returns and machine-coordinate moves ----
// The machine's Z is the spindle's own axis (on a table-tilting machine it stays along the tool
// in the work frame; on a head-tilting one it retracts the head), so a machine-coordinate move
// of Z is a retract: the tip goes far along the tool axis. X/Y alone move the tip in machine
// coordinates, which is only unambiguous with the tool along +Z. A machine whose zero is known
// (MachineConfig::g53_literal, e.g. LinuxCNC's rs274) moves to the point named, as G28 does to a
// configured position.
void Interpreter::State::machine_move(const Vec3& gauge, unsigned mask, MoveKind kind,
                                      double move_feed) {
  Vec3 target = tip_below(gauge);
  Vec3 end = tool.pos;
  for (int i = 0; i < 3; ++i)
    if ((mask >> i) & 1u) end[i] = target[i];
  bool along_z = glm::dot(tool.axis, Vec3(0, 0, 1)) >= 1 - kSameDirection;
  if (machine.g53_literal && along_z && tool.far) {
    tool.pos = end;
    if (mask & 4u) tool.far = false;  // the height is now known
    return;
  }
  if (((mask & 4u) && !(machine.g53_literal && along_z)) || tool.far) {
    tool.pos = end;
    go_far();
    return;
  }
  if (!along_z)
    error(context.motion_column,
          "G53 X/Y with a tilted tool depends on the machine's kinematics; "
          "retract with G53 Z (or G28) first");
  if (kind == MoveKind::feed && modal.feed_mode == FeedMode::inverse_time) {
    inverse_time_rate(glm::length(end - tool.pos));
    move_feed = modal.feed;
  }
  emit(kind, tool.pos, end, move_feed);
  tool.pos = end;
}

void Interpreter::State::home_return(bool second) {
  int column = w.find_g(second ? kG30 : kG28);
  if (second && w.has('P')) {
    if (integer('P', "G30 reference number", 2, 2) != 2) error(w.col('P'), "only G30 P2");
  }
  unsigned mask = 0;
  for (int i = 0; i < 3; ++i)
    if (w.has(kAxisLetter[i])) mask |= 1u << i;
  const bool rotary = w.has('A') || w.has('B') || w.has('C');
  if (mask) linear(MoveKind::rapid, 0.0);  // the intermediate point
  if (!mask && !rotary) mask = 7;
  // The named rotary axes go to their zero. With a kinematic model that moves the part or tilts
  // the tool only when one of them was not at zero already; without one, only when the tool
  // was oriented off +Z (G53.1 and the like), which the return brings back. Otherwise the
  // linear axes return as if no rotary word were given (a 4-axis post's `G28 X0 Y0 A0`).
  bool turns =
      rotary && !machine.kinematics && glm::dot(tool.axis, Vec3(0, 0, 1)) < 1 - kSameDirection;
  for (char c : {'A', 'B', 'C'})
    if (w.has(c)) {
      w.take(c);
      const std::size_t i = static_cast<std::size_t>(rotary_index(c));
      // The machine's zero: a rotary work offset's fixture then stands turned back by it.
      const double home_angle = -frame.rotary_offset()[i];
      double& angle = frame.rotary_position[i];
      turns = turns || (machine.kinematics && angle != home_angle);
      angle = home_angle;
    }
  const Vec3& target = second ? machine.reference2 : machine.home;
  bool is_default = second ? machine.reference2_is_default : machine.home_is_default;
  bool& warned = second ? warned_once.reference2 : warned_once.home;
  // Returning Z alone (the posts' `G28 G91 Z0`) retracts to the top of Z's travel on any mill,
  // which the far rule models exactly; only a return of X or Y lands at a position the default
  // reference has to guess.
  bool guesses_lateral = (mask & 3u) != 0;
  if (is_default && guesses_lateral && !warned) {
    warn(column, std::string(second ? "G30" : "G28") +
                     " returns X or Y to the default reference position (unknown: the tool is "
                     "left far above the work); a machine file (--machine) sets it, \"home\" "
                     "and \"reference2\"");
    warned = true;
  }
  // With the tool along +Z, returning X/Y only is a plain rapid at the current height (on any
  // machine). Anything else is a retract: the tip goes far along the tool axis, the homed
  // axes' coordinates kept for the lateral position.
  if (mask && !(mask & 4u) && !turns && !tool.far &&
      glm::dot(tool.axis, Vec3(0, 0, 1)) >= 1 - kSameDirection) {
    machine_move(target, mask, MoveKind::rapid, 0.0);
    return;
  }
  // A machine file that sets the position makes the return a known rapid (tool along +Z: the
  // machine's axes are the work's).
  if (!is_default && !turns && glm::dot(tool.axis, Vec3(0, 0, 1)) >= 1 - kSameDirection) {
    Vec3 end = tool.pos;
    for (int i = 0; i < 3; ++i)
      if ((mask >> i) & 1u) end[i] = tip_below(target)[i];
    if (!tool.far) {
      emit(MoveKind::rapid, tool.pos, end, 0.0);
      tool.pos = end;
      return;
    }
    tool.pos = end;
    if (mask & 4u) tool.far = false;  // the height is now known
    return;
  }
  for (int i = 0; i < 3; ++i)
    if ((mask >> i) & 1u) tool.pos[i] = target[i];
  go_far();
  if (turns) {
    // The tip goes far while the axes turn; the direction follows the kinematic model.
    tool.axis = machine.kinematics ? tool_direction(*machine.kinematics, frame.rotary_position)
                                   : Vec3(0, 0, 1);
    update_frame();
  }
}

}  // namespace tridex::gcode
