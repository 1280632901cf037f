// tridex — the hierarchical AABB tree over a Z-map grid (Inui, Chen and Umezu, CAD&A 19(4)
// 2022, §4.2) and exact ray queries against the Z-map's polyhedron (polyhedron.hpp).
//
// The tree is built on the grid itself: the root covers all cells; a node is halved alternately
// along x and y (along the other axis once one side is down to 4 cells) until it has at most
// 4 × 4 cells. A node stores only the lowest and highest top height over its points; its x-y
// extent follows from the split rule. It also stores the plane through three of its corners and
// a bound on how far the top strays from that plane (bottom-up: a child's bound plus the largest
// gap between the two planes at the child's corners), 28 bytes in all.
//
// Query. Instead of collecting triangle hits and pairing them (which can lose or double a hit
// where a ray grazes a shared edge or vertex), the ray's solid part is found as a 1-D sign
// analysis: inside the grid's rectangle and above the bottom, the ray is in the solid where
// g(t) = z(t) − H(x(t), y(t)) ≤ 0, H the piecewise-linear top. The traversal cuts the ray's
// parameter range at the same split lines as the tree (each cut computed once, by the parent),
// so the pieces tile the range exactly; a node whose height range (or plane band) lies wholly
// above or below the ray over its piece is settled without descending (the paper's pruning,
// tightened for flat regions), and a leaf
// walks its cells, cutting at grid lines and cell diagonals (and, in a fine cell, at its
// sub-grid's lines and diagonals), where g is linear. The result is a sorted list of disjoint
// intervals — boundary crossings come out paired by construction. A fine cell's vertical steps
// need no faces here: H jumps between the pieces on either side of the cell's edge.
#pragma once

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <vector>

#include "tridex/error.hpp"
#include "tridex/polyhedron.hpp"
#include "tridex/zmap.hpp"

namespace tridex {

// A span [enter, exit] of ray parameter inside the solid.
struct RaySpan {
  double enter;
  double exit;
};

// One crossing of the polyhedron's boundary: t along the ray and whether the ray enters there.
struct RayHit {
  double t;
  bool entering;
};

class GridTree {
 public:
  static constexpr int kLeafCells = 4;

  struct Node {
    float lo, hi;        // lowest and highest top height over the node's points
    std::uint32_t left;  // first child (the second is left + 1); 0 for a leaf
    // A plane through the node's corners (i0, j0), (i1, j0), (i0, j1):
    // P(x, y) = c + a·(x − x(i0)) + b·(y − y(j0)), and a bound on |H − P| over the node.
    float a, b, c, deviation;
  };

  // The tree refers to `map` (it stores no heights of its own): keep the map alive and unchanged
  // while the tree is used. Throws tridex::Error for a map with fewer than 2 × 2 points.
  explicit GridTree(const ZMap& map) : map_(&map) {
    detail::require_solid_zmap(map, "grid tree");
    bottom_ = detail::zmap_bottom(map);
    const Range root{0, 0, map.grid.nx - 1, map.grid.ny - 1, 0};
    nodes_.reserve(root.count());  // exactly: no regrowth of a vector of millions of nodes
    nodes_.push_back({});
    build(0, root);
  }

  const ZMap& map() const { return *map_; }

  // The cells [i0, i1) × [j0, j1) of each node, by node index (for inspection and tests).
  struct NodeCells {
    int i0, j0, i1, j1;
  };
  std::vector<NodeCells> node_cells() const {
    std::vector<NodeCells> cells(nodes_.size());
    std::vector<std::pair<std::uint32_t, Range>> stack{
        {0, Range{0, 0, map_->grid.nx - 1, map_->grid.ny - 1, 0}}};
    while (!stack.empty()) {
      auto [index, r] = stack.back();
      stack.pop_back();
      cells[index] = {r.i0, r.j0, r.i1, r.j1};
      if (nodes_[index].left == 0) continue;
      int at;
      int axis = r.split(at);
      stack.push_back({nodes_[index].left, r.child(axis, at, false)});
      stack.push_back({nodes_[index].left + 1, r.child(axis, at, true)});
    }
    return cells;
  }

