// Simultaneous 5-axis at scale (issue 34): the finishing program of bench/five_axis_program.py
// cut through the kernel's sweep API directly (plan_sweep_parts, sweep_remove), with no G-code.
//
// Workload: a wavy 100 × 100 mm surface (z = 20 + 3 sin(x/8) cos(y/11) + 0.01 x, centred on the
// origin), the stock that surface 0.5 mm oversize from z = 0 (a closed heightfield mesh of 0.5 mm
// cells, dexelized), rows along X 0.2 mm apart of 2000 segments each (0.05 mm), the tool axis
// leaning about 20° from the normal toward +Y and turning along the path, under TCP on an A/C
// table (the tip straight, A and C linear in angle; the axis (sin A sin C, sin A cos C, cos A) as
// the bundled ac-trunnion turns it), the tip placed so that each cutter (6 mm ball, flat, bull
// nose r1, as tall as the pipeline makes a tool without a shank: profile + 4 R) touches the
// surface at the row's point. Tolerance a tenth of the 0.1 mm spacing, the bull nose's torus as
// chords of a quarter of it: the pipeline's settings (tools/cli/pipeline/simultaneous.cpp).
//
// BM_sweep_scale/segments/cutter/threads: the process's CPU seconds (all threads) and wall
// seconds of planning (plan_sweep_parts per move against SweepMaterial) and of sweep_remove, the
// stock's dexelization outside both; counters per segment and per segment·core.
#include <benchmark/benchmark.h>

#include <time.h>

#include <chrono>
#include <cmath>
#include <vector>

#include "tridex/dexelize.hpp"
#include "tridex/sweep.hpp"

namespace {

using namespace tridex;

constexpr double kHalf = 50, kStepover = 0.2, kAllowance = 0.5, kLean = 0.4;
constexpr int kRowSegments = 2000;

double surface(double x, double y) {
  return 20 + 3 * std::sin(x / 8) * std::cos(y / 11) + 0.01 * x;
}

// The tip and the rotary angles (A, C in radians) that touch the surface at (x, y).
struct ScalePose {
  Vec3 tip;
  double a, c;
};

ScalePose scale_pose(double x, double y, double radius, double corner) {
  const double fx = 3.0 / 8 * std::cos(x / 8) * std::cos(y / 11) + 0.01;
  const double fy = -3.0 / 11 * std::sin(x / 8) * std::sin(y / 11);
  const Vec3 n = glm::normalize(Vec3(-fx, -fy, 1)), a = glm::normalize(Vec3(-fx, -fy + kLean, 1));
  const Vec3 side = glm::normalize(n - glm::dot(n, a) * a);
  const Vec3 tip = Vec3(x, y, surface(x, y)) + corner * n - corner * a + (radius - corner) * side;
  return {tip, std::acos(a.z), std::atan2(a.x, a.y)};
}

Vec3 axis_of(double a, double c) {
  return Vec3(std::sin(a) * std::sin(c), std::sin(a) * std::cos(c), std::cos(a));
}

Mesh stock_mesh(double cell) {
  Mesh m;
  const int n = static_cast<int>(std::lround(2 * kHalf / cell));
  auto vertex = [&](int i, int j, bool top) {
    const double x = -kHalf + i * cell, y = -kHalf + j * cell;
    m.positions.emplace_back(x, y, top ? surface(x, y) + kAllowance : 0.0);
    return static_cast<unsigned>(m.positions.size() - 1);
  };
  auto quad = [&](unsigned a, unsigned b, unsigned c, unsigned d) {  // counter-clockwise outside
    m.triangles.emplace_back(a, b, c);
    m.triangles.emplace_back(a, c, d);
  };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      quad(vertex(i, j, true), vertex(i + 1, j, true), vertex(i + 1, j + 1, true),
           vertex(i, j + 1, true));
      quad(vertex(i, j, false), vertex(i, j + 1, false), vertex(i + 1, j + 1, false),
           vertex(i + 1, j, false));
    }
  for (int i = 0; i < n; ++i) {
    quad(vertex(i, 0, false), vertex(i + 1, 0, false), vertex(i + 1, 0, true), vertex(i, 0, true));
    quad(vertex(i + 1, n, false), vertex(i, n, false), vertex(i, n, true), vertex(i + 1, n, true));
    quad(vertex(0, i + 1, false), vertex(0, i, false), vertex(0, i, true), vertex(0, i + 1, true));
    quad(vertex(n, i, false), vertex(n, i + 1, false), vertex(n, i + 1, true), vertex(n, i, true));
  }
  return m;
}

