// Steps 2 and 3 of the method (Inui, Chen and Umezu, CAD&A 19(4) 2022): Z-map → triple dexel
// through the grid tree, and the intersection of six models with the stock.
//
// Workload: a 150 × 150 × 100 mm box stock; a triple-dexel lattice with 1021 cells across its
// longest side (1024 × 1024 × 684 nodes, 0.147 mm); six spindle directions (+Z, and tilted 30°
// towards ±X and ±Y, and 45° towards +X+Y), each with a Z-map of 5000 points across its longer
// side, "milled" by an analytic mold-like surface (a deep round pocket, a ridge and waves) so that
// every map has cut and uncut regions. Maps are built once, outside the timed region.
// Counters: peak_rss_MiB is the process's ru_maxrss (cumulative: run one benchmark per process,
// with --benchmark_filter, for a per-step figure, which then includes its inputs: a Z-map of
// 25 M points is 100 MB); cpu_s is processor time per iteration over all threads.
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <cmath>
#include <memory>
#include <vector>

#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/intersect_milled.hpp"

namespace {

using namespace tridex;

const Aabb kStock{Vec3(0), Vec3(150, 150, 100)};

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;  // Linux: kilobytes
}

Frame direction(int i) {
  switch (i) {
    case 0:
      return Frame{};
    case 1:
      return Frame::from_rotation(rotation_y(30), kStock.center());
    case 2:
      return Frame::from_rotation(rotation_y(-30), kStock.center());
    case 3:
      return Frame::from_rotation(rotation_x(30), kStock.center());
    case 4:
      return Frame::from_rotation(rotation_x(-30), kStock.center());
    default:
      return Frame::from_rotation(rotation_z(45) * rotation_y(45) * rotation_z(-45),
                                  kStock.center());
  }
}

// A Z-map of the stock in direction i with about 5000 points across, lowered to a mold-like
// surface below the stock's top.
ZMap mold_map(int i) {
  Frame frame = direction(i);
  Aabb local = local_bounds(frame, kStock);
  double cell = std::max(local.max.x - local.min.x, local.max.y - local.min.y) / 4998.0;
  ZMap map = ZMap::from_box(frame, kStock, cell);
  const ZMapGrid& g = map.grid;
  double cx = 0.5 * (local.min.x + local.max.x) + 10 * i,
         cy = 0.5 * (local.min.y + local.max.y) - 7 * i;
  for (int j = 0; j < g.ny; ++j)
    for (int k = 0; k < g.nx; ++k) {
      float& h = map.heights[g.index(k, j)];
      if (h <= map.empty_height) continue;
      double x = g.x(k), y = g.y(j);
      double r2 = ((x - cx) * (x - cx) + (y - cy) * (y - cy)) / (40.0 * 40.0);
      double surface = local.max.z - 4 - 30 * std::max(0.0, 1 - r2) -
                       2 * std::sin(x / 7) * std::cos(y / 9) -
                       8 * std::exp(-std::pow((x - cx + 50) / 6, 2));
      h = std::max(map.empty_height, std::min(h, static_cast<float>(surface)));
    }
  return map;
}

// Each direction's map is built on first use, so that a benchmark's peak memory counts only the
// maps it needs.
const ZMap& map_of(int i) {
  static std::unique_ptr<ZMap> built[6];
  if (!built[i]) built[i] = std::make_unique<ZMap>(mold_map(i));
  return *built[i];
}

const std::vector<ZMap>& maps() {
  static const std::vector<ZMap> all = [] {
    std::vector<ZMap> m;
    for (int i = 0; i < 6; ++i) m.push_back(mold_map(i));
    return m;
  }();
  return all;
}

