// Surface extraction (surface.hpp) against analytic solids: triple dexels are built here
// directly from signed distance functions (ray intervals by bracketing and bisection), and the
// extracted mesh is checked for closedness, orientation, degenerate triangles, enclosed volume
// and two-sided Hausdorff distance to the analytic surface.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <optional>
#include <random>
#include <string>
#include <vector>

#include "tridex/dexel_ops.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/surface.hpp"

using namespace tridex;

namespace {

constexpr double kPi = 3.14159265358979323846;

// A solid as a signed distance function (negative inside) plus its exact volume and area.
struct Solid {
  const char* name;
  std::function<double(const Vec3&)> sdf;
  double volume;
  double area;
  Aabb bounds;
};

double sphere_sdf(const Vec3& p, const Vec3& c, double r) { return glm::length(p - c) - r; }
double box_sdf(const Vec3& p, const Vec3& lo, const Vec3& hi) {
  Vec3 c = 0.5 * (lo + hi), e = 0.5 * (hi - lo);
  Vec3 q = glm::abs(p - c) - e;
  return glm::length(glm::max(q, Vec3(0))) + std::min(std::max({q.x, q.y, q.z}), 0.0);
}

Solid sphere(const Vec3& c, double r) {
  return {"sphere", [=](const Vec3& p) { return sphere_sdf(p, c, r); }, 4.0 / 3.0 * kPi * r * r * r,
          4 * kPi * r * r, Aabb{c - Vec3(r), c + Vec3(r)}};
}
Solid box(const Vec3& lo, const Vec3& hi) {
  Vec3 e = hi - lo;
  return {"box", [=](const Vec3& p) { return box_sdf(p, lo, hi); }, e.x * e.y * e.z,
          2 * (e.x * e.y + e.y * e.z + e.z * e.x), Aabb{lo, hi}};
}
Solid cylinder(const Vec3& c, double r, double half_height) {  // axis z
  auto sdf = [=](const Vec3& p) {
    Vec2 d(glm::length(Vec2(p.x - c.x, p.y - c.y)) - r, std::abs(p.z - c.z) - half_height);
    return std::min(std::max(d.x, d.y), 0.0) + glm::length(glm::max(d, Vec2(0)));
  };
  return {"cylinder", sdf, kPi * r * r * 2 * half_height,
          2 * kPi * r * r + 2 * kPi * r * 2 * half_height,
          Aabb{c - Vec3(r, r, half_height), c + Vec3(r, r, half_height)}};
}
Solid torus(const Vec3& c, double major, double minor) {  // axis z
  auto sdf = [=](const Vec3& p) {
    Vec2 q(glm::length(Vec2(p.x - c.x, p.y - c.y)) - major, p.z - c.z);
    return glm::length(q) - minor;
  };
  double rr = major + minor;
  return {"torus", sdf, 2 * kPi * kPi * major * minor * minor, 4 * kPi * kPi * major * minor,
          Aabb{c - Vec3(rr, rr, minor), c + Vec3(rr, rr, minor)}};
}
// Box minus a sphere whose centre is on the top face: a hemispherical pocket of radius r.
Solid pocketed_box(const Vec3& lo, const Vec3& hi, double r) {
  Vec3 c(0.5 * (lo.x + hi.x), 0.5 * (lo.y + hi.y), hi.z);
  Vec3 e = hi - lo;
  auto sdf = [=](const Vec3& p) { return std::max(box_sdf(p, lo, hi), -sphere_sdf(p, c, r)); };
  return {"pocketed box", sdf, e.x * e.y * e.z - 2.0 / 3.0 * kPi * r * r * r,
          2 * (e.x * e.y + e.y * e.z + e.z * e.x) + kPi * r * r, Aabb{lo, hi}};
}
// Two equal spheres of radius r whose centres are 2·a apart (a < r): lens volume subtracted once.
Solid two_spheres(const Vec3& c, double r, double a, const Vec3& dir) {
  Vec3 c1 = c - a * dir, c2 = c + a * dir;
  double cap_h = r - a;  // height of each spherical cap inside the other sphere
  double cap = kPi * cap_h * cap_h * (3 * r - cap_h) / 3;
  auto sdf = [=](const Vec3& p) { return std::min(sphere_sdf(p, c1, r), sphere_sdf(p, c2, r)); };
  Aabb b{glm::min(c1, c2) - Vec3(r), glm::max(c1, c2) + Vec3(r)};
  return {"two spheres", sdf, 2 * (4.0 / 3.0 * kPi * r * r * r) - 2 * cap,
          2 * (4 * kPi * r * r - 2 * kPi * r * cap_h), b};
}

// Intervals of {sdf < 0} along ray `a` through (pu, pv) over [lo, hi]: sign changes at steps of
// step, refined by bisection.
std::vector<DexelInterval> ray_intervals(const Solid& s, int a, double pu, double pv, double lo,
                                         double hi, double step) {
  int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
  auto f = [&](double t) {
    Vec3 p;
    p[a] = t, p[u] = pu, p[v] = pv;
    return s.sdf(p);
  };
  auto root = [&](double x0, double x1) {
    bool in0 = f(x0) < 0;
    for (int it = 0; it < 60; ++it) {
      double m = 0.5 * (x0 + x1);
      ((f(m) < 0) == in0 ? x0 : x1) = m;
    }
    return 0.5 * (x0 + x1);
  };
  std::vector<DexelInterval> out;
  double t = lo, enter = 0;
  bool inside = f(lo) < 0;
  if (inside) enter = lo;
  while (t < hi) {
    double t1 = std::min(hi, t + step);
    bool in1 = f(t1) < 0;
    if (in1 != inside) {
      double x = root(t, t1);
      if (in1)
        enter = x;
      else
        out.push_back({float(enter), float(x)});
      inside = in1;
    }
    t = t1;
  }
  if (inside) out.push_back({float(enter), float(hi)});
  // Rounding to float may make intervals empty or touching: drop or merge them.
  std::vector<DexelInterval> clean;
  for (DexelInterval s2 : out) {
    if (!(s2.enter < s2.exit)) continue;
    if (!clean.empty() && !(s2.enter > clean.back().exit))
      clean.back().exit = std::max(clean.back().exit, s2.exit);
    else
      clean.push_back(s2);
  }
  return clean;
}

TripleDexel dexelize_solid(const Solid& s, const DexelLattice& lattice) {
  TripleDexel d = TripleDexel::empty(lattice);
  for (int a = 0; a < 3; ++a) {
    DexelGrid& g = d.grids[a];
    int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
    double lo = lattice.origin[a] - lattice.spacing,
           hi = lattice.origin[a] + lattice.spacing * lattice.n[a];
    for (int iv = 0; iv < g.nv; ++iv)
      for (int iu = 0; iu < g.nu; ++iu) {
        double pu = lattice.origin[u] + lattice.spacing * iu,
               pv = lattice.origin[v] + lattice.spacing * iv;
        for (DexelInterval x : ray_intervals(s, a, pu, pv, lo, hi, lattice.spacing / 16))
          g.intervals.push_back(x);
        g.offsets[g.ray_index(iu, iv) + 1] = static_cast<std::uint32_t>(g.intervals.size());
      }
  }
  validate(d);
  return d;
}

// The box [lo, hi) as a triple dexel: a ray gets [lo, hi] along its axis when its transverse
// position p satisfies lo <= p < hi on both other axes (the half-open rule of dexel_ops.hpp).
TripleDexel box_dexel(const DexelLattice& lattice, const Aabb& b) {
  TripleDexel d = TripleDexel::empty(lattice);
  for (int a = 0; a < 3; ++a) {
    DexelGrid& g = d.grids[a];
    int u = TripleDexel::u_axis(a), v = TripleDexel::v_axis(a);
    for (int iv = 0; iv < g.nv; ++iv)
      for (int iu = 0; iu < g.nu; ++iu) {
        double pu = lattice.origin[u] + lattice.spacing * iu,
               pv = lattice.origin[v] + lattice.spacing * iv;
        if (pu >= b.min[u] && pu < b.max[u] && pv >= b.min[v] && pv < b.max[v])
          g.intervals.push_back({float(b.min[a]), float(b.max[a])});
        g.offsets[g.ray_index(iu, iv) + 1] = static_cast<std::uint32_t>(g.intervals.size());
      }
  }
  return d;
}

double point_triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  // Ericson, Real-Time Collision Detection, §5.1.5.
  Vec3 ab = b - a, ac = c - a, ap = p - a;
  double d1 = glm::dot(ab, ap), d2 = glm::dot(ac, ap);
  if (d1 <= 0 && d2 <= 0) return glm::length(p - a);
  Vec3 bp = p - b;
  double d3 = glm::dot(ab, bp), d4 = glm::dot(ac, bp);
  if (d3 >= 0 && d4 <= d3) return glm::length(p - b);
  double vc = d1 * d4 - d3 * d2;
  if (vc <= 0 && d1 >= 0 && d3 <= 0) return glm::length(p - (a + ab * (d1 / (d1 - d3))));
  Vec3 cp = p - c;
  double d5 = glm::dot(ab, cp), d6 = glm::dot(ac, cp);
  if (d6 >= 0 && d5 <= d6) return glm::length(p - c);
  double vb = d5 * d2 - d1 * d6;
  if (vb <= 0 && d2 >= 0 && d6 <= 0) return glm::length(p - (a + ac * (d2 / (d2 - d6))));
  double va = d3 * d6 - d5 * d4;
  if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0)
    return glm::length(p - (b + (c - b) * ((d4 - d3) / ((d4 - d3) + (d5 - d6)))));
  double denom = 1 / (va + vb + vc);
  return glm::length(p - (a + ab * (vb * denom) + ac * (vc * denom)));
}

