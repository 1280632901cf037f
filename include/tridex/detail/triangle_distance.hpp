// tridex — exact closest-point primitives for the triangle tree (collide.hpp): point–triangle,
// segment–segment and triangle–triangle distances, in double.
//
// Point–triangle: Ericson, "Real-Time Collision Detection", Morgan Kaufmann 2005, §5.1.5 (the
// Voronoi regions of the vertices, edges and face). Segment–segment: ibid. §5.1.9 (the clamped
// closest parameters). Triangle–triangle: two triangles that do not intersect have their closest
// pair on an edge of one against the other (an edge–edge pair or a vertex–face pair), so the
// distance is the least of the 9 edge–edge and 6 vertex–triangle distances; when they intersect
// (an edge of one crosses the other) the distance is 0.
#pragma once

#include <algorithm>
#include <array>
#include <cmath>

#include "tridex/geometry.hpp"

namespace tridex::detail {

struct Triangle3 {
  Vec3 a, b, c;
};

// The point of triangle t closest to p.
inline Vec3 closest_on_triangle(const Vec3& p, const Triangle3& t) {
  const Vec3 ab = t.b - t.a, ac = t.c - t.a, ap = p - t.a;
  const double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return t.a;
  const Vec3 bp = p - t.b;
  const double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return t.b;
  const double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return t.a + ab * (d1 / (d1 - d3));
  const Vec3 cp = p - t.c;
  const double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return t.c;
  const double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return t.a + ac * (d2 / (d2 - d6));
  const double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return t.b + (t.c - t.b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)));
  const double sum = va + vb + vc;
  if (!(sum > 0)) return t.a;  // a degenerate triangle: its vertices and edges were tried above
  return t.a + ab * (vb / sum) + ac * (vc / sum);
}

inline double point_triangle_distance2(const Vec3& p, const Triangle3& t) {
  const Vec3 d = p - closest_on_triangle(p, t);
  return glm::dot(d, d);
}

// Squared distance between segments [p1, q1] and [p2, q2].
inline double segment_distance2(const Vec3& p1, const Vec3& q1, const Vec3& p2, const Vec3& q2) {
  const Vec3 d1 = q1 - p1, d2 = q2 - p2, r = p1 - p2;
  const double a = glm::dot(d1, d1), e = glm::dot(d2, d2), f = glm::dot(d2, r);
  double s = 0, t = 0;
  if (a <= 1e-300 && e <= 1e-300) return glm::dot(r, r);
  if (a <= 1e-300) {
    t = std::clamp(f / e, 0.0, 1.0);
  } else {
    const double c = glm::dot(d1, r);
    if (e <= 1e-300) {
      s = std::clamp(-c / a, 0.0, 1.0);
    } else {
      const double b = glm::dot(d1, d2), denom = a * e - b * b;
      s = denom > 0 ? std::clamp((b * f - c * e) / denom, 0.0, 1.0) : 0.0;
      t = (b * s + f) / e;
      if (t < 0) {
        t = 0, s = std::clamp(-c / a, 0.0, 1.0);
      } else if (t > 1) {
        t = 1, s = std::clamp((b - c) / a, 0.0, 1.0);
      }
    }
  }
  const Vec3 d = (p1 + d1 * s) - (p2 + d2 * t);
  return glm::dot(d, d);
}

// Whether segment [p, q] crosses triangle t (touching counts).
inline bool segment_crosses_triangle(const Vec3& p, const Vec3& q, const Triangle3& t) {
  const Vec3 n = glm::cross(t.b - t.a, t.c - t.a);
  const double dp = glm::dot(n, p - t.a), dq = glm::dot(n, q - t.a);
  if ((dp > 0 && dq > 0) || (dp < 0 && dq < 0) || dp == dq) return false;
  const Vec3 x = p + (q - p) * (dp / (dp - dq));
  const double s1 = glm::dot(n, glm::cross(t.b - t.a, x - t.a));
  const double s2 = glm::dot(n, glm::cross(t.c - t.b, x - t.b));
  const double s3 = glm::dot(n, glm::cross(t.a - t.c, x - t.c));
  return (s1 >= 0 && s2 >= 0 && s3 >= 0) || (s1 <= 0 && s2 <= 0 && s3 <= 0);
}

// Squared distance between two triangles; 0 when they intersect.
inline double triangle_distance2(const Triangle3& s, const Triangle3& t) {
  const std::array<Vec3, 3> u{s.a, s.b, s.c}, v{t.a, t.b, t.c};
  for (int i = 0; i < 3; ++i) {
    if (segment_crosses_triangle(u[i], u[(i + 1) % 3], t)) return 0;
    if (segment_crosses_triangle(v[i], v[(i + 1) % 3], s)) return 0;
  }
  double best = std::numeric_limits<double>::infinity();
  for (int i = 0; i < 3; ++i) {
    best = std::min(best, point_triangle_distance2(u[i], t));
    best = std::min(best, point_triangle_distance2(v[i], s));
    for (int j = 0; j < 3; ++j)
      best = std::min(best, segment_distance2(u[i], u[(i + 1) % 3], v[j], v[(j + 1) % 3]));
  }
  return best;
}

}  // namespace tridex::detail
