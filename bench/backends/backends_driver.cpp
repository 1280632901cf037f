// tridex bench — every backend on one paper-scale workload, one table (Inui, Chen and Umezu,
// CAD&A 19(4) 2022, Table 1: Step 1 Z-map milling, Step 2 Z-map → triple dexel, Step 3
// Boolean intersection; plus surface extraction, total and peak memory).
//
// The program is parsed once (the G-code front end), its moves grouped by spindle direction
// and kept as tool-tip segments in each direction's frame. Each backend configuration then runs
// in forked processes, so that its peak resident memory (getrusage) is its own: a child per
// Z-map backend mills one Z-map per direction (Step 1, once), then a grandchild per dexel
// backend dexelizes each map on the stock's lattice (Step 2) and intersects the results with
// the stock (Step 3), as the paper splits them, and once more fused through machine_with (what
// `tridex simulate` runs: each ray cut by every map in turn, rays already empty skipped), then
// extracts the surface. Figures are medians
// over --runs runs; the backends of one run share the machine's state, so compare them as
// ratios within one table.
//
//   bench_backends_driver --segments 1460000 --runs 3            (model-A-like, full size)
//   bench_backends_driver --segments 200000 --zmap 1500 --dexel 300   (a quick run)
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <stdexcept>
#include <string>
#include <vector>

#include "tridex/backends/backends.hpp"
#include "tridex/backends/embree_dexelize.hpp"
#include "tridex/backends/gl_mill.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "tridex/mill.hpp"
#include "tridex/scan_dexelize.hpp"
#include "tridex/surface.hpp"
#include "workload.hpp"

using namespace tridex;
namespace be = tridex::backends;