double distance_to_mesh(const Mesh& m, const Vec3& p) {
  double best = std::numeric_limits<double>::infinity();
  for (const glm::uvec3& t : m.triangles)
    best = std::min(best, point_triangle_distance(p, Vec3(m.positions[t.x]), Vec3(m.positions[t.y]),
                                                  Vec3(m.positions[t.z])));
  return best;
}

// Largest |sdf| over the mesh's vertices and random points of its triangles (mesh → surface).
double mesh_to_surface(const Mesh& m, const Solid& s, std::mt19937& rng) {
  std::uniform_real_distribution<double> unit(0, 1);
  double worst = 0;
  for (const glm::vec3& p : m.positions) worst = std::max(worst, std::abs(s.sdf(Vec3(p))));
  for (const glm::uvec3& t : m.triangles) {
    double r1 = unit(rng), r2 = unit(rng);
    if (r1 + r2 > 1) r1 = 1 - r1, r2 = 1 - r2;
    Vec3 a(m.positions[t.x]), b(m.positions[t.y]), c(m.positions[t.z]);
    worst = std::max(worst, std::abs(s.sdf(a + r1 * (b - a) + r2 * (c - a))));
  }
  return worst;
}

// Random points on the analytic surface (projected along the sdf gradient), farthest from the mesh.
double surface_to_mesh(const Mesh& m, const Solid& s, std::mt19937& rng, int samples) {
  Aabb b = s.bounds.inflated(0.1 * glm::length(s.bounds.size()));
  std::uniform_real_distribution<double> x(b.min.x, b.max.x), y(b.min.y, b.max.y),
      z(b.min.z, b.max.z);
  double worst = 0;
  int found = 0;
  for (int tries = 0; found < samples && tries < 100 * samples; ++tries) {
    Vec3 p(x(rng), y(rng), z(rng));
    for (int it = 0; it < 8; ++it) {
      const double e = 1e-6;
      Vec3 g(s.sdf(p + Vec3(e, 0, 0)) - s.sdf(p - Vec3(e, 0, 0)),
             s.sdf(p + Vec3(0, e, 0)) - s.sdf(p - Vec3(0, e, 0)),
             s.sdf(p + Vec3(0, 0, e)) - s.sdf(p - Vec3(0, 0, e)));
      if (glm::length(g) == 0) break;
      p -= s.sdf(p) * glm::normalize(g);
    }
    if (!(std::abs(s.sdf(p)) < 1e-9)) continue;
    ++found;
    worst = std::max(worst, distance_to_mesh(m, p));
  }
  REQUIRE(found == samples);
  return worst;
}

