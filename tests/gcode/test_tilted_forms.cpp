// The tilted-plane forms of tilted_plane.hpp against frames computed by hand from the controls'
// definitions, against an independent rotation (Rodrigues) applied step by step as each
// definition says, and against each other where they describe the same plane.
#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <string>

#include "helpers.hpp"
#include "tridex/error.hpp"
#include "tridex/gcode/tilted_plane.hpp"

using namespace tridex;
using namespace tridex::gcode;
using tridex::gcode::test::about;
using tridex::gcode::test::message_of;
using tridex::gcode::test::near;

namespace {

const Vec3 kX(1, 0, 0), kY(0, 1, 0), kZ(0, 0, 1);
Vec3 unit_axis(int n) { return n == 1 ? kX : n == 2 ? kY : kZ; }

bool same_frame(const Frame& a, const Frame& b, double eps = 1e-9) {
  for (int c = 0; c < 3; ++c)
    if (!near(a.rotation[c], b.rotation[c], eps)) return false;
  return near(a.origin, b.origin, eps);
}

bool same_rotation(const Mat3& a, const Mat3& b, double eps = 1e-9) {
  for (int c = 0; c < 3; ++c)
    if (!near(a[c], b[c], eps)) return false;
  return true;
}

// A random proper rotation (Z-X-Z with uniform angles; not uniform on SO(3), which these tests
// do not need).
Mat3 random_rotation(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(-180, 180);
  return about(kZ, angle(rng)) * about(kX, angle(rng)) * about(kZ, angle(rng));
}

}  // namespace

TEST_CASE("G68.2 P0 I J K is Euler Z-X-Z, with docs/design.md's check directions") {
  CHECK(near(fanuc_euler(Vec3(0), 90, 90, 0).rotation[2], kX));
  CHECK(near(fanuc_euler(Vec3(0), -90, 90, 0).rotation[2], -kX));
  CHECK(near(fanuc_euler(Vec3(0), 0, 90, 0).rotation[2], -kY));
  CHECK(near(fanuc_euler(Vec3(0), 180, 90, 0).rotation[2], kY));
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> angle(-360, 360), length(-100, 100);
  for (int n = 0; n < 200; ++n) {
    double i = angle(rng), j = angle(rng), k = angle(rng);
    Vec3 o(length(rng), length(rng), length(rng));
    // Intrinsic Z, X', Z'': turn about Z, then about the turned X, then about the twice-turned Z.
    Mat3 first = about(kZ, i);
    Mat3 second = about(first * kX, j) * first;
    Mat3 third = about(second * kZ, k) * second;
    Frame f = fanuc_euler(o, i, j, k);
    CHECK(same_rotation(f.rotation, third));
    CHECK(near(f.origin, o));
  }
}

TEST_CASE("G68.2 P1 / G268: rotations about the fixed axes in the order Q names") {
  // By hand: Q123 I90 K90 turns Z by 90° about X to −Y, then about Z to +X; Q321 turns it about
  // Z first (no change), then about X to −Y; Q213 I90 J90: about Y to +X, then about X (no
  // change).
  CHECK(near(fixed_axis_angles(Vec3(0), 90, 0, 90, 123).rotation[2], kX));
  CHECK(near(fixed_axis_angles(Vec3(0), 90, 0, 90, 321).rotation[2], -kY));
  CHECK(near(fixed_axis_angles(Vec3(0), 90, 90, 0, 213).rotation[2], kX));
  // The same angles in the order Q123: about X to −Y, then about Y (no change).
  CHECK(near(fixed_axis_angles(Vec3(0), 90, 90, 0, 123).rotation[2], -kY));

  std::mt19937 rng(11);
  std::uniform_real_distribution<double> angle(-360, 360);
  for (int q : {123, 132, 213, 231, 312, 321}) {
    for (int n = 0; n < 50; ++n) {
      double ijk[3] = {angle(rng), angle(rng), angle(rng)};
      int digits[3] = {q / 100, q / 10 % 10, q % 10};
      // Each rotation about a FIXED axis acts on the vectors the previous ones produced.
      Mat3 r(1.0);
      for (int d : digits) r = about(unit_axis(d), ijk[d - 1]) * r;
      Frame f = fixed_axis_angles(Vec3(1, 2, 3), ijk[0], ijk[1], ijk[2], q);
      CHECK_MESSAGE(same_rotation(f.rotation, r), "Q" << q);
    }
  }
  // Haas G268 Q123 (docs/design.md): R = Rz(K)·Ry(J)·Rx(I).
  Frame haas = fixed_axis_angles(Vec3(0), 10, 20, 30, 123);
  CHECK(same_rotation(haas.rotation, about(kZ, 30) * about(kY, 20) * about(kX, 10)));
}

