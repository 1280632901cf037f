// tridex — cube and face tables for surface extraction (surface.hpp).
//
// Instead of typing in Lorensen & Cline's 256-case marching-cubes table (whose face-ambiguity
// choices are not consistent between neighbouring cells and leave holes), the tables are derived
// once from a single per-face rule, in the spirit of Nielsen & Hamann's face-consistent
// marching cubes (IEEE Vis 1991): walk each face's four corners counter-clockwise seen from
// outside the cube; the edge crossings alternate between "enter" (outside → inside corner) and
// "leave"; every enter crossing is joined to the next crossing of the walk. On an ambiguous face
// (inside corners diagonal) this always separates the two inside corners. The rule depends only
// on the face's own corners, so the two cells sharing a face draw the same segments, in opposite
// directions; each crossing is an enter on one of its two faces and a leave on the other, so the
// segments of a cube close into disjoint loops, oriented counter-clockwise seen from outside the
// solid. The same walk gives the caps where the solid meets the lattice's outer faces.
//
// Cube corner c = bx + 2·by + 4·bz sits at (bx, by, bz). Cube edge e = 4·a + bu + 2·bv runs along
// axis a from the corner with bit a clear, u = (a+1) % 3 and v = (a+2) % 3 being the other axes
// (the layout of dexel.hpp). Face f = 2·a + s is the face with coordinate a equal to s.
#pragma once

#include <array>
#include <cstdint>

