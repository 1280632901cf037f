#include <doctest/doctest.h>

#include <cmath>
#include <random>
#include <string>

#include "helpers.hpp"
#include "tridex/backends/backends.hpp"
#include "tridex/backends/gl_mill.hpp"

using namespace tridex;
using namespace backend_tests;

namespace {

// A cutter kind with the two references that bracket its tessellation P (C ⊖ B_ε ⊂ P ⊂ C):
// `outer` contains C, its tip `outer_drop` lower (a dilation by δ, for float rounding of the
// drawn vertices); `inner` is C's erosion by ε, its tip `inner_lift` higher.
struct Bracket {
  Cutter cutter, outer, inner;
  double outer_drop, inner_lift;
};

Bracket bracket(int kind, double eps, double delta) {
  const double R = 0.5;
  switch (kind) {
    case 0:
      return {Cutter::flat(R), Cutter::bull_nose(R + delta, delta), Cutter::flat(R - eps), delta,
              eps};
    case 1:
      return {Cutter::ball(R), Cutter::ball(R + delta), Cutter::ball(R - eps), delta, eps};
    case 2:
      return {Cutter::bull_nose(R, 0.2), Cutter::bull_nose(R + delta, 0.2 + delta),
              Cutter::bull_nose(R - eps, 0.2 - eps), delta, eps};
    default: {  // chamfer: flat tip r0, then a 40° cone; erosion keeps a flat tip of r0'
      const double r0 = 0.2, alpha = glm::radians(40.0);
      double r0_inner = r0 - eps * std::cos(alpha) + eps * (1 - std::sin(alpha)) * std::tan(alpha);
      return {Cutter::chamfer(R, r0, 40), Cutter::chamfer(R + delta, r0 + delta, 40),
              Cutter::chamfer(R - eps, r0_inner, 40), delta, eps};
    }
  }
}

std::vector<CutMove> random_moves(std::mt19937& rng, const ZMap& map, int count) {
  std::uniform_real_distribution<double> unit(0, 1);
  const ZMapGrid& g = map.grid;
  auto point = [&] {
    return Vec3(g.x(0) + unit(rng) * (g.x(g.nx - 1) - g.x(0)),
                g.y(0) + unit(rng) * (g.y(g.ny - 1) - g.y(0)), 0.6 + 1.2 * unit(rng));
  };
  std::vector<CutMove> moves;
  for (int k = 0; k < count; ++k) {
    Vec3 a = point(), b = point();
    if (k % 4 == 1) b.z = a.z;                // level
    if (k % 4 == 2) b = Vec3(a.x, a.y, b.z);  // plunge or retract
    if (k % 7 == 3) b = a;                    // a point
    moves.push_back({Segment{a, b}, 0});
  }
  return moves;
}

std::vector<CutMove> shifted(std::vector<CutMove> moves, double dz) {
  for (CutMove& m : moves) m.tip.a.z += dz, m.tip.b.z += dz;
  return moves;
}

}  // namespace

TEST_CASE(
    "gl milling is bracketed by the exact milling of the cutter and of its erosion by the "
    "tolerance") {
  if (!backends::gl_available()) {
    MESSAGE("no OSMesa float depth framebuffer here: skipped");
    return;
  }
  std::mt19937 rng(404);
  const double eps = 0.02, delta = 1e-3, tau = 1e-5;
  const Aabb stock{Vec3(0, 0, 0), Vec3(5, 3.5, 2)};
  for (int kind = 0; kind < 4; ++kind)
    for (int tiled = 0; tiled < 2; ++tiled) {
      Bracket b = bracket(kind, eps, delta);
      ZMap initial = ZMap::from_box(Frame{}, stock, 0.05);
      std::vector<CutMove> moves = random_moves(rng, initial, 14);
      ZMap gl = initial, exact = initial, outer = initial, inner = initial;
      backends::gl_mill(gl, std::span(&b.cutter, 1), moves,
                        {.tolerance = eps, .max_tile = tiled ? 32 : 0});
      mill(exact, std::span(&b.cutter, 1), moves);
      auto lowered = shifted(moves, -b.outer_drop), raised = shifted(moves, b.inner_lift);
      mill(outer, std::span(&b.outer, 1), lowered);
      mill(inner, std::span(&b.inner, 1), raised);
      std::size_t below = 0, above = 0, cut = 0;
      double mean_error = 0;
      for (std::size_t k = 0; k < gl.heights.size(); ++k) {
        if (gl.heights[k] < outer.heights[k] - tau) ++below;
        if (gl.heights[k] > inner.heights[k] + tau) ++above;
        if (exact.heights[k] < initial.heights[k]) ++cut;
        mean_error += std::abs(double(gl.heights[k]) - exact.heights[k]);
      }
      mean_error /= double(gl.heights.size());
      INFO("cutter ", b.cutter.name(), std::string(tiled ? " tiled" : ""), ": below ", below,
           " above ", above, " cut ", cut, " mean |gl - cpu| ", mean_error);
      CHECK(below == 0);
      CHECK(above == 0);
      CHECK(cut > gl.heights.size() / 10);
      CHECK(mean_error < eps);
    }
}

