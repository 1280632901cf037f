#include <doctest/doctest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <random>

#include "reference.hpp"
#include "tridex/mill.hpp"

using namespace tridex;

namespace {

struct KindCase {
  Cutter cutter;
  test::RadiusFunction reference;
};

// A random cutter of kind `kind` (0..5 cycles through every kind).
KindCase random_cutter(int kind, std::mt19937& rng) {
  std::uniform_real_distribution<double> u(0, 1);
  double r = 0.6 + 2.5 * u(rng);
  switch (kind % 6) {
    case 0:
      return {Cutter::flat(r), test::flat_rho(r)};
    case 1:
      return {Cutter::ball(r), test::ball_rho(r)};
    case 2: {
      double c = r * (0.1 + 0.8 * u(rng));
      return {Cutter::bull_nose(r, c), test::bull_rho(r, c)};
    }
    case 3: {
      double a = 20 + 50 * u(rng);
      return {Cutter::cone(r, a), test::chamfer_rho(r, 0, a)};
    }
    case 4: {
      double tip = r * 0.5 * u(rng), a = 20 + 50 * u(rng);
      return {Cutter::chamfer(r, tip, a), test::chamfer_rho(r, tip, a)};
    }
    default: {
      double tip = r * (0.2 + 0.5 * u(rng)), a = 3 + 30 * u(rng);
      return {Cutter::tapered_ball(r, tip, a), test::tapered_ball_rho(r, tip, a)};
    }
  }
}

// Random moves over a grid spanning [0, 12] × [0, 10]: long and short, tilted, horizontal,
// vertical plunges, zero-length, and moves that leave the grid.
std::vector<Segment> random_segments(std::mt19937& rng, int count) {
  std::uniform_real_distribution<double> x(-3, 15), y(-3, 13), z(0, 4), u(0, 1);
  std::vector<Segment> s;
  for (int k = 0; k < count; ++k) {
    Vec3 a(x(rng), y(rng), z(rng)), b(x(rng), y(rng), z(rng));
    switch (k % 6) {
      case 0:
        b = Vec3(a.x, a.y, z(rng));
        break;  // plunge or retract
      case 1:
        b = a;
        break;  // zero length
      case 2:
        b.z = a.z;
        break;  // horizontal
      case 3:
        b = a + Vec3(0.5 * u(rng), 0.5 * u(rng), 0.3 * u(rng));
        break;  // short
      case 4:
        b = Vec3(a.x + 1e-9, a.y, z(rng));
        break;  // nearly vertical
      default:
        break;
    }
    s.push_back({a, b});
  }
  return s;
}

}  // namespace

TEST_CASE(
    "the ball end's vector form agrees with the scalar one, and its plane and across bound hold") {
  // BallLanes (one square root, kLanes points) against MoveGeometry (the closed form for t*):
  // heights, coverage, the supporting plane, and the quadratic rise across the move.
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> u(-1, 1);
  const double r = 1.7;
  const Cutter ball = Cutter::ball(r);
  int covered = 0, planes = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    Segment s{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng))};
    if (trial % 4 == 0) s.b.z = s.a.z;                                               // level
    if (trial % 7 == 0) s.b = s.a + Vec3(0.01 * u(rng), 0.01 * u(rng), 2 * u(rng));  // steep
    detail::MoveGeometry m(ball, s);
    if (m.vertical) continue;
    detail::BallLanes lanes(m);
    detail::DoubleN x{}, y{};
    for (int l = 0; l < detail::kLanes; ++l) x[l] = 3 * u(rng), y[l] = 3 * u(rng);
    detail::DoubleN z = lanes.at(x - lanes.ax, y - lanes.ay);
    detail::BallLanes::Plane p = lanes.plane_at(x - lanes.ax, y - lanes.ay);
    for (int l = 0; l < detail::kLanes; ++l) {
      const double expected = m.lowest_above(x[l], y[l]);
      CAPTURE(trial);
      if (!(expected < 1e300)) {
        // Not covered: the vector form agrees, unless the point is on the rim within rounding.
        const double rim_gap =
            std::sqrt(distance2_point_segment(Vec2(x[l], y[l]), Vec2(s.a), Vec2(s.b))) - r;
        CHECK((z[l] > 1e300 || std::abs(rim_gap) < 1e-9));
        continue;
      }
      ++covered;
      REQUIRE(z[l] == doctest::Approx(expected).epsilon(0).scale(1).epsilon(1e-9));
      REQUIRE(p.z[l] == doctest::Approx(expected).epsilon(0).scale(1).epsilon(1e-9));
      if (!p.has_plane[l]) continue;
      ++planes;
      // S(q) >= S(c) + g·(q − c) + ((q − c)·n)² / 2R around c.
      for (int k = 0; k < 20; ++k) {
        const double qx = x[l] + 0.5 * u(rng), qy = y[l] + 0.5 * u(rng);
        const double s_q = m.lowest_above(qx, qy);
        if (!(s_q < 1e300)) continue;
        const double across = (qx - x[l]) * lanes.nx + (qy - y[l]) * lanes.ny;
        const double bound = p.z[l] + p.gx[l] * (qx - x[l]) + p.gy[l] * (qy - y[l]) +
                             across * across * lanes.inv_diameter;
        REQUIRE(s_q >= bound - 1e-9);
      }
    }
  }
  CHECK(covered > 1000);
  CHECK(planes > 1000);
}

