// tridex — surface extraction's machinery (surface.hpp's contract): the Extractor, which walks
// the triple dexel's lattice in slabs of cell layers on threads and joins the slabs' meshes;
// the triangles of one cell are surface_cells.hpp.
//
//
// Method. Marching cubes (Lorensen & Cline, SIGGRAPH 1987) on the triple-dexel lattice, with the
// two refinements that triple dexels make natural:
//  * every lattice edge lies on a dexel ray, so its crossing is a dexel end point: exact, not
//    interpolated (the surface error is bounded by the spacing, not by half a voxel);
//  * sharp edges and corners are kept as in Extended Marching Cubes (Kobbelt, Botsch,
//    Schwanecke & Seidel, SIGGRAPH 2001): where the normals of a cell's crossings spread by more
//    than SurfaceOptions::feature_angle, the cell's loop is fanned around the point that
//    minimises Σ (n_i·(x − p_i))² (a quadric error function solved with a truncated
//    pseudo-inverse), and edges between two such fans are flipped so that the fans' apexes join
//    along the feature. Normals come from the neighbouring rays' end points: central
//    differences of the end-point heights, or, across an edge, the one-sided difference whose
//    continuation is straighter (as in ENO schemes), not from any field.
//
// Consistency. Node inside/outside comes from ONE rule: the z ray through the node, with
// half-open intervals [enter, exit) — the convention of dexel_ops.hpp's `contains` and of
// TripleDexel::box, so a face lying on a node plane puts its nodes on the same side in all three
// families. Topology is derived from these states alone (surface_tables.hpp: a
// per-face rule that never depends on the neighbouring cell), so every mesh edge joins exactly
// two triangles, in opposite directions, whatever the rays say; the x and y rays only place
// crossings. Where a ray disagrees with the node states (a node within rounding of the surface),
// the crossing goes to the node the ray disagrees about. Crossings are kept a small fraction of the
// spacing away from nodes so that no two vertices coincide and no triangle degenerates (three
// points interior to distinct cube edges are never collinear); triangles around feature or centre
// points, and flipped ones, are checked in float before they are kept. Positions are float, so this
// holds while coordinates stay within about 10^5 spacings of the world origin. The solid is clipped
// to the lattice box: where it reaches the outer nodes, caps on the box faces close it.
//
// Cost. Node states of one lattice layer are kept as bit rows updated by the z rays' state
// changes; cells whose eight corners agree are skipped 64 at a time, so only cells next to the
// surface are visited. Layers are cut into a fixed number of slabs that run on threads; slabs are
// joined in order, and their shared vertices matched by lattice edge, so the output does not
// depend on the thread count.
// Part of surface.hpp, which includes it after SurfaceOptions; not for inclusion on its own.
#pragma once

#include <algorithm>
#include <array>
#include <bit>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <glm/glm.hpp>
#include <limits>
#include <span>
#include <type_traits>
#include <unordered_set>
#include <utility>
#include <vector>

#include "tridex/dexel.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/error.hpp"
#include "tridex/mesh.hpp"
#include "tridex/parallel.hpp"
#include "tridex/surface_tables.hpp"

