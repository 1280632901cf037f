// tridex — cutters: convex solids of revolution around the tool axis.
//
// The conventions of docs/design.md: the programmed point is the tool tip (the lowest point
// on the axis); a cutter is given by its radius ρ(h) at height h above the tip and continues
// upward at full radius forever. Milling needs the inverse view, the cutter's *lower surface*:
// the height h(d) of its lowest point at horizontal distance d from the axis, for 0 ≤ d ≤ R.
// For a convex cutter h is convex and non-decreasing. It is stored as a short chain of pieces,
// each a straight line or an arc of a circle, so that every shape here is exact:
//   flat end          h = 0
//   ball end          h = R − √(R² − d²)
//   bull nose         h = 0 for d ≤ R − r, then r − √(r² − (d − R + r)²)
//   cone (V-bit)      h = d / tan α
//   chamfer           h = 0 for d ≤ r₀, then (d − r₀) / tan α
//   tapered ball      ball of radius r up to the tangent point, then a cone of half-angle α
//   from_profile      a convex polyline of (ρ, h) points, for any other shape
#pragma once

#include <cmath>
#include <limits>
#include <string>
#include <vector>

#include "tridex/error.hpp"
#include "tridex/geometry.hpp"

namespace tridex {

enum class CutterShape { flat, ball, bull_nose, general };

// One piece of the lower surface on d ∈ [d0, d1]: a line h = h0 + slope·(d − d0), or the lower
// half of the circle with centre (centre_d, centre_h) and radius `radius`.
struct ProfilePiece {
  double d0 = 0, d1 = 0;
  bool is_arc = false;
  double h0 = 0, slope = 0;                       // line
  double centre_d = 0, centre_h = 0, radius = 0;  // arc

  double height(double d) const {
    if (!is_arc) return h0 + slope * (d - d0);
    double x = d - centre_d;
    return centre_h - std::sqrt(std::max(0.0, radius * radius - x * x));
  }
  double derivative(double d) const {
    if (!is_arc) return slope;
    double x = d - centre_d;
    double root = std::sqrt(std::max(0.0, radius * radius - x * x));
    return root > 0 ? x / root : std::numeric_limits<double>::infinity();
  }
};

class Cutter {
 public:
  static Cutter flat(double radius) {
    detail::require_positive(radius, "flat end cutter radius");
    Cutter c(CutterShape::flat, radius, "flat end");
    c.add_line(0, radius, 0, 0);
    return c;
  }

  static Cutter ball(double radius) {
    detail::require_positive(radius, "ball end cutter radius");
    Cutter c(CutterShape::ball, radius, "ball end");
    c.add_arc(0, radius, 0, radius, radius);
    return c;
  }

  static Cutter bull_nose(double radius, double corner_radius) {
    detail::require_positive(radius, "bull nose cutter radius");
    detail::require_positive(corner_radius, "bull nose corner radius");
    if (corner_radius > radius)
      detail::fail("bull nose corner radius ", corner_radius, " exceeds the cutter radius ",
                   radius);
    if (corner_radius == radius) return ball(radius);
    Cutter c(CutterShape::bull_nose, radius, "bull nose");
    c.corner_ = corner_radius;
    double flat = radius - corner_radius;
    c.add_line(0, flat, 0, 0);
    c.add_arc(flat, radius, flat, corner_radius, corner_radius);
    return c;
  }

  // A sharp cone (engraving V-bit) with half-angle `half_angle_deg` between side and axis.
  static Cutter cone(double radius, double half_angle_deg) {
    return chamfer(radius, 0, half_angle_deg);
  }

  // A flat tip of radius `tip_radius`, then a cone of half-angle `half_angle_deg` up to `radius`.
  static Cutter chamfer(double radius, double tip_radius, double half_angle_deg) {
    detail::require_positive(radius, "chamfer cutter radius");
    detail::require_finite(tip_radius, "chamfer tip radius");
    detail::require_finite(half_angle_deg, "chamfer half angle");
    if (tip_radius < 0 || tip_radius >= radius)
      detail::fail("chamfer tip radius ", tip_radius, " must lie in [0, ", radius, ")");
    if (!(half_angle_deg > 0 && half_angle_deg < 90))
      detail::fail("cutter half angle ", half_angle_deg, " must lie in (0, 90) degrees");
    Cutter c(CutterShape::general, radius, tip_radius > 0 ? "chamfer" : "cone");
    if (tip_radius > 0) c.add_line(0, tip_radius, 0, 0);
    c.add_line(tip_radius, radius, 0, 1.0 / std::tan(glm::radians(half_angle_deg)));
    return c;
  }

