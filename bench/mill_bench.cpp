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
//     above it (roughing leaves stock for the ball), and each roughing raster alone;
//   * the finishing raster placed for the ball, the flat end and the bull nose to touch the surface
//     (drop-cutter), as a CAM system writes it: the tips of the raster above follow the surface, so
//     that a flat bottom cuts below it wherever it slopes.
#include <benchmark/benchmark.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <vector>

#include "tridex/mill.hpp"

namespace {

using namespace tridex;

constexpr double kSide = 100, kCell = 0.02;

double wavy(double x, double y) { return 20 + 3 * std::sin(x / 8) * std::cos(y / 11) + 0.01 * x; }

// The lowest tip at (x, y) from which `shape` stays on or above the wavy surface: the surface
// sampled every 0.1 mm over the footprint (drop-cutter), as a CAM system places a finishing tool.
// Sampling leaves the tip at most a few µm low, which does not matter to a timing.
double touching_tip(const Cutter& shape, double x, double y) {
  const double radius = shape.radius(), step = 0.1;
  double tip = -std::numeric_limits<double>::infinity();
  for (double dy = -radius; dy <= radius; dy += step)
    for (double dx = -radius; dx <= radius; dx += step) {
      const double d = std::sqrt(dx * dx + dy * dy);
      if (d <= radius) tip = std::max(tip, wavy(x + dx, y + dy) - shape.lower_height(d));
    }
  return tip;
}

// A zig-zag raster over the wavy surface raised by `lift`, cut with cutter `cutter`; with
// `touching`, the tips are placed so that that cutter touches the surface instead of its tip
// following it (which makes a flat end or a bull nose cut below the surface on a slope).
std::vector<CutMove> raster(double stepover, double step, double lift, std::uint32_t cutter,
                            const Cutter* touching = nullptr) {
  std::vector<CutMove> moves;
  int lines = static_cast<int>(kSide / stepover) + 1, steps = static_cast<int>(kSide / step);
  std::vector<double> tips(static_cast<std::size_t>(lines) * static_cast<std::size_t>(steps + 1));
  for (int l = 0; l < lines; ++l)
    for (int s = 0; s <= steps; ++s) {
      const double x = s * step, y = l * stepover;
      tips[static_cast<std::size_t>(l * (steps + 1) + s)] =
          touching ? touching_tip(*touching, x, y) : wavy(x, y);
    }
  for (int l = 0; l < lines; ++l) {
    double y = l * stepover;
    for (int s = 0; s < steps; ++s) {
      int s0 = l % 2 ? steps - s : s, s1 = s0 + (l % 2 ? -1 : 1);
      double z0 = tips[static_cast<std::size_t>(l * (steps + 1) + s0)] + lift;
      double z1 = tips[static_cast<std::size_t>(l * (steps + 1) + s1)] + lift;
      moves.push_back({Segment{Vec3(s0 * step, y, z0), Vec3(s1 * step, y, z1)}, cutter});
    }
  }
  return moves;
}

void mill_moves(benchmark::State& state, const std::vector<Cutter>& cutters,
                const std::vector<CutMove>& moves) {
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
  state.counters["segments/s"] = benchmark::Counter(static_cast<double>(moves.size()),
                                                    benchmark::Counter::kIsIterationInvariantRate);
}

const std::vector<CutMove>& finishing() {
  static const std::vector<CutMove> moves = raster(0.5, 0.5, 0, 0);
  return moves;
}

void one_cutter(benchmark::State& state, Cutter cutter) {
  mill_moves(state, {cutter}, finishing());
}

void ball_d6(benchmark::State& s) { one_cutter(s, Cutter::ball(3)); }
void flat_d6(benchmark::State& s) { one_cutter(s, Cutter::flat(3)); }
void bull_d6_r1(benchmark::State& s) { one_cutter(s, Cutter::bull_nose(3, 1)); }
void cone_d6_45(benchmark::State& s) { one_cutter(s, Cutter::cone(3, 45)); }
void chamfer_d6_tip1_45(benchmark::State& s) { one_cutter(s, Cutter::chamfer(3, 1, 45)); }
void tapered_d6_r1_10(benchmark::State& s) { one_cutter(s, Cutter::tapered_ball(3, 1, 10)); }
void profile_d6(benchmark::State& s) {
  one_cutter(s, Cutter::from_profile({Vec2(0.5, 0), Vec2(1.5, 0.2), Vec2(2.5, 0.8), Vec2(3, 1.5)}));
}

// The finishing raster placed for a cutter to touch the surface (see `raster`), made once (it
// takes seconds) however often the benchmark library calls the benchmark.
void touching(benchmark::State& state, const Cutter& cutter, std::vector<CutMove>& moves) {
  if (moves.empty()) moves = raster(0.5, 0.5, 0, 0, &cutter);
  mill_moves(state, {cutter}, moves);
}
void ball_d6_touching(benchmark::State& s) {
  static std::vector<CutMove> moves;
  touching(s, Cutter::ball(3), moves);
}
void flat_d6_touching(benchmark::State& s) {
  static std::vector<CutMove> moves;
  touching(s, Cutter::flat(3), moves);
}
void bull_d6_r1_touching(benchmark::State& s) {
  static std::vector<CutMove> moves;
  touching(s, Cutter::bull_nose(3, 1), moves);
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
void ball_and_bull_d8_below(benchmark::State& s) {
  roughing(s, Cutter::bull_nose(4, 1), -0.4, true);
}
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
BENCHMARK(ball_d6_touching)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(flat_d6_touching)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(bull_d6_r1_touching)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(flat_d10_rough_below)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(ball_and_flat_d10_below)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(bull_d8_rough_below)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(ball_and_bull_d8_below)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(flat_d10_rough_above)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(ball_and_flat_d10_above)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