namespace tridex::detail::surface {

constexpr std::uint32_t kNone = std::numeric_limits<std::uint32_t>::max();

// Half-open membership of coordinate x on one ray: enter ≤ x < exit.
inline bool ray_contains(std::span<const DexelInterval> ray, double x) {
  auto it = std::upper_bound(ray.begin(), ray.end(), x, [](double value, const DexelInterval& s) {
    return value < double(s.exit);
  });
  return it != ray.end() && double(it->enter) <= x;
}

// Symmetric 3×3 eigen-decomposition by cyclic Jacobi rotations (the QEF is tiny; no library).
inline void symmetric_eigen(Mat3 a, Vec3& values, Mat3& vectors) {
  vectors = Mat3(1.0);
  for (int sweep = 0; sweep < 16; ++sweep) {
    double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
    if (off < 1e-24) break;
    for (int p = 0; p < 2; ++p)
      for (int q = p + 1; q < 3; ++q) {
        if (std::abs(a[p][q]) < 1e-30) continue;
        double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
        double t = (theta >= 0 ? 1.0 : -1.0) / (std::abs(theta) + std::sqrt(theta * theta + 1));
        double c = 1 / std::sqrt(t * t + 1), s = t * c;
        Mat3 r(1.0);
        r[p][p] = c, r[q][q] = c, r[q][p] = s, r[p][q] = -s;  // glm: r[column][row]
        a = glm::transpose(r) * a * r;
        vectors = vectors * r;
      }
  }
  values = Vec3(a[0][0], a[1][1], a[2][2]);
}

// A triangle that will survive as such in float: its doubled area, computed from the float
// positions it will have, is clearly above rounding noise relative to its longest edge.
inline bool well_shaped(const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 fa{glm::vec3(a)}, fb{glm::vec3(b)}, fc{glm::vec3(c)};
  double longest = std::max(
      {glm::dot(fb - fa, fb - fa), glm::dot(fc - fb, fc - fb), glm::dot(fa - fc, fa - fc)});
  return glm::length(glm::cross(fb - fa, fc - fa)) > 1e-8 * longest;
}

struct SlabMesh {
  std::vector<glm::vec3> positions;
  std::vector<glm::vec3> normals;  // per vertex: estimated outward normal, zero if unknown
  std::vector<glm::uvec3> triangles;
  std::vector<std::uint32_t>
      feature_triangles;  // triangles fanned from a feature point (apex first)
  // Vertices on the slab's bottom and top node layers, keyed by lattice element, sorted by key;
  // the bottom ones duplicate the previous slab's top ones and are matched when slabs are joined.
  std::vector<std::pair<std::uint64_t, std::uint32_t>> bottom, top;
};

// Feature points are accepted only when they lie within this many spacings of every crossing's
// tangent plane, and of the box around the cell's crossings (measured on a randomly rotated box
// and on machined stock: looser bounds let blurred normals put apexes up to half a spacing off
// the surface; tighter ones only lose oblique features, which then stay as plain chamfers).
constexpr double kFeatureResidual = 0.1;
constexpr double kFeatureOvershoot = 0.05;

// How far crossings are kept off the nodes, in spacings: at least 32 float ulps of the lattice's
// largest coordinate (the dexel end points are floats) and never more than 1% of a cell.
inline double crossing_margin(const DexelLattice& l) {
  double extent = 0;
  for (int a = 0; a < 3; ++a)
    extent = std::max(extent, std::abs(l.origin[a]) + l.spacing * (l.n[a] - 1));
  return std::clamp(32.0 * double(std::numeric_limits<float>::epsilon()) * extent / l.spacing, 1e-4,
                    1e-2);
}

class Extractor {
 public:
  Extractor(const TripleDexel& d, const SurfaceOptions& options)
      : d_(d), nx_(d.n.x), ny_(d.n.y), nz_(d.n.z), h_(d.spacing), words_((d.n.x + 63) / 64) {
    sharp_ = options.sharp_features;
    cos_feature_ = std::cos(options.feature_angle * 3.14159265358979323846 / 180.0);
    delta_ = crossing_margin(d.lattice());
    build_flips();
  }

  Mesh run(unsigned threads) {
    const int layers = nz_ - 1;  // cell layers
    const int slab = std::max(8, (layers + 31) / 32);
    const int slabs = (layers + slab - 1) / slab;
    std::vector<SlabMesh> parts(static_cast<std::size_t>(slabs));
    detail::for_each_chunk_with(
        static_cast<std::size_t>(slabs), threads, [&](unsigned) { return Scratch(*this); },
        [&](std::size_t chunk, Scratch& scratch) {
          const int s = static_cast<int>(chunk);
          SlabMesh& part = parts[chunk];
          process_slab(s * slab, std::min(layers, (s + 1) * slab), scratch, part);
          // Normals were only needed inside the slab; the rest waits for the
          // join, at its size.
          std::vector<glm::vec3>().swap(part.normals);
          part.positions.shrink_to_fit();
          part.triangles.shrink_to_fit();
        });
    return join(parts, threads);
  }

