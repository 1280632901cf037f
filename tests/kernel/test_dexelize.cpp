#include <doctest/doctest.h>

#include <map>
#include <random>
#include <set>

#include "test_dexel_shapes.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/mesh_check.hpp"

using namespace tridex;
using namespace tridex_test;

namespace {

double surface_area(const Mesh& m) {
  double area = 0;
  for (const glm::uvec3& t : m.triangles)
    area += 0.5 * glm::length(glm::cross(Vec3(m.positions[t.y]) - Vec3(m.positions[t.x]),
                                         Vec3(m.positions[t.z]) - Vec3(m.positions[t.x])));
  return area;
}

// Every ray of `d` against the brute-force crossings of `m` (rays in general position only).
void check_rays_against_brute_force(const TripleDexel& d, const Mesh& m, int& compared,
                                    int stride = 1) {
  for (int a = 0; a < 3; ++a) {
    int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
    const DexelGrid& g = d.grids[a];
    for (int iv = 0; iv < g.nv; iv += stride)
      for (int iu = 0; iu < g.nu; iu += stride) {
        Vec3 o(0), dir(0);
        o[u] = d.origin[u] + d.spacing * iu, o[v] = d.origin[v] + d.spacing * iv;
        dir[a] = 1;
        if (distance_to_edges(m, o, dir) < 1e-5) continue;
        std::vector<double> hits = brute_force_hits(m, o, dir);
        auto ray = g.ray(iu, iv);
        REQUIRE(hits.size() % 2 == 0);
        REQUIRE(ray.size() * 2 == hits.size());
        for (std::size_t k = 0; k < ray.size(); ++k) {
          CHECK(ray[k].enter == doctest::Approx(hits[2 * k]).epsilon(1e-5));
          CHECK(ray[k].exit == doctest::Approx(hits[2 * k + 1]).epsilon(1e-5));
        }
        ++compared;
      }
  }
}

}  // namespace

TEST_CASE(
    "dexelize mesh: box, sphere, cylinder, torus — rays match brute force, volume within the "
    "spacing") {
  std::mt19937 rng(21);
  std::uniform_real_distribution<double> unit(0, 1);
  int compared = 0;
  for (int trial = 0; trial < 8; ++trial) {
    Vec3 c(10 * unit(rng) - 5, 10 * unit(rng) - 5, 10 * unit(rng) - 5);
    std::vector<Mesh> shapes{
        box_mesh(c, c + Vec3(1 + 3 * unit(rng), 1 + 3 * unit(rng), 1 + 3 * unit(rng))),
        sphere_mesh(c, 1 + 2 * unit(rng)), cylinder_mesh(c, 1 + unit(rng), 1 + 3 * unit(rng)),
        torus_mesh(c, 2 + unit(rng), 0.5 + 0.5 * unit(rng))};
    for (const Mesh& m : shapes) {
      double s = 0.05 + 0.15 * unit(rng);
      DexelLattice l = DexelLattice::covering(m.bounds(), s);
      l.origin += Vec3(unit(rng), unit(rng), unit(rng)) * (0.3 * s);  // off any symmetry
      TripleDexel d = dexelize(m, l, {.threads = 1 + static_cast<unsigned>(trial % 3)});
      validate(d);
      double exact = m.signed_volume();
      CHECK(std::abs(volume(d) - exact) <= 0.5 * surface_area(m) * s);
      check_rays_against_brute_force(d, m, compared, 3);
    }
  }
  CHECK(compared > 5000);
}

TEST_CASE("dexelize mesh: the volume error shrinks with the spacing") {
  Mesh m = sphere_mesh(Vec3(0.3, -0.2, 0.1), 2.0, 96, 48);
  double exact = m.signed_volume(), previous = 1e9;
  for (double s : {0.4, 0.1, 0.025}) {
    double error = std::abs(volume(dexelize(m, DexelLattice::covering(m.bounds(), s))) - exact);
    CHECK(error < 0.5 * previous + 1e-3);
    previous = error;
  }
  CHECK(previous < 1e-3 * exact);
}

