// Simultaneous 5-axis sweeps on the triple dexel (sweep.hpp): the exact oracle on random turning
// moves of every cutter shape, the analytic C-turning groove, and thread-count identity.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include "tridex/sweep.hpp"

namespace test_sweep {

using namespace tridex;

// A turning move: tip from a to b along a bowed path, axis turning from one direction to another
// (a rotation about a fixed unit vector), with certified speed bounds.
struct TurningMove {
  Vec3 a{0.0}, b{0.0}, bow{0.0};
  Vec3 axis0{0, 0, 1}, turn_about{1, 0, 0};
  double turn = 0;  // radians over the move
  bool straight = false;
  ToolPose at(double s) const {
    const Vec3 tip = a + s * (b - a) + (straight ? 0.0 : 4 * s * (1 - s)) * bow;
    const double t = turn * s, c = std::cos(t), sn = std::sin(t);
    const Vec3& k = turn_about;
    const Vec3 axis = axis0 * c + glm::cross(k, axis0) * sn + k * glm::dot(k, axis0) * (1 - c);
    return {tip, glm::normalize(axis)};
  }
  PoseBounds bounds() const {
    // |tip'| ≤ |b − a| + 4|bow| (|d/ds 4s(1−s)| ≤ 4); |axis'| = turn·|k × axis| ≤ turn.
    return {glm::length(b - a) + (straight ? 0.0 : 4 * glm::length(bow)), std::abs(turn), straight};
  }
};

std::vector<SweepCutter> shapes() {
  return {{Cutter::ball(1.5), 5},
          {Cutter::flat(1.5), 5},
          {Cutter::bull_nose(1.5, 0.5), 5},
          {Cutter::cone(1.5, 30), 5},
          {Cutter::chamfer(1.5, 0.5, 45), 5}};
}

// sweep_ray subtracts each step's interval in place (detail::subtract_one); it must give what
// the general subtract_ray gives, on rays of 0 to 4 spans and cuts snapped to a coarse grid so
// that ends coincide, touch and nest, and empty (point) cuts occur.
TEST_CASE("sweep: in-place subtraction of one interval equals subtract_ray") {
  std::mt19937 rng(34);
  std::uniform_int_distribution<int> coord(0, 12), count(0, 4);
  for (int trial = 0; trial < 20000; ++trial) {
    std::vector<int> ends;
    for (int k = 2 * count(rng); k > 0; --k) ends.push_back(coord(rng));
    std::sort(ends.begin(), ends.end());
    ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
    if (ends.size() % 2) ends.pop_back();
    std::vector<DexelInterval> ray;
    for (std::size_t k = 0; k < ends.size(); k += 2)
      ray.push_back({static_cast<float>(ends[k]), static_cast<float>(ends[k + 1])});
    int a = coord(rng), b = coord(rng);
    if (a > b) std::swap(a, b);
    const DexelInterval cut{static_cast<float>(a), static_cast<float>(b)};
    std::vector<DexelInterval> expected, got = ray;
    detail::subtract_ray(ray, {&cut, 1}, expected);
    detail::subtract_one(got, cut);
    REQUIRE(got.size() == expected.size());
    for (std::size_t k = 0; k < got.size(); ++k) {
      CHECK(got[k].enter == expected[k].enter);
      CHECK(got[k].exit == expected[k].exit);
    }
  }
}

TEST_CASE("sweep: the meridian distance is exact on a flat end and a ball") {
  SweepCutter flat{Cutter::flat(2), 6};
  CHECK(flat.distance(Vec3(0), Vec3(0, 0, 1), Vec3(0, 0, -1)) == doctest::Approx(1));
  CHECK(flat.distance(Vec3(0), Vec3(0, 0, 1), Vec3(3, 0, 3)) == doctest::Approx(1));
  CHECK(flat.distance(Vec3(0), Vec3(0, 0, 1), Vec3(0, 0, 1)) == doctest::Approx(-1));
  CHECK(flat.distance(Vec3(0), Vec3(0, 0, 1), Vec3(0, 0, 7)) == doctest::Approx(1));
  SweepCutter ball{Cutter::ball(2), 6};
  CHECK(ball.distance(Vec3(0), Vec3(1, 0, 0), Vec3(2, 3, 0)) == doctest::Approx(1));
  CHECK(ball.distance(Vec3(0), Vec3(1, 0, 0), Vec3(-1, 0, 0)) == doctest::Approx(1));
  CHECK(ball.distance(Vec3(0), Vec3(0, 0, 1), Vec3(0, 0, 1)) == doctest::Approx(-1));
}

// Material is removed by the true moving cutter iff min over t of the signed distance is ≤ 0.
// The oracle samples t finely; with body points moving at most vmax per unit t, the sampled
// minimum exceeds the true one by at most vmax·dt/2. A dexel sample may differ from the oracle
// only where the true minimum lies within the band (plus the precision and float rounding).
// Returns the samples wrong beyond that; `checked` counts those compared (every third ray from
// `offset`, samples every 0.23 mm).
long long oracle_wrong(const TurningMove& m, const SweepCutter& cutter, const SweepPlan& plan,
                       const TripleDexel& d, const Aabb& stock, int offset, long long& checked) {
  const int oracle_steps = 200;
  const double vmax = m.bounds().tip_speed + cutter.reach() * m.bounds().turn_rate;
  const double slack = vmax / oracle_steps / 2 + 1e-3;
  long long wrong = 0;
  for (int a = 0; a < 3; ++a) {
    const DexelGrid& g = d.grids[a];
    const int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
    for (int iv = offset % 3; iv < g.nv; iv += 3)
      for (int iu = (offset / 3) % 3; iu < g.nu; iu += 3) {
        auto ray = g.ray(iu, iv);
        for (double x = stock.min[a] + 0.013; x < stock.max[a]; x += 0.23) {
          Vec3 p = d.origin;
          p[u] += d.spacing * iu, p[v] += d.spacing * iv, p[a] = x;
          if (!stock.contains(p)) continue;
          bool material = false;
          for (const DexelInterval& s : ray) material |= s.enter <= x && x <= s.exit;
          double oracle = 1e300;
          for (int k = 0; k <= oracle_steps; ++k) {
            const ToolPose pose = m.at(double(k) / oracle_steps);
            oracle = std::min(oracle, cutter.distance(pose.tip, pose.axis, p));
          }
          ++checked;
          if (material && oracle < -(plan.band + slack)) ++wrong;
          if (!material && oracle - slack > plan.band + 1e-3) ++wrong;
        }
      }
  }
  return wrong;
}

TurningMove random_move(std::mt19937& rng, bool straight, double depth) {
  std::uniform_real_distribution<double> unit(-1, 1);
  TurningMove m;
  m.a = Vec3(unit(rng), unit(rng), unit(rng)) * 2.0 - Vec3(0, 0, depth);
  m.b = Vec3(unit(rng), unit(rng), unit(rng)) * 2.0 - Vec3(0, 0, depth);
  m.bow = Vec3(unit(rng), unit(rng), unit(rng)) * 0.6;
  m.straight = straight;
  m.axis0 = glm::normalize(Vec3(unit(rng), unit(rng), 2.0));
  m.turn_about = glm::normalize(Vec3(unit(rng), unit(rng), unit(rng)));
  m.turn = 0.8 * unit(rng);
  return m;
}

TEST_CASE("sweep: zero dexel samples wrong by more than the band, random turning moves") {
  std::mt19937 rng(34);
  const Aabb stock{Vec3(-4, -4, -4), Vec3(4, 4, 4)};
  const DexelLattice lattice = DexelLattice::covering(stock, 0.4);
  const std::vector<SweepCutter> cutters = shapes();
  long long checked = 0, wrong = 0;
  for (std::uint32_t c = 0; c < cutters.size(); ++c) {
    const int trial = static_cast<int>(c % 2);
    const TurningMove m = random_move(rng, trial == 1, 1);
    const double tolerance = lattice.spacing / 10;
    const SweepPlan plan =
        plan_sweep([&](double s) { return m.at(s); }, m.bounds(), cutters[c].reach(), tolerance, c);
    REQUIRE(plan.band <= tolerance);
    TripleDexel d = TripleDexel::box(lattice, stock);
    sweep_remove(d, cutters, plan.steps, 2);
    wrong += oracle_wrong(m, cutters[c], plan, d, stock, trial + 3 * static_cast<int>(c), checked);
  }
  CHECK(checked > 2500);
  CHECK(wrong == 0);
}

// The pipeline's planner: tip and shank apart, a ball along its centre's path, closed-form bands
// under a straight tip, sub-steps whose grown box holds no material dropped. The stock's top is
// near the tips, so the shanks' sub-steps are often dropped; the oracle still finds no sample
// wrong beyond the band, for every cutter shape (the bull nose searched and as chords), straight
// and bowed tips.
TEST_CASE("sweep: plan_sweep_parts, zero samples wrong beyond the band") {
  std::mt19937 rng(3434);
  const Aabb stock{Vec3(-4, -4, -4), Vec3(4, 4, 0.5)};
  const DexelLattice lattice = DexelLattice::covering(stock, 0.4);
  std::vector<SweepCutter> cutters = shapes();
  cutters.push_back({Cutter::tapered_ball(1.5, 0.5, 10), 5});
  cutters.push_back({Cutter::bull_nose(1.5, 0.5), 5, 0.01});  // the torus as chords
  long long checked = 0, wrong = 0, dropped = 0;
  for (std::uint32_t c = 0; c < cutters.size(); ++c)
    for (int trial = 0; trial < 2; ++trial) {
      const TurningMove m = random_move(rng, trial == 1, 0.5);
      const double tolerance = lattice.spacing / 10;
      TripleDexel d = TripleDexel::box(lattice, stock);
      const SweepMaterial material(d);
      const SweepShape shape = sweep_shape(cutters[c]);
      const SweepPlan plan =
          plan_sweep_parts([&](double s) { return m.at(s); }, m.bounds(), cutters[c], shape,
                           tolerance, c, [&](const Aabb& box) { return material.may_touch(box); });
      REQUIRE(plan.band <= tolerance);
      const SweepPlan kept_all =
          plan_sweep_parts([&](double s) { return m.at(s); }, m.bounds(), cutters[c], shape,
                           tolerance, c, [](const Aabb&) { return true; });
      dropped += static_cast<long long>(kept_all.steps.size() - plan.steps.size());
      sweep_remove(d, cutters, plan.steps, 2);
      wrong +=
          oracle_wrong(m, cutters[c], plan, d, stock, trial + 2 * static_cast<int>(c), checked);
    }
  CHECK(checked > 5000);
  CHECK(dropped > 0);
  CHECK(wrong == 0);
}

// A flat end of radius R standing parallel to C at radius r, plunged d into the stock, while C
// turns by φ: the part sees the tool run an arc, removing d(2φrR + πR²).
TEST_CASE("sweep: the C-turning groove's volume, and the same dexels on 1, 2 and 8 threads") {
  const double radius = 3, arc = 12, depth = 2, phi = std::numbers::pi / 2;
  auto pose = [&](double s) {
    return ToolPose{Vec3(arc * std::cos(phi * s), arc * std::sin(phi * s), -depth), Vec3(0, 0, 1)};
  };
  const std::vector<SweepCutter> cutters{{Cutter::flat(radius), 8}};
  const double spacing = 0.3;
  const SweepPlan plan =
      plan_sweep(pose, PoseBounds{arc * phi, 0, false}, cutters[0].reach(), spacing / 10);
  CHECK(plan.band <= spacing / 10);
  CHECK(plan.steps.size() <= 128);
  const Aabb stock{Vec3(-18, -18, -6), Vec3(18, 18, 0)};
  const DexelLattice lattice = DexelLattice::covering(stock, spacing);
  std::vector<TripleDexel> results;
  for (unsigned threads : {1u, 2u, 8u}) {
    TripleDexel d = TripleDexel::box(lattice, stock);
    // The Z rays run along the tool: each measures the depth exactly, so their sum is the
    // groove's area by the midpoint rule, within about its outline's length times the spacing
    // (the X and Y rays also round the depth to their rows: O(h) too, larger here).
    auto z_length = [](const TripleDexel& t) {
      double sum = 0;
      for (const DexelInterval& s : t.grids[2].intervals) sum += double(s.exit) - double(s.enter);
      return sum * t.spacing * t.spacing;
    };
    const double before = z_length(d);
    sweep_remove(d, cutters, plan.steps, threads);
    if (threads == 1) {
      const double expected = depth * (2 * phi * arc * radius + std::numbers::pi * radius * radius);
      const double removed = before - z_length(d);
      const double outline = 2 * phi * arc + 2 * std::numbers::pi * radius;
      INFO("removed " << removed << " expected " << expected);
      CHECK(std::abs(removed - expected) < 0.5 * outline * spacing * depth);
      CHECK(std::abs(removed - expected) < 0.01 * expected);
    }
    results.push_back(std::move(d));
  }
  for (const TripleDexel& d : results)
    for (int a = 0; a < 3; ++a) {
      CHECK(d.grids[a].offsets == results[0].grids[a].offsets);
      CHECK(std::equal(d.grids[a].intervals.begin(), d.grids[a].intervals.end(),
                       results[0].grids[a].intervals.begin(), results[0].grids[a].intervals.end(),
                       [](const DexelInterval& x, const DexelInterval& y) {
                         return x.enter == y.enter && x.exit == y.exit;
                       }));
    }
}

// sweep_remove skips the pieces of a part that cannot widen a ray's interval or meet its material
// (sweep_step_interval) and subtracts in place: brute force does neither. For every step, on
// every ray of the three grids, the hull of all its pieces' intervals is subtracted by
// subtract_ray, in step order. Random turning moves of every closed-form cutter (the bull nose
// as chords), planned by plan_sweep_parts (tips and shanks), deep enough for the shanks to cut,
// and the same moves again over the material the first pass left.
// The intervals of `f` not bit-identical to `b`'s, both of one lattice with the same rays' counts.
long long differing_intervals(const TripleDexel& f, const TripleDexel& b) {
  long long differ = 0;
  for (std::size_t a = 0; a < 3; ++a) {
    const DexelGrid &fa = f.grids[a], &ba = b.grids[a];
    REQUIRE(fa.offsets == ba.offsets);
    for (std::size_t k = 0; k < fa.intervals.size(); ++k)
      differ += fa.intervals[k].enter != ba.intervals[k].enter ||
                fa.intervals[k].exit != ba.intervals[k].exit;
  }
  return differ;
}

TEST_CASE("sweep: skipping pieces gives the brute-force dexels") {
  std::mt19937 rng(3435);
  const Aabb stock{Vec3(-4, -4, -4), Vec3(4, 4, 1)};
  const DexelLattice lattice = DexelLattice::covering(stock, 0.25);
  const std::vector<SweepCutter> cutters{{Cutter::bull_nose(1.5, 0.5), 5, 0.005},
                                         {Cutter::flat(1.5), 5},
                                         {Cutter::cone(1.5, 30), 5},
                                         {Cutter::chamfer(1.5, 0.5, 45), 5},
                                         {Cutter::tapered_ball(1.5, 0.5, 10), 5},
                                         {Cutter::ball(1.5), 5}};
  std::vector<SweepShape> shapes;
  for (const SweepCutter& c : cutters) shapes.push_back(sweep_shape(c));
  std::vector<SweepStep> steps;
  for (std::uint32_t c = 0; c < cutters.size(); ++c)
    for (int trial = 0; trial < 2; ++trial) {
      const TurningMove m = random_move(rng, trial == 1, 1.5);
      const SweepPlan plan =
          plan_sweep_parts([&](double s) { return m.at(s); }, m.bounds(), cutters[c], shapes[c],
                           0.05, c, [](const Aabb&) { return true; });
      steps.insert(steps.end(), plan.steps.begin(), plan.steps.end());
    }
  TripleDexel fast = TripleDexel::box(lattice, stock), brute = fast;
  long long cut_rays = 0;
  for (int pass = 0; pass < 2; ++pass) {
    sweep_remove(fast, cutters, steps, 2);
    for (int a = 0; a < 3; ++a) {
      DexelGrid& g = brute.grids[static_cast<std::size_t>(a)];
      const int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
      std::vector<DexelInterval> intervals;
      std::vector<std::uint32_t> offsets{0};
      for (int iv = 0; iv < g.nv; ++iv)
        for (int iu = 0; iu < g.nu; ++iu) {
          const auto ray = g.ray(iu, iv);
          std::vector<DexelInterval> current(ray.begin(), ray.end()), next;
          Vec3 point = brute.origin;
          point[u] += brute.spacing * iu, point[v] += brute.spacing * iv;
          for (const SweepStep& step : steps) {
            const SweepPartShape& part =
                shapes[step.cutter].parts[static_cast<std::size_t>(step.part)];
            REQUIRE(part.closed);
            std::optional<std::pair<double, double>> hull;
            for (const detail::SweepPiece& piece : part.pieces) {
              const auto cut = detail::sweep_piece_interval(piece, step.from, step.to - step.from,
                                                            step.axis, point, a);
              if (cut)
                hull = hull ? std::pair{std::min(hull->first, cut->first),
                                        std::max(hull->second, cut->second)}
                            : *cut;
            }
            if (!hull) continue;
            const DexelInterval removed{static_cast<float>(hull->first),
                                        static_cast<float>(hull->second)};
            next.clear();
            detail::subtract_ray(current, {&removed, 1}, next);
            current.swap(next);
          }
          cut_rays += current.size() != ray.size();
          intervals.insert(intervals.end(), current.begin(), current.end());
          offsets.push_back(static_cast<std::uint32_t>(intervals.size()));
        }
      g.intervals = std::move(intervals);
      g.offsets = std::move(offsets);
    }
    CHECK(differing_intervals(fast, brute) == 0);
  }
  CHECK(cut_rays > 500);
}

// A finishing program's moves are short against the cutter: sweep_remove groups consecutive steps
// under a bound (detail/sweep_rows.hpp) that a ray skips whole. Rows of 0.1 mm moves whose axis
// tilts along the row, for a ball, flat, bull nose and chamfer: the same dexels as the steps cut
// one at a time (in program order, no groups), on 1, 2 and 8 threads, and groups of every bound
// (the part's pieces, grown for the members' turn, for the flat, bull nose and chamfer).
TEST_CASE("sweep: grouped short steps give the dexels of each step cut alone") {
  const Aabb stock{Vec3(-4, -4, -4), Vec3(4, 4, 1)};
  const DexelLattice lattice = DexelLattice::covering(stock, 0.25);
  const std::vector<SweepCutter> cutters{{Cutter::ball(1.5), 5},
                                         {Cutter::flat(1.5), 5},
                                         {Cutter::bull_nose(1.5, 0.5), 5, 0.005},
                                         {Cutter::chamfer(1.5, 0.5, 45), 5}};
  std::vector<SweepShape> shapes;
  for (const SweepCutter& c : cutters) shapes.push_back(sweep_shape(c));
  auto pose_at = [](double x, double y) {
    return ToolPose{Vec3(x, y, 0.4 - 0.3 * std::sin(x)),
                    glm::normalize(Vec3(0.3 * std::sin(x), 0.3 + 0.1 * y, 1))};
  };
  std::vector<SweepStep> steps;
  for (std::uint32_t c = 0; c < cutters.size(); ++c)
    for (int row = 0; row < 3; ++row)
      for (int k = 0; k < 50; ++k) {
        const double y = -0.6 + 0.6 * row + 0.2 * c;
        const double x0 = -2.5 + 0.1 * (row % 2 ? 50 - k : k), x1 = x0 + (row % 2 ? -0.1 : 0.1);
        const ToolPose p0 = pose_at(x0, y), p1 = pose_at(x1, y);
        auto pose = [&](double s) {
          return ToolPose{p0.tip + s * (p1.tip - p0.tip),
                          glm::normalize(p0.axis + s * (p1.axis - p0.axis))};
        };
        // The axis is interpolated linearly then normalised: it turns at most at |Δaxis| / 0.9
        // (|axis| ≥ 0.9 between unit ends this close), and bends far less than Ω².
        const PoseBounds bounds{glm::length(p1.tip - p0.tip), 2 * glm::length(p1.axis - p0.axis),
                                true};
        const SweepPlan plan = plan_sweep_parts(pose, bounds, cutters[c], shapes[c], 0.025, c,
                                                [](const Aabb&) { return true; });
        steps.insert(steps.end(), plan.steps.begin(), plan.steps.end());
      }
  // The groups sweep_remove forms: far fewer than the steps, with capsule and cylinder bounds.
  std::vector<detail::SweepStepCut> cuts;
  for (const SweepStep& step : steps)
    cuts.push_back(detail::sweep_step_cut(
        cutters[step.cutter], shapes[step.cutter].parts[static_cast<std::size_t>(step.part)],
        step));
  int bounds[3] = {0, 0, 0};
  const detail::SweepGroups groups = detail::sweep_groups(
      cuts, 3 * cutters.size(),
      [&](std::size_t k) { return 3 * steps[k].cutter + static_cast<std::size_t>(steps[k].part); },
      [](std::size_t) { return detail::kSweepGroup; }, 8 * lattice.spacing, true,
      [&](std::span<const std::uint32_t> members, detail::SweepGroup& g) {
        const SweepStep& step = steps[members.front()];
        detail::sweep_group_bound(shapes[step.cutter].parts[static_cast<std::size_t>(step.part)],
                                  steps, cuts, members, g);
      });
  int turning = 0;  // pieces bounds grown for their members' turn
  for (const detail::SweepGroup& g : groups.groups) {
    ++bounds[static_cast<int>(g.bound)];
    turning += g.bound == detail::SweepBound::pieces && g.turn > 0;
  }
  CHECK(turning > 0);
  CHECK(groups.groups.size() * 4 < steps.size());
  CHECK(bounds[static_cast<int>(detail::SweepBound::capsule)] > 0);
  CHECK(bounds[static_cast<int>(detail::SweepBound::pieces)] > 0);
  TripleDexel alone = TripleDexel::box(lattice, stock);
  for (const SweepStep& step : steps) sweep_remove(alone, cutters, {&step, 1}, 1);
  for (unsigned threads : {1u, 2u, 8u}) {
    TripleDexel grouped = TripleDexel::box(lattice, stock);
    sweep_remove(grouped, cutters, steps, threads);
    CHECK(differing_intervals(grouped, alone) == 0);
  }
  CHECK(volume(alone) < volume(TripleDexel::box(lattice, stock)) - 10);
}

// A ray tangent to a ball's capsule meets it in one point: subtracting that point inside a span
// would split it into two touching spans, which no valid dexel holds (validate throws). Seen at
// 10^6 flat-end segments, where grouping changed the order in which such a point met a span.
TEST_CASE("sweep: a cut that rounds to a point leaves the ray whole") {
  const DexelLattice lattice{Vec3(-2), 0.5, glm::ivec3(9)};
  const Aabb stock{Vec3(-2), Vec3(2)};
  TripleDexel d = TripleDexel::box(lattice, stock);
  // The Z ray through (0, 0) lies exactly the ball's radius from its centre's path y = 1.5.
  const std::vector<SweepCutter> cutters{{Cutter::ball(1.5), 5}};
  const SweepStep step{Vec3(-1, 1.5, -0.5), Vec3(1, 1.5, -0.5), Vec3(0, 0, 1), 0, SweepPart::tip};
  const detail::SweepStepCut cut =
      detail::sweep_step_cut(cutters[0], sweep_shape(cutters[0]).parts[1], step);
  const auto point = detail::capsule_interval(cut.c0, cut.c1, cut.radius, Vec3(0), 2);
  REQUIRE(point);
  CHECK(point->first == point->second);
  sweep_remove(d, cutters, {&step, 1}, 1);
  CHECK_NOTHROW(validate(d));
  const auto ray = d.grids[2].ray(4, 4);
  REQUIRE(ray.size() == 1);
  CHECK(ray[0].enter == -2.0f);
  CHECK(ray[0].exit == 2.0f);
}

// A random frustum piece: cylinders, cones widening or narrowing upward, and nearly flat ones
// (a bull nose's lowest chord has slope ~15).
detail::SweepPiece random_frustum(std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0, 1);
  const double slopes[] = {0, 0.3, -0.6, 1.5, 4.5, 15.3, -15.3, 40};
  const double slope = slopes[rng() % 8] * (0.5 + unit(rng));
  const double lo = 2 * unit(rng), hi = lo + (std::abs(slope) > 4 ? 0.02 : 1) * (0.1 + unit(rng));
  const double rho0 = slope < 0 ? -slope * (hi - lo) + 0.5 * unit(rng) : 2 * unit(rng);
  return {lo, hi, false, rho0, slope, 0, 0};
}

