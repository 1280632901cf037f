// Simultaneous 5-axis sweeps on the triple dexel (sweep.hpp): milliseconds per segment and
// sub-steps per move, by cutter.
//
// Workload: a 100 × 100 × 40 mm box stock at the lattice spacing of the benchmark's argument (in
// hundredths of a mm: 10 is the 0.1 mm, 1004 × 1004 × 404 nodes); a 6 mm cutter (ball,
// flat, bull nose with a 1 mm corner; 30 mm tall) running 200 segments of a zig-zag 1 mm deep
// across the top, each 2 mm long, its axis tilting 2° about Y and turning back, as a swarf
// pass's tool-axis wobble (under TCP: the tip runs straight). The stock is rebuilt outside the
// timed region. Planner 0 is plan_sweep (the whole cutter, sub-steps doubled until the band fits),
// 1 plan_sweep_parts (tip and shank apart, a ball along its centre's path, sub-steps that cannot
// reach material dropped: the pipeline's). Counters: ms_per_segment (sweep_remove's wall time over
// the segments), plan_ms_per_segment (planning, outside the timed region), sub_steps_per_move,
// band_mm (the largest e). BM_sweep_cpu: CPU milliseconds per segment and core (one thread, the
// process's CPU clock, the grids' rebuild subtracted) over 800 segments with the parts planner.
#include <benchmark/benchmark.h>

#include <time.h>

#include <chrono>
#include <cmath>
#include <vector>

#include "tridex/sweep.hpp"

namespace {

using namespace tridex;

const Aabb kStock{Vec3(0), Vec3(100, 100, 40)};
constexpr int kSegments = 200;

SweepCutter bench_cutter(int shape, double chord) {
  switch (shape) {
    case 0:
      return {Cutter::ball(3), 30};
    case 1:
      return {Cutter::flat(3), 30};
    default:
      return {Cutter::bull_nose(3, 1), 30, chord};
  }
}

Vec3 tilted(double degrees) {
  const double t = degrees * 3.141592653589793 / 180;
  return Vec3(std::sin(t), 0, std::cos(t));
}

// The process's CPU time (all threads), s.
double cpu_seconds() {
  timespec t{};
  clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &t);
  return static_cast<double>(t.tv_sec) + 1e-9 * static_cast<double>(t.tv_nsec);
}

// The workload's steps: `segments` moves of the zig-zag (40 a row, rows 2 mm apart).
std::vector<SweepStep> bench_steps(const SweepCutter& cutter, double spacing, int segments,
                                   bool parts, double& band) {
  const double tolerance = spacing / 10;
  const DexelLattice lattice = DexelLattice::covering(kStock, spacing);
  std::vector<SweepStep> steps;
  const SweepShape shape = sweep_shape(cutter);
  const SweepMaterial material(TripleDexel::box(lattice, kStock));
  for (int k = 0; k < segments; ++k) {
    const Vec3 a(10 + 2.0 * (k % 40), 10 + 2.0 * (k / 40), 39), b = a + Vec3(2, 0, 0);
    const double from = (k % 2) ? 2 : 0, to = (k % 2) ? 0 : 2;
    auto pose = [&](double s) { return ToolPose{a + s * (b - a), tilted(from + s * (to - from))}; };
    const PoseBounds bounds{2, 2 * 3.141592653589793 / 180, true};
    const SweepPlan plan =
        parts ? plan_sweep_parts(pose, bounds, cutter, shape, tolerance, 0,
                                 [&](const Aabb& box) { return material.may_touch(box); })
              : plan_sweep(pose, bounds, cutter.reach(), tolerance);
    band = std::max(band, plan.band);
    steps.insert(steps.end(), plan.steps.begin(), plan.steps.end());
  }
  return steps;
}

void BM_sweep_segments(benchmark::State& state) {
  const double spacing = static_cast<double>(state.range(0)) / 100;
  // plan_sweep_parts cuts the bull nose's torus as chords of sagitta ≤ a quarter of the tolerance.
  const double tolerance = spacing / 10;
  const std::vector<SweepCutter> cutters{
      bench_cutter(static_cast<int>(state.range(1)), state.range(2) == 1 ? tolerance / 4 : 0)};
  const DexelLattice lattice = DexelLattice::covering(kStock, spacing);
  double band = 0;
  const auto plan_start = std::chrono::steady_clock::now();
  const std::vector<SweepStep> steps =
      bench_steps(cutters[0], spacing, kSegments, state.range(2) == 1, band);
  const double plan_seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - plan_start).count();
  double seconds = 0;
  for (auto _ : state) {
    state.PauseTiming();
    TripleDexel d = TripleDexel::box(lattice, kStock);
    state.ResumeTiming();
    const auto start = std::chrono::steady_clock::now();
    sweep_remove(d, cutters, steps, 0, spacing / 1000);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    benchmark::DoNotOptimize(d.grids[2].intervals.data());
  }
  state.counters["ms_per_segment"] =
      1000.0 * seconds / (static_cast<double>(state.iterations()) * kSegments);
  state.counters["plan_ms_per_segment"] = 1000.0 * plan_seconds / kSegments;
  state.counters["sub_steps_per_move"] = static_cast<double>(steps.size()) / kSegments;
  state.counters["band_mm"] = band;
}
// Args: spacing in 1/100 mm, cutter (0 ball, 1 flat, 2 bull nose), planner (0 plan_sweep, 1 parts).
BENCHMARK(BM_sweep_segments)
    ->ArgsProduct({{10, 50}, {0, 1, 2}, {0, 1}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

// CPU seconds per segment and core: 800 segments (20 rows; the bull nose 100) of the same
// zig-zag with the parts planner, cut on one thread, timed by the process's CPU clock (steadier
// than wall time on a shared machine), less the same call with no steps (the three grids' rebuild).
// Args: spacing in 1/100 mm, cutter (0 ball, 1 flat, 2 bull nose), segments.
void BM_sweep_cpu(benchmark::State& state) {
  const double spacing = static_cast<double>(state.range(0)) / 100;
  const int segments = static_cast<int>(state.range(2));
  const std::vector<SweepCutter> cutters{
      bench_cutter(static_cast<int>(state.range(1)), spacing / 40)};
  const DexelLattice lattice = DexelLattice::covering(kStock, spacing);
  double band = 0;
  const std::vector<SweepStep> steps = bench_steps(cutters[0], spacing, segments, true, band);
  double seconds = 0;
  for (auto _ : state) {
    TripleDexel d = TripleDexel::box(lattice, kStock);
    double start = cpu_seconds();
    sweep_remove(d, cutters, std::span<const SweepStep>(), 1, spacing / 1000);
    const double rebuild = cpu_seconds() - start;
    start = cpu_seconds();
    sweep_remove(d, cutters, steps, 1, spacing / 1000);
    seconds += cpu_seconds() - start - rebuild;
    benchmark::DoNotOptimize(d.grids[2].intervals.data());
  }
  state.counters["cpu_ms_per_segment"] =
      1000.0 * seconds / (static_cast<double>(state.iterations()) * segments);
  state.counters["sub_steps_per_move"] = static_cast<double>(steps.size()) / segments;
  state.counters["band_mm"] = band;
}
BENCHMARK(BM_sweep_cpu)
    ->Args({10, 0, 800})
    ->Args({10, 1, 800})
    ->Args({10, 2, 100})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
