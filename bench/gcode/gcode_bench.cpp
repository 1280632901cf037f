// Throughput of the G-code front end: blocks per second on large generated programs (the issue's
// target: at least 2 million blocks/s on one core). The program text is generated once and read
// from memory through a stream buffer, so the figures are the lexer and interpreter alone.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <istream>
#include <random>
#include <streambuf>
#include <string>

#include "tridex/gcode/grouping.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "tridex/gcode/lexer.hpp"

using namespace tridex::gcode;

namespace {

struct MemoryBuffer : std::streambuf {
  explicit MemoryBuffer(std::string& text) {
    setg(text.data(), text.data(), text.data() + text.size());
  }
};

// A 3-axis finishing program as CAM systems write it: N numbers, G1 with three coordinates of
// three decimals, a feed on some blocks, occasional rapids and arcs.
std::string finishing_program(long long blocks, bool arcs) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> coord(-100, 100), depth(-20, 0);
  std::string text =
      "%\nO1000\nG21 G90 G17 G40 G49 G80\nT1 M6\nS10000 M3\nG0 X0 Y0\nG43 Z10 H1\nF1200\n";
  char line[160];
  double x = 0, y = 0;
  for (long long i = 0; i < blocks; ++i) {
    int kind = static_cast<int>(rng() % 100);
    if (arcs && kind < 10) {
      // A quarter circle of radius 2 around a point to the left (G3).
      double cx = x - 2, cy = y;
      std::snprintf(line, sizeof line, "N%lld G3 X%.3f Y%.3f I-2. J0.\n", i, cx, cy + 2);
      x = cx;
      y = cy + 2;
    } else if (kind < 2) {
      x = coord(rng);
      y = coord(rng);
      std::snprintf(line, sizeof line, "N%lld G0 X%.3f Y%.3f Z5.\n", i, x, y);
    } else {
      x = coord(rng);
      y = coord(rng);
      std::snprintf(line, sizeof line, "N%lld G1 X%.3f Y%.3f Z%.3f%s\n", i, x, y, depth(rng),
                    kind < 20 ? " F1200." : "");
    }
    text += line;
  }
  text += "M30\n%\n";
  return text;
}

// The same kind of program computed by macros: a Fanuc Macro B raster whose every coordinate is an
// expression (five blocks a pass: WHILE, two settings, G1, END), and the finishing program with
// each coordinate written as an expression over parameters.
std::string macro_raster(long long passes) {
  return "%\nO1000\nG21 G90 G17\nT1 M6\nG0 X0 Y0 Z5.\nF1200\n#1 = 0\n#10 = " +
         std::to_string(passes) +
         "\nWHILE [#1 LT #10] DO1\n#2 = [#1 * 0.4]\nG1 X[#2 MOD 100] Y[FIX[#2 / 100] * 0.5] "
         "Z[-1 - SIN[#1] * 0.5]\n#1 = #1 + 1\nEND1\nM30\n%\n";
}

std::string expression_program(long long blocks) {
  std::mt19937_64 rng(1);
  std::uniform_real_distribution<double> coord(-100, 100), depth(-20, 0);
  std::string text =
      "%\nO1000\nG21 G90 G17\nT1 M6\nG0 X0 Y0 Z5.\nF1200\n#1 = 0.5\n#2 = 2.\n#<z> = -1\n";
  char line[200];
  for (long long i = 0; i < blocks; ++i) {
    std::snprintf(line, sizeof line, "N%lld G1 X[%.3f + #1] Y[%.3f * #2] Z[#<z> + %.3f]\n", i,
                  coord(rng), coord(rng) / 2, depth(rng));
    text += line;
  }
  return text + "M30\n%\n";
}

void run_program(benchmark::State& state, std::string& text, long long blocks) {
  InterpreterOptions options;
  Interpreter interpreter(options);
  double sum = 0;
  for (auto _ : state) {
    MemoryBuffer buffer(text);
    std::istream in(&buffer);
    interpreter.run(in, "bench.nc", [&](const Move& m) { sum += m.end.x; });
    benchmark::DoNotOptimize(sum);
  }
  state.counters["blocks/s"] = benchmark::Counter(static_cast<double>(blocks),
                                                  benchmark::Counter::kIsIterationInvariantRate);
  state.counters["MB/s"] = benchmark::Counter(static_cast<double>(text.size()) / 1e6,
                                              benchmark::Counter::kIsIterationInvariantRate);
}

void BM_interpret_macro_loop(benchmark::State& state) {
  static std::string text = macro_raster(200'000);
  run_program(state, text, 200'000 * 5);
}
BENCHMARK(BM_interpret_macro_loop)->Unit(benchmark::kMillisecond);

void BM_interpret_expressions(benchmark::State& state) {
  static std::string text = expression_program(1'000'000);
  run_program(state, text, 1'000'000);
}
BENCHMARK(BM_interpret_expressions)->Unit(benchmark::kMillisecond);

void BM_interpret_linear(benchmark::State& state) {
  static std::string text = finishing_program(1'000'000, false);
  run_program(state, text, 1'000'000);
}
BENCHMARK(BM_interpret_linear)->Unit(benchmark::kMillisecond);

void BM_interpret_with_arcs(benchmark::State& state) {
  static std::string text = finishing_program(1'000'000, true);
  run_program(state, text, 1'000'000);
}
BENCHMARK(BM_interpret_with_arcs)->Unit(benchmark::kMillisecond);

void BM_lex_only(benchmark::State& state) {
  static std::string text = finishing_program(1'000'000, false);
  Block block;
  LexError error;
  for (auto _ : state) {
    std::size_t words = 0, at = 0;
    while (at < text.size()) {
      std::size_t end = text.find('\n', at);
      if (end == std::string::npos) end = text.size();
      lex_line(std::string_view(text).substr(at, end - at), block, error);
      words += block.words.size();
      at = end + 1;
    }
    benchmark::DoNotOptimize(words);
  }
  state.counters["blocks/s"] =
      benchmark::Counter(1e6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_lex_only)->Unit(benchmark::kMillisecond);

void BM_interpret_and_group(benchmark::State& state) {
  static std::string text = finishing_program(1'000'000, false);
  Interpreter interpreter;
  for (auto _ : state) {
    MemoryBuffer buffer(text);
    std::istream in(&buffer);
    DirectionGrouper grouper;
    interpreter.run(in, "bench.nc", [&](const Move& m) { grouper.add(m); });
    benchmark::DoNotOptimize(grouper.groups().data());
  }
  state.counters["blocks/s"] =
      benchmark::Counter(1e6, benchmark::Counter::kIsIterationInvariantRate);
}
BENCHMARK(BM_interpret_and_group)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