Vec3 random_unit(std::mt19937& rng) {
  std::normal_distribution<double> n(0, 1);
  return glm::normalize(Vec3(n(rng), n(rng), n(rng)));
}

// The interval of a ray in a swept frustum as sweep_conic_range finds it with the four sides
// (0 ≤ s ≤ 1, lo ≤ h ≤ hi): what sweep_frustum_range must reproduce.
std::optional<std::pair<double, double>> general_frustum_interval(const detail::SweepPiece& piece,
                                                                  const Vec3& from,
                                                                  const Vec3& travel,
                                                                  const Vec3& axis,
                                                                  const Vec3& point, int ray_axis) {
  Vec3 w = point - from;
  w[ray_axis] = -from[ray_axis];
  const double hw = glm::dot(w, axis), hu = axis[ray_axis], hs = -glm::dot(travel, axis);
  detail::SweepConic f;
  for (int i = 0; i < 3; ++i) f.add_square(w[i], i == ray_axis ? 1.0 : 0.0, -travel[i], 1);
  f.add_square(hw, hu, hs, -1);
  const double m = piece.slope;
  f.add_square(piece.rho0 + m * (hw - piece.lo), m * hu, m * hs, -1);
  const double size = piece.hi + glm::length(travel) + piece.rho0 + m * (piece.hi - piece.lo);
  const detail::SweepSide sides[4] = {
      {0, 1, 0}, {0, -1, 1}, {hu, hs, hw - piece.lo}, {-hu, -hs, piece.hi - hw}};
  const double tol = 1e-9 * (1 + size);
  return detail::sweep_conic_range(f, sides, 2 * tol * (1 + size), tol);
}

