// tridex render — pictures of meshes and Z-maps, off-screen (no display needed).
//
// Meshes are drawn with OSMesa (Mesa's software off-screen OpenGL): flat-shaded triangles with
// two directional lights, an orthographic camera fitted to the mesh, 2×2 supersampled. Z-maps
// are drawn on the CPU as height pictures: a colour ramp over the heights, hill-shaded, empty
// points dark. Both return an RGB image that encode_png turns into a file's bytes.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "tridex/geometry.hpp"
#include "tridex/mesh.hpp"
#include "tridex/zmap.hpp"

namespace tridex::render {

struct Image {
  int width = 0, height = 0;
  std::vector<std::uint8_t> rgb;  // pixel (x, y) at rgb[3·(x + width·y)], row 0 at the top
};

struct MeshView {
  Vec3 eye_direction{1, -1, 0.8};  // from the model's centre towards the camera (world)
  Vec3 up{0, 0, 1};
};

struct MeshRenderOptions {
  int panel_width = 800;  // pixels per view
  int panel_height = 800;
  // One panel per view, side by side. The default pair sees the top and all four sides.
  std::vector<MeshView> views{MeshView{{1, -1, 0.8}, {0, 0, 1}}, MeshView{{-1, 1, 0.8}, {0, 0, 1}}};
  glm::vec3 colour{0.62f, 0.70f, 0.80f};
  glm::vec3 background{0.96f, 0.96f, 0.97f};
  // One colour per mesh vertex (each triangle takes its last vertex's colour, flat shaded);
  // empty: `colour` everywhere.
  std::vector<glm::vec3> vertex_colours;
};

// A key drawn in the picture's top-left corner: a swatch and a label per entry. Labels use a
// built-in 5x7 pixel font: letters (drawn upper case), digits, space and . , : - + < > / % ( ).
struct LegendEntry {
  glm::vec3 colour;
  std::string label;
};
void draw_legend(Image& image, const std::vector<LegendEntry>& entries, int scale = 2);

// Throws tridex::Error if OSMesa cannot make a context or the mesh is empty.
Image render_mesh(const Mesh& mesh, const MeshRenderOptions& options = {});

// A height picture of a Z-map, at most `max_side` pixels along its longer side (x to the right,
// y up).
Image render_heights(const ZMap& map, int max_side = 1600);

// The PNG file of an image (8-bit RGB).
std::vector<std::uint8_t> encode_png(const Image& image);

}  // namespace tridex::render
