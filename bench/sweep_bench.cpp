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
// band_mm (the largest e).
#include <benchmark/benchmark.h>

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

void BM_sweep_segments(benchmark::State& state) {
  const double spacing = static_cast<double>(state.range(0)) / 100;
  // plan_sweep_parts cuts the bull nose's torus as chords of sagitta ≤ a quarter of the tolerance.
  const double tolerance = spacing / 10;
  const std::vector<SweepCutter> cutters{
      bench_cutter(static_cast<int>(state.range(1)), state.range(2) == 1 ? tolerance / 4 : 0)};
  const DexelLattice lattice = DexelLattice::covering(kStock, spacing);
  std::vector<SweepStep> steps;
  double band = 0;
  const bool parts = state.range(2) == 1;
  const SweepShape shape = sweep_shape(cutters[0]);
  const auto plan_start = std::chrono::steady_clock::now();
  const SweepMaterial material(TripleDexel::box(lattice, kStock));
  for (int k = 0; k < kSegments; ++k) {
    const Vec3 a(10 + 2.0 * (k % 40), 10 + 2.0 * (k / 40), 39), b = a + Vec3(2, 0, 0);
    const double from = (k % 2) ? 2 : 0, to = (k % 2) ? 0 : 2;
    auto pose = [&](double s) { return ToolPose{a + s * (b - a), tilted(from + s * (to - from))}; };
    const PoseBounds bounds{2, 2 * 3.141592653589793 / 180, true};
    const SweepPlan plan =
        parts ? plan_sweep_parts(pose, bounds, cutters[0], shape, tolerance, 0,
                                 [&](const Aabb& box) { return material.may_touch(box); })
              : plan_sweep(pose, bounds, cutters[0].reach(), tolerance);
    band = std::max(band, plan.band);
    steps.insert(steps.end(), plan.steps.begin(), plan.steps.end());
  }
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

}  // namespace

BENCHMARK_MAIN();