namespace {

// A solid made of unit voxels, its faces between filled and empty cells triangulated with a
// random diagonal, vertices at integers and shared. Rays of a lattice with integer origin and
// spacing 1 run exactly along voxel edges and through voxel corners.
struct Voxels {
  int n;
  std::vector<char> filled;
  bool at(int x, int y, int z) const {
    if (x < 0 || y < 0 || z < 0 || x >= n || y >= n || z >= n) return false;
    return filled[static_cast<std::size_t>(x + n * (y + n * z))] != 0;
  }
};

Mesh voxel_mesh(const Voxels& vox, std::mt19937& rng) {
  Mesh m;
  std::map<std::tuple<int, int, int>, std::uint32_t> index;
  auto vertex = [&](glm::ivec3 p) {
    auto [it, inserted] =
        index.try_emplace({p.x, p.y, p.z}, static_cast<std::uint32_t>(m.positions.size()));
    if (inserted)
      m.positions.emplace_back(static_cast<float>(p.x), static_cast<float>(p.y),
                               static_cast<float>(p.z));
    return it->second;
  };
  for (int z = 0; z < vox.n; ++z)
    for (int y = 0; y < vox.n; ++y)
      for (int x = 0; x < vox.n; ++x) {
        if (!vox.at(x, y, z)) continue;
        for (int a = 0; a < 3; ++a)
          for (int side = 0; side < 2; ++side) {
            glm::ivec3 cell(x, y, z), step(0);
            step[a] = side ? 1 : -1;
            glm::ivec3 nb = cell + step;
            if (vox.at(nb.x, nb.y, nb.z)) continue;
            int u = (a + 1) % 3, v = (a + 2) % 3;
            glm::ivec3 base = cell;
            base[a] += side;
            glm::ivec3 eu(0), ev(0);
            eu[u] = 1, ev[v] = 1;
            // Counter-clockwise seen from outside (+a side: u then v; −a side: reversed).
            std::uint32_t q[4] = {vertex(base), vertex(base + eu), vertex(base + eu + ev),
                                  vertex(base + ev)};
            if (!side) std::swap(q[1], q[3]);
            if (rng() & 1) {
              m.triangles.emplace_back(q[0], q[1], q[2]),
                  m.triangles.emplace_back(q[0], q[2], q[3]);
            } else {
              m.triangles.emplace_back(q[1], q[2], q[3]),
                  m.triangles.emplace_back(q[1], q[3], q[0]);
            }
          }
      }
  return m;
}

}  // namespace

TEST_CASE(
    "dexelize mesh: rays exactly through vertices and along edges neither lose nor double a hit") {
  std::mt19937 rng(77);
  for (int trial = 0; trial < 25; ++trial) {
    Voxels vox{7, {}};
    vox.filled.resize(7 * 7 * 7);
    for (char& f : vox.filled) f = (rng() % 100) < 45;
    Mesh m = voxel_mesh(vox, rng);
    int count = 0;
    for (char f : vox.filled) count += f;
    // Integer lattice: every ray lies on voxel edges; the perturbation (u + ε, v + ε²) puts ray
    // (iu, iv) inside the voxel column (iu, iv) for the u, v axes.
    DexelLattice l{Vec3(-1), 1.0, glm::ivec3(10)};
    TripleDexel d = dexelize(m, l);
    validate(d);
    CHECK(volume(d) == doctest::Approx(count));
    for (int a = 0; a < 3; ++a) {
      int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
      for (int iv = 0; iv < 10; ++iv)
        for (int iu = 0; iu < 10; ++iu) {
          std::vector<DexelInterval> expected;
          for (int k = 0; k < 7; ++k) {
            glm::ivec3 c(0);
            c[a] = k, c[u] = iu - 1, c[v] = iv - 1;
            if (!vox.at(c.x, c.y, c.z)) continue;
            if (!expected.empty() && expected.back().exit == float(k))
              expected.back().exit = float(k + 1);
            else
              expected.push_back({float(k), float(k + 1)});
          }
          auto ray = d.grids[a].ray(iu, iv);
          REQUIRE(ray.size() == expected.size());
          for (std::size_t k = 0; k < ray.size(); ++k) {
            CHECK(ray[k].enter == expected[k].enter);
            CHECK(ray[k].exit == expected[k].exit);
          }
        }
    }
    // Half-integer origin: rays through face centres and, for the third family, along faces.
    DexelLattice half{Vec3(-0.5), 0.5, glm::ivec3(17)};
    CHECK(volume(dexelize(m, half)) == doctest::Approx(count).epsilon(0.2));
  }
}