 private:
  // Vertex ids of one lattice column (i, j): on its x edge, y edge and node in the node layers
  // of each parity (layer m uses index m & 1), and on its z edge of the current cell layer. One
  // record per column keeps a cell's lookups in a few cache lines.
  struct ColumnSlots {
    std::array<std::uint32_t, 2> xe{kNone, kNone}, ye{kNone, kNone}, node{kNone, kNone};
    std::uint32_t ze = kNone;
  };
  struct Scratch {
    std::vector<std::uint64_t> s0, s1;  // node states, layers k and k+1
    std::vector<ColumnSlots> slots;
    std::array<std::vector<std::uint32_t>, 2> xe_used, ye_used,
        node_used;  // columns set, by parity
    std::vector<std::uint32_t> ze_used;
    explicit Scratch(const Extractor& e) {
      s0.assign(static_cast<std::size_t>(e.ny_) * static_cast<std::size_t>(e.words_), 0);
      s1 = s0;
      slots.resize(static_cast<std::size_t>(e.nx_) * static_cast<std::size_t>(e.ny_));
    }
    // Forgets the vertices of node layers of parity p.
    void clear_layer(int p) {
      std::size_t q = static_cast<std::size_t>(p);
      for (std::uint32_t c : xe_used[q]) slots[c].xe[q] = kNone;
      for (std::uint32_t c : ye_used[q]) slots[c].ye[q] = kNone;
      for (std::uint32_t c : node_used[q]) slots[c].node[q] = kNone;
      xe_used[q].clear(), ye_used[q].clear(), node_used[q].clear();
    }
    void clear_z() {
      for (std::uint32_t c : ze_used) slots[c].ze = kNone;
      ze_used.clear();
    }
  };

  double coord(int a, int m) const { return d_.origin[a] + h_ * m; }
  std::size_t column(int i, int j) const {
    return static_cast<std::size_t>(i) +
           static_cast<std::size_t>(nx_) * static_cast<std::size_t>(j);
  }

  // The node range [first, last] of the z axis whose nodes lie in [enter, exit).
  int first_node_at_or_above(double value) const {
    double f = std::ceil((value - d_.origin.z) / h_);
    int k = static_cast<int>(std::clamp(f, 0.0, double(nz_)));
    while (k > 0 && coord(2, k - 1) >= value) --k;
    while (k < nz_ && coord(2, k) < value) ++k;
    return k;
  }
  int last_node_below(double value) const {
    double f = std::floor((value - d_.origin.z) / h_);
    int k = static_cast<int>(std::clamp(f, -1.0, double(nz_ - 1)));
    while (k + 1 < nz_ && coord(2, k + 1) < value) ++k;
    while (k >= 0 && coord(2, k) >= value) --k;
    return k;
  }

  // For every z ray, the layers where its node state changes (state(k) = state(k−1) xor flip).
  void build_flips() {
    const DexelGrid& g = d_.grids[2];
    flip_offsets_.assign(static_cast<std::size_t>(nz_) + 1, 0);
    for (int pass = 0; pass < 2; ++pass) {
      std::vector<std::uint32_t> fill;
      if (pass == 1) {
        for (int k = 0; k < nz_; ++k)
          flip_offsets_[static_cast<std::size_t>(k) + 1] +=
              flip_offsets_[static_cast<std::size_t>(k)];
        flip_columns_.resize(flip_offsets_.back());
        fill.assign(flip_offsets_.begin(), flip_offsets_.end() - 1);
      }
      auto flip = [&](int k, std::size_t col) {
        if (k <= 0 || k >= nz_) return;  // layer 0 is evaluated directly; beyond the top is nothing
        if (pass == 0)
          ++flip_offsets_[static_cast<std::size_t>(k) + 1];
        else
          flip_columns_[fill[static_cast<std::size_t>(k)]++] = static_cast<std::uint32_t>(col);
      };
      for (int j = 0; j < ny_; ++j)
        for (int i = 0; i < nx_; ++i) {
          std::size_t col = column(i, j);
          int start = 0, end = -2;  // merged node range, closed
          for (const DexelInterval& s : g.ray(i, j)) {
            int a = first_node_at_or_above(double(s.enter)), b = last_node_below(double(s.exit));
            if (a > b) continue;
            if (a <= end + 1) {
              end = std::max(end, b);
            } else {
              if (end >= start) flip(start, col), flip(end + 1, col);
              start = a, end = b;
            }
          }
          if (end >= start) flip(start, col), flip(end + 1, col);
        }
    }
  }

  static bool bit(const std::vector<std::uint64_t>& s, int words, int i, int j) {
    return (s[static_cast<std::size_t>(j) * static_cast<std::size_t>(words) +
              static_cast<std::size_t>(i >> 6)] >>
            (i & 63)) &
           1u;
  }