Solid random_solid(int kind, std::mt19937& rng) {
  std::uniform_real_distribution<double> c(-3, 3), r(2, 4), dir(-1, 1);
  Vec3 centre(c(rng), c(rng), c(rng));
  switch (kind) {
    case 0:
      return sphere(centre, r(rng));
    case 1:
      return box(centre - Vec3(r(rng), r(rng), r(rng)), centre + Vec3(r(rng), r(rng), r(rng)));
    case 2:
      return cylinder(centre, r(rng), r(rng));
    case 3: {
      double major = r(rng) + 1;
      return torus(centre, major, std::uniform_real_distribution<double>(1.0, major - 1.0)(rng));
    }
    case 4: {
      Vec3 lo = centre - Vec3(4, 4, 3), hi = centre + Vec3(4, 4, 1.5);
      return pocketed_box(lo, hi, std::uniform_real_distribution<double>(1.5, 3.0)(rng));
    }
    default: {
      Vec3 d(dir(rng), dir(rng), dir(rng));
      if (glm::length(d) < 0.1) d = Vec3(1, 0, 0);
      double rad = r(rng);
      return two_spheres(centre, rad, std::uniform_real_distribution<double>(0.2, 0.8)(rng) * rad,
                         glm::normalize(d));
    }
  }
}