TEST_CASE("G68.2 P1: Q orders that are not three distinct axes are errors naming Q") {
  for (int q : {121, 0, 124, 1234, 333, 12, -123}) {
    std::string m = message_of([&] { fixed_axis_angles(Vec3(0), 1, 2, 3, q); });
    CHECK_MESSAGE(m.find(tridex::gcode::test::cat("Q", q)) != std::string::npos, m);
  }
}

TEST_CASE("LinuxCNC G68.2 Q121: the issue's plane") {
  // The issue: `G68.2 … I30 J15 Q121` means (0.259, −0.483, 0.837); read as Fanuc's Z-X-Z it
  // came out (0.129, −0.224, 0.966).
  Frame f = linuxcnc_angles_frame(0, 121, Vec3(0), 30, 15, 0);
  Vec3 want(std::sin(glm::radians(15.0)),
            -std::sin(glm::radians(30.0)) * std::cos(glm::radians(15.0)),
            std::cos(glm::radians(30.0)) * std::cos(glm::radians(15.0)));
  CHECK(near(f.rotation[2], want, 1e-12));
  CHECK(near(f.rotation[2], Vec3(0.259, -0.483, 0.837), 1e-3));
  CHECK(near(fanuc_euler(Vec3(0), 30, 15, 0).rotation[2], Vec3(0.129, -0.224, 0.966), 1e-3));
}

TEST_CASE("LinuxCNC's Euler orders: intrinsic, I J K the first, second and third angle") {
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> angle(-180, 180);
  for (int p : {0, 1}) {
    for (int q : p == 0 ? std::vector<int>{121, 131, 212, 232, 313, 323}
                        : std::vector<int>{123, 132, 213, 231, 312, 321}) {
      double a[3] = {angle(rng), angle(rng), angle(rng)};
      int d[3] = {q / 100, q / 10 % 10, q % 10};
      // Intrinsic: each rotation about the axis as the previous rotations left it.
      Mat3 r(1.0);
      for (int n = 0; n < 3; ++n) r = about(r * unit_axis(d[n]), a[n]) * r;
      CHECK_MESSAGE(same_rotation(linuxcnc_euler_rotation(a[0], a[1], a[2], q, p), r), "Q" << q);
    }
  }
  // Q313 is Fanuc's P0; LinuxCNC P1 Q321 with the angles (K, J, I) is Fanuc P1 Q123 with (I, J, K).
  CHECK(same_frame(linuxcnc_angles_frame(0, 313, Vec3(1, 2, 3), 10, 20, 30),
                   fanuc_euler(Vec3(1, 2, 3), 10, 20, 30)));
  CHECK(same_frame(linuxcnc_angles_frame(1, 321, Vec3(0), 30, 20, 10),
                   fixed_axis_angles(Vec3(0), 10, 20, 30, 123)));
  // The R word turns about the work Z, on the left.
  CHECK(same_rotation(linuxcnc_angles_frame(0, 313, Vec3(0), 10, 20, 30, 40).rotation,
                      about(kZ, 40) * fanuc_euler(Vec3(0), 10, 20, 30).rotation));
  // P0 takes proper Euler orders only, P1 Tait-Bryan only.
  CHECK(message_of([] { linuxcnc_euler_rotation(0, 0, 0, 123, 0); }).find("Q123") !=
        std::string::npos);
  CHECK(message_of([] { linuxcnc_euler_rotation(0, 0, 0, 121, 1); }).find("Q121") !=
        std::string::npos);
  CHECK_THROWS_AS(linuxcnc_euler_rotation(0, 0, 0, 313, 2), tridex::Error);
}