  // Corner states of cell (i, j, ·) from the two node layers: bit c = bx + 2·by + 4·bz.
  unsigned cell_mask(const Scratch& s, int i, int j) const {
    unsigned m = 0;
    for (int c = 0; c < 8; ++c) {
      const std::vector<std::uint64_t>& layer = (c & 4) ? s.s1 : s.s0;
      m |= unsigned(bit(layer, words_, i + (c & 1), j + ((c >> 1) & 1))) << c;
    }
    return m;
  }

  void init_layer(std::vector<std::uint64_t>& s, int k) const {
    std::fill(s.begin(), s.end(), 0);
    double z = coord(2, k);
    for (int j = 0; j < ny_; ++j)
      for (int i = 0; i < nx_; ++i)
        if (ray_contains(d_.grids[2].ray(i, j), z))
          s[static_cast<std::size_t>(j) * static_cast<std::size_t>(words_) +
            static_cast<std::size_t>(i >> 6)] |= std::uint64_t(1) << (i & 63);
  }

  // ---- vertices ------------------------------------------------------------------------------

  struct SlabState {
    Scratch& s;
    SlabMesh& out;
    int k;  // current cell layer
  };

  std::uint32_t add_vertex(SlabMesh& out, const Vec3& p, const glm::vec3& normal) const {
    out.positions.emplace_back(p);
    if (sharp_) out.normals.push_back(normal);
    return static_cast<std::uint32_t>(out.positions.size() - 1);
  }

  // Vertex on the lattice edge along axis a that starts at node (n0, n1, n2).
  std::uint32_t edge_vertex(SlabState& st, int a, glm::ivec3 node, bool start_inside) const;

  // Outward normal at the end point x of ray (iu, iv) of grid a, from the neighbouring rays' end
  // points of the same kind: the surface is locally x = f(u, v), with normal ±(e_a − f_u e_u −
  // f_v e_v). Zero when no neighbour has a matching end point within two spacings.
  glm::vec3 crossing_normal(int a, int iu, int iv, double x, bool enter) const;

  std::uint32_t node_vertex(SlabState& st, glm::ivec3 node) const;

  std::uint32_t cube_edge_vertex(SlabState& st, int i, int j, unsigned mask, int e) const;

  // ---- polygons ------------------------------------------------------------------------------

  void emit(SlabMesh& out, std::uint32_t a, std::uint32_t b, std::uint32_t c) const {
    out.triangles.emplace_back(a, b, c);
  }

  // True when every triangle (apex, p_i, p_i+1) has a clearly non-zero area and faces the way
  // the surface does there: along the estimated normals of its two loop vertices where known
  // (a tall corner apex tilts its triangles far from the loop's mean normal), else along `n`.
  bool fan_is_valid(const Vec3& apex, std::span<const Vec3> p, const glm::vec3* normals,
                    const Vec3& n) const;

  void emit_loop(SlabState& st, int i, int j, const std::uint8_t* edges, int size, int fan_start,
                 unsigned mask) const;

