// A program outside the project that uses the installed kernel: mills one plunge into a box.
#include <cstdio>
#include <vector>

#include <tridex/mill.hpp>

int main() {
  using namespace tridex;
  ZMap map = ZMap::from_box(Frame{}, Aabb{Vec3(0), Vec3(10, 10, 5)}, 0.5);
  std::vector<Cutter> cutters{Cutter::ball(2.0)};
  std::vector<CutMove> moves{{Segment{Vec3(5, 5, 10), Vec3(5, 5, 3)}, 0}};
  mill(map, cutters, moves);
  int i = static_cast<int>((5 - map.grid.x0) / map.grid.cell + 0.5);
  int j = static_cast<int>((5 - map.grid.y0) / map.grid.cell + 0.5);
  float centre = map.height(i, j);
  std::printf("height at the plunge: %g\n", static_cast<double>(centre));
  return centre == 3.0f ? 0 : 1;
}
