// Step 1 throughput: segments per second of Z-map milling on a raster finishing path.
//
// Workload (issue "Kernel, part 1"): a 100×100 mm Z-map at 0.02 mm cells (5002×5002 points), a
// zig-zag raster of 0.5 mm segments at 0.5 mm stepover following a wavy surface, milled from a
// fresh flat stock each iteration, with a ball end D6, a flat end D10 and a bull nose D8 r1.
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "tridex/mill.hpp"

namespace {

using namespace tridex;

constexpr double kSide = 100, kCell = 0.02, kStep = 0.5;

double wavy(double x, double y) { return 20 + 3 * std::sin(x / 8) * std::cos(y / 11) + 0.01 * x; }

std::vector<CutMove> raster() {
  std::vector<CutMove> moves;
  int lines = static_cast<int>(kSide / kStep) + 1, steps = static_cast<int>(kSide / kStep);
  for (int l = 0; l < lines; ++l) {
    double y = l * kStep;
    for (int s = 0; s < steps; ++s) {
      double x0 = (l % 2 ? steps - s : s) * kStep, x1 = x0 + (l % 2 ? -kStep : kStep);
      moves.push_back({Segment{Vec3(x0, y, wavy(x0, y)), Vec3(x1, y, wavy(x1, y))}, 0});
    }
  }
  return moves;
}

void mill_raster(benchmark::State& state, Cutter cutter) {
  static const ZMap stock = ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(kSide, kSide, 25)}, kCell);
  static const std::vector<CutMove> moves = raster();
  std::vector<Cutter> cutters{cutter};
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

void ball_d6(benchmark::State& s) { mill_raster(s, Cutter::ball(3)); }
void flat_d10(benchmark::State& s) { mill_raster(s, Cutter::flat(5)); }
void bull_d8_r1(benchmark::State& s) { mill_raster(s, Cutter::bull_nose(4, 1)); }

// Argument: thread count (0 = every hardware thread).
BENCHMARK(ball_d6)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(flat_d10)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(bull_d8_r1)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