  // Extended Marching Cubes: when the crossings' normals spread beyond the feature angle, the
  // minimiser of Σ (n_i·(x − p_i))² nearest the centroid (pseudo-inverse, small eigenvalues
  // dropped), if it lies in the cell.
  bool feature_point(const SlabState& st, const std::uint32_t* id, std::span<const Vec3> p,
                     const Vec3& centroid, int i, int j, Vec3& out) const {
    std::array<Vec3, 12> n;
    std::size_t count = 0;
    for (std::size_t q = 0; q < p.size(); ++q) {
      glm::vec3 normal = st.out.normals[id[q]];
      if (normal != glm::vec3(0.0f)) n[count++] = Vec3(normal);
    }
    // A crossing without a normal (no neighbouring ray ends near it: a thin ridge or spike)
    // leaves the point free along some direction; no feature then.
    if (count < p.size()) return false;
    double min_dot = 1;
    for (std::size_t a = 0; a < count; ++a)
      for (std::size_t b = a + 1; b < count; ++b) min_dot = std::min(min_dot, glm::dot(n[a], n[b]));
    if (min_dot >= cos_feature_) return false;
    Mat3 ata(0.0);
    Vec3 atb(0);
    for (std::size_t q = 0, c = 0; q < p.size(); ++q) {
      glm::vec3 normal = st.out.normals[id[q]];
      if (normal == glm::vec3(0.0f)) continue;
      const Vec3& m = n[c++];
      ata += glm::outerProduct(m, m);
      atb += m * glm::dot(m, p[q] - centroid);
    }
    Vec3 values;
    Mat3 vectors;
    symmetric_eigen(ata, values, vectors);
    double largest = std::max({values.x, values.y, values.z});
    Vec3 x(0);
    for (int e = 0; e < 3; ++e)
      if (values[e] > 0.02 * largest) x += vectors[e] * (glm::dot(vectors[e], atb) / values[e]);
    out = centroid + x;
    // Normals that do not agree with their points (noisy, or blurred across an edge) leave the
    // point off some tangent planes: no feature then, rather than an apex standing off the surface.
    for (std::size_t q = 0, c = 0; q < p.size(); ++q) {
      if (st.out.normals[id[q]] == glm::vec3(0.0f)) continue;
      if (std::abs(glm::dot(n[c++], out - p[q])) > kFeatureResidual * h_) return false;
    }
    // Three crossings always meet in a point, right or wrong, so the residual cannot catch normals
    // blurred across a neighbouring edge. The apex may stand out of the box of its loop by a
    // little (a ridge between rays), not by much; and it stays in its cell.
    Aabb loop;
    for (const Vec3& q : p) loop.extend(q);
    loop = loop.inflated(kFeatureOvershoot * h_);
    Aabb cell{Vec3(coord(0, i), coord(1, j), coord(2, st.k)),
              Vec3(coord(0, i + 1), coord(1, j + 1), coord(2, st.k + 1))};
    return loop.contains(out) && cell.inflated(1e-9 * h_).contains(out);
  }

  void emit_cell(SlabState& st, int i, int j, unsigned mask) const;

  // The part of face f of cell (i, j, k) inside the solid, on the lattice's outer boundary.
  void emit_cap(SlabState& st, int i, int j, unsigned mask, int f) const;

  // ---- slabs ---------------------------------------------------------------------------------

  static std::uint64_t shifted(const std::uint64_t* row, int w, int words) {
    return (row[w] >> 1) | (w + 1 < words ? row[w + 1] << 63 : 0);
  }

  void record_keys(const Scratch& s, int node_layer,
                   std::vector<std::pair<std::uint64_t, std::uint32_t>>& keys) const {
    const std::uint64_t layer = static_cast<std::uint64_t>(nx_) * static_cast<std::uint64_t>(ny_);
    const std::size_t p = static_cast<std::size_t>(node_layer & 1);
    for (std::uint32_t c : s.xe_used[p]) keys.emplace_back(c, s.slots[c].xe[p]);
    for (std::uint32_t c : s.ye_used[p]) keys.emplace_back(layer + c, s.slots[c].ye[p]);
    for (std::uint32_t c : s.node_used[p]) keys.emplace_back(2 * layer + c, s.slots[c].node[p]);
    std::sort(keys.begin(), keys.end());
  }

