// Benchmarks of the `tridex` command on the bundled example (gcode/examples/mold_3plus2.*), and
// the shank and holder check on it and on the paper-scale workload (bench/backends/workload.hpp).
#include <benchmark/benchmark.h>

#include <sys/resource.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>

#include "../backends/workload.hpp"
#include "commands.hpp"
#include "inputs/program_input.hpp"
#include "json_text.hpp"
#include "pipeline/pipeline.hpp"
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
  state.counters["moves/s"] =
      benchmark::Counter(static_cast<double>(moves), benchmark::Counter::kIsRate);
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
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tridex-bench-" + std::to_string(::getpid()));
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

// Steps 1-3 of `simulate` on the example with fine cells at the walls (second argument 1) or
// without (0), at --dexel-res RES (first argument): what the refinement (fine_cells.hpp) costs.
// Counters: Step 1 (zmap_s), the maps' preparation for Step 2 with the refinement
// (prepare_s: raise_uncut, refine_steep_cells, the stock's triple dexel), Steps 2-3 (intersect_s,
// where the scan converter reads the fine cells).
void BM_simulate_fine_cells(benchmark::State& state) {
  cli::SimulateOptions options;
  options.quiet = true;
  options.program = kExamples + "mold_3plus2.camotics";
  options.dexel_res = static_cast<int>(state.range(0));
  cli::PipelineRequest request;
  request.fine_cells = state.range(1) != 0;
  cli::Progress progress(false);
  for (auto _ : state) {
    cli::SimulationResult r = cli::simulate_program(options, progress, request);
    state.counters["zmap_s"] = r.timings.zmap;
    state.counters["prepare_s"] = r.timings.dexelize;
    state.counters["intersect_s"] = r.timings.intersect;
    state.counters["steps123_s"] = r.timings.zmap + r.timings.dexelize + r.timings.intersect;
  }
}
BENCHMARK(BM_simulate_fine_cells)
    ->Args({cli::kDefaultDexelRes, 0})
    ->Args({cli::kDefaultDexelRes, 1})
    ->Args({640, 0})
    ->Args({640, 1})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

// A tool table whose tools (the given cutters) all have 25 mm flutes, a shank of their diameter,
// 40 mm out of a Ø40 × 30 mm holder body under a cone widening to Ø63 over 20 mm.
std::string tools_with_holders(const std::vector<std::pair<int, std::string>>& cutters) {
  std::string text = "{";
  for (const auto& [number, cutter] : cutters)
    text += (text.size() > 1 ? ",\n" : "\n") + std::string("\"") + std::to_string(number) +
            "\": {" + cutter +
            ", \"flute-length\": 25, \"stick-out\": 40, \"holder\": [{\"bottom-diameter\": 40, "
            "\"top-diameter\": 40, \"length\": 30}, {\"bottom-diameter\": 40, \"top-diameter\": "
            "63, \"length\": 20}]}";
  return text + "}";
}

// `check`'s pipeline (every direction milled in program order, rapids checked) with the shank and
// holder check (second argument 1) or without (0): on the example (first argument 0, at
// --dexel-res 320) or on the paper-scale workload of that many thousand segments (--dexel-res 512).
void BM_collision_check(benchmark::State& state) {
  std::filesystem::path dir =
      std::filesystem::temp_directory_path() / ("tridex-bench-cc-" + std::to_string(::getpid()));
  std::filesystem::create_directories(dir);
  cli::SimulateOptions options;
  options.quiet = true;
  options.tools = (dir / "tools.json").string();
  if (state.range(0) == 0) {
    options.program = kExamples + "mold_3plus2.camotics";
    options.dexel_res = cli::kDefaultDexelRes;
    std::ofstream(options.tools) << tools_with_holders(
        {{1, R"("shape": "cylindrical", "diameter": 10)"},
         {2, R"("shape": "ballnose", "diameter": 8)"},
         {3, R"("shape": "ballnose", "diameter": 4)"},
         {4, R"("shape": "ballnose", "diameter": 2)"}});
  } else {
    options.program = (dir / "workload.nc").string();
    std::FILE* out = std::fopen(options.program.c_str(), "w");
    bench::write_workload(out, state.range(0) * 1000);
    std::fclose(out);
    options.stock = "box:0,0,0,200,200,130";
    options.dexel_res = 512;
    std::ofstream(options.tools) << tools_with_holders(
        {{1, R"("shape": "cylindrical", "diameter": 10)"},
         {2, R"("shape": "bullnose", "diameter": 8, "corner-radius": 1)"},
         {3, R"("shape": "ballnose", "diameter": 6)"},
         {4, R"("shape": "ballnose", "diameter": 3)"}});
  }
  cli::PipelineRequest request;
  request.rapid_check = cli::RapidCheck::in_program_order;
  if (state.range(1)) request.body_clearance = cli::kDefaultClearance;
  cli::Progress progress(false);
  for (auto _ : state) {
    cli::SimulationResult r = cli::simulate_program(options, progress, request);
    state.counters["zmap_s"] = r.timings.zmap;
    state.counters["body_s"] = r.body.seconds;
    state.counters["collisions"] = static_cast<double>(r.body.collisions.size());
    state.counters["near_misses"] = static_cast<double>(r.body.near_misses.size());
    state.counters["segments"] = static_cast<double>(r.segments);
  }
  std::filesystem::remove_all(dir);
}
BENCHMARK(BM_collision_check)
    ->Args({0, 0})
    ->Args({0, 1})
    ->Args({500, 0})
    ->Args({500, 1})
    ->Args({5000, 0})  // the paper's size (its model D has 5.17 M segments)
    ->Args({5000, 1})
    ->Unit(benchmark::kSecond)
    ->Iterations(1);

}  // namespace

BENCHMARK_MAIN();