TEST_CASE("the flat end's and the bull nose's vector forms agree with the scalar ones") {
  // FlatLanes (closed form) and BullLanes (Newton on the corner's root equation) against
  // MoveGeometry::lowest (the flat end's interval ends, the bull nose's bracketed Newton on f'):
  // heights and coverage, on rising, falling, level and steep moves; and only the wanted lanes.
  std::mt19937 rng(43);
  std::uniform_real_distribution<double> u(-1, 1);
  int covered[2] = {0, 0};
  for (int trial = 0; trial < 6000; ++trial) {
    const double r = 1.7, corner = r * (0.5 + 0.45 * u(rng));
    const bool flat = trial % 3 == 0;
    const Cutter cutter = flat ? Cutter::flat(r) : Cutter::bull_nose(r, corner);
    Segment s{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng))};
    if (trial % 4 == 0) s.b.z = s.a.z;                                               // level
    if (trial % 7 == 0) s.b = s.a + Vec3(0.01 * u(rng), 0.01 * u(rng), 2 * u(rng));  // steep
    if (trial % 11 == 0) s.b = s.a + Vec3(2 * u(rng), 2 * u(rng), 1e-4 * u(rng));    // nearly level
    detail::MoveGeometry m(cutter, s);
    if (m.vertical) continue;
    detail::FlatLanes flat_lanes(m);
    detail::BullLanes bull_lanes(m);
    detail::DoubleN x{}, y{};
    detail::MaskN wanted{};
    for (int l = 0; l < detail::kLanes; ++l)
      x[l] = 3 * u(rng), y[l] = 3 * u(rng), wanted[l] = l % 5 == 4 ? 0 : -1;
    const detail::DoubleN z = flat ? flat_lanes.at(x - flat_lanes.ax, y - flat_lanes.ay)
                                   : bull_lanes.at(x - bull_lanes.ax, y - bull_lanes.ay, wanted);
    for (int l = 0; l < detail::kLanes; ++l) {
      CAPTURE(trial);
      CAPTURE(l);
      const double expected = m.lowest_above(x[l], y[l]);
      if (!flat && !wanted[l]) {
        CHECK(z[l] > 1e300);
        continue;
      }
      if (!(expected < 1e300)) {
        const double rim_gap =
            std::sqrt(distance2_point_segment(Vec2(x[l], y[l]), Vec2(s.a), Vec2(s.b))) - r;
        CHECK((z[l] > 1e300 || std::abs(rim_gap) < 1e-9));
        continue;
      }
      ++covered[flat ? 0 : 1];
      REQUIRE(z[l] == doctest::Approx(expected).epsilon(0).scale(1).epsilon(1e-9));
    }
  }
  CHECK(covered[0] > 250 * detail::kLanes);
  CHECK(covered[1] > 500 * detail::kLanes);
}