double cpu_now() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

double wall_now() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

SweepCutter scale_cutter(int shape, double chord) {
  const Cutter c = shape == 0   ? Cutter::ball(3)
                   : shape == 1 ? Cutter::flat(3)
                                : Cutter::bull_nose(3, 1);
  return {c, c.profile_height() + 4 * c.radius(), shape == 2 ? chord : 0.0};
}

// The program's poses in order: rows zig-zag, each row's first point linked from the last's end.
std::vector<ScalePose> scale_program(int segments, double radius, double corner) {
  std::vector<ScalePose> poses;
  const int rows = std::max(1, segments / kRowSegments);
  for (int row = 0; row < rows; ++row)
    for (int k = 0; k <= kRowSegments; ++k) {
      const double s = static_cast<double>(k) / kRowSegments;
      const double x = -kHalf + 2 * kHalf * (row % 2 == 0 ? s : 1 - s);
      poses.push_back(scale_pose(x, -kHalf + row * kStepover, radius, corner));
    }
  return poses;
}

void BM_sweep_scale(benchmark::State& state) {
  const double spacing = 0.1, tolerance = spacing / 10;
  const int shape = static_cast<int>(state.range(1));
  const auto threads = static_cast<unsigned>(state.range(2));
  const std::vector<SweepCutter> cutters{scale_cutter(shape, tolerance / 4)};
  const SweepShape sweep = sweep_shape(cutters[0]);
  const double corner = shape == 0 ? 3 : shape == 1 ? 0 : 1;
  const std::vector<ScalePose> poses = scale_program(static_cast<int>(state.range(0)), 3, corner);
  const Aabb box{Vec3(-kHalf, -kHalf, 0), Vec3(kHalf, kHalf, 30)};
  const DexelLattice lattice = DexelLattice::covering(box, spacing);
  const Mesh mesh = stock_mesh(0.5);
  double plan_cpu = 0, plan_wall = 0, cut_cpu = 0, cut_wall = 0, removed = 0;
  std::size_t steps_total = 0;
  for (auto _ : state) {
    TripleDexel d = dexelize(mesh, lattice, {threads});
    const double before = volume(d);
    double c0 = cpu_now(), w0 = wall_now();
    const SweepMaterial material(d);
    std::vector<SweepStep> steps;
    for (std::size_t k = 1; k < poses.size(); ++k) {
      const ScalePose &p0 = poses[k - 1], &p1 = poses[k];
      auto pose = [&](double s) {
        return ToolPose{p0.tip + s * (p1.tip - p0.tip),
                        axis_of(p0.a + s * (p1.a - p0.a), p0.c + s * (p1.c - p0.c))};
      };
      const PoseBounds bounds{glm::length(p1.tip - p0.tip),
                              std::abs(p1.a - p0.a) + std::abs(p1.c - p0.c), true};
      const SweepPlan plan = plan_sweep_parts(pose, bounds, cutters[0], sweep, tolerance, 0,
                                              [&](const Aabb& b) { return material.may_touch(b); });
      steps.insert(steps.end(), plan.steps.begin(), plan.steps.end());
    }
    plan_cpu += cpu_now() - c0, plan_wall += wall_now() - w0;
    c0 = cpu_now(), w0 = wall_now();
    sweep_remove(d, cutters, steps, threads, tolerance / 100);
    cut_cpu += cpu_now() - c0, cut_wall += wall_now() - w0;
    removed = before - volume(d);
    steps_total = steps.size();
  }
  const double n = static_cast<double>(state.iterations());
  const double segments = static_cast<double>(poses.size() - 1);
  state.counters["plan_cpu_s"] = plan_cpu / n;
  state.counters["plan_wall_s"] = plan_wall / n;
  state.counters["remove_cpu_s"] = cut_cpu / n;
  state.counters["remove_wall_s"] = cut_wall / n;
  state.counters["cpu_ms_per_segment"] = 1000 * (plan_cpu + cut_cpu) / n / segments;
  state.counters["sub_steps_per_move"] = static_cast<double>(steps_total) / segments;
  state.counters["removed_mm3"] = removed;
}
// Args: segments (rows of 2000), cutter (0 ball, 1 flat, 2 bull nose), threads.
BENCHMARK(BM_sweep_scale)
    ->ArgsProduct({{100000, 1000000}, {0, 1, 2}, {1, 2}})
    ->Unit(benchmark::kSecond)
    ->Iterations(1)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