  // Node `index`'s plane P at frame-local (x, y); `c` its cells from node_cells().
  double plane_at(std::uint32_t index, const NodeCells& c, double x, double y) const {
    return plane_at(nodes_[index], Range{c.i0, c.j0, c.i1, c.j1, 0}, x, y);
  }
  const std::vector<Node>& nodes() const { return nodes_; }
  double bottom() const { return bottom_; }

  // The spans of o + t·d (frame-local origin and direction, d non-zero) inside the polyhedron,
  // sorted and disjoint, for t in [t_min, t_max]; appended to `out`.
  void spans(const Vec3& o, const Vec3& d, std::vector<RaySpan>& out,
             double t_min = -std::numeric_limits<double>::infinity(),
             double t_max = std::numeric_limits<double>::infinity()) const {
    const ZMapGrid& g = map_->grid;
    double ta = t_min, tb = t_max;
    // Clip to the box: the grid's rectangle, and the bottom up to the highest top.
    const double lo[3] = {g.x(0), g.y(0), bottom_},
                 hi[3] = {g.x(g.nx - 1), g.y(g.ny - 1), double(nodes_[0].hi)};
    for (int a = 0; a < 3; ++a) {
      if (d[a] == 0) {
        if (o[a] < lo[a] || o[a] > hi[a]) return;
        continue;
      }
      double t0 = (lo[a] - o[a]) / d[a], t1 = (hi[a] - o[a]) / d[a];
      if (t0 > t1) std::swap(t0, t1);
      ta = std::max(ta, t0), tb = std::min(tb, t1);
    }
    if (!(ta <= tb)) return;
    std::size_t first = out.size();
    Walker w{*this, o, d, out, first};
    w.visit(0, Range{0, 0, g.nx - 1, g.ny - 1, 0}, ta, tb);
  }

  // Every crossing of the ray o + t·d with the polyhedron's boundary, sorted by t: the ends of
  // the spans, so entering and leaving alternate.
  std::vector<RayHit> hits(const Vec3& o, const Vec3& d) const {
    std::vector<RaySpan> s;
    spans(o, d, s);
    std::vector<RayHit> out;
    out.reserve(2 * s.size());
    for (const RaySpan& span : s)
      out.push_back({span.enter, true}), out.push_back({span.exit, false});
    return out;
  }

 private:
  // Cells [i0, i1) × [j0, j1) and the depth that picks the split axis.
  struct Range {
    int i0, j0, i1, j1, depth;
    bool leaf() const { return i1 - i0 <= kLeafCells && j1 - j0 <= kLeafCells; }
    // Split along x at even depths, along y at odd ones, along the other axis once one side is
    // down to a leaf's width; at the block of 4 cells nearest the middle, so that leaves are
    // full 4 × 4 blocks (plain halving of 4999 cells ends in leaves of 2 or 3). Returns the axis
    // (0 = x, 1 = y) and the split grid line.
    int split(int& at) const {
      bool x = (depth % 2 == 0) ? (i1 - i0 > kLeafCells) : !(j1 - j0 > kLeafCells);
      int lo = x ? i0 : j0, hi = x ? i1 : j1;
      int blocks = (hi - lo + kLeafCells - 1) / kLeafCells;
      at = lo + kLeafCells * (blocks / 2);
      return x ? 0 : 1;
    }
    std::size_t count() const {  // nodes in the subtree
      if (leaf()) return 1;
      int at;
      int axis = split(at);
      return 1 + child(axis, at, false).count() + child(axis, at, true).count();
    }
    Range child(int axis, int at, bool upper) const {
      Range r = *this;
      ++r.depth;
      if (axis == 0)
        (upper ? r.i0 : r.i1) = at;
      else
        (upper ? r.j0 : r.j1) = at;
      return r;
    }
  };

  double top(int i, int j) const { return detail::zmap_top(*map_, map_->grid.index(i, j)); }

  // The corner plane of range r, with coefficients rounded to float as stored.
  void set_plane(Node& node, const Range& r) const {
    const ZMapGrid& g = map_->grid;
    double h00 = top(r.i0, r.j0);
    node.c = static_cast<float>(h00);
    node.a = static_cast<float>((top(r.i1, r.j0) - h00) / (g.x(r.i1) - g.x(r.i0)));
    node.b = static_cast<float>((top(r.i0, r.j1) - h00) / (g.y(r.j1) - g.y(r.j0)));
  }

