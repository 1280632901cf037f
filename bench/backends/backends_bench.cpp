// tridex bench — the backends of Step 1 (cpu, gl) and Step 2 (tree, embree, scan) on the same
// synthetic inputs (Inui, Chen and Umezu, CAD&A 19(4) 2022, §3.1 and §4.2).
//
//   bench_backends --benchmark_repetitions=5 --benchmark_report_aggregates_only=true
#include <benchmark/benchmark.h>

#include <cmath>
#include <vector>

#include "tridex/backends/backends.hpp"
#include "tridex/backends/embree_dexelize.hpp"
#include "tridex/backends/gl_mill.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/scan_dexelize.hpp"

using namespace tridex;
namespace be = tridex::backends;

namespace {

const Aabb kStock{Vec3(0, 0, 0), Vec3(100, 100, 60)};

// A mold-like height field (dome with ripples) as the milled map of a frame tilted by `tilt`.
ZMap mold_map(double tilt_deg, int points) {
  Frame frame = Frame::from_rotation(rotation_x(tilt_deg));
  Aabb local = local_bounds(frame, kStock);
  double cell = std::max(local.size().x, local.size().y) / (points - 1);
  ZMap map = ZMap::from_box(frame, kStock, cell);
  for (int j = 0; j < map.grid.ny; ++j)
    for (int i = 0; i < map.grid.nx; ++i) {
      float& h = map.heights[map.grid.index(i, j)];
      if (h <= map.empty_height) continue;
      double x = (map.grid.x(i) - local.center().x) / 50,
             y = (map.grid.y(j) - local.center().y) / 50;
      double surface = local.max.z - 20 + 12 * std::exp(-2 * (x * x + y * y)) +
                       1.5 * std::sin(9 * x) * std::cos(7 * y);
      h = std::min(h, static_cast<float>(surface));
    }
  return map;
}

// A zig-zag raster of short ball-end moves over a map.
std::vector<CutMove> raster(const ZMap& map, int lines, int per_line) {
  const ZMapGrid& g = map.grid;
  float top = *std::max_element(map.heights.begin(), map.heights.end());
  std::vector<CutMove> moves;
  auto point = [&](double s, double t) {
    double x = g.x(0) + s * (g.x(g.nx - 1) - g.x(0)), y = g.y(0) + t * (g.y(g.ny - 1) - g.y(0));
    return Vec3(x, y, top - 3 + 2 * std::sin(x / 7) * std::cos(y / 9));
  };
  for (int l = 0; l < lines; ++l)
    for (int k = 0; k < per_line; ++k) {
      double t = double(l) / (lines - 1);
      moves.push_back(
          {Segment{point(double(k) / per_line, t), point(double(k + 1) / per_line, t)}, 0});
    }
  return moves;
}

void BM_dexelize(benchmark::State& state) {
  const auto backend = static_cast<be::DexelBackend>(state.range(0));
  const int points = static_cast<int>(state.range(1));
  static ZMap map;
  static int made = 0;
  if (made != points) map = mold_map(30, points), made = points;
  const DexelLattice lattice = DexelLattice::covering_resolution(kStock, 256);
  for (auto _ : state) {
    TripleDexel d = backend == be::DexelBackend::tree   ? dexelize(map, lattice)
                    : backend == be::DexelBackend::scan ? scan_dexelize(map, lattice)
                                                        : be::embree_dexelize(map, lattice);
    benchmark::DoNotOptimize(d.grids[0].intervals.data());
  }
  state.SetLabel(be::to_string(backend));
  state.counters["zmap_points"] = double(map.grid.size());
}
BENCHMARK(BM_dexelize)
    ->ArgsProduct({{int(be::DexelBackend::tree), int(be::DexelBackend::embree),
                    int(be::DexelBackend::scan)},
                   {1000, 2000}})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

void BM_mill(benchmark::State& state) {
  const auto backend = static_cast<be::ZMapBackend>(state.range(0));
  const ZMap initial = ZMap::from_box(Frame{}, kStock, 0.1);
  const std::vector<CutMove> moves = raster(initial, 100, 100);
  const Cutter ball = Cutter::ball(2);
  for (auto _ : state) {
    state.PauseTiming();
    ZMap map = initial;
    state.ResumeTiming();
    be::mill_with(backend, map, std::span(&ball, 1), moves);
    benchmark::DoNotOptimize(map.heights.data());
  }
  state.SetLabel(be::to_string(backend));
  state.counters["moves"] = double(moves.size());
}
BENCHMARK(BM_mill)
    ->Arg(int(be::ZMapBackend::cpu))
    ->Arg(int(be::ZMapBackend::gl))
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