TEST_CASE("the other profiles' vector form agrees with the scalar one") {
  // ProfileLanes (a closed form per line or arc piece, its tests squared) against
  // MoveGeometry::lowest (convex_minimum): the cone (a kink on the axis), the chamfer (a kink
  // between its flat tip and its cone), the tapered ball (an arc on the axis, then a line) and a
  // polyline profile, on rising, falling, level, steep and nearly level moves; only wanted lanes.
  std::mt19937 rng(17);
  std::uniform_real_distribution<double> u(-1, 1);
  const std::array<Cutter, 4> cutters{
      Cutter::cone(1.7, 35), Cutter::chamfer(1.7, 0.6, 50), Cutter::tapered_ball(1.7, 0.8, 12),
      Cutter::from_profile({Vec2(0.4, 0), Vec2(0.9, 0.1), Vec2(1.4, 0.5), Vec2(1.7, 1.2)})};
  std::array<int, 4> covered{};
  std::array<int, 4> inside{};  // minimiser strictly inside the move
  for (int trial = 0; trial < 8000; ++trial) {
    const std::size_t kind = static_cast<std::size_t>(trial % 4);
    const Cutter& cutter = cutters[kind];
    REQUIRE(detail::ProfileLanes::closed_form(cutter));
    Segment s{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng))};
    if (trial % 5 == 0) s.b.z = s.a.z;                                               // level
    if (trial % 7 == 0) s.b = s.a + Vec3(0.01 * u(rng), 0.01 * u(rng), 2 * u(rng));  // steep
    if (trial % 11 == 0) s.b = s.a + Vec3(2 * u(rng), 2 * u(rng), 1e-4 * u(rng));    // nearly level
    detail::MoveGeometry m(cutter, s);
    if (m.vertical) continue;
    detail::ProfileLanes lanes(m);
    detail::DoubleN x{}, y{};
    detail::MaskN wanted{};
    for (int l = 0; l < detail::kLanes; ++l)
      x[l] = 3 * u(rng), y[l] = 3 * u(rng), wanted[l] = l % 5 == 4 ? 0 : -1;
    const detail::DoubleN z = lanes.at(x - lanes.ax, y - lanes.ay, wanted);
    for (int l = 0; l < detail::kLanes; ++l) {
      CAPTURE(trial);
      CAPTURE(l);
      if (!wanted[l]) {
        CHECK(z[l] > 1e300);
        continue;
      }
      const detail::MoveGeometry::Lowest expected = m.lowest(x[l], y[l]);
      if (!(expected.z < 1e300)) {
        const double rim_gap =
            std::sqrt(distance2_point_segment(Vec2(x[l], y[l]), Vec2(s.a), Vec2(s.b))) - 1.7;
        CHECK((z[l] > 1e300 || std::abs(rim_gap) < 1e-9));
        continue;
      }
      ++covered[kind];
      if (expected.t > 1e-9 && expected.t < 1 - 1e-9) ++inside[kind];
      REQUIRE(z[l] == doctest::Approx(expected.z).epsilon(0).scale(1).epsilon(1e-9));
    }
  }
  for (std::size_t kind = 0; kind < 4; ++kind) {
    CHECK(covered[kind] > 400 * detail::kLanes);
    CHECK(inside[kind] > 100 * detail::kLanes);
  }
}

TEST_CASE("the bull nose's root: extreme slopes and corners, and each point's value its own") {
  // BullLanes finds the corner's contact reach by Halley's method with a guarded step, each lane
  // stopping on its own. Against the scalar bracketed Newton (MoveGeometry::lowest) at slopes
  // from 1e-6 to 1e3 and corner radii from 0.01R to 0.99R; and every lane's height is the same,
  // to the bit, whether its neighbours are evaluated with it or not (so that the milled result
  // cannot depend on which points of a row a move is tested on).
  std::mt19937 rng(53);
  std::uniform_real_distribution<double> u(-1, 1), unit(0, 1);
  const double r = 2;
  int inside = 0;
  for (int trial = 0; trial < 3000; ++trial) {
    const double corner =
        r * std::array{0.01, 0.1, 0.5, 0.9, 0.99}[static_cast<std::size_t>(trial % 5)];
    const double slope = std::pow(10.0, -6 + 9 * unit(rng)), angle = 6.3 * unit(rng),
                 length = 0.2 + 3 * unit(rng);
    const Vec3 a(u(rng), u(rng), u(rng));
    const Segment s{a, a + Vec3(length * std::cos(angle), length * std::sin(angle),
                                (trial % 2 ? 1 : -1) * slope * length)};
    const Cutter cutter = Cutter::bull_nose(r, corner);
    detail::MoveGeometry m(cutter, s);
    detail::BullLanes bull(m);
    detail::DoubleN x{}, y{};
    detail::MaskN all{};
    for (int l = 0; l < detail::kLanes; ++l) {
      // Most points beside the move, where the minimum is inside it.
      const double along = unit(rng), across = r * u(rng);
      x[l] = s.a.x + along * (s.b.x - s.a.x) - across * std::sin(angle);
      y[l] = s.a.y + along * (s.b.y - s.a.y) + across * std::cos(angle);
      all[l] = -1;
    }
    const detail::DoubleN ux = x - bull.ax, uy = y - bull.ay;
    const detail::DoubleN together = bull.at(ux, uy, all);
    for (int l = 0; l < detail::kLanes; ++l) {
      CAPTURE(trial);
      CAPTURE(l);
      detail::MaskN one{};
      one[l] = -1;
      // The same point with no other lane wanted.
      REQUIRE(bull.at(ux, uy, one)[l] == together[l]);
      const detail::MoveGeometry::Lowest expected = m.lowest(x[l], y[l]);
      if (!(expected.z < 1e300)) continue;
      if (expected.t > 1e-9 && expected.t < 1 - 1e-9) ++inside;
      REQUIRE(together[l] == doctest::Approx(expected.z).epsilon(0).scale(1).epsilon(1e-9));
    }
  }
  CHECK(inside > 1000 * detail::kLanes);
}

