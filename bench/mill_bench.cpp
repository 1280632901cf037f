// Step 1 throughput: segments per second of Z-map milling, each cutter shape on one raster.
//
// Workload (issues "Kernel, part 1" and 13): a 100×100 mm Z-map at 0.02 mm cells (5002×5002
// points), a zig-zag raster of 0.5 mm segments at 0.5 mm stepover following a wavy surface
// (sloped 3-axis finishing, 40,200 segments), milled from a fresh flat stock each iteration:
//   * the same raster with each cutter shape of diameter 6 (ball, flat, bull nose, cone,
//     chamfer, tapered ball, a profile), so that their times compare as ratios to the ball's;
//   * mixed cutters in one map: that ball raster plus a coarse roughing raster (2 mm stepover,
//     1 mm segments, 5,100 segments) with a flat end D10 or a bull nose D8 r1, either 0.4 mm
//     below the finishing surface (the ball ends then cut air, the case of issue 13) or 0.3 mm
//     above it (roughing leaves stock for the ball), and each roughing raster alone.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "tridex/mill.hpp"

namespace {

using namespace tridex;

constexpr double kSide = 100, kCell = 0.02;

double wavy(double x, double y) { return 20 + 3 * std::sin(x / 8) * std::cos(y / 11) + 0.01 * x; }

// A zig-zag raster over the wavy surface raised by `lift`, cut with cutter `cutter`.
std::vector<CutMove> raster(double stepover, double step, double lift, std::uint32_t cutter) {
  std::vector<CutMove> moves;
  int lines = static_cast<int>(kSide / stepover) + 1, steps = static_cast<int>(kSide / step);
  for (int l = 0; l < lines; ++l) {
    double y = l * stepover;
    for (int s = 0; s < steps; ++s) {
      double x0 = (l % 2 ? steps - s : s) * step, x1 = x0 + (l % 2 ? -step : step);
      moves.push_back({Segment{Vec3(x0, y, wavy(x0, y) + lift), Vec3(x1, y, wavy(x1, y) + lift)}, cutter});
    }
  }
  return moves;
}

void mill_moves(benchmark::State& state, const std::vector<Cutter>& cutters, const std::vector<CutMove>& moves) {
  static const ZMap stock = ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(kSide, kSide, 25)}, kCell);
  MillOptions options{static_cast<unsigned>(state.range(0))};
  ZMap map = stock;
  for (auto _ : state) {
    state.PauseTiming();
    map.heights = stock.heights;
    state.ResumeTiming();
    mill(map, cutters, moves, options);
    benchmark::DoNotOptimize(map.heights.data());
  }
  state.SetItemsProcessed(static_cast<int64_t>(state.iterations() * moves.size()));
  state.counters["segments/s"] =
      benchmark::Counter(static_cast<double>(moves.size()), benchmark::Counter::kIsIterationInvariantRate);
}

const std::vector<CutMove>& finishing() {
  static const std::vector<CutMove> moves = raster(0.5, 0.5, 0, 0);
  return moves;
}

void one_cutter(benchmark::State& state, Cutter cutter) { mill_moves(state, {cutter}, finishing()); }

void ball_d6(benchmark::State& s) { one_cutter(s, Cutter::ball(3)); }
void flat_d6(benchmark::State& s) { one_cutter(s, Cutter::flat(3)); }
void bull_d6_r1(benchmark::State& s) { one_cutter(s, Cutter::bull_nose(3, 1)); }
void cone_d6_45(benchmark::State& s) { one_cutter(s, Cutter::cone(3, 45)); }
void chamfer_d6_tip1_45(benchmark::State& s) { one_cutter(s, Cutter::chamfer(3, 1, 45)); }
void tapered_d6_r1_10(benchmark::State& s) { one_cutter(s, Cutter::tapered_ball(3, 1, 10)); }
void profile_d6(benchmark::State& s) {
  one_cutter(s, Cutter::from_profile({Vec2(0.5, 0), Vec2(1.5, 0.2), Vec2(2.5, 0.8), Vec2(3, 1.5)}));
}

// Roughing (cutter 1) `lift` above the finishing surface, alone or with the ball raster (cutter 0).
void roughing(benchmark::State& state, Cutter rough, double lift, bool with_ball) {
  std::vector<CutMove> moves = raster(2, 1, lift, 1);
  if (with_ball) moves.insert(moves.end(), finishing().begin(), finishing().end());
  mill_moves(state, {Cutter::ball(3), rough}, moves);
}
void flat_d10_rough_below(benchmark::State& s) { roughing(s, Cutter::flat(5), -0.4, false); }
void ball_and_flat_d10_below(benchmark::State& s) { roughing(s, Cutter::flat(5), -0.4, true); }
void bull_d8_rough_below(benchmark::State& s) { roughing(s, Cutter::bull_nose(4, 1), -0.4, false); }
void ball_and_bull_d8_below(benchmark::State& s) { roughing(s, Cutter::bull_nose(4, 1), -0.4, true); }
void flat_d10_rough_above(benchmark::State& s) { roughing(s, Cutter::flat(5), 0.3, false); }
void ball_and_flat_d10_above(benchmark::State& s) { roughing(s, Cutter::flat(5), 0.3, true); }

// Argument: thread count (0 = every hardware thread). One thread's CPU time is the figure to
// trust on a loaded machine.
BENCHMARK(ball_d6)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(flat_d6)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(bull_d6_r1)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(cone_d6_45)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(chamfer_d6_tip1_45)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(tapered_d6_r1_10)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(profile_d6)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(flat_d10_rough_below)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(ball_and_flat_d10_below)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(bull_d8_rough_below)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(ball_and_bull_d8_below)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(flat_d10_rough_above)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(ball_and_flat_d10_above)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