  void process_slab(int k0, int k1, Scratch& s, SlabMesh& out) const {
    s.clear_layer(0), s.clear_layer(1), s.clear_z();
    init_layer(s.s0, k0);
    const std::size_t row_words = static_cast<std::size_t>(words_);
    for (int k = k0; k < k1; ++k) {
      SlabState st{s, out, k};
      s.s1 = s.s0;
      for (std::uint32_t f = flip_offsets_[static_cast<std::size_t>(k) + 1];
           f < flip_offsets_[static_cast<std::size_t>(k) + 2]; ++f) {
        std::uint32_t col = flip_columns_[f];
        int i = static_cast<int>(col % static_cast<std::uint32_t>(nx_)),
            j = static_cast<int>(col / static_cast<std::uint32_t>(nx_));
        s.s1[static_cast<std::size_t>(j) * row_words + static_cast<std::size_t>(i >> 6)] ^=
            std::uint64_t(1) << (i & 63);
      }
      const std::uint64_t last_mask =
          ((nx_ - 1) & 63) ? (std::uint64_t(1) << ((nx_ - 1) & 63)) - 1 : ~std::uint64_t(0);
      const int cell_words = (nx_ - 1 + 63) / 64;  // words holding cells 0 .. nx−2
      auto for_cells = [&](const std::vector<std::uint64_t>* const* layers, int nlayers, bool any,
                           int j, auto&& body) {
        for (int w = 0; w < cell_words; ++w) {
          std::uint64_t acc = 0, ref = 0;
          bool first = true;
          for (int l = 0; l < nlayers; ++l)
            for (int r = 0; r < 2; ++r) {
              const std::uint64_t* row =
                  layers[l]->data() + static_cast<std::size_t>(j + r) * row_words;
              std::uint64_t x = row[w], y = shifted(row, w, words_);
              if (any) {
                acc |= x | y;
              } else {
                if (first) ref = x, first = false;
                acc |= (x ^ ref) | (y ^ ref);
              }
            }
          if (w == cell_words - 1) acc &= last_mask;
          while (acc) {
            int b = std::countr_zero(acc);
            acc &= acc - 1;
            body(w * 64 + b);
          }
        }
      };
      const std::vector<std::uint64_t>* both[2] = {&s.s0, &s.s1};
      const std::vector<std::uint64_t>* lower[1] = {&s.s0};
      const std::vector<std::uint64_t>* upper[1] = {&s.s1};
      if (k == 0)
        for (int j = 0; j + 1 < ny_; ++j)
          for_cells(lower, 1, true, j, [&](int i) { emit_cap(st, i, j, cell_mask(s, i, j), 4); });
      for (int j = 0; j + 1 < ny_; ++j)
        for_cells(both, 2, false, j, [&](int i) { emit_cell(st, i, j, cell_mask(s, i, j)); });
      for (int j = 0; j + 1 < ny_; ++j) {
        emit_cap(st, 0, j, cell_mask(s, 0, j), 0);
        emit_cap(st, nx_ - 2, j, cell_mask(s, nx_ - 2, j), 1);
      }
      for (int i = 0; i + 1 < nx_; ++i) {
        emit_cap(st, i, 0, cell_mask(s, i, 0), 2);
        emit_cap(st, i, ny_ - 2, cell_mask(s, i, ny_ - 2), 3);
      }
      if (k == nz_ - 2)
        for (int j = 0; j + 1 < ny_; ++j)
          for_cells(upper, 1, true, j, [&](int i) { emit_cap(st, i, j, cell_mask(s, i, j), 5); });
      if (k == k0 && k0 > 0) record_keys(s, k, out.bottom);
      if (k == k1 - 1 && k1 < nz_ - 1) record_keys(s, k + 1, out.top);
      // Roll: node layer k+1 becomes the lower layer.
      std::swap(s.s0, s.s1);
      s.clear_z();
      s.clear_layer(k & 1);  // node layer k is done; its parity is reused by layer k + 2
    }
  }

  // Room for n elements in `v`, its pages first touched on `threads` threads. The join fills the
  // mesh on one thread, and the kernel's zeroing of the fresh pages as it met them took most of
  // the join (0.15-0.3 s of model-D's 150 MB surface, bench/README.md, issue 37); the pages
  // written here are the ones the elements then take (a trivially copyable type).
  template <class T>
  static void reserve_touched(std::vector<T>& v, std::size_t n, unsigned threads) {
    static_assert(std::is_trivially_copyable_v<T>);
    v.reserve(n);
    auto* bytes = reinterpret_cast<unsigned char*>(v.data() + v.size());
    const std::size_t total = (v.capacity() - v.size()) * sizeof(T);
    constexpr std::size_t kChunk = std::size_t{2} << 20;
    detail::for_each_chunk((total + kChunk - 1) / kChunk, threads, [&](std::size_t c) {
      std::memset(bytes + c * kChunk, 0, std::min(kChunk, total - c * kChunk));
    });
  }

