#include "checks/machine_check.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numbers>

namespace tridex::cli {

namespace {

// Closer than the clearance by less than this is contact: conservative advancement only reaches
// the clearance in the limit, so it stops here (mm).
constexpr double kMachineContactSlack = 1e-4;
// At most this many poses a pair and move (a pair that stays within the near-miss distance along
// a long move steps by the gap to the clearance; the cap keeps a pathological move finite, and a
// pair stopped by it is reported at its closest pose as a near miss).
constexpr int kMachineMaxSteps = 20000;
// Travel along a move: samples where machine coordinates are not straight (TCP with turning
// rotaries), then a golden-section refinement of the worst.
constexpr int kTravelSamples = 64;
// A pair's distance is searched only up to what the move needs (the near-miss distance plus how
// far the bodies can close in over the rest of the move) plus this margin, kept for the moves
// that follow (MachineCheck::PairBound): a larger margin skips more moves after a query, a
// smaller one prunes more of the trees in it (mm; bench/machine_bench.cpp).
constexpr double kMachineReuseMargin = 10;

Frame mc_compose(const Frame& a, const Frame& b) {
  return Frame{a.rotation * b.rotation, a.rotation * b.origin + a.origin};
}

Frame mc_turn(const gcode::RotaryAxis& axis, double degrees) {
  const Mat3 r = rotation_about(axis.direction, degrees);
  return Frame{r, axis.pivot - r * axis.pivot};
}

double mc_angle(const gcode::RotaryPositions& r, const gcode::RotaryAxis& axis) {
  return r[static_cast<std::size_t>(gcode::rotary_index(axis.letter))];
}

bool mc_is_head_side(LinkKind k) {
  return k == LinkKind::head || k == LinkKind::spindle || k == LinkKind::tool;
}

}  // namespace

MachineCheck::MachineCheck(std::optional<gcode::Kinematics> kinematics,
                           std::array<bool, 3> linear_on_head, gcode::CollisionSettings settings)
    : kin_(std::move(kinematics)), on_head_(linear_on_head), settings_(std::move(settings)) {
  if (kin_)
    for (const gcode::RotaryAxis& axis : kin_->axes)
      (axis.on_head ? head_axes_ : table_axes_).push_back(&axis);
}

void MachineCheck::add(MachineBody body) {
  const Aabb box = body.tree->bounds();
  body.centre = box.center();
  body.radius = body.tree->radius_about(body.centre);
  body.pieces = body.tree->piece_vertices();
  bodies_.push_back(std::move(body));
}

MachineState MachineCheck::state_at(const MachineMove& move, double t) const {
  MachineState s;
  for (std::size_t k = 0; k < 3; ++k)
    s.rotary[k] = move.from.rotary[k] + t * (move.to.rotary[k] - move.from.rotary[k]);
  if (move.tip_linear && kin_)
    s.x = gcode::machine_from_part(
        *kin_, move.tip_from + t * (move.tip_to - move.tip_from) + move.offset, s.rotary);
  else
    s.x = move.from.x + t * (move.to.x - move.from.x);
  return s;
}

Frame MachineCheck::frame_of(const MachineBody& body, const MachineState& s,
                             const MachineMove& move) const {
  Vec3 head(0), table(0);
  for (int k = 0; k < 3; ++k) (on_head_[static_cast<std::size_t>(k)] ? head : table)[k] = s.x[k];
  const Link& link = body.link;
  auto chain = [&](const std::vector<const gcode::RotaryAxis*>& axes, std::size_t depth,
                   const Vec3& shift) {
    Frame f{Mat3(1.0), shift};
    for (std::size_t k = 0; k < depth && k < axes.size(); ++k)
      f = mc_compose(f, mc_turn(*axes[k], mc_angle(s.rotary, *axes[k])));
    return f;
  };
  switch (link.kind) {
    case LinkKind::bed:
      return Frame{};
    case LinkKind::carriage: {
      Vec3 shift(0);
      const auto k = static_cast<std::size_t>(link.index);
      shift[link.index] = on_head_[k] ? s.x[link.index] : -s.x[link.index];
      return Frame{Mat3(1.0), shift};
    }
    case LinkKind::table:
      return chain(table_axes_, static_cast<std::size_t>(link.index), -table);
    case LinkKind::work:
      return mc_compose(chain(table_axes_, table_axes_.size(), -table),
                        Frame{Mat3(1.0), move.offset});
    case LinkKind::head:
      return chain(head_axes_, static_cast<std::size_t>(link.index), head);
    case LinkKind::tool:
      return chain(head_axes_, head_axes_.size(), head);
    case LinkKind::spindle:
      return mc_compose(chain(head_axes_, head_axes_.size(), head),
                        Frame{Mat3(1.0), Vec3(0, 0, move.gauge)});
  }
  return Frame{};
}

// How far a point of `body` can move, per unit of t, along the move: its side's linear speed
// (`linear`) plus, for each rotary axis it rides on, the turn (radians) times the farthest the
// body reaches from that axis: its bounding sphere about the outermost axis's pivot, plus the
// distances between the pivots further out (a turn further out keeps a point's distance to its
// own pivot; ‖v − q_j‖ ≤ ‖v − q_k‖ + ‖q_k − q_j‖).
double MachineCheck::speed_bound(const MachineBody& body, const MachineMove& move,
                                 double linear) const {
  const LinkKind kind = body.link.kind;
  if (kind == LinkKind::bed) return 0;
  if (kind == LinkKind::carriage) {
    const int k = body.link.index;
    return std::abs(move.to.x[k] - move.from.x[k]) + (move.tip_linear ? linear : 0);
  }
  const bool head = mc_is_head_side(kind);
  const auto& axes = head ? head_axes_ : table_axes_;
  std::size_t depth = axes.size();
  if (kind == LinkKind::table || kind == LinkKind::head)
    depth = std::min(depth, static_cast<std::size_t>(body.link.index));
  Vec3 shift(0);  // the body's coordinates to the zero pose's
  if (kind == LinkKind::work) shift = move.offset;
  if (kind == LinkKind::spindle) shift = Vec3(0, 0, move.gauge);
  double v = linear, reach = 0;
  for (std::size_t j = depth; j-- > 0;) {
    reach = j + 1 == depth ? glm::length(body.centre + shift - axes[j]->pivot) + body.radius
                           : reach + glm::length(axes[j + 1]->pivot - axes[j]->pivot);
    v += glm::radians(
             std::abs(mc_angle(move.to.rotary, *axes[j]) - mc_angle(move.from.rotary, *axes[j]))) *
         reach;
  }
  return v;
}

// A bound on |dX/dt|: straight machine axes move by X1 − X0; under TCP the tip moves straight on
// the part, so X = T(p) − H(0) moves by at most |Δp| plus each table turn times p's reach from
// its axis and each head turn times the tip's reach from its axis.
double MachineCheck::linear_speed_bound(const MachineMove& move) const {
  if (!move.tip_linear || !kin_) return glm::length(move.to.x - move.from.x);
  double v = glm::length(move.tip_to - move.tip_from);
  auto add_side = [&](const std::vector<const gcode::RotaryAxis*>& axes, double point_reach_last) {
    double reach = 0;
    for (std::size_t j = axes.size(); j-- > 0;) {
      reach = j + 1 == axes.size() ? point_reach_last
                                   : reach + glm::length(axes[j + 1]->pivot - axes[j]->pivot);
      v += glm::radians(std::abs(mc_angle(move.to.rotary, *axes[j]) -
                                 mc_angle(move.from.rotary, *axes[j]))) *
           reach;
    }
  };
  if (!table_axes_.empty()) {
    const Vec3 q = table_axes_.back()->pivot;
    add_side(table_axes_, std::max(glm::length(move.tip_from + move.offset - q),
                                   glm::length(move.tip_to + move.offset - q)));
  }
  if (!head_axes_.empty()) add_side(head_axes_, glm::length(head_axes_.back()->pivot));
  return v;
}

bool MachineCheck::pair_tested(const MachineBody& a, const MachineBody& b, int tool) const {
  if (a.tool >= 0 && a.tool != tool) return false;
  if (b.tool >= 0 && b.tool != tool) return false;
  for (const auto& [x, y] : settings_.ignore)
    if ((x == a.name && y == b.name) || (x == b.name && y == a.name)) return false;
  const Link &p = a.link, &q = b.link;
  if (p == q) return false;
  const bool head_a =
      mc_is_head_side(p.kind) || (p.kind == LinkKind::carriage && on_head_[p.index]);
  const bool head_b =
      mc_is_head_side(q.kind) || (q.kind == LinkKind::carriage && on_head_[q.index]);
  // Within one side only the chain's parts that are not neighbours: a tool's parts, the spindle,
  // the head axes and their carriages move together or next to each other; fixtures sit on the
  // table; the table's links on each other.
  if (head_a == head_b) {
    auto level = [&](const Link& l) {
      switch (l.kind) {
        case LinkKind::bed:
          return 0;
        case LinkKind::carriage:
          return 1;
        case LinkKind::table:
        case LinkKind::head:
          return 1 + l.index;
        default:  // work, spindle, tool: the end of the chain
          return 2 + static_cast<int>(head_a ? head_axes_.size() : table_axes_.size());
      }
    };
    if (p.kind == LinkKind::tool || q.kind == LinkKind::tool) return false;
    if (p.kind == LinkKind::work || q.kind == LinkKind::work) return false;
    return std::abs(level(p) - level(q)) > 1;
  }
  return true;
}

void MachineCheck::check(const MachineMove& move, MachineFindings& found) {
  const auto start = std::chrono::steady_clock::now();
  ++found.moves;
  const std::size_t n = bodies_.size();
  bounds_.resize(n * n);
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j)
      if (pair_tested(bodies_[i], bodies_[j], move.tool) &&
          (move.gauge_known || (bodies_[i].link.kind != LinkKind::spindle &&
                                bodies_[j].link.kind != LinkKind::spindle)))
        check_pair(bodies_[i], bodies_[j], move, found, bounds_[i * n + j]);
  if (kin_) check_travel(move, found);
  found.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

// A straight move (no rotary turns): every body keeps its orientation, so in one body's
// coordinates the other moves along one segment. The prism the smaller body sweeps (collide.hpp,
// swept_triangles) settles the move: the bodies meet where the other body's surface crosses that
// swept surface, or where a connected piece of it lies wholly inside a swept prism, when its
// every point, a representative vertex included, passes through the moving triangle (tested as
// that vertex's path against the moving body). When they do not meet, the least distance from
// the swept surface is the least distance over the move, exactly. Returns it (≤ the clearance
// and the slack where they meet; at most `cap`).
double MachineCheck::swept_distance(const MachineBody& a, const MachineBody& b,
                                    const MachineMove& move, double cap) const {
  const bool swap = a.tree->size() > b.tree->size();
  const MachineBody& moving = swap ? b : a;  // the one swept
  const MachineBody& other = swap ? a : b;
  const MachineState s0 = state_at(move, 0), s1 = state_at(move, 1);
  const Frame fm0 = frame_of(moving, s0, move), fo0 = frame_of(other, s0, move);
  const Frame fm1 = frame_of(moving, s1, move), fo1 = frame_of(other, s1, move);
  // How far `moving` moves in `other`'s coordinates (its orientation there stays).
  const Vec3 in_other = fo1.to_local(fm1.origin) - fo0.to_local(fm0.origin);
  const Vec3 in_moving = glm::transpose(fm0.rotation) * (fo0.rotation * in_other);
  const double slack = settings_.clearance + kMachineContactSlack;
  cap = std::max(cap, 2 * slack);  // a cap at or below the contact distance would say "contact"
  const TriangleTree swept(swept_triangles(*moving.tree, in_moving));
  const double least = tree_distance(swept, fm0, *other.tree, fo0, slack, cap).distance;
  if (least <= slack) return least;
  // Each piece of `other` that could lie inside a prism: its representative's path, in moving's
  // coordinates at t = 0, runs from r to r − in_moving.
  for (const Vec3& r : other.pieces) {
    const Vec3 p = fm0.to_local(fo0.to_world(r));
    if (moving.tree->distance(p, p - in_moving) <= slack) return 0;
  }
  return least;
}

void MachineCheck::check_pair(const MachineBody& a, const MachineBody& b, const MachineMove& move,
                              MachineFindings& found, PairBound& bound) const {
  const double linear = linear_speed_bound(move);
  const double v = speed_bound(a, move, linear) + speed_bound(b, move, linear);
  const double clearance = settings_.clearance;
  const double near = std::max(settings_.near_miss, clearance);
  const bool straight = move.from.rotary == move.to.rotary;
  // The bound the last move left (PairBound), carried to this move's start.
  double lower = -1;
  if (bounded_ && bound.valid && bound.tool == move.tool && bound.gauge == move.gauge &&
      bound.at.rotary == move.from.rotary)
    lower = bound.lower - glm::length(move.from.x - bound.at.x) -
            glm::length(move.offset - bound.offset);
  bound = PairBound{true, state_at(move, 1), move.offset, move.gauge, move.tool, 0};
  if (lower > near + v) {  // cannot come within the near-miss distance anywhere on the move
    bound.lower = lower - v;
    return;
  }
  auto finding = [&](double distance, double at, const TreeDistance& where) {
    const MachineState here = state_at(move, at);
    MachineBody work_body;
    work_body.link = {LinkKind::work, 0};
    const Frame work = frame_of(work_body, here, move), to_work = work.inverse();
    MachineFinding f;
    f.file = move.file, f.line = move.line, f.tool = move.tool;
    f.a = a.name, f.b = b.name, f.distance = distance, f.t = at, f.state = here;
    f.where = work.to_local(0.5 * (where.on_a + where.on_b));
    f.body_a = static_cast<int>(&a - bodies_.data());
    f.body_b = static_cast<int>(&b - bodies_.data());
    f.pose_a = mc_compose(to_work, frame_of(a, here, move));
    f.pose_b = mc_compose(to_work, frame_of(b, here, move));
    return f;
  };
  auto at = [&](double t, double cap) {
    const MachineState s = state_at(move, t);
    ++found.queries;
    return tree_distance(*a.tree, frame_of(a, s, move), *b.tree, frame_of(b, s, move),
                         clearance + kMachineContactSlack, cap);
  };
  // Conservative advancement (machine_check.hpp) from t = 0: while outside the near-miss distance
  // step to where it may be reached; inside, to where the clearance may be. A straight move that
  // comes near is settled by its swept surfaces instead of by small steps.
  double t = 0, closest = std::numeric_limits<double>::infinity(), closest_t = 0;
  TreeDistance closest_d;
  bool settled_contact = false;
  for (int step = 0; step < kMachineMaxSteps; ++step) {
    // Searched up to what this move needs and the margin (a result at the cap means "at least").
    const TreeDistance d = at(t, bounded_ ? near + v * (1 - t) + kMachineReuseMargin
                                          : std::numeric_limits<double>::infinity());
    bound.lower = d.distance - v * (1 - t);
    if (d.distance < closest) closest = d.distance, closest_t = t, closest_d = d;
    if (d.distance <= clearance + kMachineContactSlack) {
      found.collisions.push_back(finding(std::max(0.0, d.distance), t, d));
      bound.valid = false;
      return;
    }
    if (t >= 1 || !(v > 0)) break;
    if (straight && !settled_contact && d.distance <= near + v * (1 - t)) {
      found.queries += 2;
      const double least = swept_distance(a, b, move, near);
      if (least > clearance + kMachineContactSlack) {
        if (least < settings_.near_miss) {
          // The pose of the closest approach: the nearest of a few samples.
          for (int k = 1; k <= 16; ++k)
            if (const TreeDistance e = at(k / 16.0, near); e.distance < closest)
              closest = e.distance, closest_t = k / 16.0, closest_d = e;
          closest = least;
        }
        bound.lower = least;  // the least over the whole move
        break;
      }
      settled_contact = true;  // they meet: find where first, stepping to the clearance
    }
    const double gap =
        d.distance > near && !settled_contact ? d.distance - near : d.distance - clearance;
    t = std::min(1.0, t + std::max(gap, 0.5 * kMachineContactSlack) / v);
  }
  if (settled_contact) {  // the step cap reached while grazing: the closest pose found
    found.collisions.push_back(finding(std::max(0.0, closest), closest_t, closest_d));
    bound.valid = false;
    return;
  }
  if (closest < settings_.near_miss)
    found.near_misses.push_back(finding(closest, closest_t, closest_d));
}

// Travel along a move: with straight machine axes the ends bound every axis (the pipeline checks
// them); under TCP with turning rotaries machine coordinates bend, so each axis is sampled and its
// worst sample refined (golden section), and a limit passed inside the move is reported.
void MachineCheck::check_travel(const MachineMove& move, MachineFindings& found) const {
  if (!move.tip_linear || move.from.rotary == move.to.rotary) return;
  for (int k = 0; k < 3; ++k) {
    const auto& range = kin_->travel[static_cast<std::size_t>(k)];
    if (!range) continue;
    for (int side = 0; side < 2; ++side) {
      // side 0: how far below the minimum; 1: above the maximum (positive: outside).
      auto excess = [&](double t) {
        const double x = state_at(move, t).x[k];
        return side == 0 ? (*range)[0] - x : x - (*range)[1];
      };
      if (excess(0) > 0 || excess(1) > 0) continue;  // the ends: the pipeline's findings
      int best = 0;
      double best_value = -std::numeric_limits<double>::infinity();
      for (int i = 0; i <= kTravelSamples; ++i)
        if (double e = excess(double(i) / kTravelSamples); e > best_value) best_value = e, best = i;
      double lo = std::max(0, best - 1) / double(kTravelSamples),
             hi = std::min(kTravelSamples, best + 1) / double(kTravelSamples);
      const double g = (std::sqrt(5.0) - 1) / 2;
      for (int it = 0; it < 40; ++it) {
        const double m1 = hi - g * (hi - lo), m2 = lo + g * (hi - lo);
        (excess(m1) > excess(m2) ? hi : lo) = excess(m1) > excess(m2) ? m2 : m1;
      }
      const double t = 0.5 * (lo + hi);
      if (excess(t) > 0)
        found.travel.push_back({move.file, move.line, static_cast<char>('X' + k),
                                state_at(move, t).x[k], (*range)[side], t});
    }
  }
}

}  // namespace tridex::cli