// sweep_piece_interval solves a frustum with sweep_frustum_range, which tests each candidate of
// the general conic only against the sides it does not lie on: the same intervals on rays near
// random swept frusta (axes along and across the rays included).
TEST_CASE("sweep: a frustum's own range gives the general conic's intervals") {
  std::mt19937 rng(3434);
  std::uniform_real_distribution<double> u(-3, 3);
  int met = 0, differ = 0;
  for (int k = 0; k < 20000; ++k) {
    const detail::SweepPiece piece = random_frustum(rng);
    Vec3 axis = random_unit(rng);
    if (k % 5 == 0) axis = Vec3(0, 0, k % 10 == 0 ? 1.0 : -1.0);
    if (k % 7 == 0) axis = glm::normalize(Vec3(axis.x, axis.y, 0));
    const Vec3 from(u(rng), u(rng), u(rng));
    const Vec3 travel = (k % 3 == 0 ? 0.05 : 2.0) * Vec3(u(rng), u(rng), u(rng));
    const Vec3 point(u(rng), u(rng), u(rng));
    const int ray_axis = static_cast<int>(rng() % 3);
    const auto fast = detail::sweep_piece_interval(piece, from, travel, axis, point, ray_axis);
    const auto general = general_frustum_interval(piece, from, travel, axis, point, ray_axis);
    met += general.has_value();
    // The same candidates from the same formulas: equal but for rounding (the compiler may fuse
    // multiply-adds differently in the two, which a ray nearly tangent to the sweep magnifies),
    // and a tangent ray's point of contact either way.
    if (fast && general) {
      const double slack = 1e-7 * (1 + std::abs(general->first) + std::abs(general->second));
      differ += std::abs(fast->first - general->first) > slack ||
                std::abs(fast->second - general->second) > slack;
    } else if (fast || general) {
      const auto& one = fast ? fast : general;
      differ += one->second - one->first > 1e-6;
    }
  }
  CHECK(differ == 0);
  CHECK(met > 2000);
}