// Vertices whose link (the opposite edges of their triangles) is not one cycle: where two
// sheets of surface touch in a single vertex. check_mesh only looks at edges.
std::size_t non_manifold_vertices(const Mesh& m) {
  std::vector<std::vector<std::pair<std::uint32_t, std::uint32_t>>> link(m.positions.size());
  for (const glm::uvec3& t : m.triangles) {
    link[t.x].emplace_back(t.y, t.z);
    link[t.y].emplace_back(t.z, t.x);
    link[t.z].emplace_back(t.x, t.y);
  }
  std::size_t bad = 0;
  for (auto& l : link) {
    if (l.empty()) continue;
    std::sort(l.begin(), l.end());
    auto next = [&](std::uint32_t a) {
      auto it = std::lower_bound(l.begin(), l.end(), std::make_pair(a, std::uint32_t(0)));
      return it != l.end() && it->first == a ? std::optional<std::uint32_t>(it->second)
                                             : std::nullopt;
    };
    std::uint32_t start = l[0].first, at = start;
    std::size_t steps = 0;
    do {
      std::optional<std::uint32_t> b = next(at);
      if (!b) break;
      at = *b, ++steps;
    } while (at != start && steps <= l.size());
    if (at != start || steps != l.size()) ++bad;
  }
  return bad;
}

void check_closed(const Mesh& m) {
  CHECK(non_manifold_vertices(m) == 0);
  MeshCheck check = check_mesh(m);
  CHECK(check.boundary_edges == 0);
  CHECK(check.non_manifold_edges == 0);
  CHECK(check.misoriented_edges == 0);
  CHECK(check.degenerate_triangles == 0);
}

bool same_mesh(const Mesh& a, const Mesh& b) {
  return a.positions == b.positions && a.triangles == b.triangles;
}

}  // namespace

TEST_CASE("extract_surface: an empty triple dexel gives an empty mesh") {
  DexelLattice lattice{Vec3(-1, 2, 0.5), 0.25, glm::ivec3(9, 7, 11)};
  Mesh m = extract_surface(TripleDexel::empty(lattice));
  CHECK(m.positions.empty());
  CHECK(m.triangles.empty());
  // A lattice one node thick holds no volume either.
  DexelLattice flat{Vec3(0), 1.0, glm::ivec3(5, 1, 5)};
  CHECK(extract_surface(box_dexel(flat, Aabb{Vec3(-1), Vec3(10)})).triangles.empty());
}

TEST_CASE("extract_surface: a full lattice gives its six faces with the exact volume") {
  std::mt19937 rng(7);
  for (int trial = 0; trial < 6; ++trial) {
    std::uniform_int_distribution<int> count(2, 13), shift(-40, 40);
    DexelLattice lattice{Vec3(shift(rng), shift(rng), shift(rng)) * 0.125, 0.25 * (1 + trial % 3),
                         glm::ivec3(count(rng), count(rng), count(rng))};
    // Every ray spans the lattice with half a spacing to spare: every node is inside.
    TripleDexel d = box_dexel(lattice, lattice.bounds().inflated(0.5 * lattice.spacing));
    for (bool sharp : {false, true}) {
      Mesh m = extract_surface(d, {.threads = 2, .sharp_features = sharp});
      check_closed(m);
      Vec3 e = lattice.bounds().size();
      CHECK(m.signed_volume() == doctest::Approx(e.x * e.y * e.z).epsilon(1e-6));
      // Every triangle lies in one face of the box and faces outward.
      Aabb b = lattice.bounds();
      for (const glm::uvec3& t : m.triangles) {
        Vec3 p0(m.positions[t.x]), p1(m.positions[t.y]), p2(m.positions[t.z]);
        Vec3 n = glm::normalize(glm::cross(p1 - p0, p2 - p0));
        int axis = std::abs(n.x) > 0.5 ? 0 : std::abs(n.y) > 0.5 ? 1 : 2;
        double plane = n[axis] > 0 ? b.max[axis] : b.min[axis];
        CHECK(std::abs(std::abs(n[axis]) - 1) < 1e-9);
        CHECK(p0[axis] == plane);
        CHECK(p1[axis] == plane);
        CHECK(p2[axis] == plane);
      }
      // Two triangles per boundary square.
      glm::ivec3 c = lattice.n - 1;
      CHECK(m.triangles.size() == std::size_t(4 * (c.x * c.y + c.y * c.z + c.z * c.x)));
    }
  }
}

