// The triangle tree's distances (collide.hpp) against brute force on random meshes.
#include <doctest/doctest.h>

#include <random>

#include "tridex/collide.hpp"

namespace test_collide {

using namespace tridex;
using detail::Triangle3;

// A soup of `n` random triangles of size about `size` scattered over a box of side `spread`.
std::vector<Triangle3> random_soup(std::mt19937& rng, int n, double spread, double size) {
  std::uniform_real_distribution<double> u(-1, 1);
  std::vector<Triangle3> out;
  for (int k = 0; k < n; ++k) {
    const Vec3 c(u(rng) * spread, u(rng) * spread, u(rng) * spread);
    out.push_back({c + size * Vec3(u(rng), u(rng), u(rng)), c + size * Vec3(u(rng), u(rng), u(rng)),
                   c + size * Vec3(u(rng), u(rng), u(rng))});
  }
  return out;
}

Frame random_frame(std::mt19937& rng, double shift) {
  std::uniform_real_distribution<double> u(-1, 1);
  const Mat3 r = rotation_z(180 * u(rng)) * rotation_x(180 * u(rng)) * rotation_y(180 * u(rng));
  return Frame{r, shift * Vec3(u(rng), u(rng), u(rng))};
}

Triangle3 placed(const Frame& f, const Triangle3& t) {
  return {f.to_world(t.a), f.to_world(t.b), f.to_world(t.c)};
}

// The least distance between dense samples of two triangles: an upper bound of the true one,
// within the sampling's spacing of it.
double sampled_distance(const Triangle3& s, const Triangle3& t, int n) {
  double best = std::numeric_limits<double>::infinity();
  std::vector<Vec3> ps, qs;
  for (int i = 0; i <= n; ++i)
    for (int j = 0; i + j <= n; ++j) {
      const double a = double(i) / n, b = double(j) / n;
      ps.push_back(s.a + a * (s.b - s.a) + b * (s.c - s.a));
      qs.push_back(t.a + a * (t.b - t.a) + b * (t.c - t.a));
    }
  for (const Vec3& p : ps)
    for (const Vec3& q : qs) best = std::min(best, glm::length(p - q));
  return best;
}

TEST_CASE("triangle distance: exact, against dense sampling of random pairs") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  int touching = 0;
  for (int trial = 0; trial < 300; ++trial) {
    Triangle3 s{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)),
                Vec3(u(rng), u(rng), u(rng))};
    Triangle3 t{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng)),
                Vec3(u(rng), u(rng), u(rng))};
    const double exact = std::sqrt(detail::triangle_distance2(s, t));
    const double sampled = sampled_distance(s, t, 24);
    // Samples 1/24 of each side apart lie within 2 * (2/24) * sqrt(3) of any point.
    CHECK(exact <= sampled + 1e-12);
    CHECK(exact >= sampled - 0.3);
    touching += exact == 0;
  }
  CHECK(touching > 20);  // the set has crossing pairs as well as apart ones
}

TEST_CASE("tree distance: the same as every pair's, placed by random frames") {
  std::mt19937 rng(11);
  for (int trial = 0; trial < 20; ++trial) {
    const std::vector<Triangle3> sa = random_soup(rng, 150, 10, 1.5);
    const std::vector<Triangle3> sb = random_soup(rng, 120, 8, 2.0);
    const TriangleTree a(sa), b(sb);
    const Frame fa = random_frame(rng, 5), fb = random_frame(rng, 25);
    double brute2 = std::numeric_limits<double>::infinity();
    for (const Triangle3& s : sa)
      for (const Triangle3& t : sb)
        brute2 = std::min(brute2, detail::triangle_distance2(placed(fa, s), placed(fb, t)));
    const TreeDistance d = tree_distance(a, fa, b, fb);
    CHECK(d.distance == doctest::Approx(std::sqrt(brute2)).epsilon(1e-9));
    // A cap below the distance gives the cap; a stop above it gives some pair within the stop.
    if (brute2 > 0)
      CHECK(tree_distance(a, fa, b, fb, 0, 0.5 * std::sqrt(brute2)).distance ==
            0.5 * std::sqrt(brute2));
    CHECK(tree_distance(a, fa, b, fb, std::sqrt(brute2) + 1).distance <= std::sqrt(brute2) + 1);
  }
}

TEST_CASE("point and segment distances against brute force; containment by parity") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> u(-12, 12);
  const std::vector<Triangle3> soup = random_soup(rng, 400, 10, 1.0);
  const TriangleTree tree(soup);
  for (int k = 0; k < 200; ++k) {
    const Vec3 p(u(rng), u(rng), u(rng)), q(u(rng), u(rng), u(rng));
    double point2 = std::numeric_limits<double>::infinity(), seg2 = point2;
    for (const Triangle3& t : soup) {
      point2 = std::min(point2, detail::point_triangle_distance2(p, t));
      // The segment as a degenerate triangle: triangle_distance2 handles it exactly.
      seg2 = std::min(seg2, detail::triangle_distance2(Triangle3{p, q, q}, t));
    }
    CHECK(tree.distance(p) == doctest::Approx(std::sqrt(point2)).epsilon(1e-12));
    CHECK(tree.distance(p, q) == doctest::Approx(std::sqrt(seg2)).epsilon(1e-9));
  }
  // A closed box [0,2]^3 of 12 triangles: inside and outside points.
  const Vec3 c[8] = {{0, 0, 0}, {2, 0, 0}, {2, 2, 0}, {0, 2, 0},
                     {0, 0, 2}, {2, 0, 2}, {2, 2, 2}, {0, 2, 2}};
  const int f[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                        {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::vector<Triangle3> box;
  for (const auto& t : f) box.push_back({c[t[0]], c[t[1]], c[t[2]]});
  const TriangleTree solid(box);
  std::uniform_real_distribution<double> v(-1, 3);
  for (int k = 0; k < 500; ++k) {
    const Vec3 p(v(rng), v(rng), v(rng));
    const bool inside = p.x > 0 && p.x < 2 && p.y > 0 && p.y < 2 && p.z > 0 && p.z < 2;
    if (solid.distance(p) > 1e-9) CHECK(solid.contains(p) == inside);
  }
}

}  // namespace test_collide