namespace tridex::detail::surface {

struct CubeCase {
  std::uint8_t loop_count = 0;
  std::array<std::uint8_t, 4> loop_size{};  // loops are stored one after the other in `edges`
  std::array<std::uint8_t, 12> edges{};
  // For each loop, a vertex from which a fan of diagonals never lies in a cube face (two such
  // diagonals of neighbouring cells could coincide and meet four triangles), or 255 if none.
  std::array<std::uint8_t, 4> fan_start{};
};

// A cap polygon on one face: items 0..3 are the face's corners, 4..7 the crossing on the face
// edge from corner k to corner k+1 (item 4 + k), counter-clockwise seen from outside the cube.
struct FaceCap {
  std::uint8_t polygon_count = 0;
  std::array<std::uint8_t, 2> polygon_size{};
  std::array<std::uint8_t, 8> items{};
};

struct CubeTables {
  std::array<std::array<std::uint8_t, 2>, 12> edge_corners{};  // from, to (along +axis)
  std::array<std::uint8_t, 12> edge_faces{};                   // bit f set when face f holds edge e
  std::array<std::array<std::uint8_t, 4>, 6> face_corners{};   // counter-clockwise from outside
  std::array<std::array<std::uint8_t, 4>, 6> face_edges{};     // edge from face corner k to k+1
  std::array<CubeCase, 256> cases{};
  std::array<std::array<FaceCap, 16>, 6> caps{};  // [face][bit k = face corner k inside]
};

constexpr int cube_edge(int a, int bu, int bv) { return 4 * a + bu + 2 * bv; }

constexpr CubeTables make_cube_tables() {
  CubeTables t{};
  for (int a = 0; a < 3; ++a) {
    int u = (a + 1) % 3, v = (a + 2) % 3;
    for (int bv = 0; bv < 2; ++bv)
      for (int bu = 0; bu < 2; ++bu) {
        int e = cube_edge(a, bu, bv);
        int from = (bu << u) | (bv << v);
        t.edge_corners[e] = {static_cast<std::uint8_t>(from),
                             static_cast<std::uint8_t>(from | (1 << a))};
        t.edge_faces[e] = static_cast<std::uint8_t>((1 << (2 * u + bu)) | (1 << (2 * v + bv)));
      }
  }
  // Seen from +a, (u, v) is right-handed (e_u × e_v = e_a), so (0,0) (1,0) (1,1) (0,1) turns
  // counter-clockwise; seen from −a the order is reversed.
  for (int a = 0; a < 3; ++a) {
    int u = (a + 1) % 3, v = (a + 2) % 3;
    for (int s = 0; s < 2; ++s) {
      const int plus[4][2] = {{0, 0}, {1, 0}, {1, 1}, {0, 1}};
      const int minus[4][2] = {{0, 0}, {0, 1}, {1, 1}, {1, 0}};
      int f = 2 * a + s;
      for (int k = 0; k < 4; ++k) {
        const int* uv = s ? plus[k] : minus[k];
        t.face_corners[f][k] = static_cast<std::uint8_t>((s << a) | (uv[0] << u) | (uv[1] << v));
      }
      for (int k = 0; k < 4; ++k) {
        int c = t.face_corners[f][k], d = t.face_corners[f][(k + 1) % 4];
        int diff = c ^ d, axis = diff == 1 ? 0 : diff == 2 ? 1 : 2;
        int base = c & d, eu = (axis + 1) % 3, ev = (axis + 2) % 3;
        t.face_edges[f][k] =
            static_cast<std::uint8_t>(cube_edge(axis, (base >> eu) & 1, (base >> ev) & 1));
      }
    }
  }
  for (int mask = 0; mask < 256; ++mask) {
    int next[12] = {-1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1, -1};
    for (int f = 0; f < 6; ++f) {
      int crossing[4] = {}, enter[4] = {}, count = 0;
      for (int k = 0; k < 4; ++k) {
        bool in_c = (mask >> t.face_corners[f][k]) & 1,
             in_d = (mask >> t.face_corners[f][(k + 1) % 4]) & 1;
        if (in_c != in_d) crossing[count] = t.face_edges[f][k], enter[count++] = !in_c;
      }
      for (int p = 0; p < count; ++p)
        if (enter[p]) next[crossing[p]] = crossing[(p + 1) % count];
    }
    CubeCase& cc = t.cases[mask];
    bool seen[12] = {};
    int written = 0;
    for (int start = 0; start < 12; ++start) {
      if (next[start] < 0 || seen[start]) continue;
      int size = 0, first = written;
      for (int e = start; !seen[e]; e = next[e]) {
        seen[e] = true;
        cc.edges[written++] = static_cast<std::uint8_t>(e);
        ++size;
      }
      std::uint8_t fan = 255;
      for (int r = 0; r < size && fan == 255; ++r) {
        bool ok = true;
        for (int i = 2; i + 1 < size; ++i)
          if (t.edge_faces[cc.edges[first + r]] & t.edge_faces[cc.edges[first + (r + i) % size]])
            ok = false;
        if (ok) fan = static_cast<std::uint8_t>(r);
      }
      cc.loop_size[cc.loop_count] = static_cast<std::uint8_t>(size);
      cc.fan_start[cc.loop_count++] = fan;
    }
  }
  for (int f = 0; f < 6; ++f)
    for (int mask = 0; mask < 16; ++mask) {
      FaceCap& cap = t.caps[f][mask];
      auto in = [&](int k) { return ((mask >> (k & 3)) & 1) != 0; };
      if (mask == 15) {
        cap.polygon_count = 1, cap.polygon_size[0] = 4;
        for (int k = 0; k < 4; ++k) cap.items[k] = static_cast<std::uint8_t>(k);
        continue;
      }
      int written = 0;
      for (int k = 0; k < 4; ++k) {
        if (in(k) || !in(k + 1)) continue;  // a polygon starts at each enter crossing
        int first = written;
        cap.items[written++] = static_cast<std::uint8_t>(4 + k);
        int c = (k + 1) & 3;
        while (in(c)) {
          cap.items[written++] = static_cast<std::uint8_t>(c);
          c = (c + 1) & 3;
        }
        cap.items[written++] = static_cast<std::uint8_t>(4 + ((c + 3) & 3));  // leave crossing
        cap.polygon_size[cap.polygon_count++] = static_cast<std::uint8_t>(written - first);
      }
    }
  return t;
}

inline constexpr CubeTables kCubeTables = make_cube_tables();

}  // namespace tridex::detail::surface