TEST_CASE(
    "extract_surface: analytic solids are closed, without degenerate triangles, with the right "
    "volume "
    "and within one spacing of the surface") {
  std::mt19937 rng(2026);
  for (int trial = 0; trial < 18; ++trial) {
    int kind = trial % 6;
    Solid s = random_solid(kind, rng);
    double h = std::uniform_real_distribution<double>(0.22, 0.45)(rng);
    DexelLattice lattice = DexelLattice::covering(s.bounds, h);
    // Shift the lattice by a random fraction of a cell so nodes fall anywhere relative to the
    // solid.
    std::uniform_real_distribution<double> frac(-0.5, 0.5);
    lattice.origin += h * Vec3(frac(rng), frac(rng), frac(rng));
    TripleDexel d = dexelize_solid(s, lattice);
    for (bool sharp : {false, true}) {
      CAPTURE(std::string(s.name));
      CAPTURE(h);
      CAPTURE(sharp);
      Mesh m = extract_surface(d, {.threads = 2, .sharp_features = sharp});
      check_closed(m);
      // Marching cubes with exact crossings: the volume error is a small fraction of area × h.
      double volume = m.signed_volume();
      CHECK(std::abs(volume - s.volume) <= 0.05 * s.area * h);
      // The dexel volume estimate (mean of the three grids' midpoint sums) is itself only within
      // about area × h / 2 of the truth.
      CHECK(std::abs(volume - tridex::volume(d)) <= 0.5 * s.area * h);
      double out = mesh_to_surface(m, s, rng);
      double in = surface_to_mesh(m, s, rng, 150);
      CHECK(out <= h);
      CHECK(in <= h);
      if (kind == 0 || kind == 3) {  // smooth solids: exact crossings keep the mesh much closer
        CHECK(out <= 0.25 * h);
        CHECK(in <= 0.25 * h);
      }
    }
  }
}

TEST_CASE("extract_surface: vertices on lattice edges are the rays' end points") {
  std::mt19937 rng(17);
  for (int kind : {0, 3, 5}) {
    Solid s = random_solid(kind, rng);
    DexelLattice lattice = DexelLattice::covering(s.bounds, 0.3);
    TripleDexel d = dexelize_solid(s, lattice);
    Mesh m = extract_surface(d, {.sharp_features = false});
    std::size_t on_edges = 0;
    for (const glm::vec3& p : m.positions) {
      Vec3 g = (Vec3(p) - lattice.origin) / lattice.spacing;
      int off_node = -1, count = 0;
      for (int a = 0; a < 3; ++a)
        if (std::abs(g[a] - std::round(g[a])) > 1e-4) off_node = a, ++count;
      if (count != 1) continue;  // a loop's centre point
      ++on_edges;
      int u = TripleDexel::u_axis(off_node), v = TripleDexel::v_axis(off_node);
      double nearest = std::numeric_limits<double>::infinity();
      for (DexelInterval x : d.grids[off_node].ray(int(std::lround(g[u])), int(std::lround(g[v]))))
        nearest = std::min({nearest, std::abs(double(x.enter) - p[off_node]),
                            std::abs(double(x.exit) - p[off_node])});
      // Exact up to float rounding, or moved by at most 1% of a spacing off a node.
      CHECK(nearest <= 0.011 * lattice.spacing);
    }
    CHECK(double(on_edges) >= 0.99 * double(m.positions.size()));
  }
}