TEST_CASE(
    "the vector supporting planes (flat end, bull nose, other profiles): the scalar ones, and "
    "below S everywhere") {
  // FlatLanes::plane_at, BullLanes::plane_at and ProfileLanes::plane_at against
  // MoveGeometry::lowest_with_plane, and S(q) ≥ S(c) + g·(q − c) at random q around c (S is
  // convex; the flat end's plane is its tangent at the end disc's entry edge, the others'
  // h'(d)/d·(q − C(t*))); no plane where the scalar form has none.
  std::mt19937 rng(47);
  std::uniform_real_distribution<double> u(-1, 1);
  const double r = 1.3;
  int missing = 0;  // lanes with no vector plane where the scalar form has one
  auto check = [&](const Cutter& cutter, auto make_lanes, int& planes, int& sloped) {
    for (int trial = 0; trial < 4000; ++trial) {
      Segment s{Vec3(u(rng), u(rng), u(rng)), Vec3(u(rng), u(rng), u(rng))};
      if (trial % 4 == 0) s.b.z = s.a.z;                                               // level
      if (trial % 7 == 0) s.b = s.a + Vec3(0.01 * u(rng), 0.01 * u(rng), 2 * u(rng));  // steep
      detail::MoveGeometry m(cutter, s);
      if (m.vertical) continue;
      const auto lanes = make_lanes(m);
      detail::DoubleN x{}, y{};
      for (int l = 0; l < detail::kLanes; ++l) x[l] = 2.5 * u(rng), y[l] = 2.5 * u(rng);
      const detail::FlatLanes::Plane p = lanes.plane_at(x - lanes.ax, y - lanes.ay);
      for (int l = 0; l < detail::kLanes; ++l) {
        CAPTURE(trial);
        CAPTURE(l);
        detail::MoveGeometry::Lowest centre;
        Vec2 gradient(0);
        const bool scalar_plane = m.lowest_with_plane(x[l], y[l], centre, gradient);
        if (!p.has_plane[l]) {
          // Only where the scalar form has none, or q is at a rim or kink up to rounding.
          if (scalar_plane) ++missing;
          continue;
        }
        ++planes;
        REQUIRE(scalar_plane);
        REQUIRE(p.z[l] == doctest::Approx(centre.z).epsilon(1e-9));
        REQUIRE(p.gx[l] == doctest::Approx(gradient.x).epsilon(1e-6).scale(1));
        REQUIRE(p.gy[l] == doctest::Approx(gradient.y).epsilon(1e-6).scale(1));
        if (p.gx[l] != 0 || p.gy[l] != 0) ++sloped;
        for (int k = 0; k < 20; ++k) {
          const double qx = x[l] + 0.5 * u(rng), qy = y[l] + 0.5 * u(rng);
          const double s_q = m.lowest_above(qx, qy);
          if (s_q < 1e300)
            REQUIRE(s_q >= p.z[l] + p.gx[l] * (qx - x[l]) + p.gy[l] * (qy - y[l]) - 1e-9);
        }
      }
    }
  };
  int planes = 0, sloped = 0;
  check(
      Cutter::flat(r), [](const detail::MoveGeometry& m) { return detail::FlatLanes(m); }, planes,
      sloped);
  CHECK(planes > 1000);
  CHECK(sloped > 300);
  int bull_planes = 0, bull_sloped = 0;
  check(
      Cutter::bull_nose(r, 0.6), [](const detail::MoveGeometry& m) { return detail::BullLanes(m); },
      bull_planes, bull_sloped);
  CHECK(bull_planes > 1000);
  CHECK(bull_sloped > 1000);
  const std::array<Cutter, 4> profiles{
      Cutter::cone(r, 35), Cutter::chamfer(r, 0.5, 50), Cutter::tapered_ball(r, 0.6, 12),
      Cutter::from_profile({Vec2(0.3, 0), Vec2(0.7, 0.1), Vec2(1.0, 0.4), Vec2(r, 0.9)})};
  for (const Cutter& cutter : profiles) {
    CAPTURE(cutter.name());
    REQUIRE(detail::ProfileLanes::closed_form(cutter));
    int profile_planes = 0, profile_sloped = 0;
    check(
        cutter, [](const detail::MoveGeometry& m) { return detail::ProfileLanes(m); },
        profile_planes, profile_sloped);
    CHECK(profile_planes > 1000);
    CHECK(profile_sloped > 1000);
  }
  CHECK(missing < 20);
}

