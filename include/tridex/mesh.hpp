// tridex — indexed triangle meshes.
//
// Positions are float (the precision of STL, and half the memory of double for the tens of
// millions of vertices a polyhedrized Z-map has). Triangles are counter-clockwise seen from
// outside, so that a closed mesh encloses a positive signed volume.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/glm.hpp>

#include "tridex/geometry.hpp"

namespace tridex {

struct Mesh {
  std::vector<glm::vec3> positions;   // vertex i at positions[i]
  std::vector<glm::uvec3> triangles;  // indices into positions, counter-clockwise from outside

  Aabb bounds() const {
    Aabb box;
    for (const glm::vec3& p : positions) box.extend(Vec3(p));
    return box;
  }

  // Signed enclosed volume by the divergence theorem (sum of signed tetrahedra to the origin),
  // accumulated in double; positive for a closed, outward-oriented mesh.
  double signed_volume() const {
    double six_volume = 0;
    for (const glm::uvec3& t : triangles) {
      Vec3 a(positions[t.x]), b(positions[t.y]), c(positions[t.z]);
      six_volume += glm::dot(a, glm::cross(b, c));
    }
    return six_volume / 6.0;
  }
};

}  // namespace tridex
