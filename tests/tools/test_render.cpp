// The off-screen renderer and the PNG encoder.
#include <doctest/doctest.h>

#include <png.h>

#include <cstring>
#include <random>
#include <set>

#include "render.hpp"

using namespace tridex;
using namespace tridex::render;

namespace {

Mesh box_mesh(const Aabb& box) {
  Mesh m;
  for (const Vec3& c : box.corners()) m.positions.emplace_back(c);
  // Corner i has x from bit 0, y from bit 1, z from bit 2; faces counter-clockwise from outside.
  const unsigned faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    m.triangles.emplace_back(f[0], f[1], f[2]);
    m.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return m;
}

Image decode_png(const std::vector<std::uint8_t>& bytes) {
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  REQUIRE(png_image_begin_read_from_memory(&image, bytes.data(), bytes.size()));
  image.format = PNG_FORMAT_RGB;
  Image out;
  out.width = static_cast<int>(image.width);
  out.height = static_cast<int>(image.height);
  out.rgb.resize(PNG_IMAGE_SIZE(image));
  REQUIRE(png_image_finish_read(&image, nullptr, out.rgb.data(), 0, nullptr));
  return out;
}

const std::uint8_t* pixel(const Image& image, int x, int y) {
  return &image.rgb[3 * (static_cast<std::size_t>(x) +
                         static_cast<std::size_t>(image.width) * static_cast<std::size_t>(y))];
}

}  // namespace

TEST_CASE("PNG encoding round-trips random pixels") {
  std::mt19937 random(11);
  Image image;
  image.width = 37, image.height = 23;
  image.rgb.resize(37 * 23 * 3);
  for (auto& v : image.rgb) v = static_cast<std::uint8_t>(random());
  Image back = decode_png(encode_png(image));
  CHECK(back.width == 37);
  CHECK(back.height == 23);
  CHECK(back.rgb == image.rgb);
  Image bad = image;
  bad.rgb.pop_back();
  CHECK_THROWS_AS(encode_png(bad), tridex::Error);
}

TEST_CASE("a rendered box covers the picture's centre and leaves its corners to the background") {
  MeshRenderOptions options;
  options.panel_width = 120, options.panel_height = 90;
  Mesh mesh = box_mesh(Aabb{Vec3(-3, -2, 0), Vec3(5, 4, 3)});
  Image image = render_mesh(mesh, options);
  REQUIRE(image.width == 240);
  REQUIRE(image.height == 90);
  auto is_background = [&](const std::uint8_t* p) {
    return std::abs(p[0] - 245) <= 2 && std::abs(p[1] - 245) <= 2 && std::abs(p[2] - 247) <= 2;
  };
  for (int panel = 0; panel < 2; ++panel) {
    int x0 = panel * 120;
    CHECK(is_background(pixel(image, x0 + 1, 1)));
    CHECK(is_background(pixel(image, x0 + 118, 88)));
    CHECK(!is_background(pixel(image, x0 + 60, 45)));
  }
  // Faces at different angles to the light get different shades: more than one surface colour.
  std::set<int> shades;
  for (int y = 0; y < 90; ++y)
    for (int x = 0; x < 120; ++x)
      if (!is_background(pixel(image, x, y))) shades.insert(pixel(image, x, y)[0] / 8);
  CHECK(shades.size() >= 3);
  CHECK_THROWS_AS(render_mesh(Mesh{}, options), tridex::Error);
}

TEST_CASE("a height picture orders colours by height and marks empty points") {
  ZMapGrid g;
  g.cell = 1, g.nx = 50, g.ny = 40;
  ZMap map(g, 0.0f, -5.0f);
  for (int j = 0; j < g.ny; ++j)
    for (int i = 0; i < g.nx; ++i) map.heights[g.index(i, j)] = static_cast<float>(i) * 0.1f;
  for (int j = 0; j < 5; ++j)
    for (int i = 0; i < 5; ++i) map.heights[g.index(i, j)] = -5.0f;  // empty corner at (0, 0)
  Image image = render_heights(map);
  REQUIRE(image.width == 50);
  REQUIRE(image.height == 40);
  // Empty points (bottom-left in the picture: y grows upward) are dark grey.
  CHECK(pixel(image, 1, 38)[0] < 40);
  // Low heights are the dark blue end of the ramp, high ones the yellow end.
  CHECK(pixel(image, 48, 20)[1] > pixel(image, 10, 20)[1]);
  CHECK(render_heights(map, 10).width == 10);
}