TEST_CASE("milled heights are the exact lowest point of the swept cutter (every cutter kind)") {
  std::mt19937 rng(2026);
  for (int trial = 0; trial < 12; ++trial) {
    KindCase kind = random_cutter(trial, rng);
    CAPTURE(kind.cutter.name());
    CAPTURE(trial);
    ZMapGrid g;
    g.x0 = -0.13 * trial, g.y0 = 0.07 * trial, g.cell = 0.25, g.nx = 49, g.ny = 41;
    const float top = 5, empty = -0.5f;
    ZMap map(g, top, empty);
    std::vector<Segment> segments = random_segments(rng, 12);
    std::vector<CutMove> moves;
    for (const Segment& s : segments) moves.push_back({s, 0});
    std::vector<Cutter> cutters{kind.cutter};
    mill(map, cutters, moves, {.threads = 2});

    int lowered = 0;
    for (int j = 0; j < g.ny; ++j)
      for (int i = 0; i < g.nx; ++i) {
        double x = g.x(i), y = g.y(j);
        double exact = top, sampled = top;
        for (const Segment& s : segments) {
          exact = std::min(exact, test::refined_lowest(kind.reference, s, x, y));
          sampled = std::min(sampled, test::sampled_lowest(kind.reference, s, x, y, 64));
        }
        exact = std::max(exact, double(empty));
        sampled = std::max(sampled, double(empty));
        double got = map.height(i, j);
        CAPTURE(x);
        CAPTURE(y);
        // Never above any sampled position of the cutter (method-independent)...
        REQUIRE(got <= sampled + 1e-5);
        // ...and equal to the refined minimum within float resolution.
        REQUIRE(got == doctest::Approx(exact).epsilon(0).scale(1).epsilon(2e-5));
        if (got < top) ++lowered;
      }
    CHECK(lowered > 0);
  }
}

TEST_CASE("milling gives identical heights for any thread count and any move order") {
  std::mt19937 rng(99);
  std::vector<Cutter> cutters;
  for (int k = 0; k < 6; ++k) cutters.push_back(random_cutter(k, rng).cutter);
  ZMapGrid g;
  g.cell = 0.05, g.nx = 260, g.ny = 220;  // several tiles and work blocks
  std::vector<CutMove> moves;
  std::uniform_int_distribution<std::uint32_t> pick(0, 5);
  for (const Segment& s : random_segments(rng, 300)) moves.push_back({s, pick(rng)});

  ZMap reference(g, 5, -1);
  mill(reference, cutters, moves, {.threads = 1});
  for (unsigned threads : {2u, 3u, 8u}) {
    ZMap map(g, 5, -1);
    mill(map, cutters, moves, {.threads = threads});
    CHECK(map.heights == reference.heights);
  }
  std::shuffle(moves.begin(), moves.end(), rng);
  ZMap shuffled(g, 5, -1);
  mill(shuffled, cutters, moves, {.threads = 2});
  CHECK(shuffled.heights == reference.heights);
  // Milling in two halves is the same as milling at once.
  ZMap halves(g, 5, -1);
  std::span<const CutMove> all(moves);
  mill(halves, cutters, all.first(moves.size() / 2));
  mill(halves, cutters, all.subspan(moves.size() / 2));
  CHECK(halves.heights == reference.heights);
}

TEST_CASE("a tilted Z-map: a flat end plunge in the frame leaves a flat-bottomed hole") {
  Frame f = Frame::from_axis(Vec3(1, 0, 0));
  ZMap map = ZMap::from_box(f, Aabb{Vec3(0), Vec3(10, 10, 10)}, 0.1);
  Vec3 centre_local = f.to_local(Vec3(10, 5, 5));
  std::vector<Cutter> cutters{Cutter::flat(2)};
  std::vector<CutMove> moves{
      {Segment{centre_local + Vec3(0, 0, 5), centre_local - Vec3(0, 0, 3)}, 0}};
  mill(map, cutters, moves);
  int i = static_cast<int>(std::lround((centre_local.x - map.grid.x0) / map.grid.cell));
  int j = static_cast<int>(std::lround((centre_local.y - map.grid.y0) / map.grid.cell));
  CHECK(map.height(i, j) == doctest::Approx(centre_local.z - 3).epsilon(1e-6));
  CHECK(map.height(i + 15, j) == doctest::Approx(centre_local.z - 3).epsilon(1e-6));
  CHECK(map.height(i + 25, j) == doctest::Approx(centre_local.z).epsilon(1e-6));
}

