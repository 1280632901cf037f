// tridex::gcode — feature frames of the tilted-working-plane forms (see tilted_plane.hpp for the
// definitions and their sources).
#include "tridex/gcode/tilted_plane.hpp"

#include <algorithm>
#include <array>
#include <cmath>

#include "tridex/error.hpp"

namespace tridex::gcode {
namespace {

// Below this |a × b| / (|a| |b|) two directions count as parallel, and below this length a
// vector counts as zero: far below any angle or length a program writes (1e-9 rad, 1e-12 mm).
constexpr double kParallel = 1e-9;
constexpr double kZeroLength = 1e-12;
constexpr double kNormalCosine = 1e-3;  // "normal to each other" for vectors posted to 6 places

Vec3 unit(const Vec3& v, const char* what) {
  if (!is_finite(v)) detail::fail(what, " must be finite");
  double length = glm::length(v);
  if (!(length > kZeroLength))
    detail::fail(what, " is a zero vector (", v.x, ", ", v.y, ", ", v.z, ")");
  return v / length;
}

void require_finite_origin(const Vec3& origin) {
  if (!is_finite(origin)) detail::fail("the feature origin X Y Z must be finite");
}

// The frame with unit X and a Y that is normal to it (right-handed).
Frame from_x_y(const Vec3& origin, const Vec3& x, const Vec3& y) {
  return Frame{Mat3(x, y, glm::cross(x, y)), origin};
}

// The angle of the fixed-axis form that belongs to axis n (1 = X: I, 2 = Y: J, 3 = Z: K).
double angle_of_axis(int n, double i, double j, double k) { return n == 1 ? i : n == 2 ? j : k; }

// The three digits of a rotation order word, each 1..3; false when q is not of that shape.
bool order_digits(int q, std::array<int, 3>& digits) {
  if (q < 111 || q > 333) return false;
  digits = {q / 100, q / 10 % 10, q % 10};
  for (int d : digits)
    if (d < 1 || d > 3) return false;
  return true;
}

}  // namespace

Mat3 axis_rotation(int axis, double degrees) {
  switch (axis) {
    case 1:
      return rotation_x(degrees);
    case 2:
      return rotation_y(degrees);
    case 3:
      return rotation_z(degrees);
    default:
      detail::fail("rotation axis must be 1 (X), 2 (Y) or 3 (Z), got ", axis);
  }
}

Frame fanuc_euler(const Vec3& origin, double i, double j, double k) {
  require_finite_origin(origin);
  return Frame{rotation_z(i) * rotation_x(j) * rotation_z(k), origin};
}

Frame fixed_axis_angles(const Vec3& origin, double i, double j, double k, int q) {
  require_finite_origin(origin);
  std::array<int, 3> d{};
  if (!order_digits(q, d) || d[0] == d[1] || d[1] == d[2] || d[0] == d[2])
    detail::fail("rotation order Q", q,
                 " is not one of Q123 Q132 Q213 Q231 Q312 Q321 (three distinct axes)");
  // About fixed axes, each later rotation multiplies from the left.
  Mat3 r = axis_rotation(d[2], angle_of_axis(d[2], i, j, k)) *
           axis_rotation(d[1], angle_of_axis(d[1], i, j, k)) *
           axis_rotation(d[0], angle_of_axis(d[0], i, j, k));
  return Frame{r, origin};
}

Frame three_point_frame(const Vec3& p1, const Vec3& p2, const Vec3& p3) {
  for (const Vec3* p : {&p1, &p2, &p3})
    if (!is_finite(*p)) detail::fail("the three points of G68.2 P2 must be finite");
  Vec3 along = p2 - p1, across = p3 - p1;
  if (!(glm::length(along) > kZeroLength))
    detail::fail("G68.2 P2: the first and second points coincide, so they give no X direction");
  if (!(glm::length(across) > kZeroLength))
    detail::fail("G68.2 P2: the first and third points coincide, so they give no plane");
  Vec3 normal = glm::cross(along, across);
  if (!(glm::length(normal) > kParallel * glm::length(along) * glm::length(across)))
    detail::fail("G68.2 P2: the three points lie on one line, so they give no plane");
  Vec3 x = glm::normalize(along), z = glm::normalize(normal);
  return Frame{Mat3(x, glm::cross(z, x), z), p1};
}

Frame two_vector_frame(const Vec3& origin, const Vec3& x_direction, const Vec3& z_direction) {
  require_finite_origin(origin);
  Vec3 x = unit(x_direction, "G68.2 P3: the X direction (first block's I J K)");
  Vec3 z = unit(z_direction, "G68.2 P3: the Z direction (second block's I J K)");
  double cosine = glm::dot(x, z);
  // cos 85° = 0.0872: Fanuc's alarm limit on the angle between the two vectors.
  if (std::abs(cosine) > std::cos(glm::radians(85.0)))
    detail::fail("G68.2 P3: the X and Z directions are ",
                 glm::degrees(std::acos(std::clamp(cosine, -1.0, 1.0))),
                 " degrees apart; they must be 85 to 95 degrees apart");
  x = glm::normalize(x - cosine * z);
  return Frame{Mat3(x, glm::cross(z, x), z), origin};
}

Frame hurco_vector_frame(const Vec3& origin, const Vec3& x_direction, const Vec3& y_direction) {
  require_finite_origin(origin);
  Vec3 x = unit(x_direction, "G68.2 I J K (the feature X direction)");
  Vec3 y = unit(y_direction, "G68.2 U V W (the feature Y direction)");
  double cosine = glm::dot(x, y);
  if (std::abs(cosine) > kNormalCosine)
    detail::fail(
        "G68.2: the X direction I J K and the Y direction U V W are not normal to each "
        "other (cosine ",
        cosine, ")");
  return from_x_y(origin, x, glm::normalize(y - cosine * x));
}

Frame tool_axis_frame(const Vec3& origin, const Vec3& tool_axis, double r, const Vec3& reference) {
  require_finite_origin(origin);
  if (!std::isfinite(r)) detail::fail("G68.3 R must be finite");
  Vec3 z = unit(tool_axis, "G68.3: the tool axis");
  Vec3 p = unit(reference, "G68.3: the reference direction");
  Vec3 x = glm::cross(p, z);
  if (!(glm::length(x) > kParallel))
    detail::fail("G68.3: the tool axis (", z.x, ", ", z.y, ", ", z.z,
                 ") is parallel to the reference direction, so it gives no X axis");
  x = glm::normalize(x);
  return rotated_about_own_z(Frame{Mat3(x, glm::cross(z, x), z), origin}, r);
}

Frame rotated_about_own_z(const Frame& frame, double degrees) {
  return Frame{frame.rotation * rotation_z(degrees), frame.origin};
}

Frame compose(const Frame& current, const Frame& incremental) {
  return Frame{current.rotation * incremental.rotation, current.to_world(incremental.origin)};
}

Mat3 linuxcnc_euler_rotation(double first, double second, double third, int q, int p) {
  std::array<int, 3> d{};
  bool shape = order_digits(q, d) && d[0] != d[1] && d[1] != d[2];
  bool proper = shape && d[0] == d[2];      // 121 131 212 232 313 323
  bool tait_bryan = shape && d[0] != d[2];  // 123 132 213 231 312 321
  if (p == 0 && !proper)
    detail::fail("G68.2 P0 Q", q, ": LinuxCNC takes Q121 Q131 Q212 Q232 Q313 Q323");
  if (p == 1 && !tait_bryan)
    detail::fail("G68.2 P1 Q", q, ": LinuxCNC takes Q123 Q132 Q213 Q231 Q312 Q321");
  if (p != 0 && p != 1) detail::fail("LinuxCNC's angle forms are P0 and P1, got P", p);
  return axis_rotation(d[0], first) * axis_rotation(d[1], second) * axis_rotation(d[2], third);
}

Frame linuxcnc_angles_frame(int p, int q, const Vec3& origin, double i, double j, double k,
                            double r) {
  require_finite_origin(origin);
  return Frame{rotation_z(r) * linuxcnc_euler_rotation(i, j, k, q, p), origin};
}

Frame linuxcnc_three_point_frame(const Vec3& origin, double r, const Vec3& p1, const Vec3& p2,
                                 const Vec3& p3) {
  require_finite_origin(origin);
  return Frame{rotation_z(r) * three_point_frame(p1, p2, p3).rotation, origin};
}

Frame linuxcnc_two_vector_frame(const Vec3& origin, const Vec3& point_on_x, double r,
                                const Vec3& z_direction) {
  require_finite_origin(origin);
  Vec3 x = unit(point_on_x - origin, "G68.2 P3 Q0: the X direction (I J K minus X Y Z)");
  Vec3 z = unit(z_direction, "G68.2 P3 Q1: the Z direction I J K");
  double cosine = glm::dot(x, z);
  if (std::abs(cosine) > kNormalCosine)
    detail::fail("G68.2 P3: the X and Z directions are not normal to each other (cosine ", cosine,
                 ")");
  x = glm::normalize(x - cosine * z);
  return Frame{rotation_z(r) * Mat3(x, glm::cross(z, x), z), origin};
}

}  // namespace tridex::gcode
