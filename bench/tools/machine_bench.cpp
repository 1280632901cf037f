// The machine check (issue 33, tools/cli/checks/machine_check.hpp): seconds per 10⁵ moves and
// distance queries per move, with a machine of about 100 k triangles and a vise of 10 k.
//
// Workload: the bc-trunnion profile's kinematics with its parts finely tessellated (each box face
// a grid of squares, each cylinder 4096 facets): a bed (19,200 triangles), the trunnion's cradle
// (a C housing, a floor and two side plates: 48,784), the platter (16,384) and a spindle nose on
// the spindle (16,384): 100,752 in all; a vise of two jaws and a base (9,804) as a fixture; a
// D10 flat end's flutes (96) with a 110 mm gauge length. The program: a part 100 × 60 × 40 in the
// vise, cut at B0 C0 by a zig-zag of 1 mm moves 2 mm above the jaws' top and 6 mm from them,
// every 200 moves a rapid up and over and, every 2000, an indexed turn of B and C (to B30 C90 and
// back). Arguments: moves; 1 = bounded search and bound reuse (the default), 0 = exact distances
// every query (the first version). Counters: s_per_1e5_moves, queries_per_move.
#include <benchmark/benchmark.h>

#include <chrono>
#include <vector>

#include "checks/machine_check.hpp"
#include "tridex/gcode/machine.hpp"

namespace {

using namespace tridex;
using namespace tridex::cli;

// A box whose every face is an n × n grid of squares (12 n² triangles).
Mesh grid_box(const Vec3& lo, const Vec3& hi, int n) {
  Mesh m;
  const Vec3 size = hi - lo;
  for (int axis = 0; axis < 3; ++axis)
    for (int side = 0; side < 2; ++side) {
      const int u = (axis + 1) % 3, w = (axis + 2) % 3;
      const auto base = static_cast<unsigned>(m.positions.size());
      for (int i = 0; i <= n; ++i)
        for (int j = 0; j <= n; ++j) {
          Vec3 p = lo;
          p[axis] += side * size[axis];
          p[u] += size[u] * i / n, p[w] += size[w] * j / n;
          m.positions.emplace_back(p);
        }
      for (unsigned i = 0; i < unsigned(n); ++i)
        for (unsigned j = 0; j < unsigned(n); ++j) {
          const unsigned a = base + i * (n + 1) + j, b = a + n + 1;
          if (side == 0)
            m.triangles.emplace_back(a, a + 1, b), m.triangles.emplace_back(b, a + 1, b + 1);
          else
            m.triangles.emplace_back(a, b, a + 1), m.triangles.emplace_back(b, b + 1, a + 1);
        }
    }
  return m;
}

MachineBody bench_body(const std::string& name, Link link, const Mesh& mesh) {
  MachineBody b;
  b.name = name, b.group = "bench", b.link = link;
  b.tree = std::make_shared<const TriangleTree>(mesh);
  return b;
}

std::size_t triangles(const MachineCheck& check, const std::string& group_name) {
  std::size_t n = 0;
  for (const MachineBody& b : check.bodies())
    if (b.name.rfind(group_name, 0) == 0) n += b.tree->size();
  return n;
}

void BM_machine_check(benchmark::State& state) {
  const auto moves = static_cast<int>(state.range(0));
  const gcode::MachineConfig machine = *gcode::MachineConfig::bundled("bc-trunnion");
  MachineCheck check(machine.kinematics, {true, true, true}, machine.collision);
  check.set_bounded_search(state.range(1) != 0);
  const Link bed{LinkKind::bed, 0}, b_axis{LinkKind::table, 1}, c_axis{LinkKind::table, 2};
  check.add(bench_body("machine bed", bed, grid_box({-600, -400, -500}, {600, 400, -420}, 40)));
  check.add(bench_body("machine cradle", b_axis,
                       merge_meshes({make_frustum_mesh(100, 100, -110, -30, 4096),
                                     grid_box({-90, -210, -110}, {90, 210, -85}, 30),
                                     grid_box({-110, -210, -110}, {110, -180, -20}, 30),
                                     grid_box({-110, 180, -110}, {110, 210, -20}, 30)})));
  check.add(bench_body("machine platter", c_axis, make_frustum_mesh(100, 100, -30, 0, 4096)));
  check.add(
      bench_body("machine nose", {LinkKind::spindle, 0}, make_frustum_mesh(45, 45, 0, 150, 4096)));
  check.add(bench_body("vise", {LinkKind::work, 0},
                       merge_meshes({grid_box({-60, -55, 0}, {60, -35, 40}, 12),
                                     grid_box({-60, 35, 0}, {60, 55, 40}, 12),
                                     grid_box({-70, -60, -10}, {70, 60, 0}, 23)})));
  check.add(bench_body("tool 1 flutes", {LinkKind::tool, 0}, make_frustum_mesh(5, 5, 0, 40)));
  state.counters["machine_triangles"] = double(triangles(check, "machine"));
  state.counters["vise_triangles"] = double(triangles(check, "vise"));

  // The program as moves (no TCP: B and C index, the linear axes move straight).
  std::vector<MachineMove> program;
  MachineState at;
  at.x = Vec3(-40, -29, 60);
  auto go = [&](MachineState to) {
    MachineMove m;
    m.line = int(program.size()) + 1, m.tool = 1, m.gauge = 110, m.from = at, m.to = to;
    program.push_back(m);
    at = to;
  };
  for (int k = 0; program.size() < std::size_t(moves); ++k) {
    MachineState next = at;
    if (k % 2000 == 1999) {
      next.rotary[1] = 30, next.rotary[2] = 90, next.x = Vec3(0, 0, 150);
      go(next);
      next.rotary = {}, go(next);
    } else if (k % 200 == 199) {
      next.x.z = 60, go(next);
      next.x = Vec3(-40, -29, 60), go(next);
      next.x.z = 42, go(next);
    } else {
      const int row = (k % 200) / 40, column = k % 40;
      next.x = Vec3((row % 2 ? 40 - column : column - 40) * 1.0, -29 + 2.0 * row, 42);
      go(next);
    }
  }
  program.resize(std::size_t(moves));
  double seconds = 0;
  long long queries = 0, collisions = 0;
  for (auto _ : state) {
    MachineFindings found;
    const auto start = std::chrono::steady_clock::now();
    for (const MachineMove& m : program) check.check(m, found);
    seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    queries += found.queries, collisions += static_cast<long long>(found.collisions.size());
  }
  const double runs = double(state.iterations());
  state.counters["s_per_1e5_moves"] = seconds / runs / moves * 1e5;
  state.counters["queries_per_move"] = double(queries) / runs / moves;
  state.counters["collisions"] = double(collisions) / runs;
}

}  // namespace

BENCHMARK(BM_machine_check)
    ->Args({100000, 1})
    ->Args({5000, 1})
    ->Args({5000, 0})
    ->Unit(benchmark::kMillisecond)
    ->Iterations(1);

BENCHMARK_MAIN();
