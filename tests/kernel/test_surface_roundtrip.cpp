// Surface extraction after the mesh dexelizer (dexelize.hpp): a randomly rotated box mesh →
// triple dexel → mesh must be closed and stay within one spacing of the box; and extracting,
// dexelizing the result again and extracting once more must keep the volume.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <random>

#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/surface.hpp"

using namespace tridex;

namespace {

struct RotatedBox {
  Frame frame;  // local → world
  Vec3 half;    // half extents in the local frame
  double sdf(const Vec3& p) const {
    Vec3 q = glm::abs(frame.to_local(p)) - half;
    return glm::length(glm::max(q, Vec3(0))) + std::min(std::max({q.x, q.y, q.z}), 0.0);
  }
  double volume() const { return 8 * half.x * half.y * half.z; }
  double area() const { return 8 * (half.x * half.y + half.y * half.z + half.z * half.x); }
  Mesh mesh() const {
    Mesh m;
    for (int c = 0; c < 8; ++c)
      m.positions.emplace_back(frame.to_world(Vec3(
          (c & 1) ? half.x : -half.x, (c & 2) ? half.y : -half.y, (c & 4) ? half.z : -half.z)));
    for (int a = 0; a < 3; ++a) {
      int u = (a + 1) % 3, v = (a + 2) % 3;
      for (int s = 0; s < 2; ++s) {
        // Counter-clockwise seen from outside: (u, v) = (0,0) (1,0) (1,1) (0,1) on the +a side.
        const int order[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
        unsigned q[4];
        for (int k = 0; k < 4; ++k) {
          const int* uv = order[s ? k : (4 - k) % 4];
          q[k] = unsigned((s << a) | (uv[0] << u) | (uv[1] << v));
        }
        m.triangles.emplace_back(q[0], q[1], q[2]);
        m.triangles.emplace_back(q[0], q[2], q[3]);
      }
    }
    return m;
  }
  Vec3 random_surface_point(std::mt19937& rng) const {
    std::uniform_real_distribution<double> unit(-1, 1);
    std::uniform_int_distribution<int> face(0, 5);
    int f = face(rng), a = f / 2;
    Vec3 local(unit(rng) * half.x, unit(rng) * half.y, unit(rng) * half.z);
    local[a] = (f % 2 ? 1 : -1) * half[a];
    return frame.to_world(local);
  }
};

double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  Vec3 ab = b - a;
  double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}

double triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  Vec3 n = glm::cross(b - a, c - a);
  double nn = glm::dot(n, n);
  if (nn > 0) {
    Vec3 q = p - n * (glm::dot(p - a, n) / nn);  // projection onto the plane
    bool inside = glm::dot(glm::cross(b - a, q - a), n) >= 0 &&
                  glm::dot(glm::cross(c - b, q - b), n) >= 0 &&
                  glm::dot(glm::cross(a - c, q - c), n) >= 0;
    if (inside) return glm::length(p - q);
  }
  return std::min(
      {segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}

double distance_to(const Mesh& m, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const glm::uvec3& t : m.triangles)
    best = std::min(best, triangle_distance(p, Vec3(m.positions[t.x]), Vec3(m.positions[t.y]),
                                            Vec3(m.positions[t.z])));
  return best;
}

RotatedBox random_box(std::mt19937& rng) {
  std::uniform_real_distribution<double> angle(0, 360), extent(1.0, 2.5), shift(-1, 1);
  Mat3 r = rotation_z(angle(rng)) * rotation_x(angle(rng)) * rotation_z(angle(rng));
  return RotatedBox{Frame::from_rotation(r, Vec3(shift(rng), shift(rng), shift(rng))),
                    Vec3(extent(rng), extent(rng), extent(rng))};
}

}  // namespace

TEST_CASE(
    "extract_surface after dexelize: a rotated box comes back closed and within one spacing") {
  std::mt19937 rng(31);
  for (int trial = 0; trial < 6; ++trial) {
    RotatedBox box = random_box(rng);
    Mesh input = box.mesh();
    REQUIRE(check_mesh(input).closed());
    REQUIRE(input.signed_volume() == doctest::Approx(box.volume()));
    double h = std::uniform_real_distribution<double>(0.15, 0.3)(rng);
    TripleDexel d = dexelize(input, DexelLattice::covering(input.bounds(), h));
    for (bool sharp : {false, true}) {
      CAPTURE(sharp);
      Mesh m = extract_surface(d, {.sharp_features = sharp});
      MeshCheck check = check_mesh(m);
      CHECK(check.closed());
      CHECK(check.degenerate_triangles == 0);
      CHECK(std::abs(m.signed_volume() - box.volume()) <= 0.05 * box.area() * h);
      double out = 0, in = 0;
      for (const glm::vec3& p : m.positions) out = std::max(out, std::abs(box.sdf(Vec3(p))));
      for (int q = 0; q < 100; ++q)
        in = std::max(in, distance_to(m, box.random_surface_point(rng)));
      CHECK(out <= h);
      CHECK(in <= h);
    }
  }
}

TEST_CASE("extract_surface after dexelize: extract, dexelize and extract again keeps the volume") {
  std::mt19937 rng(37);
  for (int trial = 0; trial < 4; ++trial) {
    RotatedBox box = random_box(rng);
    const double h = 0.25;
    DexelLattice lattice = DexelLattice::covering(box.mesh().bounds(), h);
    TripleDexel first = dexelize(box.mesh(), lattice);
    Mesh once = extract_surface(first);
    TripleDexel second = dexelize(once, lattice);
    Mesh twice = extract_surface(second);
    CHECK(check_mesh(twice).closed());
    CHECK(std::abs(volume(second) - volume(first)) <= 0.05 * box.area() * h);
    CHECK(std::abs(twice.signed_volume() - once.signed_volume()) <= 0.05 * box.area() * h);
  }
}