  double plane_at(const Node& node, const Range& r, double x, double y) const {
    const ZMapGrid& g = map_->grid;
    return double(node.c) + double(node.a) * (x - g.x(r.i0)) + double(node.b) * (y - g.y(r.j0));
  }

  // A float at least as large as `bound`, with headroom for the double rounding of the tests.
  static float round_up(double bound) {
    auto f = static_cast<float>(bound * (1 + 1e-6) + 1e-9);
    return std::nextafter(f, std::numeric_limits<float>::infinity());
  }

  void build(std::uint32_t index, const Range& r) {
    const ZMapGrid& g = map_->grid;
    if (r.leaf()) {
      Node node{};
      set_plane(node, r);
      float lo = std::numeric_limits<float>::infinity(), hi = -lo;
      double deviation = 0;
      for (int j = r.j0; j <= r.j1; ++j)
        for (int i = r.i0; i <= r.i1; ++i) {
          double h = top(i, j);
          lo = std::min(lo, static_cast<float>(h)), hi = std::max(hi, static_cast<float>(h));
          deviation = std::max(deviation, std::abs(h - plane_at(node, r, g.x(i), g.y(j))));
        }
      // A fine cell's sub-points may stray beyond its corners (a rib between grid points).
      constexpr int kSteps = ZMapFineCells::kSteps, kSide = ZMapFineCells::kSide;
      for (int j = r.j0; j < r.j1 && !map_->fine.empty(); ++j)
        for (int i = r.i0; i < r.i1; ++i)
          if (const float* f = map_->fine_cell(i, j))
            for (int b = 0; b < kSide; ++b)
              for (int a = 0; a < kSide; ++a) {
                const float h = f[a + kSide * b];
                lo = std::min(lo, h), hi = std::max(hi, h);
                const double x = g.x(i) + a * (g.cell / kSteps), y = g.y(j) + b * (g.cell / kSteps);
                deviation = std::max(deviation, std::abs(double(h) - plane_at(node, r, x, y)));
              }
      node.lo = lo, node.hi = hi, node.left = 0, node.deviation = round_up(deviation);
      nodes_[index] = node;
      return;
    }
    int at;
    int axis = r.split(at);
    auto left = static_cast<std::uint32_t>(nodes_.size());
    nodes_.push_back({}), nodes_.push_back({});
    Range children[2] = {r.child(axis, at, false), r.child(axis, at, true)};
    build(left, children[0]);
    build(left + 1, children[1]);
    Node node{};
    set_plane(node, r);
    node.lo = std::min(nodes_[left].lo, nodes_[left + 1].lo);
    node.hi = std::max(nodes_[left].hi, nodes_[left + 1].hi);
    node.left = left;
    // |H − P| ≤ |H − P_child| + |P_child − P|, and the last, being linear, peaks at a corner.
    double deviation = 0;
    for (int k = 0; k < 2; ++k) {
      const Node& child = nodes_[left + static_cast<std::uint32_t>(k)];
      const Range& c = children[k];
      double worst = 0;
      for (double x : {g.x(c.i0), g.x(c.i1)})
        for (double y : {g.y(c.j0), g.y(c.j1)})
          worst = std::max(worst, std::abs(plane_at(child, c, x, y) - plane_at(node, r, x, y)));
      deviation = std::max(deviation, double(child.deviation) + worst);
    }
    node.deviation = round_up(deviation);
    nodes_[index] = node;
  }

  struct Walker {
    const GridTree& tree;
    Vec3 o, d;
    std::vector<RaySpan>& out;
    std::size_t first;  // spans before this index belong to earlier queries: never merge into them

    void emit(double t0, double t1) {
      if (!(t0 <= t1)) return;
      // Pieces arrive in order and share their end values exactly: a span that starts where the
      // last ended continues it.
      // A lone zero-length piece is a touch, not a span.
      if (out.size() > first && t0 <= out.back().exit)
        out.back().exit = std::max(out.back().exit, t1);
      else if (t0 < t1)
        out.push_back({t0, t1});
    }