  // A ball of radius `tip_radius` at the tip, continued tangentially by a cone of half-angle
  // `half_angle_deg` up to `radius`.
  static Cutter tapered_ball(double radius, double tip_radius, double half_angle_deg) {
    detail::require_positive(radius, "tapered ball cutter radius");
    detail::require_positive(tip_radius, "tapered ball tip radius");
    detail::require_finite(half_angle_deg, "tapered ball half angle");
    if (!(half_angle_deg > 0 && half_angle_deg < 90))
      detail::fail("cutter half angle ", half_angle_deg, " must lie in (0, 90) degrees");
    double alpha = glm::radians(half_angle_deg);
    double tangent_d = tip_radius * std::cos(alpha);  // where the cone touches the ball
    if (tip_radius >= radius || tangent_d >= radius)
      detail::fail("tapered ball tip radius ", tip_radius, " is too large for radius ", radius);
    Cutter c(CutterShape::general, radius, "tapered ball");
    c.add_arc(0, tangent_d, 0, tip_radius, tip_radius);
    double tangent_h = tip_radius - tip_radius * std::sin(alpha);
    c.add_line(tangent_d, radius, tangent_h, 1.0 / std::tan(alpha));
    return c;
  }

  // A general convex cutter from its profile: points (ρ, h) from the tip upward, starting at
  // h = 0, with ρ strictly increasing and the slope dh/dρ non-decreasing (a convex solid). The
  // last point's ρ is the cutter's radius.
  static Cutter from_profile(const std::vector<Vec2>& rho_h) {
    if (rho_h.size() < 2) detail::fail("cutter profile needs at least two points");
    for (const Vec2& p : rho_h)
      if (!std::isfinite(p.x) || !std::isfinite(p.y))
        detail::fail("cutter profile point is not finite");
    if (rho_h[0].y != 0 || rho_h[0].x < 0)
      detail::fail("cutter profile must start at the tip (h = 0, ρ ≥ 0)");
    Cutter c(CutterShape::general, rho_h.back().x, "profile");
    if (rho_h[0].x > 0) c.add_line(0, rho_h[0].x, 0, 0);
    double previous_slope = 0;
    for (std::size_t k = 1; k < rho_h.size(); ++k) {
      Vec2 p = rho_h[k - 1], q = rho_h[k];
      if (!(q.x > p.x) || !(q.y >= p.y))
        detail::fail("cutter profile point ", k, " must have larger ρ and no smaller h");
      double slope = (q.y - p.y) / (q.x - p.x);
      if (slope < previous_slope - 1e-12) detail::fail("cutter profile is not convex at point ", k);
      previous_slope = slope;
      c.add_line(p.x, q.x, p.y, slope);
    }
    detail::require_positive(c.radius_, "cutter profile radius");
    return c;
  }

  CutterShape shape() const { return shape_; }
  const std::string& name() const { return name_; }
  double radius() const { return radius_; }
  double corner_radius() const { return corner_; }
  const std::vector<ProfilePiece>& pieces() const { return pieces_; }

  // Height above the tip of the lowest cutter point at horizontal distance d ≥ 0 from the axis;
  // +infinity beyond the radius.
  double lower_height(double d) const { return piece_at(d) ? piece_at(d)->height(d) : kNone; }

  // dh/dd at d (the right derivative at a corner of the profile).
  double lower_slope(double d) const {
    const ProfilePiece* p = piece_at(d);
    return p ? p->derivative(d) : std::numeric_limits<double>::infinity();
  }

  // Height of the cutter's cutting part (where it reaches full radius); the shank continues.
  double profile_height() const { return pieces_.back().height(radius_); }

  static constexpr double kNone = std::numeric_limits<double>::infinity();

 private:
  Cutter(CutterShape shape, double radius, std::string name)
      : shape_(shape), radius_(radius), name_(std::move(name)) {}

  const ProfilePiece* piece_at(double d) const {
    if (!(d <= radius_)) return nullptr;
    for (const ProfilePiece& p : pieces_)
      if (d <= p.d1) return &p;
    return &pieces_.back();
  }
  void add_line(double d0, double d1, double h0, double slope) {
    ProfilePiece p;
    p.d0 = d0, p.d1 = d1, p.h0 = h0, p.slope = slope;
    pieces_.push_back(p);
  }
  void add_arc(double d0, double d1, double centre_d, double centre_h, double radius) {
    ProfilePiece p;
    p.d0 = d0, p.d1 = d1, p.is_arc = true;
    p.centre_d = centre_d, p.centre_h = centre_h, p.radius = radius;
    pieces_.push_back(p);
  }

  CutterShape shape_;
  double radius_;
  double corner_ = 0;
  std::string name_;
  std::vector<ProfilePiece> pieces_;
};

}  // namespace tridex