TEST_CASE("bad moves are rejected before anything is milled") {
  ZMapGrid g;
  g.nx = 10, g.ny = 10;
  ZMap map(g, 1, -1);
  std::vector<Cutter> cutters{Cutter::ball(1)};
  std::vector<CutMove> nan_move{{Segment{Vec3(1, 1, 0), Vec3(NAN, 1, 0)}, 0}};
  std::vector<CutMove> inf_move{{Segment{Vec3(1, 1, -INFINITY), Vec3(1, 1, 0)}, 0}};
  std::vector<CutMove> bad_cutter{{Segment{Vec3(1, 1, 0), Vec3(2, 1, 0)}, 0},
                                  {Segment{Vec3(1, 1, 0), Vec3(2, 1, 0)}, 3}};
  CHECK_THROWS_WITH_AS(mill(map, cutters, nan_move), doctest::Contains("move 0"), Error);
  CHECK_THROWS_AS(mill(map, cutters, inf_move), Error);
  CHECK_THROWS_WITH_AS(mill(map, cutters, bad_cutter), doctest::Contains("cutter 3"), Error);
  CHECK(std::all_of(map.heights.begin(), map.heights.end(), [](float h) { return h == 1; }));
  // Far-away and enormous coordinates are fine: they simply miss the grid.
  std::vector<CutMove> far{{Segment{Vec3(1e300, 1e300, 0), Vec3(-1e300, 1e300, 0)}, 0}};
  mill(map, cutters, far);
  CHECK(std::all_of(map.heights.begin(), map.heights.end(), [](float h) { return h == 1; }));
  // Cuts below the stock stop at the empty height.
  std::vector<CutMove> deep{{Segment{Vec3(4, 4, -100), Vec3(4, 4, -100)}, 0}};
  mill(map, cutters, deep);
  CHECK(map.is_empty(4, 4));
  CHECK(map.height(4, 4) == -1);
}

// A raster over a wavy surface, and a plunge: many moves reach every tile, so most are skipped
// by the tile, row and plane bounds.
std::vector<Segment> dense_raster() {
  auto wavy = [](double x, double y) {
    return 2 + 0.8 * std::sin(x / 1.3) * std::cos(y / 1.7) + 0.05 * x;
  };
  std::vector<Segment> path;
  for (int line = 0; line <= 24; ++line) {
    double y = line * 0.25;
    for (int step = 0; step < 24; ++step) {
      double x0 = (line % 2 ? 24 - step : step) * 0.25, x1 = x0 + (line % 2 ? -0.25 : 0.25);
      path.push_back({Vec3(x0, y, wavy(x0, y)), Vec3(x1, y, wavy(x1, y))});
    }
  }
  path.push_back({Vec3(3, 3, 6), Vec3(3, 3, 1.2)});
  return path;
}

TEST_CASE("tile skipping never skips a point a move lowers (dense raster, every cutter kind)") {
  // Compared with evaluating every move at every point.
  std::mt19937 rng(5);
  const std::vector<Segment> path = dense_raster();
  for (int kind = 0; kind < 6; ++kind) {
    Cutter cutter = random_cutter(kind, rng).cutter;
    CAPTURE(cutter.name());
    ZMapGrid g;
    g.x0 = -0.5, g.y0 = -0.5, g.cell = 0.02, g.nx = 350, g.ny = 350;
    ZMap map(g, 4, -1);
    std::vector<Cutter> cutters{cutter};
    std::vector<CutMove> moves;
    for (const Segment& s : path) moves.push_back({s, 0});
    mill(map, cutters, moves);
    std::vector<detail::MoveGeometry> geometry;
    for (const Segment& s : path) geometry.emplace_back(cutter, s);
    int mismatches = 0;
    for (int j = 0; j < g.ny; j += 3)
      for (int i = 0; i < g.nx; i += 3) {
        double expected = 4;
        for (const detail::MoveGeometry& m : geometry)
          expected = std::min(expected, m.lowest_above(g.x(i), g.y(j)));
        expected = std::max(expected, -1.0);
        if (std::abs(map.height(i, j) - expected) > 1e-5) ++mismatches;
      }
    CHECK(mismatches == 0);
  }
}

