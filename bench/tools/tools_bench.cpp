// Benchmarks of the `tridex` command on the bundled example (gcode/examples/mold_3plus2.*).
#include <benchmark/benchmark.h>

#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "commands.hpp"
#include "json_text.hpp"
#include "program_input.hpp"
#include "render.hpp"

using namespace tridex;

namespace {

const std::string kExamples = TRIDEX_SOURCE_DIR "/gcode/examples/";

double peak_rss_mib() {
  rusage usage{};
  ::getrusage(RUSAGE_SELF, &usage);
  return static_cast<double>(usage.ru_maxrss) / 1024.0;
}

// Interpreting the example and formatting every move as `tridex moves` does (to memory).
void BM_moves_json_lines(benchmark::State& state) {
  cli::CommonOptions options;
  options.program = kExamples + "mold_3plus2.nc";
  cli::ProgramInput input = cli::resolve_program(options);
  long long moves = 0;
  std::size_t bytes = 0;
  for (auto _ : state) {
    std::string record;
    cli::interpret(input, {}, [&](const gcode::Move& m, std::size_t) {
      record.clear();
      cli::append_vec3(record, m.start);
      cli::append_vec3(record, m.end);
      cli::append_vec3(record, m.axis);
      cli::append_number(record, m.feed);
      bytes += record.size();
      ++moves;
    });
  }
  benchmark::DoNotOptimize(bytes);
  state.counters["moves/s"] = benchmark::Counter(static_cast<double>(moves), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_moves_json_lines)->Unit(benchmark::kMillisecond);

// A wavy closed surface of about 2·n² triangles (a torus with ripples), rendered off-screen.
Mesh ripple_torus(int n) {
  Mesh mesh;
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      double u = 2 * M_PI * i / n, v = 2 * M_PI * j / n;
      double r = 10 + 0.5 * std::sin(12 * u) * std::cos(9 * v);
      mesh.positions.emplace_back(static_cast<float>((30 + r * std::cos(v)) * std::cos(u)),
                                  static_cast<float>((30 + r * std::cos(v)) * std::sin(u)),
                                  static_cast<float>(r * std::sin(v)));
    }
  auto at = [n](int i, int j) { return static_cast<unsigned>(((i + n) % n) * n + (j + n) % n); };
  for (int i = 0; i < n; ++i)
    for (int j = 0; j < n; ++j) {
      mesh.triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      mesh.triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  return mesh;
}

void BM_render_mesh(benchmark::State& state) {
  Mesh mesh = ripple_torus(static_cast<int>(state.range(0)));
  for (auto _ : state) {
    render::Image image = render::render_mesh(mesh);
    benchmark::DoNotOptimize(image.rgb.data());
  }
  state.counters["triangles"] = static_cast<double>(mesh.triangles.size());
}
BENCHMARK(BM_render_mesh)->Arg(250)->Arg(600)->Unit(benchmark::kMillisecond);

// `tridex simulate` on the example's project with the given --dexel-res and --zmap-cell (µm),
// writing the STL, the picture and the report to a scratch folder; the command's own timings
// of each stage become counters.
void BM_simulate_example(benchmark::State& state) {
  std::filesystem::path dir = std::filesystem::temp_directory_path() / ("tridex-bench-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  cli::SimulateOptions options;
  options.program = kExamples + "mold_3plus2.camotics";
  options.dexel_res = static_cast<int>(state.range(0));
  options.zmap_cell = state.range(1) > 0 ? static_cast<double>(state.range(1)) / 1000.0 : 0.0;
  options.output = (dir / "example.stl").string();
  options.png = (dir / "example.png").string();
  options.report = (dir / "example.json").string();
  options.quiet = true;
  for (auto _ : state) cli::run_simulate(options);
  auto report = cli::Json::parse(std::ifstream(options.report));
  for (const char* stage : {"zmap", "intersect", "mesh"})
    state.counters[std::string(stage) + "_s"] = report["timings_s"][stage].get<double>();
  state.counters["triangles"] = report["result"]["triangles"].get<double>();
  state.counters["peak_rss_MiB"] = peak_rss_mib();
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_simulate_example)
    ->Args({128, 300})
    ->Args({cli::kDefaultDexelRes, 0})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
