// tridex — points, boxes, segments and rigid frames.
//
// A Frame is the rigid transform T_i of the method (docs/design.md): its local z axis is a
// spindle direction. `to_local` maps world points into the frame (the spindle onto +z);
// `to_world` is its inverse. The rotation's columns are the frame's x, y, z axes in world
// coordinates, so `rotation * local + origin == world`.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>

#include <glm/glm.hpp>

#include "tridex/error.hpp"

namespace tridex {

using Vec2 = glm::dvec2;
using Vec3 = glm::dvec3;
using Mat3 = glm::dmat3;

// Rotation by `degrees` about the unit axis `k`, right-handed (Rodrigues' formula).
inline Mat3 rotation_about(const Vec3& k, double degrees) {
  const double t = glm::radians(degrees), c = std::cos(t), s = std::sin(t);
  Mat3 m;
  for (int col = 0; col < 3; ++col) {
    Vec3 e(0.0);
    e[col] = 1;
    m[col] = e * c + glm::cross(k, e) * s + k * glm::dot(k, e) * (1 - c);
  }
  return m;
}

inline bool is_finite(const Vec3& p) {
  return std::isfinite(p.x) && std::isfinite(p.y) && std::isfinite(p.z);
}

// Axis-aligned box; default-constructed it is empty (min > max) and grows with `extend`.
struct Aabb {
  Vec3 min{std::numeric_limits<double>::infinity()};
  Vec3 max{-std::numeric_limits<double>::infinity()};

  static Aabb of(const Vec3& a, const Vec3& b) { return Aabb{glm::min(a, b), glm::max(a, b)}; }
  bool empty() const { return !(min.x <= max.x && min.y <= max.y && min.z <= max.z); }
  Vec3 size() const { return empty() ? Vec3(0) : max - min; }
  Vec3 center() const { return 0.5 * (min + max); }
  void extend(const Vec3& p) {
    min = glm::min(min, p);
    max = glm::max(max, p);
  }
  void extend(const Aabb& b) {
    min = glm::min(min, b.min);
    max = glm::max(max, b.max);
  }
  Aabb inflated(double margin) const { return Aabb{min - Vec3(margin), max + Vec3(margin)}; }
  bool contains(const Vec3& p) const {
    return p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y && p.z >= min.z &&
           p.z <= max.z;
  }
  std::array<Vec3, 8> corners() const {
    std::array<Vec3, 8> c;
    for (int i = 0; i < 8; ++i)
      c[static_cast<std::size_t>(i)] =
          Vec3((i & 1) ? max.x : min.x, (i & 2) ? max.y : min.y, (i & 4) ? max.z : min.z);
    return c;
  }
};

// A straight move of the tool tip from `a` to `b`.
struct Segment {
  Vec3 a;
  Vec3 b;
};

struct Frame {
  Mat3 rotation{1.0};  // columns: the frame's x, y, z axes in world coordinates
  Vec3 origin{0.0};    // the frame's origin in world coordinates

  Vec3 axis() const { return rotation[2]; }
  Vec3 to_world(const Vec3& local) const { return rotation * local + origin; }
  Vec3 to_local(const Vec3& world) const { return glm::transpose(rotation) * (world - origin); }
  Vec3 direction_to_world(const Vec3& local) const { return rotation * local; }
  Vec3 direction_to_local(const Vec3& world) const { return glm::transpose(rotation) * world; }
  Frame inverse() const {
    Mat3 rt = glm::transpose(rotation);
    return Frame{rt, -(rt * origin)};
  }

  // The canonical frame of a spindle direction: z = the unit direction; x = world X projected
  // onto the plane normal to z (world Y when the direction is nearly ±X), so that every move with
  // the same direction gets the same frame.
  static Frame from_axis(const Vec3& direction, const Vec3& origin = Vec3(0)) {
    if (!is_finite(direction) || !is_finite(origin))
      detail::fail("frame: direction and origin must be finite");
    double length = glm::length(direction);
    if (!(length > 1e-12)) detail::fail("frame: spindle direction must be non-zero");
    Vec3 z = direction / length;
    Vec3 reference = std::abs(z.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0);
    Vec3 x = glm::normalize(reference - glm::dot(reference, z) * z);
    Vec3 y = glm::cross(z, x);
    return Frame{Mat3(x, y, z), origin};
  }

  // A frame from a rotation matrix such as G68.2's R = Rz(a)·Rx(b)·Rz(c); R must be a proper
  // rotation (orthonormal, determinant +1) within `tolerance`.
  static Frame from_rotation(const Mat3& rotation, const Vec3& origin = Vec3(0),
                             double tolerance = 1e-9) {
    for (int c = 0; c < 3; ++c)
      if (!is_finite(rotation[c])) detail::fail("frame: rotation must be finite");
    if (!is_finite(origin)) detail::fail("frame: origin must be finite");
    Mat3 error = glm::transpose(rotation) * rotation - Mat3(1.0);
    double worst = 0;
    for (int c = 0; c < 3; ++c)
      for (int r = 0; r < 3; ++r) worst = std::max(worst, std::abs(error[c][r]));
    if (worst > tolerance || glm::determinant(rotation) < 0)
      detail::fail("frame: matrix is not a rotation (orthonormality error ", worst, ")");
    return Frame{rotation, origin};
  }
};

// Rotation about a coordinate axis by `degrees`, right-handed.
inline Mat3 rotation_x(double degrees) {
  double r = glm::radians(degrees), c = std::cos(r), s = std::sin(r);
  return Mat3(Vec3(1, 0, 0), Vec3(0, c, s), Vec3(0, -s, c));
}
inline Mat3 rotation_y(double degrees) {
  double r = glm::radians(degrees), c = std::cos(r), s = std::sin(r);
  return Mat3(Vec3(c, 0, -s), Vec3(0, 1, 0), Vec3(s, 0, c));
}
inline Mat3 rotation_z(double degrees) {
  double r = glm::radians(degrees), c = std::cos(r), s = std::sin(r);
  return Mat3(Vec3(c, s, 0), Vec3(-s, c, 0), Vec3(0, 0, 1));
}

// The box around a box seen in `frame` (its 8 corners mapped to local coordinates).
inline Aabb local_bounds(const Frame& frame, const Aabb& world_box) {
  Aabb local;
  for (const Vec3& c : world_box.corners()) local.extend(frame.to_local(c));
  return local;
}

// Squared distance from point p to the 2-D segment [a, b].
inline double distance2_point_segment(const Vec2& p, const Vec2& a, const Vec2& b) {
  Vec2 ab = b - a, ap = p - a;
  double len2 = glm::dot(ab, ab);
  double t = len2 > 0 ? std::clamp(glm::dot(ap, ab) / len2, 0.0, 1.0) : 0.0;
  Vec2 d = ap - t * ab;
  return glm::dot(d, d);
}

}  // namespace tridex