TEST_CASE("moves of several cutters in one call: each point at the lowest of them all") {
  // The ball end's vector path and the scalar path of the others share tiles and bounds.
  const std::vector<Segment> path = dense_raster();
  std::vector<Cutter> cutters{Cutter::ball(0.8), Cutter::bull_nose(1.1, 0.3), Cutter::flat(0.6),
                              Cutter::ball(1.7)};
  ZMapGrid g;
  g.x0 = -0.5, g.y0 = -0.5, g.cell = 0.02, g.nx = 350, g.ny = 350;
  ZMap map(g, 4, -1);
  std::vector<CutMove> moves;
  for (std::size_t k = 0; k < path.size(); ++k) {
    const Vec3 lift(0, 0,
                    0.1 * static_cast<double>(k % 3));  // so that every cutter shows somewhere
    moves.push_back({Segment{path[k].a + lift, path[k].b + lift},
                     static_cast<std::uint32_t>(k % cutters.size())});
  }
  mill(map, cutters, moves);
  int mismatches = 0;
  for (int j = 0; j < g.ny; j += 2)
    for (int i = 0; i < g.nx; i += 2) {
      double expected = 4;
      for (const CutMove& m : moves)
        expected = std::min(
            expected, detail::MoveGeometry(cutters[m.cutter], m.tip).lowest_above(g.x(i), g.y(j)));
      expected = std::max(expected, -1.0);
      if (std::abs(map.height(i, j) - expected) > 1e-5) ++mismatches;
    }
  CHECK(mismatches == 0);
}

TEST_CASE("cut_depth: how deep a move would cut, equal to what milling it removes") {
  std::mt19937 rng(17);
  int cutting = 0;
  for (int trial = 0; trial < 24; ++trial) {
    Cutter cutter = random_cutter(trial, rng).cutter;
    ZMapGrid g;
    g.cell = 0.1, g.nx = 120, g.ny = 100;
    ZMap map(g, 3, -1);
    std::vector<Cutter> cutters{cutter};
    std::vector<Segment> segments = random_segments(rng, 2);
    std::vector<CutMove> first{{segments[0], 0}};
    mill(map, cutters, first);
    CutDepth predicted = cut_depth(map, cutter, segments[1]);
    ZMap after = map;
    std::vector<CutMove> second{{segments[1], 0}};
    mill(after, cutters, second);
    double removed = 0;
    for (std::size_t p = 0; p < map.heights.size(); ++p)
      if (!map.is_empty(static_cast<int>(p % 120), static_cast<int>(p / 120)))
        removed = std::max(removed, double(map.heights[p] - after.heights[p]));
    CAPTURE(trial);
    if (predicted.depth > 1e-4 && after.height(predicted.i, predicted.j) > after.empty_height) {
      CHECK(removed == doctest::Approx(predicted.depth).epsilon(1e-4));
      ++cutting;
    } else {
      CHECK(removed <= std::max(0.0, predicted.depth) + 1e-4);
    }
  }
  CHECK(cutting >= 6);
  CHECK(cut_depth(ZMap(ZMapGrid{Frame{}, 0, 0, 1, 4, 4}, 0, -1), Cutter::ball(1),
                  Segment{Vec3(100, 100, 0), Vec3(101, 100, 0)})
            .i == -1);
}

TEST_CASE(
    "mixed cutters: random moves of every kind in one call, and roughing below or above a finish") {
  // Each point at the lowest of every move, evaluated everywhere (no bounds): the vector forms,
  // the scalar path and the tile, row and plane bounds of a tile whose first cut was any cutter.
  std::mt19937 rng(77);
  std::vector<Cutter> cutters;
  for (int k = 0; k < 6; ++k) cutters.push_back(random_cutter(k, rng).cutter);
  std::vector<CutMove> random_moves;
  std::uniform_int_distribution<std::uint32_t> pick(0, 5);
  for (const Segment& s : random_segments(rng, 240)) random_moves.push_back({s, pick(rng)});
  // A flat end (1) or bull nose (2) raster 0.3 below or 0.2 above a ball end (0) raster.
  const std::vector<Segment> path = dense_raster();
  std::vector<Cutter> raster_cutters{Cutter::ball(0.7), Cutter::flat(1.2),
                                     Cutter::bull_nose(1.1, 0.35)};
  std::vector<std::vector<CutMove>> raster_cases;
  for (std::uint32_t rough : {1u, 2u})
    for (double lift : {-0.3, 0.2}) {
      std::vector<CutMove> moves;
      for (std::size_t k = 0; k < path.size(); ++k) {
        moves.push_back({path[k], 0});
        if (k % 2 == 0)
          moves.push_back(
              {Segment{path[k].a + Vec3(0, 0, lift), path[k].b + Vec3(0, 0, lift)}, rough});
      }
      raster_cases.push_back(moves);
    }
  auto check = [](const std::vector<Cutter>& kinds, const std::vector<CutMove>& moves) {
    ZMapGrid g;
    g.x0 = -0.5, g.y0 = -0.5, g.cell = 0.03, g.nx = 230, g.ny = 230;
    ZMap map(g, 4, -1);
    mill(map, kinds, moves, {.threads = 2});
    std::vector<detail::MoveGeometry> geometry;
    for (const CutMove& m : moves) geometry.emplace_back(kinds[m.cutter], m.tip);
    int mismatches = 0, lowered = 0;
    for (int j = 0; j < g.ny; j += 2)
      for (int i = 0; i < g.nx; i += 2) {
        double expected = 4;
        for (const detail::MoveGeometry& m : geometry)
          expected = std::min(expected, m.lowest_above(g.x(i), g.y(j)));
        expected = std::max(expected, -1.0);
        if (std::abs(map.height(i, j) - expected) > 1e-5) ++mismatches;
        if (expected < 4) ++lowered;
      }
    CHECK(mismatches == 0);
    CHECK(lowered > 1000);
  };
  check(cutters, random_moves);
  for (const std::vector<CutMove>& moves : raster_cases) check(raster_cutters, moves);
}

