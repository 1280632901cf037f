#include <doctest/doctest.h>

#include <random>

#include "reference.hpp"
#include "tridex/cutter.hpp"

using namespace tridex;
using test::RadiusFunction;

namespace {

struct Case {
  Cutter cutter;
  RadiusFunction reference;
};

std::vector<Case> every_kind() {
  return {
      {Cutter::flat(5), test::flat_rho(5)},
      {Cutter::ball(3), test::ball_rho(3)},
      {Cutter::bull_nose(4, 1), test::bull_rho(4, 1)},
      {Cutter::cone(3, 45), test::chamfer_rho(3, 0, 45)},
      {Cutter::chamfer(5, 1.5, 30), test::chamfer_rho(5, 1.5, 30)},
      {Cutter::tapered_ball(4, 1, 10), test::tapered_ball_rho(4, 1, 10)},
      {Cutter::from_profile({{0.5, 0}, {2, 1}, {3, 3}}),
       {3, [](double h) { return h <= 1 ? 0.5 + 1.5 * h : std::min(3.0, 2 + (h - 1) / 2); }}},
  };
}

}  // namespace

TEST_CASE("lower surface of every cutter kind matches its radius function") {
  std::mt19937 rng(7);
  for (const Case& c : every_kind()) {
    CAPTURE(c.cutter.name());
    CHECK(c.cutter.radius() == c.reference.radius);
    std::uniform_real_distribution<double> d(0, c.cutter.radius());
    for (int k = 0; k < 500; ++k) {
      double distance = k == 0 ? 0 : k == 1 ? c.cutter.radius() : d(rng);
      CAPTURE(distance);
      // The reference inverts ρ by bisection, which is ill-conditioned where the profile is
      // vertical (the rim of a ball), so compare heights loosely and radii tightly.
      double h = c.cutter.lower_height(distance);
      CHECK(h == doctest::Approx(test::lowest_height(c.reference, distance)).epsilon(1e-6));
      CHECK(c.reference.rho(h) >= distance - 1e-9);               // reaches d at h...
      if (h > 1e-6) CHECK(c.reference.rho(h - 1e-6) < distance);  // ...and not below it
    }
    CHECK(std::isinf(c.cutter.lower_height(c.cutter.radius() * 1.0001)));
  }
}

TEST_CASE("lower surface is convex and non-decreasing, with a matching slope") {
  for (const Case& c : every_kind()) {
    CAPTURE(c.cutter.name());
    const int n = 2000;
    double r = c.cutter.radius();
    for (int k = 1; k < n; ++k) {
      double d0 = r * (k - 1) / n, d1 = r * k / n, d2 = r * (k + 1) / n;
      double h0 = c.cutter.lower_height(d0), h1 = c.cutter.lower_height(d1),
             h2 = c.cutter.lower_height(d2);
      CHECK(h1 >= h0 - 1e-12);
      CHECK(h0 + h2 - 2 * h1 >= -1e-9);
      double numeric = (h2 - h1) / (d2 - d1);
      double slope = c.cutter.lower_slope(d1);
      if (std::isfinite(slope) && k + 2 < n) CHECK(slope <= numeric + 1e-6);
    }
  }
}

TEST_CASE("invalid cutter parameters are rejected with a clear error") {
  CHECK_THROWS_WITH_AS(Cutter::flat(0), doctest::Contains("radius must be positive"), Error);
  CHECK_THROWS_AS(Cutter::flat(-1), Error);
  CHECK_THROWS_AS(Cutter::ball(std::nan("")), Error);
  CHECK_THROWS_AS(Cutter::ball(INFINITY), Error);
  CHECK_THROWS_WITH_AS(Cutter::bull_nose(2, 3), doctest::Contains("exceeds"), Error);
  CHECK_THROWS_AS(Cutter::bull_nose(2, 0), Error);
  CHECK_THROWS_AS(Cutter::cone(2, 90), Error);
  CHECK_THROWS_AS(Cutter::cone(2, 0), Error);
  CHECK_THROWS_AS(Cutter::chamfer(2, 2, 45), Error);
  CHECK_THROWS_AS(Cutter::tapered_ball(2, 3, 10), Error);
  CHECK_THROWS_WITH_AS(Cutter::from_profile({{0, 0}, {1, 2}, {2, 2.5}}),
                       doctest::Contains("not convex"), Error);
  CHECK_THROWS_AS(Cutter::from_profile({{0, 1}, {1, 2}}), Error);
  CHECK_THROWS_AS(Cutter::from_profile({{0, 0}}), Error);
  CHECK_THROWS_AS(Cutter::from_profile({{0, 0}, {0, 1}}), Error);
  // A bull nose whose corner is the whole radius is a ball.
  CHECK(Cutter::bull_nose(2, 2).shape() == CutterShape::ball);
}