// Processor time of the whole process (all threads), in seconds: on a shared machine this is
// steadier than wall time.
double process_cpu_s() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
         1e-6 * static_cast<double>(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

const DexelLattice& lattice() {
  static const DexelLattice l = DexelLattice::covering_resolution(kStock, 1021);
  return l;
}

void report(benchmark::State& state, const TripleDexel& d, double cpu_start) {
  state.counters["cpu_s"] = (process_cpu_s() - cpu_start) / static_cast<double>(state.iterations());
  state.counters["peak_rss_MiB"] = peak_rss_mib();
  state.counters["intervals"] = static_cast<double>(interval_count(d));
  state.counters["nodes"] = static_cast<double>(d.n.x) * d.n.y * d.n.z;
}

// Step 2: one 5000-point Z-map → triple dexel. Arguments: direction (0 = +Z, 5 = 45° tilt),
// threads (0 = all).
void step2_dexelize_zmap(benchmark::State& state) {
  const ZMap& map = map_of(static_cast<int>(state.range(0)));
  TripleDexel d;
  double cpu_start = process_cpu_s();
  for (auto _ : state) {
    d = dexelize(map, lattice(), {.threads = static_cast<unsigned>(state.range(1))});
    benchmark::DoNotOptimize(d.grids[0].intervals.data());
  }
  state.counters["zmap_points"] = static_cast<double>(map.grid.size());
  report(state, d, cpu_start);
}

// Step 3: the stock ∩ six dexelized models, on the 1024 × 1024 × 684 lattice (the models are
// dexelized once, outside the timed region).
void step3_intersect_six(benchmark::State& state) {
  static const std::vector<TripleDexel> models = [] {
    std::vector<TripleDexel> m;
    for (const ZMap& map : maps()) m.push_back(dexelize(map, lattice()));
    return m;
  }();
  const TripleDexel stock = TripleDexel::box(lattice(), kStock);
  TripleDexel result;
  double cpu_start = process_cpu_s();
  for (auto _ : state) {
    result = stock;
    for (const TripleDexel& m : models)
      result = intersect(result, m, static_cast<unsigned>(state.range(0)));
    benchmark::DoNotOptimize(result.grids[0].intervals.data());
  }
  report(state, result, cpu_start);
  state.counters["volume_mm3"] = volume(result);
}

// Steps 2 + 3 fused, as the pipeline runs them: intersect_milled() on six maps.
void machine_six(benchmark::State& state) {
  const std::vector<ZMap>& all = maps();
  TripleDexel result;
  double cpu_start = process_cpu_s();
  for (auto _ : state) {
    result = intersect_milled(kStock, lattice(), all, static_cast<unsigned>(state.range(0)));
    benchmark::DoNotOptimize(result.grids[0].intervals.data());
  }
  report(state, result, cpu_start);
  state.counters["volume_mm3"] = volume(result);
}

// A stock mesh (sphere, 20 k triangles) dexelized on a 512-cell lattice: the path for STL stock.
void dexelize_mesh_sphere(benchmark::State& state) {
  Mesh m;
  const int slices = 160, stacks = 64;
  const double r = 50;
  m.positions.emplace_back(0.0f, 0.0f, static_cast<float>(-r));
  for (int s = 1; s < stacks; ++s) {
    double phi = M_PI * s / stacks - M_PI / 2;
    for (int k = 0; k < slices; ++k) {
      double theta = 2 * M_PI * k / slices;
      m.positions.emplace_back(static_cast<float>(r * std::cos(phi) * std::cos(theta)),
                               static_cast<float>(r * std::cos(phi) * std::sin(theta)),
                               static_cast<float>(r * std::sin(phi)));
    }
  }
  m.positions.emplace_back(0.0f, 0.0f, static_cast<float>(r));
  auto at = [&](int s, int k) {
    return static_cast<std::uint32_t>(1 + (s - 1) * slices + (k % slices));
  };
  auto north = static_cast<std::uint32_t>(m.positions.size() - 1);
  for (int k = 0; k < slices; ++k) {
    m.triangles.emplace_back(0u, at(1, k + 1), at(1, k));
    m.triangles.emplace_back(north, at(stacks - 1, k), at(stacks - 1, k + 1));
    for (int s = 1; s + 1 < stacks; ++s) {
      m.triangles.emplace_back(at(s, k), at(s, k + 1), at(s + 1, k + 1));
      m.triangles.emplace_back(at(s, k), at(s + 1, k + 1), at(s + 1, k));
    }
  }
  DexelLattice l = DexelLattice::covering_resolution(m.bounds(), 509);
  TripleDexel d;
  double cpu_start = process_cpu_s();
  for (auto _ : state) {
    d = dexelize(m, l, {.threads = static_cast<unsigned>(state.range(0))});
    benchmark::DoNotOptimize(d.grids[0].intervals.data());
  }
  state.counters["triangles"] = static_cast<double>(m.triangles.size());
  report(state, d, cpu_start);
}

}  // namespace

BENCHMARK(step2_dexelize_zmap)
    ->Args({0, 0})
    ->Args({5, 0})
    ->Args({5, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();
BENCHMARK(step3_intersect_six)->Arg(0)->Arg(1)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(machine_six)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();
BENCHMARK(dexelize_mesh_sphere)->Arg(0)->Unit(benchmark::kMillisecond)->UseRealTime();

BENCHMARK_MAIN();
