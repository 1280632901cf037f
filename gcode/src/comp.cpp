// tridex::gcode — cutter radius compensation: G41/G42 D (the tool table's radius), LinuxCNC's
// G41.1/G42.1 D (a diameter), G40. The offset path is computed as LinuxCNC computes it
// (src/emc/rs274ngc/interp_convert.cc: convert_straight_comp1/2, convert_arc_comp1/2,
// convert_cutter_compensation_on/off; interp_queue.cc: move_endpoint_and_flush), so that tridex
// and `rs274` agree move for move, errors included:
// - the entry move (the first after G41/G42) ends one radius to the side of its programmed end,
//   perpendicular to itself; an entry no longer than the radius is an error. Fanuc and Haas
//   (their start-up of type A, Fanuc's default) end it perpendicular to the start of the next
//   move instead, of any length; so a hole's "line from the centre, then G3 I" needs no room
//   for a corner (comp_resolve_entry);
// - later moves end one radius to the side of their programmed ends; a convex corner gets an arc
//   about the programmed corner (a G0 gets a straight piece instead); at a concave corner the
//   moves still waiting in the queue are cut back to where the offset paths meet, an error when
//   cutting back would reverse a move or shorten an arc past its start ("gouging");
// - compensated moves therefore wait in a queue until the next move decides where they end;
//   G40, M2/M30 and the end of the program emit them.
// Compensation works in the XY plane (G17) and, as in LinuxCNC, the XZ plane (G18), whose 2D
// coordinates are (Z, X) there (interp_convert.cc comp_get_current): plane_uv of state.hpp.
#include <cmath>

#include "state.hpp"