TEST_CASE(
    "extract_surface: one vertex per sign-changing lattice edge and per inside boundary node") {
  // Brute force over every node and edge of the lattice, independent of the sparse traversal:
  // node states from the z rays (half-open), a crossing vertex on every edge whose two nodes
  // differ, a node vertex on every inside node of the lattice boundary.
  std::mt19937 rng(41);
  for (int trial = 0; trial < 8; ++trial) {
    Solid s = random_solid(trial % 6, rng);
    double h = std::uniform_real_distribution<double>(0.25, 0.4)(rng);
    DexelLattice lattice = DexelLattice::covering(s.bounds, h);
    if (trial % 2) {  // cut the solid with the lattice box so that caps appear
      Vec3 size = s.bounds.size();
      lattice.origin = s.bounds.min + 0.2 * size;
      lattice.n = glm::ivec3(glm::floor(0.7 * size / h)) + 1;
    }
    TripleDexel d = dexelize_solid(s, lattice);
    const glm::ivec3 n = lattice.n;
    auto inside = [&](int i, int j, int k) {
      double z = lattice.origin.z + lattice.spacing * k;
      for (DexelInterval x : d.grids[2].ray(i, j))
        if (double(x.enter) <= z && z < double(x.exit)) return true;
      return false;
    };
    std::size_t changing_edges = 0, boundary_inside = 0;
    for (int k = 0; k < n.z; ++k)
      for (int j = 0; j < n.y; ++j)
        for (int i = 0; i < n.x; ++i) {
          bool in = inside(i, j, k);
          if (i + 1 < n.x && in != inside(i + 1, j, k)) ++changing_edges;
          if (j + 1 < n.y && in != inside(i, j + 1, k)) ++changing_edges;
          if (k + 1 < n.z && in != inside(i, j, k + 1)) ++changing_edges;
          bool boundary =
              i == 0 || j == 0 || k == 0 || i == n.x - 1 || j == n.y - 1 || k == n.z - 1;
          if (boundary && in) ++boundary_inside;
        }
    Mesh m = extract_surface(d, {.sharp_features = false});
    std::size_t on_nodes = 0, on_edges = 0;
    for (const glm::vec3& p : m.positions) {
      Vec3 g = (Vec3(p) - lattice.origin) / lattice.spacing;
      int off = 0;
      for (int a = 0; a < 3; ++a) off += std::abs(g[a] - std::round(g[a])) > 5e-5;
      on_nodes += off == 0, on_edges += off == 1;
    }
    CAPTURE(std::string(s.name));
    CHECK(on_edges == changing_edges);
    CHECK(on_nodes == boundary_inside);
    CHECK((trial % 2 ? boundary_inside : changing_edges) > 0);
    check_closed(m);
  }
}

TEST_CASE("extract_surface: sharp features keep a box's edges and corners") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> c(-2, 2), e(1.5, 4);
  for (int trial = 0; trial < 8; ++trial) {
    Vec3 lo(c(rng), c(rng), c(rng));
    Solid s = box(lo, lo + Vec3(e(rng), e(rng), e(rng)));
    double h = std::uniform_real_distribution<double>(0.2, 0.4)(rng);
    TripleDexel d = dexelize_solid(s, DexelLattice::covering(s.bounds, h));
    Mesh plain = extract_surface(d, {.sharp_features = false});
    Mesh sharp = extract_surface(d);
    check_closed(sharp);
    double plain_error = std::abs(plain.signed_volume() - s.volume);
    double sharp_error = std::abs(sharp.signed_volume() - s.volume);
    CAPTURE(plain_error);
    CAPTURE(sharp_error);
    CHECK(plain_error > 0);
    // Edges and corners come out exact: the volume to float precision, every vertex on the box.
    CHECK(sharp_error <= 1e-5 * s.volume);
    for (const glm::vec3& p : sharp.positions) CHECK(std::abs(s.sdf(Vec3(p))) <= 1e-5);
    // Every box corner is a vertex of the sharp mesh (to float precision).
    for (const Vec3& corner : s.bounds.corners()) {
      double nearest = std::numeric_limits<double>::infinity();
      for (const glm::vec3& p : sharp.positions)
        nearest = std::min(nearest, glm::length(Vec3(p) - corner));
      CHECK(nearest < 1e-4 * h);
    }
  }
}