TEST_CASE(
    "gl milling of a tilted frame's map through mill_with, tiled, agrees with cpu within the "
    "tolerance") {
  if (!backends::gl_available()) return;
  std::mt19937 rng(9);
  const Aabb stock{Vec3(0, 0, 0), Vec3(4, 3, 2)};
  ZMap map = ZMap::from_box(random_frame(rng, true), stock, 0.05);
  std::vector<Cutter> cutters{Cutter::ball(0.4), Cutter::flat(0.3), Cutter::bull_nose(0.5, 0.1)};
  std::uniform_real_distribution<double> unit(0, 1);
  std::vector<CutMove> moves;
  const ZMapGrid& g = map.grid;
  float top = *std::max_element(map.heights.begin(), map.heights.end());
  for (int k = 0; k < 30; ++k) {
    auto point = [&] {
      return Vec3(g.x(0) + unit(rng) * (g.x(g.nx - 1) - g.x(0)),
                  g.y(0) + unit(rng) * (g.y(g.ny - 1) - g.y(0)), top - 1.5 * unit(rng));
    };
    moves.push_back({Segment{point(), point()}, static_cast<std::uint32_t>(k % 3)});
  }
  ZMap gl = map, cpu = map;
  backends::gl_mill(gl, cutters, moves, {.tolerance = 0.01, .max_tile = 40});
  backends::mill_with(backends::ZMapBackend::cpu, cpu, cutters, moves);
  // Where the surface is not steep the difference is at most the tolerance.
  std::size_t close = 0;
  for (std::size_t k = 0; k < gl.heights.size(); ++k)
    close += std::abs(gl.heights[k] - cpu.heights[k]) <= 0.01 + 1e-5;
  CHECK(close >= gl.heights.size() * 98 / 100);
  ZMap via_api = map;
  backends::mill_with(backends::ZMapBackend::gl, via_api, cutters,
                      moves);  // default tolerance cell / 4
  std::size_t close_api = 0;
  for (std::size_t k = 0; k < gl.heights.size(); ++k)
    close_api += std::abs(via_api.heights[k] - cpu.heights[k]) <= 0.0125 + 1e-5;
  CHECK(close_api >= gl.heights.size() * 98 / 100);
}

TEST_CASE("gl milling rejects bad input with clear errors") {
  ZMap map = ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(2)}, 0.1);
  Cutter ball = Cutter::ball(0.5);
  std::vector<CutMove> moves{{Segment{Vec3(1, 1, 1), Vec3(1.5, 1, 1)}, 3}};
  CHECK_THROWS_WITH_AS(backends::gl_mill(map, std::span(&ball, 1), moves),
                       doctest::Contains("cutter 3"), Error);
  moves[0].cutter = 0;
  CHECK_THROWS_WITH_AS(backends::gl_mill(map, std::span(&ball, 1), moves, {.tolerance = -1}),
                       doctest::Contains("tolerance"), Error);
  moves[0].tip.b.x = std::nan("");
  CHECK_THROWS_WITH_AS(backends::gl_mill(map, std::span(&ball, 1), moves),
                       doctest::Contains("not finite"), Error);
}

// Mesa keeps a few small allocations of its global state until exit (not ours): tell
// LeakSanitizer, in an ASan build, so that the suite's exit status reflects our code.
extern "C" const char* __lsan_default_suppressions() { return "leak:libOSMesa.so\nleak:libLLVM\n"; }
