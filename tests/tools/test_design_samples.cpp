// check's sampling of the design surface (deviation.hpp, design_samples): bounded by its budget
// for any design size — a design of more triangles than the budget used to loop for ever — with
// every sample on the surface.
#include <doctest/doctest.h>

#include <cmath>

#include "checks/deviation.hpp"

using namespace tridex;
using namespace tridex::cli;

namespace {

// A flat n × n grid of unit squares in z = 0, two triangles each.
Mesh grid(int n) {
  Mesh mesh;
  mesh.positions.reserve(static_cast<std::size_t>(n + 1) * static_cast<std::size_t>(n + 1));
  for (int j = 0; j <= n; ++j)
    for (int i = 0; i <= n; ++i) mesh.positions.emplace_back(float(i), float(j), 0.0f);
  mesh.triangles.reserve(2 * static_cast<std::size_t>(n) * static_cast<std::size_t>(n));
  auto at = [&](int i, int j) { return static_cast<std::uint32_t>(j * (n + 1) + i); };
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) {
      mesh.triangles.emplace_back(at(i, j), at(i + 1, j), at(i + 1, j + 1));
      mesh.triangles.emplace_back(at(i, j), at(i + 1, j + 1), at(i, j + 1));
    }
  return mesh;
}

// Every sample in the grid's square (one assertion, not one per sample: there are millions).
void check_on_grid(const std::vector<Vec3>& samples, int n) {
  std::size_t off = 0;
  for (const Vec3& p : samples) off += p.z != 0 || p.x < 0 || p.x > n || p.y < 0 || p.y > n;
  CHECK(off == 0);
}

}  // namespace

TEST_CASE("design samples: a small design is sampled about one step apart, within the budget") {
  const int n = 4;
  Mesh mesh = grid(n);
  std::vector<Vec3> samples = design_samples(mesh, 0.25, 1'000'000);
  // Each triangle's longest edge is √2: n = ⌈√2 / 0.25⌉ = 6, 36 samples per triangle.
  CHECK(samples.size() == mesh.positions.size() + mesh.triangles.size() * 36);
  check_on_grid(samples, n);
  // A budget below that raises the step until the samples fit.
  std::vector<Vec3> fewer = design_samples(mesh, 0.25, 500);
  CHECK(fewer.size() <= 500);
  CHECK(fewer.size() >= mesh.positions.size() + mesh.triangles.size());
  check_on_grid(fewer, n);
}

TEST_CASE("design samples: a 5-million-triangle design stays within the budget and finishes") {
  const int n = 1582;  // 2 · 1582² = 5,005,448 triangles, 2.5 million vertices
  Mesh mesh = grid(n);
  REQUIRE(mesh.triangles.size() > 5'000'000);
  for (std::size_t budget : {std::size_t{4'000'000}, std::size_t{1000}}) {
    CAPTURE(budget);
    std::vector<Vec3> samples = design_samples(mesh, 0.01, budget);
    CHECK(samples.size() <= budget);
    CHECK(samples.size() >= budget * 9 / 10);  // the budget is used, not wasted
    check_on_grid(samples, n);
  }
}