TEST_CASE("dexelize mesh: an octahedron with rays through its vertices") {
  // Vertices at (±2, 0, 0), (0, ±2, 0), (0, 0, ±2): integer lattice rays hit vertices and edges.
  Mesh m;
  for (Vec3 p : {Vec3(2, 0, 0), Vec3(-2, 0, 0), Vec3(0, 2, 0), Vec3(0, -2, 0), Vec3(0, 0, 2),
                 Vec3(0, 0, -2)})
    add_vertex(m, p);
  for (std::uint32_t x : {0u, 1u})
    for (std::uint32_t y : {2u, 3u})
      for (std::uint32_t z : {4u, 5u}) {
        glm::uvec3 t(x, y, z);
        // Outward: the normal must point along (sx, sy, sz); flip when the octant is odd.
        bool odd = (x == 1) ^ (y == 3) ^ (z == 5);
        m.triangles.push_back(odd ? glm::uvec3(x, z, y) : t);
      }
  REQUIRE(check_mesh(m).closed());
  REQUIRE(m.signed_volume() == doctest::Approx(32.0 / 3));
  for (double s : {1.0, 0.5, 0.25}) {
    TripleDexel d = dexelize(m, DexelLattice{Vec3(-3), s, glm::ivec3(static_cast<int>(6 / s) + 1)});
    validate(d);
    // Along x at (y, z): |x| ≤ 2 − |y| − |z| for the perturbed ray (y + ε, z + ε²); the perturbed
    // ray hits iff |y| + |z| < 2, or = 2 with the perturbation pointing inside.
    for (int iv = 0; iv < d.grids[0].nv; ++iv)
      for (int iu = 0; iu < d.grids[0].nu; ++iu) {
        double y = -3 + s * iu, z = -3 + s * iv;
        double half = 2 - std::abs(y) - std::abs(z);
        auto ray = d.grids[0].ray(iu, iv);
        if (half > 0) {
          REQUIRE(ray.size() == 1);
          CHECK(ray[0].enter == doctest::Approx(-half));
          CHECK(ray[0].exit == doctest::Approx(half));
        } else if (half < 0) {
          CHECK(ray.empty());
        }
      }
  }
}

TEST_CASE("dexelize mesh: open or inside-out meshes are errors naming the ray") {
  Mesh m = box_mesh(Vec3(0), Vec3(2));
  DexelLattice l = DexelLattice::covering(m.bounds(), 0.25);
  Mesh open = m;
  open.triangles.pop_back();
  CHECK_THROWS_WITH_AS(dexelize(open, l), doctest::Contains("not closed"), Error);
  Mesh inverted = m;
  for (glm::uvec3& t : inverted.triangles) std::swap(t.y, t.z);
  CHECK_THROWS_AS(dexelize(inverted, l), Error);
  Mesh bad = m;
  bad.positions[0].x = std::numeric_limits<float>::quiet_NaN();
  CHECK_THROWS_WITH_AS(dexelize(bad, l), doctest::Contains("vertex 0"), Error);
  CHECK(interval_count(dexelize(Mesh{}, l)) == 0);
}

TEST_CASE("dexelize mesh: two overlapping closed shells unite") {
  Mesh a = box_mesh(Vec3(0), Vec3(2)), b = box_mesh(Vec3(1, 1, 1), Vec3(3, 3, 3));
  Mesh both = a;
  auto base = static_cast<std::uint32_t>(both.positions.size());
  both.positions.insert(both.positions.end(), b.positions.begin(), b.positions.end());
  for (glm::uvec3 t : b.triangles) both.triangles.push_back(t + glm::uvec3(base));
  DexelLattice l = DexelLattice::covering(both.bounds(), 0.1);
  l.origin += Vec3(0.013, 0.027, 0.041);
  TripleDexel d = dexelize(both, l);
  CHECK(volume(d) == doctest::Approx(8 + 8 - 1).epsilon(0.05));
  TripleDexel u = unite(dexelize(a, l), dexelize(b, l));
  CHECK(volume(d) == doctest::Approx(volume(u)).epsilon(1e-9));
}