  // Concatenates the slabs in order; a slab's bottom vertices are the previous slab's top ones.
  Mesh join(std::vector<SlabMesh>& parts, unsigned threads) const {
    Mesh mesh;
    std::size_t vertices = 0, triangles = 0;
    for (const SlabMesh& p : parts)
      vertices += p.positions.size() - p.bottom.size(), triangles += p.triangles.size();
    reserve_touched(mesh.positions, vertices, threads);
    reserve_touched(mesh.triangles, triangles, threads);
    std::vector<std::uint32_t> feature_triangles;
    std::vector<std::pair<std::uint64_t, std::uint32_t>> previous_top;  // key → global id
    std::vector<std::uint32_t> map;
    for (SlabMesh& p : parts) {
      map.assign(p.positions.size(), kNone);
      std::size_t q = 0;
      for (const auto& [key, local] : p.bottom) {
        while (q < previous_top.size() && previous_top[q].first < key) ++q;
        if (q < previous_top.size() && previous_top[q].first == key)
          map[local] = previous_top[q].second;
      }
      for (std::size_t v = 0; v < p.positions.size(); ++v)
        if (map[v] == kNone) {
          map[v] = static_cast<std::uint32_t>(mesh.positions.size());
          mesh.positions.push_back(p.positions[v]);
        }
      std::uint32_t base = static_cast<std::uint32_t>(mesh.triangles.size());
      for (const glm::uvec3& t : p.triangles)
        mesh.triangles.emplace_back(map[t.x], map[t.y], map[t.z]);
      for (std::uint32_t t : p.feature_triangles) feature_triangles.push_back(base + t);
      previous_top.clear();
      for (const auto& [key, local] : p.top) previous_top.emplace_back(key, map[local]);
      p = SlabMesh{};
    }
    if (sharp_) flip_feature_edges(mesh, feature_triangles);
    return mesh;
  }

  // EMC's edge flip: two fans from feature points A and B that meet on a face segment (p, q)
  // become (A, p, B) and (B, q, A), so the mesh edge A–B follows the sharp edge instead of
  // dipping to the cell face. Skipped when it would duplicate an edge, fold, or degenerate.
  static void flip_feature_edges(Mesh& mesh, const std::vector<std::uint32_t>& feature_triangles) {
    std::vector<std::pair<std::uint64_t, std::uint32_t>> by_edge;
    by_edge.reserve(feature_triangles.size());
    for (std::uint32_t t : feature_triangles) {
      const glm::uvec3& tri = mesh.triangles[t];  // apex first
      std::uint64_t lo = std::min(tri.y, tri.z), hi = std::max(tri.y, tri.z);
      by_edge.emplace_back((lo << 32) | hi, t);
    }
    std::sort(by_edge.begin(), by_edge.end());
    std::unordered_set<std::uint64_t> joined;
    for (std::size_t e = 0; e + 1 < by_edge.size(); ++e) {
      if (by_edge[e].first != by_edge[e + 1].first) continue;
      glm::uvec3& t1 = mesh.triangles[by_edge[e].second];
      glm::uvec3& t2 = mesh.triangles[by_edge[e + 1].second];
      std::uint32_t a = t1.x, p = t1.y, q = t1.z, b = t2.x;
      if (t2.y != q || t2.z != p || a == b) continue;
      std::uint64_t key = (std::uint64_t(std::min(a, b)) << 32) | std::max(a, b);
      if (joined.count(key)) continue;
      auto normal = [&](std::uint32_t x, std::uint32_t y, std::uint32_t z) {
        Vec3 px(mesh.positions[x]), py(mesh.positions[y]), pz(mesh.positions[z]);
        return glm::cross(py - px, pz - px);
      };
      Vec3 before = normal(a, p, q) + normal(b, q, p);
      Vec3 n1 = normal(a, p, b), n2 = normal(b, q, a);
      double scale = glm::dot(before, before);
      if (!(glm::dot(n1, before) > 1e-6 * scale) || !(glm::dot(n2, before) > 1e-6 * scale))
        continue;
      Vec3 pa(mesh.positions[a]), pp(mesh.positions[p]), pq(mesh.positions[q]),
          pb(mesh.positions[b]);
      if (!well_shaped(pa, pp, pb) || !well_shaped(pb, pq, pa)) continue;
      t1 = glm::uvec3(a, p, b);
      t2 = glm::uvec3(b, q, a);
      joined.insert(key);
      ++e;
    }
  }

  const TripleDexel& d_;
  int nx_, ny_, nz_;
  double h_;
  int words_;
  bool sharp_ = true;
  double cos_feature_ = 0;
  double delta_ = 1e-3;
  std::vector<std::uint32_t> flip_offsets_;  // per node layer k: flips into layer k
  std::vector<std::uint32_t> flip_columns_;
};

}  // namespace tridex::detail::surface