TEST_CASE("sort_by_key orders as std::sort does the (value, index) pairs") {
  // Ties, both zeros, negatives, infinities and values one ulp apart, in random order.
  std::mt19937 rng(37);
  const std::vector<double> pool{-std::numeric_limits<double>::infinity(),
                                 -3.5,
                                 -1e-300,
                                 -0.0,
                                 0.0,
                                 1e-300,
                                 2.0,
                                 std::nextafter(2.0, 3.0),
                                 12.25,
                                 1e300,
                                 std::numeric_limits<double>::infinity()};
  for (int trial = 0; trial < 20; ++trial) {
    std::uniform_int_distribution<std::size_t> pick(0, pool.size() - 1);
    const std::size_t n = trial == 0 ? 0 : 1 + rng() % 3000;
    std::vector<std::pair<double, std::uint32_t>> pairs;
    std::vector<detail::SortKey> keys, spare;
    for (std::size_t k = 0; k < n; ++k) {
      const double v = trial % 2 ? pool[pick(rng)] : std::ldexp(double(rng() % 1000), -7) - 3;
      pairs.emplace_back(v, static_cast<std::uint32_t>(k));
      keys.push_back({detail::order_key(v), static_cast<std::uint32_t>(k)});
    }
    std::sort(pairs.begin(), pairs.end());
    detail::sort_by_key(keys, spare);
    REQUIRE(keys.size() == n);
    for (std::size_t k = 0; k < n; ++k) CHECK(keys[k].index == pairs[k].second);
  }
}

TEST_CASE("many moves, binned on the threads in chunks: each point at the lowest of them all") {
  // Over 65,536 moves (bin_moves' chunks hold 32,768), spread over the grid in program order so
  // that each work block gets moves from several chunks; some miss the grid.
  std::vector<Cutter> cutters{Cutter::ball(0.4), Cutter::flat(0.5), Cutter::bull_nose(0.6, 0.2)};
  ZMapGrid g;
  g.x0 = -0.3, g.y0 = -0.2, g.cell = 0.05, g.nx = 330, g.ny = 290;
  std::mt19937 rng(41);
  std::uniform_real_distribution<double> x(-1, 17.5), y(-1, 15.5), z(0.5, 3), step(-0.08, 0.08);
  std::vector<CutMove> moves;
  for (std::uint32_t k = 0; k < 70000; ++k) {
    const Vec3 a(x(rng), y(rng), z(rng));
    moves.push_back({Segment{a, a + Vec3(step(rng), step(rng), 0.1 * step(rng))}, k % 3});
  }
  ZMap one(g, 4, -1), two(g, 4, -1), three(g, 4, -1);
  mill(one, cutters, moves, {.threads = 1});
  mill(two, cutters, moves, {.threads = 2});
  mill(three, cutters, moves, {.threads = 3});
  CHECK(two.heights == one.heights);
  CHECK(three.heights == one.heights);
  int mismatches = 0, lowered = 0;
  for (int j = 0; j < g.ny; j += 13)
    for (int i = 0; i < g.nx; i += 11) {
      double expected = 4;
      for (const CutMove& m : moves) {
        const double reach = cutters[m.cutter].radius() + 0.2;
        if (std::abs(m.tip.a.x - g.x(i)) > reach || std::abs(m.tip.a.y - g.y(j)) > reach) continue;
        expected = std::min(
            expected, detail::MoveGeometry(cutters[m.cutter], m.tip).lowest_above(g.x(i), g.y(j)));
      }
      expected = std::max(expected, -1.0);
      if (std::abs(one.height(i, j) - expected) > 1e-5) ++mismatches;
      if (expected < 4) ++lowered;
    }
  CHECK(mismatches == 0);
  CHECK(lowered > 100);
}