TEST_CASE("one plane written five ways: Hurco's 90-degree turn about Y") {
  // Hurco's blog example: G68.2 X3 Y-3 Z-6 I0 J0 K-1 U0 V1 W0, a 90° turn about Y.
  const Vec3 o(3, -3, -6);
  Frame hurco = hurco_vector_frame(o, Vec3(0, 0, -1), Vec3(0, 1, 0));
  Frame want{about(kY, 90), o};
  CHECK(same_frame(hurco, want));
  CHECK(near(hurco.rotation[2], kX));
  CHECK(same_frame(fanuc_euler(o, 90, 90, -90), want));          // P0: Rz(90)·Rx(90)·Rz(−90)
  CHECK(same_frame(fixed_axis_angles(o, 0, 90, 0, 123), want));  // P1 Q123 J90
  CHECK(same_frame(two_vector_frame(o, Vec3(0, 0, -2), Vec3(5, 0, 0)), want));  // P3
  // P2: the origin, a point on +X (2 mm down), a point on the +Y side of the plane.
  CHECK(same_frame(three_point_frame(o, o + Vec3(0, 0, -2), o + Vec3(0, 4, -1)), want));
  // The third point on the −Y side turns the plane over.
  CHECK(near(three_point_frame(o, o + Vec3(0, 0, -2), o + Vec3(0, -4, -1)).rotation[2], -kX));
}

TEST_CASE("P2, P3 and the Hurco vectors rebuild random frames") {
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> length(-50, 50), positive(0.5, 50);
  for (int n = 0; n < 300; ++n) {
    Mat3 r = random_rotation(rng);
    Vec3 o(length(rng), length(rng), length(rng));
    Frame want{r, o};
    Vec3 x = r[0], y = r[1], z = r[2];
    CHECK(same_frame(
        three_point_frame(o, o + positive(rng) * x, o + length(rng) * x + positive(rng) * y), want,
        1e-9));
    CHECK(same_frame(two_vector_frame(o, positive(rng) * x, positive(rng) * z), want));
    CHECK(same_frame(hurco_vector_frame(o, positive(rng) * x, positive(rng) * y), want));
    // LinuxCNC's P3 gives I J K as a point on X and turns by Rz(R) on the left.
    Frame lc = linuxcnc_two_vector_frame(o, o + 3.0 * x, 25, z);
    CHECK(same_frame(lc, Frame{about(kZ, 25) * r, o}));
    Frame lc2 = linuxcnc_three_point_frame(Vec3(1, 2, 3), -15, o, o + x, o + x + y);
    CHECK(same_frame(lc2, Frame{about(kZ, -15) * r, Vec3(1, 2, 3)}));
  }
}

TEST_CASE("P3: vectors a few degrees from normal keep Z; farther is an error") {
  // X tilted 3° towards Z: inside Fanuc's 85°–95°, Z stays, X is made normal to it.
  Vec3 x = about(kY, -3) * kX;
  Frame f = two_vector_frame(Vec3(0), x, kZ);
  CHECK(same_rotation(f.rotation, Mat3(1.0)));
  std::string m = message_of([] { two_vector_frame(Vec3(0), about(kY, -10) * kX, kZ); });
  CHECK_MESSAGE(m.find("80") != std::string::npos, m);
  CHECK(message_of([] { two_vector_frame(Vec3(0), Vec3(0), kZ); }).find("zero vector") !=
        std::string::npos);
  CHECK_THROWS_AS(hurco_vector_frame(Vec3(0), kX, Vec3(0.1, 1, 0)), tridex::Error);
  CHECK_THROWS_AS(linuxcnc_two_vector_frame(Vec3(1, 1, 1), Vec3(1, 1, 1), 0, kZ), tridex::Error);
}

