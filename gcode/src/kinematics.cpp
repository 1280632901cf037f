// tridex::gcode — rotary kinematics: forward maps and the two-axis inverse (Paden–Kahan
// subproblems 1 and 2, Murray, Li and Sastry 1994, §3.2.2). See kinematics.hpp for the model.
#include "tridex/gcode/kinematics.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include "tridex/error.hpp"
#include "tridex/gcode/tilted_plane.hpp"

namespace tridex::gcode {
namespace {

constexpr double kTurn = 360.0;
constexpr double kLimitSlack = 1e-9;      // degrees: a solution this close to a limit is inside
constexpr double kSolutionsAgree = 1e-9;  // 1 − cos of the angle below which directions agree
constexpr double kFreeAxis = 1e-9;      // |component normal to an axis| below which it is along it
constexpr double kParallelAxes = 1e-6;  // |a × b| below which two rotary axes are parallel

// The rigid turn of an axis's carriage: p ↦ pivot + R·(p − pivot).
Frame axis_turn(const RotaryAxis& axis, double degrees) {
  Mat3 r = rotation_about(axis.direction, degrees);
  return Frame{r, axis.pivot - r * axis.pivot};
}

// One side's chain, from the machine outward: T1 ∘ T2 ∘ ….
Frame chain(const Kinematics& kin, const RotaryPositions& rotary, bool head) {
  Frame result;
  for (const RotaryAxis& axis : kin.axes)
    if (axis.on_head == head)
      result = compose(result, axis_turn(axis, rotary[std::size_t(rotary_index(axis.letter))]));
  return result;
}

std::string vector_text(const Vec3& v) {
  std::ostringstream out;
  out << '(' << v.x << ", " << v.y << ", " << v.z << ')';
  return out.str();
}

// Subproblem 1: the angle α with Rot(a, α)·x = y, for unit a and x, y at the same angle to a;
// nullopt when x lies along a (any α will do).
std::optional<double> turn_onto(const Vec3& a, const Vec3& x, const Vec3& y) {
  Vec3 xp = x - glm::dot(a, x) * a, yp = y - glm::dot(a, y) * a;
  if (glm::length(xp) < kFreeAxis) return std::nullopt;
  return glm::degrees(std::atan2(glm::dot(a, glm::cross(xp, yp)), glm::dot(xp, yp)));
}

// A solution of the inverse: an angle per axis of the kinematics, or free (nullopt).
struct Candidate {
  std::optional<double> first, second;
};

// Subproblem 2: the vectors z with a·z = a·x, b·z = b·y, |z| = 1 (a, b unit, not parallel; x, y
// unit): z = c1·a + c2·b + c3·(a × b). Zero, one or two of them.
std::vector<Vec3> common_vectors(const Vec3& a, const Vec3& x, const Vec3& b, const Vec3& y) {
  double g = glm::dot(a, b), ax = glm::dot(a, x), by = glm::dot(b, y);
  double d = 1 - g * g;
  double c1 = (ax - g * by) / d, c2 = (by - g * ax) / d;
  Vec3 n = glm::cross(a, b);
  double in_plane2 = c1 * c1 + c2 * c2 + 2 * c1 * c2 * g;
  double c3sq = (1 - in_plane2) / glm::dot(n, n);
  if (c3sq < -1e-12) return {};
  double c3 = std::sqrt(std::max(c3sq, 0.0));
  Vec3 base = c1 * a + c2 * b;
  if (c3 < 1e-12) return {base};
  return {base + c3 * n, base - c3 * n};
}

// The angle on the turn nearest `current` within the axis's limits; nullopt when no turn of it
// lies within them.
std::optional<double> nearest_turn(const RotaryAxis& axis, double angle, double current) {
  double k = std::round((current - angle) / kTurn);
  if (axis.limits) {
    auto [lo, hi] = *axis.limits;
    double k_lo = std::ceil((lo - kLimitSlack - angle) / kTurn);
    double k_hi = std::floor((hi + kLimitSlack - angle) / kTurn);
    if (k_lo > k_hi) return std::nullopt;
    k = std::clamp(k, k_lo, k_hi);
  }
  return angle + k * kTurn;
}

double clamp_to_limits(const RotaryAxis& axis, double angle) {
  return axis.limits ? std::clamp(angle, (*axis.limits)[0], (*axis.limits)[1]) : angle;
}

}  // namespace

int rotary_index(char letter) {
  switch (letter) {
    case 'A':
    case 'a':
      return 0;
    case 'B':
    case 'b':
      return 1;
    case 'C':
    case 'c':
      return 2;
    default:
      return -1;
  }
}

const RotaryAxis* Kinematics::find(char letter) const {
  int index = rotary_index(letter);
  for (const RotaryAxis& axis : axes)
    if (rotary_index(axis.letter) == index) return &axis;
  return nullptr;
}

void Kinematics::validate() const {
  if (axes.empty() || axes.size() > 2)
    detail::fail("kinematics: a machine here has one or two rotary axes, got ", axes.size());
  int heads = 0;
  for (std::size_t i = 0; i < axes.size(); ++i) {
    const RotaryAxis& axis = axes[i];
    if (rotary_index(axis.letter) < 0)
      detail::fail("kinematics: axis letter must be A, B or C, got '", axis.letter, "'");
    for (std::size_t k = 0; k < i; ++k)
      if (rotary_index(axes[k].letter) == rotary_index(axis.letter))
        detail::fail("kinematics: axis ", axis.letter, " appears twice");
    if (!is_finite(axis.direction) || std::abs(glm::length(axis.direction) - 1) > 1e-9)
      detail::fail("kinematics: axis ", axis.letter, " direction must be a unit vector, got ",
                   vector_text(axis.direction));
    if (!is_finite(axis.pivot))
      detail::fail("kinematics: axis ", axis.letter, " pivot must be finite");
    if (axis.limits && !((*axis.limits)[0] < (*axis.limits)[1]))
      detail::fail("kinematics: axis ", axis.letter, " limits must be min < max, got [",
                   (*axis.limits)[0], ", ", (*axis.limits)[1], "]");
    heads += axis.on_head ? 1 : 0;
  }
  int tables = int(axes.size()) - heads;
  switch (type) {
    case MachineType::table_table:
      if (heads != 0) detail::fail("kinematics: a table-table machine has no axis on the head");
      break;
    case MachineType::head_head:
      if (tables != 0) detail::fail("kinematics: a head-head machine has no axis on the table");
      break;
    case MachineType::head_table:
      if (heads != 1 || tables != 1)
        detail::fail(
            "kinematics: a head-table machine has one axis on the head and one on the "
            "table");
      break;
  }
  if (axes.size() == 2 &&
      glm::length(glm::cross(axes[0].direction, axes[1].direction)) < kParallelAxes)
    detail::fail("kinematics: axes ", axes[0].letter, " and ", axes[1].letter,
                 " are parallel, so they cannot turn the tool to an arbitrary direction");
}

Frame part_to_machine(const Kinematics& kin, const RotaryPositions& rotary) {
  return chain(kin, rotary, false);
}

Frame head_offset(const Kinematics& kin, const RotaryPositions& rotary) {
  return chain(kin, rotary, true);
}

Vec3 tool_direction(const Kinematics& kin, const RotaryPositions& rotary) {
  return glm::transpose(part_to_machine(kin, rotary).rotation) * head_offset(kin, rotary).rotation *
         Vec3(0, 0, 1);
}

Vec3 tip_in_part(const Kinematics& kin, const Vec3& machine_xyz, const RotaryPositions& rotary) {
  return part_to_machine(kin, rotary).to_local(machine_xyz + head_offset(kin, rotary).origin);
}

Vec3 machine_from_part(const Kinematics& kin, const Vec3& part_tip, const RotaryPositions& rotary) {
  return part_to_machine(kin, rotary).to_world(part_tip) - head_offset(kin, rotary).origin;
}

Frame machine_to_part(const Kinematics& kin, const RotaryPositions& rotary) {
  Frame part = part_to_machine(kin, rotary);
  Mat3 rt = glm::transpose(part.rotation);
  return Frame{rt, rt * (head_offset(kin, rotary).origin - part.origin)};
}

void check_limits(const Kinematics& kin, const RotaryPositions& rotary) {
  for (const RotaryAxis& axis : kin.axes) {
    double v = rotary[std::size_t(rotary_index(axis.letter))];
    if (!std::isfinite(v)) detail::fail(axis.letter, " must be finite, got ", v);
    if (axis.limits && (v < (*axis.limits)[0] - kLimitSlack || v > (*axis.limits)[1] + kLimitSlack))
      detail::fail(axis.letter, v, " is outside the axis limits ", (*axis.limits)[0], " to ",
                   (*axis.limits)[1]);
  }
}

std::vector<TravelViolation> travel_violations(const Kinematics& kin, const Vec3& machine_xyz,
                                               const RotaryPositions& rotary) {
  std::vector<TravelViolation> out;
  auto compare = [&](char letter, double v, const std::optional<std::array<double, 2>>& range) {
    if (!range) return;
    if (v < (*range)[0]) out.push_back({letter, v, (*range)[0]});
    if (v > (*range)[1]) out.push_back({letter, v, (*range)[1]});
  };
  for (int i = 0; i < 3; ++i) compare(char('X' + i), machine_xyz[i], kin.travel[std::size_t(i)]);
  for (char letter : {'A', 'B', 'C'})
    if (const RotaryAxis* axis = kin.find(letter))
      compare(letter, rotary[std::size_t(rotary_index(letter))], axis->limits);
  return out;
}

RotaryPositions orient_tool(const Kinematics& kin, const Vec3& part_direction,
                            const RotaryPositions& current) {
  kin.validate();
  if (!is_finite(part_direction) || !(glm::length(part_direction) > 1e-12))
    detail::fail("tool direction ", vector_text(part_direction), " is not a direction");
  const Vec3 v = glm::normalize(part_direction), ez(0, 0, 1);
  const RotaryAxis& first = kin.axes[0];
  const RotaryAxis* second = kin.axes.size() > 1 ? &kin.axes[1] : nullptr;

  // Each case writes the tool direction v(θ) as Rot(a, α)·x = Rot(b, β)·y and names which angle
  // is which (the chain equations are in kinematics.hpp).
  std::vector<Candidate> candidates;
  if (!second) {
    // One axis: table v = Rot(u, −θ)·ez ⇔ Rot(u, θ)·v = ez; head v = Rot(u, θ)·ez.
    const Vec3& u = first.direction;
    Vec3 x = first.on_head ? ez : v, y = first.on_head ? v : ez;
    if (std::abs(glm::dot(u, x) - glm::dot(u, y)) < 1e-9)
      candidates.push_back({turn_onto(u, x, y), {}});
  } else {
    // a, x, α = sa·θ(ia); b, y, β = sb·θ(ib).
    const RotaryAxis *axis_a, *axis_b;
    Vec3 x, y;
    double sa, sb;
    if (kin.type == MachineType::table_table) {
      // v = R2ᵀ·R1ᵀ·ez ⇔ Rot(u2, θ2)·v = Rot(u1, −θ1)·ez
      axis_a = second, x = v, sa = 1, axis_b = &first, y = ez, sb = -1;
    } else if (kin.type == MachineType::head_head) {
      // v = R1·R2·ez ⇔ Rot(u1, −θ1)·v = Rot(u2, θ2)·ez
      axis_a = &first, x = v, sa = -1, axis_b = second, y = ez, sb = 1;
    } else {
      // v = Rtᵀ·Rh·ez ⇔ Rot(ut, θt)·v = Rot(uh, θh)·ez
      const RotaryAxis* table = first.on_head ? second : &first;
      const RotaryAxis* head = first.on_head ? &first : second;
      axis_a = table, x = v, sa = 1, axis_b = head, y = ez, sb = 1;
    }
    for (const Vec3& z : common_vectors(axis_a->direction, x, axis_b->direction, y)) {
      std::optional<double> alpha = turn_onto(axis_a->direction, x, z);
      std::optional<double> beta = turn_onto(axis_b->direction, y, z);
      Candidate c;
      std::optional<double> theta_a = alpha ? std::optional<double>(sa * *alpha) : std::nullopt;
      std::optional<double> theta_b = beta ? std::optional<double>(sb * *beta) : std::nullopt;
      bool a_is_first = axis_a == &first;
      c.first = a_is_first ? theta_a : theta_b;
      c.second = a_is_first ? theta_b : theta_a;
      candidates.push_back(c);
    }
  }
  if (candidates.empty())
    detail::fail("tool direction ", vector_text(v),
                 " is not reachable: the machine's rotary axes "
                 "cannot turn the tool there");

  // Each candidate on the turns nearest the current positions, within the limits; the nearest.
  std::optional<RotaryPositions> best;
  double best_distance = std::numeric_limits<double>::infinity();
  std::ostringstream excluded;
  for (const Candidate& c : candidates) {
    RotaryPositions p = current;
    bool inside = true;
    for (std::size_t n = 0; n < kin.axes.size(); ++n) {
      const RotaryAxis& axis = kin.axes[n];
      auto index = std::size_t(rotary_index(axis.letter));
      const std::optional<double>& angle = n == 0 ? c.first : c.second;
      if (!angle) {
        p[index] = clamp_to_limits(axis, current[index]);
        continue;
      }
      std::optional<double> turn = nearest_turn(axis, *angle, current[index]);
      if (!turn) {
        inside = false;
        excluded << (excluded.tellp() > 0 ? "; " : "") << axis.letter << *angle << " (limits "
                 << (*axis.limits)[0] << " to " << (*axis.limits)[1] << ")";
        break;
      }
      p[index] = *turn;
    }
    if (!inside) continue;
    // Numerical guard: the pose must give the direction asked for.
    if (glm::dot(tool_direction(kin, p), v) < 1 - kSolutionsAgree) continue;
    double distance = 0;
    for (int i = 0; i < 3; ++i) distance += std::abs(p[std::size_t(i)] - current[std::size_t(i)]);
    if (distance < best_distance) best = p, best_distance = distance;
  }
  if (!best) {
    if (excluded.tellp() > 0)
      detail::fail("tool direction ", vector_text(v), " is outside the rotary limits: it needs ",
                   excluded.str());
    detail::fail("tool direction ", vector_text(v),
                 " is not reachable: the machine's rotary axes "
                 "cannot turn the tool there");
  }
  return *best;
}

}  // namespace tridex::gcode