namespace {

struct Options {
  long long segments = 1'460'000;
  std::string program;  // read this instead of generating
  std::string write = "/tmp/tridex_workload.nc";
  int zmap = 5000;   // Z-map points along the stock's longest side
  int dexel = 1023;  // lattice cells along the stock's longest side
  int runs = 1;
  unsigned threads = 0;
  double gl_tolerance = 0;  // 0: a quarter of the Z-map cell
  bool fused = true;
  std::string
      maps;  // cache of the cpu backend's milled maps: saved after Step 1, loaded if present
  bench::WorkloadVariant variant;  // of the program written (--sloped-roughing, --balls-only)
  std::vector<std::pair<be::ZMapBackend, be::DexelBackend>> configs;
};

struct Group {
  Vec3 axis;
  Frame frame;
  std::vector<CutMove> moves;
};

struct Result {
  double step1 = 0, step2 = 0, step3 = 0, fused = 0, surface = 0;
  double peak_mib = 0, volume = 0, fused_volume = 0;
  long long triangles = 0;
  int ok = 0;
  char error[200] = {};
};

double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

[[noreturn]] void usage(const char* message) {
  std::fprintf(stderr,
               "%s\nusage: bench_backends_driver [--segments N | --program FILE] [--write FILE] "
               "[--zmap N] [--dexel N]\n"
               "       [--runs R] [--threads T] [--gl-tolerance E] [--no-fused] [--maps DIR] "
               "[--configs cpu+scan,cpu+tree,...]\n"
               "       [--sloped-roughing] [--balls-only]   (variants of the program written)\n",
               message);
  std::exit(2);
}

Options parse(int argc, char** argv) {
  Options o;
  std::string configs = "cpu+scan,cpu+tree,cpu+embree,gl+scan";
  for (int k = 1; k < argc; ++k) {
    std::string a = argv[k];
    auto value = [&]() -> std::string {
      if (k + 1 >= argc) usage(("missing value after " + a).c_str());
      return argv[++k];
    };
    if (a == "--segments")
      o.segments = std::stoll(value());
    else if (a == "--program")
      o.program = value();
    else if (a == "--write")
      o.write = value();
    else if (a == "--zmap")
      o.zmap = std::stoi(value());
    else if (a == "--dexel")
      o.dexel = std::stoi(value());
    else if (a == "--runs")
      o.runs = std::stoi(value());
    else if (a == "--threads")
      o.threads = static_cast<unsigned>(std::stoul(value()));
    else if (a == "--gl-tolerance")
      o.gl_tolerance = std::stod(value());
    else if (a == "--no-fused")
      o.fused = false;
    else if (a == "--sloped-roughing")
      o.variant.sloped_roughing = true;
    else if (a == "--balls-only")
      o.variant.balls_only = true;
    else if (a == "--maps")
      o.maps = value();
    else if (a == "--configs")
      configs = value();
    else
      usage(("unknown option " + a).c_str());
  }
  if (o.segments < 1 || o.zmap < 2 || o.dexel < 1 || o.runs < 1)
    usage("sizes and counts must be positive");
  for (std::size_t at = 0; at <= configs.size();) {
    std::size_t end = std::min(configs.find(',', at), configs.size());
    std::string item = configs.substr(at, end - at);
    std::size_t plus = item.find('+');
    if (plus == std::string::npos) usage(("a config is ZMAP+DEXEL, got " + item).c_str());
    o.configs.emplace_back(be::parse_zmap_backend(item.substr(0, plus)),
                           be::parse_dexel_backend(item.substr(plus + 1)));
    at = end + 1;
  }
  return o;
}

TripleDexel dexelize_with(be::DexelBackend backend, const ZMap& map, const DexelLattice& lattice,
                          unsigned threads) {
  switch (backend) {
    case be::DexelBackend::tree:
      return dexelize(map, lattice, {.threads = threads});
    case be::DexelBackend::embree:
      return be::embree_dexelize(map, lattice, threads);
    case be::DexelBackend::scan:
      return scan_dexelize(map, lattice, threads);
  }
  throw std::logic_error("invalid dexel backend");
}

// The milled maps as raw files (grid, then heights), so that Steps 2-3 can be rerun at full size
// without Step 1.
std::string map_path(const std::string& dir, std::size_t k) {
  return dir + "/map_" + std::to_string(k) + ".bin";
}

void save_maps(const std::string& dir, const std::vector<ZMap>& maps) {
  for (std::size_t k = 0; k < maps.size(); ++k) {
    std::ofstream out(map_path(dir, k), std::ios::binary);
    const ZMap& m = maps[k];
    out.write(reinterpret_cast<const char*>(&m.grid), sizeof m.grid);
    out.write(reinterpret_cast<const char*>(&m.empty_height), sizeof m.empty_height);
    out.write(reinterpret_cast<const char*>(m.heights.data()),
              static_cast<std::streamsize>(m.heights.size() * sizeof(float)));
    if (!out) throw std::runtime_error("cannot write " + map_path(dir, k));
  }
}

bool load_maps(const std::string& dir, std::size_t count, std::vector<ZMap>& maps) {
  for (std::size_t k = 0; k < count; ++k) {
    std::ifstream in(map_path(dir, k), std::ios::binary);
    if (!in) return false;
    ZMap m;
    in.read(reinterpret_cast<char*>(&m.grid), sizeof m.grid);
    in.read(reinterpret_cast<char*>(&m.empty_height), sizeof m.empty_height);
    m.heights.resize(m.grid.size());
    in.read(reinterpret_cast<char*>(m.heights.data()),
            static_cast<std::streamsize>(m.heights.size() * sizeof(float)));
    if (!in) return false;
    maps.push_back(std::move(m));
  }
  return true;
}

// Step 1 with one Z-map backend: one milled map per direction.
std::vector<ZMap> mill_all(const Options& o, be::ZMapBackend zb, const std::vector<Group>& groups,
                           const std::vector<Cutter>& cutters) {
  const Aabb stock = bench::workload_stock();
  const Vec3 size = stock.size();
  const double cell = std::max({size.x, size.y, size.z}) / (o.zmap - 1);
  std::vector<ZMap> maps;
  for (const Group& g : groups) {
    maps.push_back(ZMap::from_box(g.frame, stock, cell));
    if (zb == be::ZMapBackend::gl)
      be::gl_mill(maps.back(), cutters, g.moves, {.tolerance = o.gl_tolerance});
    else
      be::mill_with(zb, maps.back(), cutters, g.moves, o.threads);
  }
  return maps;
}

// Steps 2, 3 (split as the paper does, and fused through machine_with) and the surface.
Result run_dexel(const Options& o, be::DexelBackend db, std::vector<ZMap>& maps) {
  Result r;
  const Aabb stock = bench::workload_stock();
  const DexelLattice lattice = DexelLattice::covering_resolution(stock, o.dexel);
  TripleDexel result = TripleDexel::box(lattice, stock);
  for (const ZMap& map : maps) {
    auto t = std::chrono::steady_clock::now();
    TripleDexel m = dexelize_with(db, map, lattice, o.threads);
    r.step2 += seconds_since(t);
    t = std::chrono::steady_clock::now();
    result = intersect(result, m, o.threads);
    r.step3 += seconds_since(t);
  }
  r.volume = volume(result);
  if (o.fused) {
    TripleDexel w0 = TripleDexel::box(lattice, stock);
    auto t = std::chrono::steady_clock::now();
    TripleDexel fused = be::machine_with(db, w0, maps, o.threads);
    r.fused = seconds_since(t);
    r.fused_volume = volume(fused);
  }
  maps.clear();
  maps.shrink_to_fit();
  auto t = std::chrono::steady_clock::now();
  Mesh mesh = extract_surface(result, {.threads = o.threads});
  r.surface = seconds_since(t);
  r.triangles = static_cast<long long>(mesh.triangles.size());
  rusage usage{};
  getrusage(RUSAGE_SELF, &usage);
  r.peak_mib = double(usage.ru_maxrss) / 1024.0;
  r.ok = 1;
  return r;
}

// Runs `work` in a child process and returns the Results it writes back; `count` of them.
template <class Work>
std::vector<Result> in_child(std::size_t count, Work&& work) {
  int pipe_fd[2];
  if (pipe(pipe_fd) != 0) throw std::runtime_error("pipe failed");
  std::fflush(stdout), std::fflush(stderr);
  pid_t child = fork();
  if (child < 0) throw std::runtime_error("fork failed");
  if (child == 0) {
    close(pipe_fd[0]);
    std::vector<Result> out(count);
    try {
      out = work();
    } catch (const std::exception& e) {
      for (Result& r : out) std::snprintf(r.error, sizeof r.error, "%s", e.what());
    }
    out.resize(count);
    ssize_t bytes = static_cast<ssize_t>(count * sizeof(Result));
    ssize_t written = write(pipe_fd[1], out.data(), static_cast<std::size_t>(bytes));
    _exit(written == bytes ? 0 : 1);
  }
  close(pipe_fd[1]);
  std::vector<Result> results(count);
  std::size_t got = 0, want = count * sizeof(Result);
  while (got < want) {
    ssize_t n = read(pipe_fd[0], reinterpret_cast<char*>(results.data()) + got, want - got);
    if (n <= 0) break;
    got += static_cast<std::size_t>(n);
  }
  close(pipe_fd[0]);
  int status = 0;
  waitpid(child, &status, 0);
  if (got != want)
    for (Result& r : results)
      r = Result{}, std::snprintf(r.error, sizeof r.error, "child died (status %d)", status);
  return results;
}

// One Z-map backend in a child (Step 1 once), each dexel backend in a grandchild of its own,
// so that each reports its own peak memory (the milled maps included).
std::vector<Result> run_zmap_backend(const Options& o, be::ZMapBackend zb,
                                     const std::vector<be::DexelBackend>& dbs,
                                     const std::vector<Group>& groups,
                                     const std::vector<Cutter>& cutters) {
  return in_child(dbs.size(), [&] {
    auto t = std::chrono::steady_clock::now();
    std::vector<ZMap> maps;
    double step1 = -1;  // loaded, not measured
    if (o.maps.empty() || zb != be::ZMapBackend::cpu || !load_maps(o.maps, groups.size(), maps)) {
      maps = mill_all(o, zb, groups, cutters);
      step1 = seconds_since(t);
      if (!o.maps.empty() && zb == be::ZMapBackend::cpu) save_maps(o.maps, maps);
    }
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    const double step1_peak =
        double(usage.ru_maxrss) / 1024.0;  // the gl context's buffers included
    std::vector<Result> out;
    for (be::DexelBackend db : dbs) {
      Result r = in_child(1, [&] { return std::vector<Result>{run_dexel(o, db, maps)}; })[0];
      r.step1 = step1;
      r.peak_mib = std::max(r.peak_mib, step1_peak);
      out.push_back(r);
    }
    return out;
  });
}

double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  std::size_t n = v.size();
  return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

int main(int argc, char** argv) {
  Options o = parse(argc, argv);
  std::string path = o.program;
  if (path.empty()) {
    auto t = std::chrono::steady_clock::now();
    std::FILE* out = std::fopen(o.write.c_str(), "w");
    if (!out) usage(("cannot write " + o.write).c_str());
    long long written = bench::write_workload(out, o.segments, o.variant);
    std::fclose(out);
    std::printf("wrote %s: %lld G01 segments in %.1f s\n", o.write.c_str(), written,
                seconds_since(t));
    path = o.write;
  }
  // Parse once; group by spindle direction as tridex::gcode::group_by_direction does.
  std::vector<Cutter> cutters;
  for (const auto& tool : bench::workload_tools()) cutters.push_back(tool.cutter);
  std::vector<Group> groups;
  long long moves = 0;
  auto t = std::chrono::steady_clock::now();
  {
    std::ifstream in(path);
    if (!in) usage(("cannot read " + path).c_str());
    gcode::Interpreter interpreter;
    const double cos_tolerance = std::cos(glm::radians(1e-3));
    interpreter.run(in, path, [&](const gcode::Move& m) {
      if (m.tool < 1 || m.tool > static_cast<int>(cutters.size()))
        throw std::runtime_error("move on line " + std::to_string(m.line) + " uses tool " +
                                 std::to_string(m.tool) + ", not one of the workload's");
      Group* g = nullptr;
      for (Group& candidate : groups)
        if (glm::dot(candidate.axis, m.axis) >= cos_tolerance) g = &candidate;
      if (!g) {
        groups.push_back({m.axis, Frame::from_axis(m.axis), {}});
        g = &groups.back();
      }
      g->moves.push_back({Segment{g->frame.to_local(m.start), g->frame.to_local(m.end)},
                          static_cast<std::uint32_t>(m.tool - 1)});
      ++moves;
    });
  }
  std::printf("parsed %s: %lld moves in %zu directions in %.1f s\n", path.c_str(), moves,
              groups.size(), seconds_since(t));
  const Aabb stock = bench::workload_stock();
  const DexelLattice lattice = DexelLattice::covering_resolution(stock, o.dexel);
  const Vec3 size = stock.size();
  const double cell = std::max({size.x, size.y, size.z}) / (o.zmap - 1);
  std::printf(
      "Z-map cell %.4f mm (%d points on the longest side); triple dexel %d x %d x %d, spacing %.4f "
      "mm; %d run(s)\n\n",
      cell, o.zmap, lattice.n.x, lattice.n.y, lattice.n.z, lattice.spacing, o.runs);

  std::vector<std::vector<Result>> results(o.configs.size());
  for (int run = 0; run < o.runs; ++run)
    for (be::ZMapBackend zb : {be::ZMapBackend::cpu, be::ZMapBackend::gl}) {
      std::vector<std::size_t> which;
      std::vector<be::DexelBackend> dbs;
      for (std::size_t c = 0; c < o.configs.size(); ++c)
        if (o.configs[c].first == zb) which.push_back(c), dbs.push_back(o.configs[c].second);
      if (dbs.empty()) continue;
      std::vector<Result> got = run_zmap_backend(o, zb, dbs, groups, cutters);
      for (std::size_t k = 0; k < which.size(); ++k) {
        const std::size_t c = which[k];
        if (!got[k].ok) {
          std::fprintf(stderr, "%s+%s failed: %s\n", be::to_string(o.configs[c].first),
                       be::to_string(o.configs[c].second), got[k].error);
          return 1;
        }
        results[c].push_back(got[k]);
      }
    }
  std::printf(
      "| backend (zmap+dexel) | Step 1 (s) | Step 2 (s) | Step 3 (s) | Steps 2+3 fused (s) | "
      "surface (s) | total (s) | peak memory (MiB) | volume (mm³) | triangles |\n");
  std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
  for (std::size_t c = 0; c < o.configs.size(); ++c) {
    auto pick = [&](auto field) {
      std::vector<double> v;
      for (const Result& r : results[c]) v.push_back(field(r));
      return median(v);
    };
    // Step 1: the median of the runs that milled (with --maps, only the first does).
    std::vector<double> milled_runs;
    for (const Result& r : results[c])
      if (r.step1 >= 0) milled_runs.push_back(r.step1);
    double s1 = milled_runs.empty() ? -1 : median(milled_runs),
           s2 = pick([](const Result&r) { return r.step2; });
    double s3 = pick([](const Result&r) { return r.step3; }),
           fu = pick([](const Result&r) { return r.fused; });
    double su = pick([](const Result& r) { return r.surface; });
    double total =
        std::max(0.0, s1) + pick([](const Result& r) { return r.step2 + r.step3 + r.surface; });
    char step1_text[32] = "loaded";
    if (s1 >= 0) std::snprintf(step1_text, sizeof step1_text, "%.2f", s1);
    char fused_text[32] = "-";
    if (o.fused) std::snprintf(fused_text, sizeof fused_text, "%.2f", fu);
    std::printf("| %s+%s | %s | %.2f | %.3f | %s | %.2f | %.2f | %.0f | %.1f | %lld |\n",
                be::to_string(o.configs[c].first), be::to_string(o.configs[c].second), step1_text,
                s2, s3, fused_text, su, total, pick([](const Result& r) { return r.peak_mib; }),
                results[c][0].volume, results[c][0].triangles);
    if (o.fused &&
        std::abs(results[c][0].fused_volume - results[c][0].volume) > 1e-6 * results[c][0].volume)
      std::printf("  (!) fused volume %.3f differs from the split one\n",
                  results[c][0].fused_volume);
  }
  std::printf(
      "\ntotal = Step 1 + Step 2 + Step 3 + surface (the paper's split); medians of %d run(s), "
      "Step 1 over\n"
      "the runs that milled (with --maps only the first does; \"loaded\": none did)\n",
      o.runs);
  return 0;
}