TEST_CASE("P2: coincident or collinear points are errors") {
  Vec3 p(1, 2, 3);
  CHECK(message_of([&] { three_point_frame(p, p, p + kY); }).find("first and second") !=
        std::string::npos);
  CHECK(message_of([&] { three_point_frame(p, p + kX, p); }).find("first and third") !=
        std::string::npos);
  CHECK(message_of([&] { three_point_frame(p, p + kX, p + 5.0 * kX); }).find("one line") !=
        std::string::npos);
  CHECK_THROWS_AS(three_point_frame(p, p + kX, Vec3(NAN, 0, 0)), tridex::Error);
}

TEST_CASE("G68.3: the frame from the tool axis") {
  // A vertical tool gives the work frame itself, turned by R about Z.
  CHECK(same_frame(tool_axis_frame(Vec3(1, 2, 3), kZ), Frame{Mat3(1.0), Vec3(1, 2, 3)}));
  CHECK(same_rotation(tool_axis_frame(Vec3(0), kZ, 30).rotation, about(kZ, 30)));
  std::mt19937 rng(9);
  for (int n = 0; n < 200; ++n) {
    Vec3 tool = random_rotation(rng) * kZ;
    if (std::abs(tool.y) > 0.999) continue;
    Frame f = tool_axis_frame(Vec3(0), tool, 20);
    Frame f0 = tool_axis_frame(Vec3(0), tool, 0);
    CHECK(near(f.rotation[2], tool));
    CHECK(std::abs(glm::dot(f0.rotation[0], kY)) < 1e-12);      // Xc normal to the reference
    CHECK(glm::dot(glm::cross(kY, tool), f0.rotation[0]) > 0);  // Xc = reference × Zc
    CHECK(glm::determinant(f.rotation) == doctest::Approx(1.0));
    CHECK(same_rotation(f.rotation, about(tool, 20) * f0.rotation));
  }
  CHECK(message_of([] { tool_axis_frame(Vec3(0), -kY); }).find("parallel") != std::string::npos);
}

TEST_CASE("G68.4: the incremental frame composes with the current one") {
  // Tilting 30° about X, then another 15° about the (tilted) X, is a 45° tilt.
  Frame current = fanuc_euler(Vec3(10, 0, 0), 0, 30, 0);
  Frame inc = fanuc_euler(Vec3(0, 0, 5), 0, 15, 0);
  Frame both = compose(current, inc);
  CHECK(same_rotation(both.rotation, fanuc_euler(Vec3(0), 0, 45, 0).rotation));
  CHECK(near(both.origin, Vec3(10, 0, 0) + about(kX, 30) * Vec3(0, 0, 5)));
  std::mt19937 rng(13);
  std::uniform_real_distribution<double> length(-50, 50);
  for (int n = 0; n < 100; ++n) {
    Frame a{random_rotation(rng), Vec3(length(rng), length(rng), length(rng))};
    Frame b{random_rotation(rng), Vec3(length(rng), length(rng), length(rng))};
    Vec3 p(length(rng), length(rng), length(rng));
    CHECK(near(compose(a, b).to_world(p), a.to_world(b.to_world(p)), 1e-9));
  }
  // The R word of Fanuc's forms turns about the frame's own Z.
  Frame t = rotated_about_own_z(current, 90);
  CHECK(near(t.rotation[2], current.rotation[2]));
  CHECK(near(t.rotation[0], current.rotation[1]));
}