TEST_CASE(
    "extract_surface: pockets from dexel Booleans, with faces between or exactly on lattice "
    "nodes") {
  // Box A minus box B (a pocket open at the top): concave edges and corners. With `snap`, every
  // face lies on a lattice plane, so rays run inside faces and end points sit on nodes.
  std::mt19937 rng(4);
  const double h = 0.25;
  DexelLattice lattice{Vec3(-0.5), h, glm::ivec3(30)};
  auto volume_of = [](const Aabb& b) {
    return b.empty() ? 0.0 : b.size().x * b.size().y * b.size().z;
  };
  for (int trial = 0; trial < 16; ++trial) {
    bool snap = trial % 2;
    auto coord = [&](double lo, double hi) {
      double x = std::uniform_real_distribution<double>(lo, hi)(rng);
      return snap ? std::round((x + 0.5) / h) * h - 0.5 : x;
    };
    Aabb a{Vec3(coord(0.3, 1.5), coord(0.3, 1.5), coord(0.3, 1.5)),
           Vec3(coord(4, 6.5), coord(4, 6.5), coord(4, 6.5))};
    Aabb b{Vec3(coord(1.5, 3), coord(1.5, 3), coord(2.5, 3.8)),
           Vec3(coord(3.2, 5), coord(3.2, 5), coord(6.8, 6.9))};
    TripleDexel d = subtract(box_dexel(lattice, a), box_dexel(lattice, b));
    Aabb common{glm::max(a.min, b.min), glm::min(a.max, b.max)};
    double exact = volume_of(a) - volume_of(common);
    Vec3 e = a.size(), p = common.size();
    double area = 2 * (e.x * e.y + e.y * e.z + e.z * e.x) + 2 * p.z * (p.x + p.y);
    for (bool sharp : {false, true}) {
      CAPTURE(snap);
      CAPTURE(sharp);
      Mesh m = extract_surface(d, {.sharp_features = sharp});
      check_closed(m);
      CHECK(std::abs(m.signed_volume() - exact) <= 0.05 * area * h);
    }
  }
}

TEST_CASE("extract_surface: a solid cut by the lattice boundary is closed by caps") {
  std::mt19937 rng(5);
  for (int trial = 0; trial < 6; ++trial) {
    Solid s = random_solid(trial % 6, rng);
    double h = 0.3;
    // A lattice covering only the middle of the solid: the solid crosses its boundary.
    Aabb b = s.bounds;
    Vec3 mid = b.center(), half = 0.35 * b.size();
    DexelLattice lattice{mid - half, h, glm::ivec3(glm::floor(2.0 * half / h)) + 1};
    TripleDexel d = dexelize_solid(s, lattice);
    Mesh m = extract_surface(d, {.threads = 3});
    CAPTURE(std::string(s.name));
    check_closed(m);
    // Reference: the solid ∩ lattice box by Monte Carlo integration with a fixed seed.
    Aabb box = lattice.bounds();
    std::uniform_real_distribution<double> x(box.min.x, box.max.x), y(box.min.y, box.max.y),
        z(box.min.z, box.max.z);
    const int samples = 200000;
    int inside = 0;
    for (int q = 0; q < samples; ++q) inside += s.sdf(Vec3(x(rng), y(rng), z(rng))) < 0;
    Vec3 e = box.size();
    double reference = double(inside) / samples * e.x * e.y * e.z;
    double area = 2 * (e.x * e.y + e.y * e.z + e.z * e.x) + s.area;
    CHECK(std::abs(m.signed_volume() - reference) <=
          0.05 * area * h + 4 * std::sqrt(double(samples)) / samples * e.x * e.y * e.z);
  }
}

TEST_CASE("extract_surface: far from the origin, float positions stay distinct") {
  // 3·10^4 spacings out (a 3 m machine table at 0.1 mm): crossings near nodes must not round
  // onto the nodes or onto each other.
  std::mt19937 rng(23);
  for (int trial = 0; trial < 3; ++trial) {
    double h = 0.1;
    std::uniform_real_distribution<double> far(-3000, 3000);
    Solid s =
        trial == 0 ? sphere(Vec3(far(rng), far(rng), far(rng)), 0.9) : random_solid(trial, rng);
    if (trial > 0) {  // move the solid far away
      Vec3 shift(far(rng), far(rng), far(rng));
      auto inner = s.sdf;
      s.sdf = [inner, shift](const Vec3& p) { return inner(p - shift); };
      s.bounds = Aabb{s.bounds.min + shift, s.bounds.max + shift};
      h = 0.3;
    }
    TripleDexel d = dexelize_solid(s, DexelLattice::covering(s.bounds, h));
    for (bool sharp : {false, true}) {
      Mesh m = extract_surface(d, {.sharp_features = sharp});
      check_closed(m);
      CHECK(std::abs(m.signed_volume() - s.volume) <= 0.05 * s.area * h);
    }
  }
}