namespace tridex::gcode {

namespace {

constexpr double kConcaveCorner = 0.05;  // rad, LinuxCNC's TOLERANCE_CONCAVE_CORNER
constexpr double kEqual = 1e-6;          // LinuxCNC's TOLERANCE_EQUAL
constexpr double kHalfPi = kPi / 2;

Vec2 polar(double angle) { return Vec2(std::cos(angle), std::sin(angle)); }
double angle_of(const Vec2& d) { return std::atan2(d.y, d.x); }

// The signed angle an arc turns from `a` to `b` about `c` (LinuxCNC's find_turn for one turn).
double find_turn(const Vec2& a, const Vec2& c, int turn, const Vec2& b) {
  if (turn == 0) return 0.0;
  double alpha = angle_of(a - c), beta = angle_of(b - c);
  if (turn > 0) {
    if (beta <= alpha) beta += 2 * kPi;
    return beta - alpha;
  }
  if (alpha <= beta) alpha += 2 * kPi;
  return beta - alpha;
}

// The tool runs inside the arc (LinuxCNC's TOOL_INSIDE_ARC): left of a counter-clockwise arc or
// right of a clockwise one.
bool inside_arc(int side, int turn) { return side * turn > 0; }

}  // namespace

void Interpreter::State::comp_forbid(int column, const std::string& what) const {
  if (comp.side != 0)
    error(column,
          what + " with cutter compensation on (turn it off with G40 first, as LinuxCNC requires)");
}

void Interpreter::State::cutter_comp_codes(int code, int column) {
  if (code == kG40) {
    if (comp_active() && !comp.first) {
      comp_move_endpoint_and_flush(plane_uv(comp.current));
      comp_dequeue();
      comp.programmed_current = true;  // LinuxCNC: the current point is the programmed one
      comp.arc_forbidden = true;
    }
    comp.side = 0;
    comp.first = true;
    comp.entry_pending = false;
    return;
  }
  std::string name = code_name('G', code);
  if (modal.plane != kG17 && modal.plane != kG18)
    error(column, name + " in " + code_name('G', modal.plane) +
                      ": cutter compensation works in the XY (G17) or XZ (G18) plane only");
  const bool was_on = comp.side != 0;
  if (was_on && (machine.dialect == Dialect::linuxcnc || code == kG41_1 || code == kG42_1))
    error(column, name + " while cutter compensation is already on (G40 first)");
  int side = code == kG41 || code == kG41_1 ? 1 : -1;
  double radius = 0;
  if (code == kG41_1 || code == kG42_1) {  // LinuxCNC: D is the diameter itself
    if (!w.has('D')) error(column, name + " needs D (the tool diameter)");
    if (w.has('L'))
      error(w.col('L'),
            name + " L (a lathe tool's orientation) is not simulated: tridex simulates mills");
    radius = length('D') / 2;
  } else {
    // LinuxCNC: D names a tool, the loaded one without D. Fanuc and Haas: D names an offset and
    // is modal; before any D the control holds D0, no offset (Haas: "a nonzero D code must be
    // specified" to compensate).
    const bool fanuc = machine.dialect != Dialect::linuxcnc;
    int number = comp.offset_d >= 0 ? comp.offset_d : fanuc ? 0 : tool.number;
    if (w.has('D'))
      number = static_cast<int>(integer('D', (name + " D (a tool number)").c_str(), 0, 99'999'999));
    if (w.has('D') && fanuc) comp.offset_d = number;
    if (fanuc && number == 0 && !w.has('D') && !warned_once.comp_without_d) {
      warned_once.comp_without_d = true;
      warn(column, name +
                       " with no D word and none before: the control compensates by D0, nothing; "
                       "write " +
                       name + " D<n> for the tool's radius");
    }
    radius = d_offset_radius(number, w.has('D') ? w.col('D') : column, name);
  }
  if (radius < 0) {  // a negative radius offsets to the other side (LinuxCNC)
    radius = -radius;
    side = -side;
  }
  if (was_on) {  // Fanuc and Haas: the mode given again, which changes nothing if side and radius
                 // stay
    if (side != comp.side || std::abs(radius - comp.radius) > 1e-9)
      error(column, name +
                        " changes the side or the radius of cutter compensation while it is on: "
                        "tridex needs G40 between (the control's transition is not simulated)");
    return;
  }
  comp.side = side;
  comp.radius = radius;
}

// The radius G41/G42 D<number> offsets by. Where the program (or the machine file) wrote that
// offset's geometry or wear (G10 L12/L13, #13001…, Haas #2401…), what the control would read:
// geometry plus wear, a radius or a diameter as the machine's D registers hold
// (MachineConfig::d_offsets), a geometry never written being the tool table's. Else half the tool
// table's diameter of tool <number>. D0 offsets by nothing.
double Interpreter::State::d_offset_radius(int number, int column, const std::string& code) {
  if (number == 0) return 0;
  const std::string d = code + " D" + std::to_string(number);
  auto diameter = machine.tool_diameters.find(number);
  auto set = comp.d_set_at.find(number);
  if (set == comp.d_set_at.end()) {
    if (diameter == machine.tool_diameters.end())
      error(column,
            code + ": tool " + std::to_string(number) +
                " is not in the tool table (its diameter sets the offset; give the tools with "
                "--tools or a project)");
    return diameter->second / 2;
  }
  const std::optional<double> scale = d_register_scale();
  if (!scale)
    error(column,
          d + ": offset " + std::to_string(number) + " was written by " + set->second +
              ", a diameter or a radius after Haas's setting 40; say which with \"d_offsets\": "
              "\"radius\" or \"diameter\" in the machine file (README: Machine files)");
  double geometry = 0;
  if (auto it = comp.d_geometry.find(number); it != comp.d_geometry.end()) {
    geometry = it->second;
  } else if (diameter != machine.tool_diameters.end()) {
    geometry = diameter->second / 2 / *scale;
  } else {
    error(column,
          d + ": offset " + std::to_string(number) + " has a wear written by " + set->second +
              " but no geometry: its geometry is tool " + std::to_string(number) +
              "'s diameter, and that tool is not in the tool table (give the tools with --tools)");
  }
  auto wear = comp.d_wear.find(number);
  return (geometry + (wear == comp.d_wear.end() ? 0.0 : wear->second)) * *scale;
}

void Interpreter::State::comp_dequeue() {
  comp.endpoint_valid = false;
  int saved_line = context.line;
  for (const CompMove& q : comp.queue) {
    context.line = q.line;
    if (q.kind == CompMove::straight) {
      Vec3 end = to_machine(q.end);
      emit(q.move_kind, tool.pos, end, q.feed);
      tool.pos = end;
    } else {
      Vec3 start = to_program(tool.pos);
      bool ccw = q.turn > 0;
      double sweep = std::abs(find_turn(plane_uv(start), q.centre, q.turn, plane_uv(q.end)));
      arc_chords(start, q.end, q.centre, ccw, sweep + 2 * kPi * q.extra_turns, q.feed);
    }
  }
  context.line = saved_line;
  comp.queue.clear();
}

// Moves the end of every queued move to `to` (where the offset paths of a concave corner meet)
// and emits them; an error where that reverses a straight move or lengthens an arc.
void Interpreter::State::comp_move_endpoint_and_flush(const Vec2& to) {
  if (comp.queue.empty()) return;
  for (CompMove& q : comp.queue) {
    if (q.kind == CompMove::arc) {
      double r1 = glm::length(plane_uv(q.end) - q.centre), r2 = glm::length(to - q.centre);
      double l2 = find_turn(comp.endpoint, q.centre, q.turn, to);
      if (std::abs(r1 - r2) > 0.01 * modal.unit)
        error(context.motion_column, "cutter compensation made an arc with mismatched radii " +
                                         format_number(r1) + " and " + format_number(r2) +
                                         " (a bug)");
      if (q.original_sweep != 0.0 && comp.endpoint_valid &&
          std::abs(l2) > std::abs(q.original_sweep) + 0.0254)
        error(context.motion_column,
              "arc move in a concave corner cannot be reached by the tool without "
              "gouging (cutter compensation)");
    } else {
      double dot = glm::dot(q.direction, to - comp.endpoint);
      if (comp.endpoint_valid && dot < 0)
        error(context.motion_column,
              std::string(q.move_kind == MoveKind::rapid ? "straight traverse" : "straight feed") +
                  " in a concave corner cannot be reached by the tool without gouging "
                  "(cutter compensation: the corner is too small for the tool radius " +
                  format_number(comp.radius) + " mm)");
    }
    q.end = with_plane_uv(q.end, to);
  }
  comp_dequeue();
  comp.endpoint = to;
  comp.endpoint_valid = true;
}

// The entry move (convert_straight_comp1): it ends one radius to the side of its programmed end.
void Interpreter::State::comp_straight_entry(CompMove& move, const Vec3& target) {
  const double r = comp.radius;
  const int side = comp.side;
  const Vec2 p = plane_uv(target);
  Vec2 c = plane_uv(to_program(tool.pos));
  double distance = glm::length(p - c);
  const bool fanuc_start = machine.dialect != Dialect::linuxcnc;
  if (fanuc_start && !(distance > kEqual)) {
    // Haas: "If cutter compensation is turned on ... in a block without any X-Y move, there is
    // no change made to cutter compensation until the next X or Y move": a plunge goes as
    // programmed, and the next move in the plane is the entry.
    const Vec3 end = to_machine(target);
    emit(move.move_kind, tool.pos, end, move.feed);
    tool.pos = end;
    return;
  }
  if (!fanuc_start && distance <= r)
    error(context.motion_column,
          "cutter compensation entry move of length " + format_number(distance) +
              " mm is not longer than the tool radius " + format_number(r) + " mm");
  comp.entry_pending = fanuc_start;
  double alpha = angle_of(p - c) + (side > 0 ? kHalfPi : -kHalfPi);
  Vec2 end = p + r * polar(alpha);
  comp.endpoint = c;
  comp.endpoint_valid = true;
  move.direction = polar(alpha);  // as LinuxCNC records it
  move.end = with_plane_uv(target, end);
  comp.queue.push_back(move);
  comp.first = false;
  comp.current = move.end;
  comp.programmed = target;
  comp.programmed_current = true;
}

void Interpreter::State::comp_straight(MoveKind kind, const Vec3& target, double move_feed) {
  if (tool.far)
    error(context.motion_column,
          "cutter compensation from a retracted (far) position: the tool's position "
          "is unknown; position it with X, Y and Z first");
  const double r = comp.radius;
  const int side = comp.side;
  const Vec2 p = plane_uv(target);
  CompMove move;
  move.move_kind = kind;
  move.line = context.line;
  move.feed = move_feed;
  if (comp.first) {
    comp_straight_entry(move, target);
    return;
  }
  // Later moves (convert_straight_comp2).
  if (comp.entry_pending) comp_resolve_entry(p - plane_uv(comp.programmed));
  const Vec2 c = plane_uv(comp.current);
  const Vec2 op = plane_uv(comp.programmed);
  Vec2 end = c;
  if (p.x == op.x && p.y == op.y) {  // no motion in the plane: stays where the tool is, for now
    move.direction = Vec2(0.0);
  } else {
    double theta = angle_of(c - op);
    double alpha = angle_of(p - op);
    double beta, gamma;
    if (side > 0) {
      if (theta < alpha) theta += 2 * kPi;
      beta = theta - alpha - kHalfPi;
      gamma = kHalfPi;
    } else {
      if (alpha < theta) alpha += 2 * kPi;
      beta = alpha - theta - kHalfPi;
      gamma = -kHalfPi;
    }
    end = p + r * polar(alpha + gamma);
    Vec2 mid = op + r * polar(alpha + gamma);
    const CompMove* front = comp.queue.empty() ? nullptr : &comp.queue.front();
    bool front_arc = front && front->kind == CompMove::arc;
    bool concave = beta < -kConcaveCorner || beta > kPi + kConcaveCorner;
    // An "h" shape: over the round part, then down beside the straight one; LinuxCNC keeps the
    // tool above and to the side instead of looping round.
    if (!concave && beta > kPi - kConcaveCorner && front_arc &&
        ((side < 0 && front->turn > 0) || (side > 0 && front->turn < 0)))
      concave = true;
    if (!concave && beta > kConcaveCorner) {  // convex corner: an arc about it (G0: a line)
      comp_move_endpoint_and_flush(c);
      CompMove corner = move;
      corner.end = with_plane_uv(comp.current, mid);
      if (kind == MoveKind::rapid) {
        corner.direction = Vec2(0.0);
      } else {
        corner.kind = CompMove::arc;
        corner.move_kind = MoveKind::arc;
        corner.centre = op;
        corner.turn = side > 0 ? -1 : 1;
      }
      comp.queue.push_back(corner);
      comp_dequeue();
      comp.endpoint = mid;
      comp.endpoint_valid = true;
    } else if (concave) {
      Vec2 meet;
      if (!front_arc) {  // line to line: back along the offset path to where they cross
        double half_corner = (beta + kPi) / 2;
        if (half_corner == 0.0)
          error(context.motion_column,
                "a zero-degree inside corner is invalid for cutter compensation");
        double retreat = r / std::tan(half_corner);
        meet = c + retreat * polar(theta + gamma);
      } else {  // arc to line: where the offset arc meets the offset line
        const CompMove& prev = *front;
        double old_radius = glm::length(prev.centre - plane_uv(prev.end));
        double base = angle_of(p - op);
        double th = prev.turn > 0 ? base + kHalfPi : base - kHalfPi;
        double phi = angle_of(prev.centre - op);
        bool inside = inside_arc(side, prev.turn);
        double programmed_radius = inside ? old_radius + r : old_radius - r;
        double d = programmed_radius * std::cos(th - phi);
        double l = (inside ? d - r : d + r) / old_radius;
        if (l > 1.0 || l < -1.0)
          error(context.motion_column,
                "arc to straight motion makes a corner the compensated tool can't "
                "fit in without gouging (cutter compensation)");
        double turn_sign = (prev.turn > 0) == inside ? -1.0 : 1.0;
        double angle = turn_sign * std::acos(l) + th + kPi;
        meet = prev.centre + old_radius * polar(angle);
      }
      comp_move_endpoint_and_flush(meet);
    } else {  // straight on (collinear, or tangent from an arc)
      comp_dequeue();
      comp.endpoint = c;
      comp.endpoint_valid = true;
    }
    move.direction = p - op;
  }
  move.end = with_plane_uv(target, end);
  comp.queue.push_back(move);
  comp.current = move.end;
  comp.programmed = target;
  comp.programmed_current = true;
}

// Fanuc's and Haas's start-up (Fanuc's type A): the entry move, queued ending perpendicular to
// itself, ends one radius to the side of its programmed end perpendicular to the next move's
// start instead; the next move then starts straight on from it, with no corner. A next move with
// no motion in the plane leaves the entry as it was.
void Interpreter::State::comp_resolve_entry(const Vec2& next_direction) {
  comp.entry_pending = false;
  const double length = glm::length(next_direction);
  if (!(length > kEqual) || comp.queue.size() != 1) return;
  const Vec2 unit_direction = next_direction / length;
  const Vec2 side = comp.side > 0 ? Vec2(-unit_direction.y, unit_direction.x)
                                  : Vec2(unit_direction.y, -unit_direction.x);
  CompMove& entry = comp.queue.front();
  entry.end = with_plane_uv(entry.end, plane_uv(comp.programmed) + comp.radius * side);
  entry.direction = plane_uv(entry.end) - comp.endpoint;  // from where the entry starts
  comp.current = entry.end;
}

// The entry arc (convert_arc_comp1): it keeps its start and ends one radius from its programmed
// end.
void Interpreter::State::comp_arc_entry(CompMove& move, bool ccw, bool inside,
                                        const std::string& too_small) {
  const double r = comp.radius;
  const int turn = move.turn;
  Vec3 current = to_program(tool.pos);
  Vec2 c = plane_uv(current);
  ArcData a = arc_data(current, ccw);
  if (modal.feed_mode == FeedMode::inverse_time)
    inverse_time_rate(arc_length(current, a, ccw, move.extra_turns));
  move.feed = modal.feed;
  Vec2 end = plane_uv(a.end);
  if (glm::length(end - c) <= r)
    error(context.motion_column,
          "cutter compensation entry arc: its end is not farther than the tool "
          "radius " +
              format_number(r) + " mm from its start");
  double arc_radius = a.programmed_radius > 0 ? a.programmed_radius : glm::length(a.centre - c);
  if (arc_radius <= r && inside) error(context.motion_column, too_small);
  double gamma = inside ? angle_of(a.centre - end) : angle_of(end - a.centre);
  comp.first = false;
  comp.programmed = a.end;
  end += r * polar(gamma);
  // The compensated arc keeps its start and passes through the new end: its centre lies on
  // the line from the end through the programmed centre, equally far from both.
  double b_len = glm::length(c - end) / 2;
  double ab = angle_of(a.centre - end);
  double a_angle = angle_of(c - end) - ab;
  if (std::abs(std::cos(a_angle)) < kEqual) error(context.motion_column, too_small);
  Vec2 centre = end + (b_len / std::cos(a_angle)) * polar(ab);
  move.end = with_plane_uv(a.end, end);
  move.centre = centre;
  move.original_sweep = find_turn(c, centre, turn, end);
  comp.queue.push_back(move);
  comp.current = move.end;
  comp.programmed_current = true;
}

void Interpreter::State::comp_arc(bool ccw) {
  if (tool.far)
    error(context.motion_column,
          "cutter compensation from a retracted (far) position: the tool's position "
          "is unknown; position it with X, Y and Z first");
  const double r = comp.radius;
  const int side = comp.side;
  const int turn = ccw ? 1 : -1;
  const bool inside = inside_arc(side, turn);
  CompMove move;
  move.kind = CompMove::arc;
  move.move_kind = MoveKind::arc;
  move.line = context.line;
  move.feed = modal.feed;
  move.turn = turn;
  move.extra_turns = arc_extra_turns();
  const std::string too_small = "the tool radius " + format_number(r) +
                                " mm is not less than the arc radius (cutter compensation)";
  if (comp.first) {
    comp_arc_entry(move, ccw, inside, too_small);
    return;
  }
  // Later arcs (convert_arc_comp2).
  ArcData a = arc_data(comp.programmed, ccw);
  if (comp.entry_pending) {  // the arc's tangent at its start
    const Vec2 radial = plane_uv(comp.programmed) - a.centre;
    comp_resolve_entry(ccw ? Vec2(-radial.y, radial.x) : Vec2(radial.y, -radial.x));
  }
  const Vec2 op = plane_uv(comp.programmed);
  const Vec2 c = plane_uv(comp.current);
  if (modal.feed_mode == FeedMode::inverse_time)
    inverse_time_rate(arc_length(comp.programmed, a, ccw, move.extra_turns));
  move.feed = modal.feed;
  const Vec2 centre = a.centre, end = plane_uv(a.end);
  double arc_radius = glm::length(centre - end);
  double theta = angle_of(c - op) + (side > 0 ? -kHalfPi : kHalfPi);
  double delta = angle_of(centre - op);
  double alpha = ccw ? delta - kHalfPi : delta + kHalfPi;
  double beta = side > 0 ? theta - alpha : alpha - theta;
  if (beta > 1.5 * kPi)
    beta -= 2 * kPi;
  else if (beta < -kHalfPi)
    beta += 2 * kPi;
  double gamma;
  if (inside) {
    gamma = angle_of(centre - end);
    if (arc_radius <= r) error(context.motion_column, too_small);
  } else {
    gamma = angle_of(end - centre);
    delta += kPi;
  }
  Vec2 new_end = end + r * polar(gamma);
  move.end = with_plane_uv(a.end, new_end);
  move.centre = centre;
  move.original_sweep = find_turn(op, centre, turn, end);
  const std::string gouge =
      "arc move in a concave corner cannot be reached by the tool without "
      "gouging (cutter compensation)";
  if (beta < -kConcaveCorner || beta > kPi + kConcaveCorner ||
      (std::abs(beta - kPi) < kConcaveCorner && !inside)) {  // concave
    const CompMove* front = comp.queue.empty() ? nullptr : &comp.queue.front();
    Vec2 meet;
    if (!front || front->kind != CompMove::arc) {  // line to arc
      double along = arc_radius * std::sin(beta - kHalfPi);
      double from_centre = inside ? arc_radius - r : arc_radius + r;
      double l = (inside ? along + r : along - r) / from_centre;
      if (l > 1.0 || l < -1.0) error(context.motion_column, gouge);
      double angle = inside ? (turn > 0 ? theta + std::asin(l) : theta - std::asin(l))
                            : (turn > 0 ? theta + kPi - std::asin(l) : theta + kPi + std::asin(l));
      meet = centre + from_centre * polar(angle);
    } else {  // arc to arc: where the two offset circles cross
      const CompMove& prev = *front;
      double old_radius = glm::length(prev.centre - plane_uv(prev.end));
      double new_radius = inside ? arc_radius - r : arc_radius + r;
      double centres = glm::length(prev.centre - centre);
      if (old_radius == 0 || centres == 0)
        error(context.motion_column,
              "arc to arc motion is invalid because the arcs have the same centre "
              "(cutter compensation)");
      double cos_pullback =
          (old_radius * old_radius + centres * centres - new_radius * new_radius) /
          (2 * old_radius * centres);
      if (cos_pullback > 1.0 || cos_pullback < -1.0)
        error(context.motion_column,
              "arc to arc motion makes a corner the compensated tool can't fit in "
              "without gouging (cutter compensation)");
      double pullback = std::acos(cos_pullback);
      double direction = angle_of(centre - prev.centre);
      bool add = inside_arc(side, prev.turn) == (turn > 0);
      meet = prev.centre + old_radius * polar(add ? direction + pullback : direction - pullback);
    }
    comp_move_endpoint_and_flush(meet);
  } else if (beta > kConcaveCorner) {  // convex: an arc about the corner first
    Vec2 mid = op + r * polar(delta);
    comp_dequeue();
    CompMove corner = move;
    corner.end = with_plane_uv(comp.current, mid);
    corner.centre = op;
    corner.turn = side > 0 ? -1 : 1;
    corner.original_sweep = 0;
    comp.queue.push_back(corner);
    comp_dequeue();
    comp.endpoint = mid;
    comp.endpoint_valid = true;
  } else {  // tangent
    comp_dequeue();
    comp.endpoint = c;
    comp.endpoint_valid = true;
  }
  comp.queue.push_back(move);
  comp.programmed = a.end;
  comp.current = move.end;
  comp.programmed_current = true;
}

}  // namespace tridex::gcode