// A group bound grows its pieces (sweep_grown_interval); a nearly flat frustum's wide end is
// capped by the cylinder of its largest radius + e. Points within e of random frusta, on rays
// through them, lie within the grown interval; and the cap makes it narrower on some rays.
TEST_CASE("sweep: a grown frustum, capped, holds every point within e of it") {
  std::mt19937 rng(3436);
  std::uniform_real_distribution<double> unit(0, 1);
  int narrower = 0;
  for (int k = 0; k < 20000; ++k) {
    const detail::SweepPiece piece = random_frustum(rng);
    const double e = 0.05 * unit(rng);
    const Vec3 axis = random_unit(rng), from(0.0), travel = 0.3 * unit(rng) * random_unit(rng);
    const Vec3 b1 =
        glm::normalize(glm::cross(axis, std::abs(axis.x) < 0.9 ? Vec3(1, 0, 0) : Vec3(0, 1, 0)));
    const Vec3 b2 = glm::cross(axis, b1);
    // A point of the piece (swept by s), moved by at most e.
    const double h = piece.lo + unit(rng) * (piece.hi - piece.lo);
    const double r = (piece.rho0 + piece.slope * (h - piece.lo)) * std::sqrt(unit(rng));
    const double angle = 2 * std::numbers::pi * unit(rng);
    const Vec3 x = from + unit(rng) * travel + h * axis +
                   r * (std::cos(angle) * b1 + std::sin(angle) * b2) +
                   e * std::cbrt(unit(rng)) * random_unit(rng);
    const int ray_axis = static_cast<int>(rng() % 3);
    const auto grown = detail::sweep_grown_interval(piece, e, from, travel, axis, x, ray_axis);
    REQUIRE(grown);
    const double slack = 1e-9 * (1 + std::abs(x[ray_axis]));
    CHECK(grown->first <= x[ray_axis] + slack);
    CHECK(grown->second >= x[ray_axis] - slack);
    const auto uncapped = detail::sweep_piece_interval(detail::sweep_grown_piece(piece, e), from,
                                                       travel, axis, x, ray_axis);
    REQUIRE(uncapped);
    CHECK(grown->first >= uncapped->first - slack);
    CHECK(grown->second <= uncapped->second + slack);
    narrower += grown->second - grown->first < uncapped->second - uncapped->first - 1e-6;
  }
  CHECK(narrower > 100);
}