    void visit(std::uint32_t index, const Range& r, double ta, double tb) {
      if (!(ta < tb)) return;  // the ray only touches this node's border: no length inside
      const Node& node = tree.nodes_[index];
      double za = o.z + ta * d.z, zb = o.z + tb * d.z;
      if (std::min(za, zb) > node.hi) return;  // wholly above the top: outside
      if (std::max(za, zb) < node.lo) {        // wholly below the top: inside
        emit(ta, tb);
        return;
      }
      // Against the node's plane: a ray running close and parallel to a flat region (an uncut
      // stock face seen at a tilt) is settled here instead of in every leaf along it.
      double ga = za - tree.plane_at(node, r, o.x + ta * d.x, o.y + ta * d.y);
      double gb = zb - tree.plane_at(node, r, o.x + tb * d.x, o.y + tb * d.y);
      if (std::min(ga, gb) > node.deviation) return;
      if (std::max(ga, gb) < -double(node.deviation)) {
        emit(ta, tb);
        return;
      }
      if (node.left == 0) {
        leaf(r, ta, tb);
        return;
      }
      int at;
      int axis = r.split(at);
      const ZMapGrid& g = tree.map_->grid;
      double line = axis == 0 ? g.x(at) : g.y(at);
      double oa = o[axis], da = d[axis];
      Range lower = r.child(axis, at, false), upper = r.child(axis, at, true);
      if (da == 0) {  // parallel to the split line: wholly on one side (the line itself: upper)
        if (oa < line)
          visit(node.left, lower, ta, tb);
        else
          visit(node.left + 1, upper, ta, tb);
        return;
      }
      double tm = std::clamp((line - oa) / da, ta, tb);
      if (da > 0) {
        visit(node.left, lower, ta, tm);
        visit(node.left + 1, upper, tm, tb);
      } else {
        visit(node.left + 1, upper, ta, tm);
        visit(node.left, lower, tm, tb);
      }
    }

    // The cells of a leaf: cut [ta, tb] at the grid lines inside the leaf, then at each cell's
    // diagonal, and solve the linear g on each piece.
    void leaf(const Range& r, double ta, double tb) {
      const ZMapGrid& g = tree.map_->grid;
      double cuts[2 * kLeafCells + 2];
      int count = 0;
      cuts[count++] = ta;
      for (int i = r.i0 + 1; i < r.i1; ++i)
        if (d.x != 0) {
          double t = (g.x(i) - o.x) / d.x;
          if (t > ta && t < tb) cuts[count++] = t;
        }
      for (int j = r.j0 + 1; j < r.j1; ++j)
        if (d.y != 0) {
          double t = (g.y(j) - o.y) / d.y;
          if (t > ta && t < tb) cuts[count++] = t;
        }
      // At most 2·3 cuts: insertion sort (std::sort on a tiny array trips GCC's bounds warning).
      for (int k = 2; k < count; ++k)
        for (int m = k; m > 1 && cuts[m] < cuts[m - 1]; --m) std::swap(cuts[m], cuts[m - 1]);
      cuts[count++] = tb;
      for (int k = 0; k + 1 < count; ++k) cell_piece(r, cuts[k], cuts[k + 1]);
    }

    void cell_piece(const Range& r, double t0, double t1) {
      const ZMapGrid& g = tree.map_->grid;
      double tm = 0.5 * (t0 + t1);
      int i = std::clamp(static_cast<int>(std::floor((o.x + tm * d.x - g.x0) / g.cell)), r.i0,
                         r.i1 - 1);
      int j = std::clamp(static_cast<int>(std::floor((o.y + tm * d.y - g.y0) / g.cell)), r.j0,
                         r.j1 - 1);
      const ZMap& map = *tree.map_;
      if (const float* f = map.fine_cell(i, j)) return fine_piece(i, j, f, t0, t1);
      double h00 = detail::zmap_top(map, g.index(i, j)),
             h10 = detail::zmap_top(map, g.index(i + 1, j));
      double h01 = detail::zmap_top(map, g.index(i, j + 1)),
             h11 = detail::zmap_top(map, g.index(i + 1, j + 1));
      quad_piece(g.x(i), g.y(j), g.cell, h00, h10, h01, h11, t0, t1);
    }

