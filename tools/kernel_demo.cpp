// Mills a ball-end raster over a wavy surface into a 60×40×20 mm box and prints the result.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "tridex/mill.hpp"

int main() {
  using namespace tridex;
  const Aabb stock{Vec3(0, 0, 0), Vec3(60, 40, 20)};
  ZMap map = ZMap::from_box(Frame{}, stock, 0.05);
  std::vector<Cutter> cutters{Cutter::ball(3.0)};
  std::vector<CutMove> moves;
  auto surface = [](double x, double y) { return 15 + 2 * std::sin(x / 6) * std::cos(y / 5); };
  for (double y = 0; y <= 40; y += 0.5)
    for (double x = 0; x < 60; x += 0.5)
      moves.push_back({Segment{Vec3(x, y, surface(x, y)), Vec3(x + 0.5, y, surface(x + 0.5, y))}, 0});
  auto start = std::chrono::steady_clock::now();
  mill(map, cutters, moves);
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  double volume = 0;
  for (float h : map.heights) volume += std::max(0.0, double(h)) * 0.05 * 0.05;
  std::printf("milled %zu moves into a %d x %d Z-map in %.3f s; material left about %.0f mm^3\n",
              moves.size(), map.grid.nx, map.grid.ny, seconds, volume);
  return 0;
}