TEST_CASE(
    "golden_minimum: the minimum of a convex 1-Lipschitz function, or a value above the bar") {
  std::mt19937 rng(34);
  std::uniform_real_distribution<double> u(-5, 5);
  for (int k = 0; k < 1000; ++k) {
    // A cone's distance along a line: convex, 1-Lipschitz, least at c.
    const double c = u(rng), floor = u(rng), slope = 0.2 + 0.8 * std::abs(u(rng)) / 5;
    auto f = [&](double z) { return floor + slope * std::abs(z - c); };
    const double lo = -6, hi = 6, precision = 1e-6;
    const auto [z, value] = detail::golden_minimum(f, lo, hi, precision);
    CHECK(std::abs(z - c) <= precision);
    CHECK(value == doctest::Approx(floor).epsilon(1e-6));
    // A bar below the minimum: the search may stop early, with a value at or above the bar.
    const double bar = floor - 0.5 * std::abs(u(rng));
    const auto stopped = detail::golden_minimum(f, lo, hi, precision, bar);
    CHECK(stopped.second >= bar);
    CHECK(stopped.second <= f(stopped.first) + 1e-12);
    // A bar above it: the true minimum is found.
    const auto found = detail::golden_minimum(f, lo, hi, precision, floor + 1);
    CHECK(std::abs(found.first - c) <= precision);
  }
}

}  // namespace test_sweep
