// Surface extraction (surface.hpp) on a mold-like solid whose triple dexel is built directly
// from an analytic height field: a block with a pocket (vertical walls, wavy floor), two round
// bosses, ball-end dimples, a slot and chamfered rims — the kind of part a 3+2 program leaves.
//
// z rays are exact ([bottom, f(x, y)]); x and y rays cross a piecewise-linear profile of f
// sampled four times per spacing, so the three families disagree slightly near steep walls, as
// dexels from different Z-maps do. Counters: triangles, vertices, and the process's peak
// resident set (getrusage ru_maxrss) before and after extraction, and the dexel's and the
// mesh's own sizes.
#include <benchmark/benchmark.h>

#include <sys/resource.h>

#include <algorithm>
#include <cmath>
#include <map>
#include <memory>
#include <vector>

#include "tridex/surface.hpp"

using namespace tridex;

namespace {

constexpr double kPi = 3.14159265358979323846;

double peak_rss_mib() {
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  return double(usage.ru_maxrss) / 1024.0;  // kilobytes on Linux
}

// The part: footprint [0, L]² (world units mm), bottom at z = 0, height field f(x, y) ≤ 60.
struct Mold {
  double size = 100;
  double height(double x, double y) const {
    double X = x / size, Y = y / size;
    double f = 60;
    // Chamfered rim: 45° over the outer 3 mm.
    double edge = std::min({x, y, size - x, size - y});
    f = std::min(f, 57 + edge);
    // Ball-end dimples (radius 4 mm) on the top face.
    const double dimples[4][2] = {{0.07, 0.08}, {0.93, 0.08}, {0.07, 0.5}, {0.93, 0.5}};
    for (const auto& d : dimples) {
      double r2 = (X - d[0]) * (X - d[0]) * size * size + (Y - d[1]) * (Y - d[1]) * size * size;
      if (r2 < 16) f = std::min(f, 63 - std::sqrt(25 - r2));  // sphere R 5 centred 3 mm above
    }
    // A slot 3 mm wide, 10 mm deep.
    if (Y > 0.9 && Y < 0.93 && X > 0.05 && X < 0.95) f = std::min(f, 50.0);
    // The pocket: rounded rectangle, vertical walls, wavy floor, two bosses.
    double px = std::max({0.15 - X, X - 0.85, 0.0}), py = std::max({0.2 - Y, Y - 0.8, 0.0});
    double cx = std::clamp(X, 0.23, 0.77), cy = std::clamp(Y, 0.28, 0.72);
    bool in_pocket = px == 0 && py == 0 && std::hypot(X - cx, Y - cy) < 0.08;
    if (in_pocket) {
      double floor = 35 + 4 * std::sin(2 * kPi * 3 * X) * std::cos(2 * kPi * 2 * Y);
      const double bosses[2][2] = {{0.35, 0.5}, {0.65, 0.5}};
      for (const auto& b : bosses)
        if (std::hypot(X - b[0], Y - b[1]) < 0.06) floor = 52;
      f = floor;
    }
    return f;
  }
};

// The triple dexel of {0 ≤ z ≤ f(x, y), (x, y) in the footprint} on a lattice with `cells`
// spacings across the part and a margin of two nodes on every side.
TripleDexel build_mold(int cells) {
  Mold mold;
  const double h = mold.size / cells;
  DexelLattice lattice{Vec3(-2 * h), h,
                       glm::ivec3(cells + 5, cells + 5, int(std::ceil(65 / h)) + 5)};
  TripleDexel d = TripleDexel::empty(lattice);
  auto node = [&](int a, int m) { return lattice.origin[a] + h * m; };
  const double lo = 0, hi = mold.size;
  // z rays.
  {
    DexelGrid& g = d.grids[2];
    for (int j = 0; j < g.nv; ++j)
      for (int i = 0; i < g.nu; ++i) {
        double x = node(0, i), y = node(1, j);
        if (x > lo && x < hi && y > lo && y < hi)
          g.intervals.push_back({0.0f, float(mold.height(x, y))});
        g.offsets[g.ray_index(i, j) + 1] = static_cast<std::uint32_t>(g.intervals.size());
      }
  }
  // x rays (a = 0: u = y, v = z) and y rays (a = 1: u = z, v = x): per line of the footprint, a
  // profile of f; its crossings with every node level go to that level's ray.
  for (int a = 0; a < 2; ++a) {
    DexelGrid& g = d.grids[a];
    const int lines = lattice.n[1 - a], levels = lattice.n.z;
    std::vector<std::vector<DexelInterval>> rays(g.ray_count());
    const int samples = 4 * cells;
    std::vector<double> t(samples + 1), f(samples + 1);
    std::vector<float> open(levels);
    for (int line = 0; line < lines; ++line) {
      double w = node(1 - a, line);
      if (!(w > lo && w < hi)) continue;
      for (int m = 0; m <= samples; ++m) {
        t[m] = lo + (hi - lo) * m / samples;
        f[m] = a == 0 ? mold.height(t[m], w) : mold.height(w, t[m]);
      }
      auto ray_of = [&](int k) { return a == 0 ? g.ray_index(line, k) : g.ray_index(k, line); };
      for (int k = 0; k < levels; ++k)
        if (node(2, k) >= 0 && node(2, k) <= f[0]) open[k] = float(t[0]);
      for (int m = 0; m < samples; ++m) {
        double f0 = f[m], f1 = f[m + 1];
        if (f0 == f1) continue;
        int k0 = std::max(0, int(std::ceil((std::min(f0, f1) - lattice.origin.z) / h)));
        int k1 = std::min(levels - 1, int(std::floor((std::max(f0, f1) - lattice.origin.z) / h)));
        for (int k = k0; k <= k1; ++k) {
          double z = node(2, k);
          if (z < 0) continue;
          bool rising = f1 > f0;
          if (rising ? !(f0 < z && z <= f1) : !(f1 < z && z <= f0)) continue;
          float x = float(t[m] + (t[m + 1] - t[m]) * (z - f0) / (f1 - f0));
          if (rising)
            open[k] = x;
          else if (x > open[k])
            rays[ray_of(k)].push_back({open[k], x});
        }
      }
      for (int k = 0; k < levels; ++k)
        if (node(2, k) >= 0 && node(2, k) <= f[samples] && float(t[samples]) > open[k])
          rays[ray_of(k)].push_back({open[k], float(t[samples])});
    }
    for (std::size_t r = 0; r < rays.size(); ++r) {
      g.intervals.insert(g.intervals.end(), rays[r].begin(), rays[r].end());
      g.offsets[r + 1] = static_cast<std::uint32_t>(g.intervals.size());
    }
  }
  return d;
}

struct CachedMold {
  TripleDexel dexel;
  double rss_after_build_mib;  // the process's peak once the dexel exists, before any extraction
};

const CachedMold& mold_dexel(int cells) {
  static std::map<int, std::unique_ptr<CachedMold>> cache;
  auto& slot = cache[cells];
  if (!slot) {
    TripleDexel d = build_mold(cells);
    slot = std::make_unique<CachedMold>(CachedMold{std::move(d), peak_rss_mib()});
  }
  return *slot;
}

double dexel_mib(const TripleDexel& d) {
  double bytes = 0;
  for (const DexelGrid& g : d.grids)
    bytes += double(g.offsets.size() * sizeof(std::uint32_t) +
                    g.intervals.size() * sizeof(DexelInterval));
  return bytes / (1024.0 * 1024.0);
}

void BM_extract_surface(benchmark::State& state) {
  const CachedMold& mold = mold_dexel(int(state.range(0)));
  const TripleDexel& d = mold.dexel;
  SurfaceOptions options;
  options.threads = unsigned(state.range(1));
  options.sharp_features = state.range(2) != 0;
  std::size_t triangles = 0, vertices = 0;
  for (auto _ : state) {
    Mesh m = extract_surface(d, options);
    triangles = m.triangles.size(), vertices = m.positions.size();
    benchmark::DoNotOptimize(m.triangles.data());
  }
  state.counters["nodes_x"] = d.n.x;
  state.counters["nodes_z"] = d.n.z;
  state.counters["triangles"] = double(triangles);
  state.counters["vertices"] = double(vertices);
  state.counters["dexel_MiB"] = dexel_mib(d);
  state.counters["mesh_MiB"] =
      double(triangles * sizeof(glm::uvec3) + vertices * sizeof(glm::vec3)) / (1024.0 * 1024.0);
  // Peak resident set of the whole process (ru_maxrss): run one configuration per process to
  // read it as "dexel + extraction"; rss_before_MiB is the peak before the first extraction.
  state.counters["rss_before_MiB"] = mold.rss_after_build_mib;
  state.counters["peak_rss_MiB"] = peak_rss_mib();
}

}  // namespace

// Arguments: cells across the part, threads, sharp features (1) or plain marching cubes (0).
// 1018 cells → 1023 × 1023 × 667 nodes, about the lattice of the paper's model D.
BENCHMARK(BM_extract_surface)
    ->Args({256, 2, 1})
    ->Args({1018, 1, 0})
    ->Args({1018, 1, 1})
    ->Args({1018, 2, 0})
    ->Args({1018, 2, 1})
    ->Unit(benchmark::kMillisecond)
    ->UseRealTime();

BENCHMARK_MAIN();