    // A fine cell (ZMapFineCells): cut [t0, t1] at its sub-grid lines, each sub-cell a quad.
    void fine_piece(int i, int j, const float* f, double t0, double t1) {
      constexpr int kSteps = ZMapFineCells::kSteps, kSide = ZMapFineCells::kSide;
      const ZMapGrid& g = tree.map_->grid;
      const double step = g.cell / kSteps, x0 = g.x(i), y0 = g.y(j);
      double cuts[2 * kSteps];
      int count = 0;
      cuts[count++] = t0;
      for (int m = 1; m < kSteps; ++m) {
        if (d.x != 0) {
          double t = (x0 + m * step - o.x) / d.x;
          if (t > t0 && t < t1) cuts[count++] = t;
        }
        if (d.y != 0) {
          double t = (y0 + m * step - o.y) / d.y;
          if (t > t0 && t < t1) cuts[count++] = t;
        }
      }
      for (int k = 2; k < count; ++k)
        for (int m = k; m > 1 && cuts[m] < cuts[m - 1]; --m) std::swap(cuts[m], cuts[m - 1]);
      cuts[count++] = t1;
      for (int k = 0; k + 1 < count; ++k) {
        const double tm = 0.5 * (cuts[k] + cuts[k + 1]);
        const int a =
            std::clamp(static_cast<int>(std::floor((o.x + tm * d.x - x0) / step)), 0, kSteps - 1);
        const int b =
            std::clamp(static_cast<int>(std::floor((o.y + tm * d.y - y0) / step)), 0, kSteps - 1);
        quad_piece(x0 + a * step, y0 + b * step, step, f[a + kSide * b], f[a + 1 + kSide * b],
                   f[a + kSide * (b + 1)], f[a + 1 + kSide * (b + 1)], cuts[k], cuts[k + 1]);
      }
    }

    // The piece [t0, t1] over one square of the triangulation (a cell, or a fine cell's
    // sub-cell) with corner (x0, y0), side `size` and corner heights h00 … h11.
    void quad_piece(double x0, double y0, double size, double h00, double h10, double h01,
                    double h11, double t0, double t1) {
      // Square-local coordinates along the ray: f(t) = (o + t·d − corner) / size.
      double fx0 = (o.x - x0) / size, fdx = d.x / size;
      double fy0 = (o.y - y0) / size, fdy = d.y / size;
      auto g_lower = [&](double t) {  // triangle fx ≥ fy
        return o.z + t * d.z -
               (h00 + (fx0 + t * fdx) * (h10 - h00) + (fy0 + t * fdy) * (h11 - h10));
      };
      auto g_upper = [&](double t) {  // triangle fx < fy
        return o.z + t * d.z -
               (h00 + (fx0 + t * fdx) * (h11 - h01) + (fy0 + t * fdy) * (h01 - h00));
      };
      // The diagonal fx = fy splits the piece where (fx0 − fy0) + t·(fdx − fdy) changes sign.
      double c0 = fx0 - fy0, cd = fdx - fdy;
      double split = cd != 0 ? -c0 / cd : std::numeric_limits<double>::quiet_NaN();
      // Each sub-piece picks its triangle at its own midpoint, so a split that rounding puts a
      // hair inside the piece cannot send the long part to the wrong triangle.
      auto solve_on = [&](double a, double b) {
        if ((c0 + 0.5 * (a + b) * cd) >= 0)
          solve(g_lower, a, b);
        else
          solve(g_upper, a, b);
      };
      if (split > t0 && split < t1) {
        solve_on(t0, split);
        solve_on(split, t1);
      } else {
        solve_on(t0, t1);
      }
    }

    // Emits the part of [t0, t1] where the linear function gf is ≤ 0.
    template <class F>
    void solve(const F& gf, double t0, double t1) {
      double g0 = gf(t0), g1 = gf(t1);
      if (g0 <= 0 && g1 <= 0) return emit(t0, t1);
      if (g0 > 0 && g1 > 0) return;
      double root = std::clamp(t0 + (t1 - t0) * (g0 / (g0 - g1)), t0, t1);
      if (g0 <= 0)
        emit(t0, root);
      else
        emit(root, t1);
    }
  };

  const ZMap* map_;
  double bottom_ = 0;
  std::vector<Node> nodes_;
};

}  // namespace tridex