TEST_CASE("extract_surface: the output does not depend on the thread count") {
  std::mt19937 rng(99);
  for (int kind = 0; kind < 6; ++kind) {
    Solid s = random_solid(kind, rng);
    TripleDexel d = dexelize_solid(s, DexelLattice::covering(s.bounds, 0.15));
    Mesh one = extract_surface(d, {.threads = 1});
    Mesh two = extract_surface(d, {.threads = 2});
    Mesh five = extract_surface(d, {.threads = 5});
    CHECK(same_mesh(one, two));
    CHECK(same_mesh(one, five));
    check_closed(one);
  }
}

TEST_CASE("extract_surface: rays that disagree with each other still give a closed mesh") {
  // Random interval soup: the three grids describe no common solid, and many end points sit exactly
  // on nodes. The topology comes from the z rays alone, so the mesh must still be closed.
  std::mt19937 rng(3);
  for (int trial = 0; trial < 20; ++trial) {
    std::uniform_int_distribution<int> count(2, 12);
    DexelLattice lattice{Vec3(0.5, -1, 2), 0.5, glm::ivec3(count(rng), count(rng), count(rng))};
    TripleDexel d = TripleDexel::empty(lattice);
    for (int a = 0; a < 3; ++a) {
      DexelGrid& g = d.grids[a];
      double lo = lattice.origin[a] - 1,
             hi = lattice.origin[a] + lattice.spacing * lattice.n[a] + 1;
      std::uniform_int_distribution<int> steps(0, int((hi - lo) / 0.25));
      std::bernoulli_distribution on_node(0.5);
      for (std::size_t r = 0; r < g.ray_count(); ++r) {
        std::vector<double> ends;
        int m = std::uniform_int_distribution<int>(0, 3)(rng) * 2;
        for (int q = 0; q < m; ++q)
          ends.push_back(on_node(rng) ? lo + 0.25 * steps(rng)
                                      : std::uniform_real_distribution<double>(lo, hi)(rng));
        std::sort(ends.begin(), ends.end());
        ends.erase(std::unique(ends.begin(), ends.end()), ends.end());
        for (std::size_t q = 0; q + 1 < ends.size(); q += 2)
          g.intervals.push_back({float(ends[q]), float(ends[q + 1])});
        g.offsets[r + 1] = static_cast<std::uint32_t>(g.intervals.size());
      }
    }
    for (bool sharp : {false, true}) {
      Mesh m = extract_surface(d, {.threads = 2, .sharp_features = sharp});
      check_closed(m);
      CHECK(m.signed_volume() >= 0);
    }
  }
}

TEST_CASE("extract_surface: malformed input is rejected") {
  DexelLattice lattice{Vec3(0), 1.0, glm::ivec3(4, 4, 4)};
  TripleDexel d = box_dexel(lattice, Aabb{Vec3(0.5), Vec3(2.5)});
  CHECK_THROWS_AS(extract_surface(d, {.feature_angle = 0}), Error);
  CHECK_THROWS_AS(extract_surface(d, {.feature_angle = std::nan("")}), Error);
  TripleDexel unsorted = d;
  unsorted.grids[2].intervals[0] = {2.0f, 1.0f};
  CHECK_THROWS_AS(extract_surface(unsorted), Error);
  TripleDexel short_offsets = d;
  short_offsets.grids[0].offsets.pop_back();
  CHECK_THROWS_AS(extract_surface(short_offsets), Error);
  TripleDexel bad_spacing = d;
  bad_spacing.spacing = -1;
  CHECK_THROWS_AS(extract_surface(bad_spacing), Error);
}

// box_surface_volume is the extracted box's volume without extracting it: random boxes, far
// and near the origin, coarse and fine lattices placed as DexelLattice::covering places them.
TEST_CASE("box_surface_volume: the volume extract_surface gives for a box stock") {
  std::mt19937 rng(11);
  std::uniform_real_distribution<double> corner(-60, 60), side(3, 90), spacing(0.07, 1.6);
  for (int k = 0; k < 10; ++k) {
    const Vec3 lo(corner(rng), corner(rng), corner(rng));
    const Aabb box{lo, lo + Vec3(side(rng), side(rng), 0.5 * side(rng))};
    const DexelLattice lattice = DexelLattice::covering(box, spacing(rng));
    const double extracted =
        extract_surface(TripleDexel::box(lattice, box), {.threads = 2}).signed_volume();
    const Vec3 size = box.size();
    CAPTURE(k);
    // The offset is real (about 3e-4 mm on each face here) and the closed form follows it.
    CHECK(extracted != size.x * size.y * size.z);
    CHECK(box_surface_volume(lattice, box) == doctest::Approx(extracted).epsilon(1e-10));
  }
}
