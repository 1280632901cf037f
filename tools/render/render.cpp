#include "render.hpp"

// OSMesa's header pulls in GL/gl.h; the legacy fixed-function pipeline is all a shaded
// picture needs and works on every Mesa build (llvmpipe or softpipe).
#include <GL/osmesa.h>
#include <png.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstring>
#include <memory>

#include <glm/gtc/matrix_transform.hpp>
#include <glm/gtc/type_ptr.hpp>

#include "tridex/error.hpp"

// Mesa's OSMesa (22.3) keeps about 200 bytes per OSMesaMakeCurrent buffer that
// OSMesaDestroyContext does not free. Under LeakSanitizer that ends every run with exit status 1,
// so sanitized builds suppress leaks from libOSMesa alone (the hook is LSan's documented one).
#if defined(__SANITIZE_ADDRESS__)
#define TRIDEX_RENDER_LSAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define TRIDEX_RENDER_LSAN 1
#endif
#endif
#ifdef TRIDEX_RENDER_LSAN
extern "C" const char* __lsan_default_suppressions() { return "leak:libOSMesa.so\n"; }
#endif

namespace tridex::render {

namespace {

constexpr int kSupersample = 2;

struct ContextDeleter {
  void operator()(osmesa_context* context) const {
    OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);  // unbind first, so Mesa frees the buffer's state
    OSMesaDestroyContext(context);
  }
};

// Draws one view into the current context's viewport.
void draw_view(const Mesh& mesh, const MeshView& view, const MeshRenderOptions& options, int width,
               int height) {
  Aabb box = mesh.bounds();
  Vec3 centre = box.center();
  double radius = std::max(1e-9, 0.5 * glm::length(box.size()));
  Vec3 eye_dir = glm::normalize(view.eye_direction);
  glm::dmat4 look = glm::lookAt(centre + eye_dir * (3 * radius), centre, view.up);
  double aspect = static_cast<double>(width) / height;
  double half_h = radius * 1.02, half_w = half_h * aspect;
  if (aspect < 1) half_w = radius * 1.02, half_h = half_w / aspect;

  glViewport(0, 0, width, height);
  glClearColor(options.background.r, options.background.g, options.background.b, 1);
  glClear(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
  glMatrixMode(GL_PROJECTION);
  glLoadIdentity();
  glOrtho(-half_w, half_w, -half_h, half_h, radius, 5 * radius);
  glMatrixMode(GL_MODELVIEW);
  // Lights are placed in eye space (identity modelview) so that they follow the camera.
  glLoadIdentity();
  glEnable(GL_LIGHTING);
  glEnable(GL_LIGHT0);
  glEnable(GL_LIGHT1);
  const GLfloat key_dir[] = {0.4f, 0.6f, 1.0f, 0.0f}, key_col[] = {0.75f, 0.75f, 0.75f, 1};
  const GLfloat fill_dir[] = {-0.6f, -0.3f, 0.5f, 0.0f}, fill_col[] = {0.25f, 0.25f, 0.28f, 1};
  const GLfloat ambient[] = {0.22f, 0.22f, 0.22f, 1};
  glLightfv(GL_LIGHT0, GL_POSITION, key_dir);
  glLightfv(GL_LIGHT0, GL_DIFFUSE, key_col);
  glLightfv(GL_LIGHT0, GL_SPECULAR, key_col);
  glLightfv(GL_LIGHT1, GL_POSITION, fill_dir);
  glLightfv(GL_LIGHT1, GL_DIFFUSE, fill_col);
  glLightModelfv(GL_LIGHT_MODEL_AMBIENT, ambient);
  const GLfloat colour[] = {options.colour.r, options.colour.g, options.colour.b, 1};
  const GLfloat specular[] = {0.15f, 0.15f, 0.15f, 1};
  glMaterialfv(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE, colour);
  glMaterialfv(GL_FRONT_AND_BACK, GL_SPECULAR, specular);
  glMaterialf(GL_FRONT_AND_BACK, GL_SHININESS, 24);
  glLoadMatrixd(glm::value_ptr(look));
  glEnable(GL_DEPTH_TEST);
  glEnable(GL_NORMALIZE);
  glShadeModel(GL_FLAT);

  // Flat shading needs one normal per triangle, so triangles are expanded into unshared
  // vertices; chunks bound the extra memory for meshes of tens of millions of triangles.
  constexpr std::size_t kChunk = 1 << 18;
  std::vector<glm::vec3> positions, normals;
  positions.reserve(3 * std::min(kChunk, mesh.triangles.size()));
  normals.reserve(positions.capacity());
  const bool coloured = !options.vertex_colours.empty();
  std::vector<glm::vec3> colours;
  if (coloured) {
    // The material follows the vertex colours (ambient and diffuse) instead of options.colour.
    glColorMaterial(GL_FRONT_AND_BACK, GL_AMBIENT_AND_DIFFUSE);
    glEnable(GL_COLOR_MATERIAL);
    glEnableClientState(GL_COLOR_ARRAY);
    colours.reserve(positions.capacity());
  }
  glEnableClientState(GL_VERTEX_ARRAY);
  glEnableClientState(GL_NORMAL_ARRAY);
  for (std::size_t first = 0; first < mesh.triangles.size(); first += kChunk) {
    positions.clear();
    normals.clear();
    colours.clear();
    std::size_t last = std::min(mesh.triangles.size(), first + kChunk);
    for (std::size_t t = first; t < last; ++t) {
      const glm::uvec3& tri = mesh.triangles[t];
      glm::vec3 a = mesh.positions[tri.x], b = mesh.positions[tri.y], c = mesh.positions[tri.z];
      glm::vec3 n = glm::cross(b - a, c - a);
      positions.insert(positions.end(), {a, b, c});
      normals.insert(normals.end(), {n, n, n});
      if (coloured)
        colours.insert(colours.end(), {options.vertex_colours[tri.x], options.vertex_colours[tri.y],
                                       options.vertex_colours[tri.z]});
    }
    if (coloured) glColorPointer(3, GL_FLOAT, 0, colours.data());
    glVertexPointer(3, GL_FLOAT, 0, positions.data());
    glNormalPointer(GL_FLOAT, 0, normals.data());
    glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(positions.size()));
  }
  glDisableClientState(GL_VERTEX_ARRAY);
  glDisableClientState(GL_NORMAL_ARRAY);
  if (coloured) {
    glDisableClientState(GL_COLOR_ARRAY);
    glDisable(GL_COLOR_MATERIAL);
  }
  glFinish();
}

}  // namespace

Image render_mesh(const Mesh& mesh, const MeshRenderOptions& options) {
  if (mesh.triangles.empty()) detail::fail("render: the mesh has no triangles");
  if (options.views.empty()) detail::fail("render: no view to draw");
  if (!options.vertex_colours.empty() && options.vertex_colours.size() != mesh.positions.size())
    detail::fail("render: ", options.vertex_colours.size(), " vertex colours for ",
                 mesh.positions.size(), " vertices");
  if (options.panel_width < 1 || options.panel_height < 1 || options.panel_width > 8192 ||
      options.panel_height > 8192)
    detail::fail("render: panel size ", options.panel_width, " x ", options.panel_height,
                 " must lie in 1..8192");
  const int w = options.panel_width * kSupersample, h = options.panel_height * kSupersample;
  std::unique_ptr<osmesa_context, ContextDeleter> context(
      OSMesaCreateContextExt(OSMESA_RGBA, 24, 0, 0, nullptr));
  if (!context) detail::fail("render: OSMesa could not create an off-screen context");
  std::vector<std::uint8_t> buffer(static_cast<std::size_t>(w) * static_cast<std::size_t>(h) * 4);
  if (!OSMesaMakeCurrent(context.get(), buffer.data(), GL_UNSIGNED_BYTE, w, h))
    detail::fail("render: OSMesa could not bind the off-screen buffer");

  Image image;
  image.width = options.panel_width * static_cast<int>(options.views.size());
  image.height = options.panel_height;
  image.rgb.assign(
      static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3, 0);
  for (std::size_t v = 0; v < options.views.size(); ++v) {
    draw_view(mesh, options.views[v], options, w, h);
    // OSMesa's rows run bottom-up; average each 2×2 block into one output pixel.
    for (int y = 0; y < options.panel_height; ++y)
      for (int x = 0; x < options.panel_width; ++x)
        for (int c = 0; c < 3; ++c) {
          unsigned sum = 0;
          for (int sy = 0; sy < kSupersample; ++sy)
            for (int sx = 0; sx < kSupersample; ++sx) {
              int bx = x * kSupersample + sx, by = h - 1 - (y * kSupersample + sy);
              sum += buffer[4 * (static_cast<std::size_t>(bx) +
                                 static_cast<std::size_t>(w) * static_cast<std::size_t>(by)) +
                            static_cast<std::size_t>(c)];
            }
          std::size_t ox =
              static_cast<std::size_t>(x) + v * static_cast<std::size_t>(options.panel_width);
          image.rgb[3 * (ox + static_cast<std::size_t>(image.width) * static_cast<std::size_t>(y)) +
                    static_cast<std::size_t>(c)] =
              static_cast<std::uint8_t>(sum / (kSupersample * kSupersample));
        }
  }
  return image;
}

namespace {

// A perceptually ordered ramp (dark blue -> teal -> yellow), piecewise linear.
glm::vec3 ramp(double t) {
  static const glm::vec3 stops[] = {{0.27f, 0.00f, 0.33f},
                                    {0.23f, 0.32f, 0.55f},
                                    {0.13f, 0.57f, 0.55f},
                                    {0.37f, 0.79f, 0.38f},
                                    {0.99f, 0.91f, 0.14f}};
  t = std::clamp(t, 0.0, 1.0) * 4;
  int k = std::min(3, static_cast<int>(t));
  float f = static_cast<float>(t - k);
  return stops[k] * (1 - f) + stops[k + 1] * f;
}

}  // namespace

Image render_heights(const ZMap& map, int max_side) {
  const ZMapGrid& g = map.grid;
  if (map.heights.size() != g.size() || g.size() == 0) detail::fail("render: Z-map is empty");
  if (max_side < 1) detail::fail("render: picture size must be positive, got ", max_side);
  int step = std::max(1, (std::max(g.nx, g.ny) + max_side - 1) / max_side);
  Image image;
  image.width = (g.nx + step - 1) / step;
  image.height = (g.ny + step - 1) / step;
  image.rgb.assign(
      static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3, 0);
  float lo = std::numeric_limits<float>::infinity(), hi = -lo;
  for (float z : map.heights)
    if (z > map.empty_height) lo = std::min(lo, z), hi = std::max(hi, z);
  double range = hi > lo ? hi - lo : 1.0;
  auto at = [&](int i, int j) {
    i = std::clamp(i, 0, g.nx - 1), j = std::clamp(j, 0, g.ny - 1);
    return static_cast<double>(map.height(i, j));
  };
  for (int y = 0; y < image.height; ++y)
    for (int x = 0; x < image.width; ++x) {
      int i = x * step, j = (image.height - 1 - y) * step;
      glm::vec3 colour(0.12f, 0.12f, 0.13f);
      if (!map.is_empty(i, j)) {
        // Hill shading from the north-west, with slopes measured over the sampling step.
        double dzdx = (at(i + step, j) - at(i - step, j)) / (2 * step * g.cell);
        double dzdy = (at(i, j + step) - at(i, j - step)) / (2 * step * g.cell);
        Vec3 normal = glm::normalize(Vec3(-dzdx, -dzdy, 1));
        double light = std::max(0.0, glm::dot(normal, glm::normalize(Vec3(-1, 1, 1.5))));
        colour = ramp((at(i, j) - lo) / range) * static_cast<float>(0.35 + 0.65 * light);
      }
      std::size_t o = 3 * (static_cast<std::size_t>(x) +
                           static_cast<std::size_t>(image.width) * static_cast<std::size_t>(y));
      for (int c = 0; c < 3; ++c)
        image.rgb[o + static_cast<std::size_t>(c)] =
            static_cast<std::uint8_t>(std::lround(255 * std::clamp(colour[c], 0.0f, 1.0f)));
    }
  return image;
}

namespace {

// The classic 5x7 LCD font, ASCII 32 (' ') to 90 ('Z'): five columns per glyph, bit r of a
// column set when row r (from the top) is ink.
constexpr std::uint8_t kFont[59][5] = {
    {0x00, 0x00, 0x00, 0x00, 0x00}, {0x00, 0x00, 0x5F, 0x00, 0x00}, {0x00, 0x07, 0x00, 0x07, 0x00},
    {0x14, 0x7F, 0x14, 0x7F, 0x14}, {0x24, 0x2A, 0x7F, 0x2A, 0x12}, {0x23, 0x13, 0x08, 0x64, 0x62},
    {0x36, 0x49, 0x56, 0x20, 0x50}, {0x00, 0x08, 0x07, 0x03, 0x00}, {0x00, 0x1C, 0x22, 0x41, 0x00},
    {0x00, 0x41, 0x22, 0x1C, 0x00}, {0x2A, 0x1C, 0x7F, 0x1C, 0x2A}, {0x08, 0x08, 0x3E, 0x08, 0x08},
    {0x00, 0x80, 0x70, 0x30, 0x00}, {0x08, 0x08, 0x08, 0x08, 0x08}, {0x00, 0x00, 0x60, 0x60, 0x00},
    {0x20, 0x10, 0x08, 0x04, 0x02}, {0x3E, 0x51, 0x49, 0x45, 0x3E}, {0x00, 0x42, 0x7F, 0x40, 0x00},
    {0x72, 0x49, 0x49, 0x49, 0x46}, {0x21, 0x41, 0x49, 0x4D, 0x33}, {0x18, 0x14, 0x12, 0x7F, 0x10},
    {0x27, 0x45, 0x45, 0x45, 0x39}, {0x3C, 0x4A, 0x49, 0x49, 0x31}, {0x41, 0x21, 0x11, 0x09, 0x07},
    {0x36, 0x49, 0x49, 0x49, 0x36}, {0x46, 0x49, 0x49, 0x29, 0x1E}, {0x00, 0x00, 0x14, 0x00, 0x00},
    {0x00, 0x40, 0x34, 0x00, 0x00}, {0x00, 0x08, 0x14, 0x22, 0x41}, {0x14, 0x14, 0x14, 0x14, 0x14},
    {0x00, 0x41, 0x22, 0x14, 0x08}, {0x02, 0x01, 0x59, 0x09, 0x06}, {0x3E, 0x41, 0x5D, 0x59, 0x4E},
    {0x7C, 0x12, 0x11, 0x12, 0x7C}, {0x7F, 0x49, 0x49, 0x49, 0x36}, {0x3E, 0x41, 0x41, 0x41, 0x22},
    {0x7F, 0x41, 0x41, 0x41, 0x3E}, {0x7F, 0x49, 0x49, 0x49, 0x41}, {0x7F, 0x09, 0x09, 0x09, 0x01},
    {0x3E, 0x41, 0x41, 0x51, 0x73}, {0x7F, 0x08, 0x08, 0x08, 0x7F}, {0x00, 0x41, 0x7F, 0x41, 0x00},
    {0x20, 0x40, 0x41, 0x3F, 0x01}, {0x7F, 0x08, 0x14, 0x22, 0x41}, {0x7F, 0x40, 0x40, 0x40, 0x40},
    {0x7F, 0x02, 0x1C, 0x02, 0x7F}, {0x7F, 0x04, 0x08, 0x10, 0x7F}, {0x3E, 0x41, 0x41, 0x41, 0x3E},
    {0x7F, 0x09, 0x09, 0x09, 0x06}, {0x3E, 0x41, 0x51, 0x21, 0x5E}, {0x7F, 0x09, 0x19, 0x29, 0x46},
    {0x26, 0x49, 0x49, 0x49, 0x32}, {0x03, 0x01, 0x7F, 0x01, 0x03}, {0x3F, 0x40, 0x40, 0x40, 0x3F},
    {0x1F, 0x20, 0x40, 0x20, 0x1F}, {0x3F, 0x40, 0x38, 0x40, 0x3F}, {0x63, 0x14, 0x08, 0x14, 0x63},
    {0x03, 0x04, 0x78, 0x04, 0x03}, {0x61, 0x59, 0x49, 0x4D, 0x43}};

void fill_rect(Image& image, int x0, int y0, int w, int h, glm::vec3 colour) {
  for (int y = std::max(0, y0); y < std::min(image.height, y0 + h); ++y)
    for (int x = std::max(0, x0); x < std::min(image.width, x0 + w); ++x)
      for (int c = 0; c < 3; ++c)
        image.rgb[3 * (static_cast<std::size_t>(x) +
                       static_cast<std::size_t>(image.width) * static_cast<std::size_t>(y)) +
                  static_cast<std::size_t>(c)] =
            static_cast<std::uint8_t>(std::clamp(colour[c], 0.0f, 1.0f) * 255.0f + 0.5f);
}

}  // namespace

void draw_legend(Image& image, const std::vector<LegendEntry>& entries, int scale) {
  if (scale < 1 || scale > 16) detail::fail("render: legend scale ", scale, " must lie in 1..16");
  const int line = 10 * scale, pad = 4 * scale, swatch = 7 * scale;
  std::size_t longest = 0;
  for (const LegendEntry& e : entries) longest = std::max(longest, e.label.size());
  const int width = pad * 3 + swatch + static_cast<int>(longest) * 6 * scale;
  const int height = pad * 2 + static_cast<int>(entries.size()) * line;
  fill_rect(image, 0, 0, width, height, glm::vec3(1));
  for (std::size_t k = 0; k < entries.size(); ++k) {
    const int top = pad + static_cast<int>(k) * line;
    fill_rect(image, pad, top, swatch, swatch, glm::vec3(0.1f));
    fill_rect(image, pad + 1, top + 1, swatch - 2, swatch - 2, entries[k].colour);
    int x = pad * 2 + swatch;
    for (char ch : entries[k].label) {
      int code = std::toupper(static_cast<unsigned char>(ch));
      const std::uint8_t* glyph = kFont[code >= 32 && code <= 90 ? code - 32 : 0];
      for (int col = 0; col < 5; ++col)
        for (int row = 0; row < 7; ++row)
          if (glyph[col] & (1 << row))
            fill_rect(image, x + col * scale, top + row * scale, scale, scale, glm::vec3(0.1f));
      x += 6 * scale;
    }
  }
}

std::vector<std::uint8_t> encode_png(const Image& image) {
  if (image.width < 1 || image.height < 1 ||
      image.rgb.size() !=
          static_cast<std::size_t>(image.width) * static_cast<std::size_t>(image.height) * 3)
    detail::fail("png: image buffer does not match its size ", image.width, " x ", image.height);
  png_structp png = png_create_write_struct(PNG_LIBPNG_VER_STRING, nullptr, nullptr, nullptr);
  if (!png) detail::fail("png: cannot create the encoder");
  png_infop info = png_create_info_struct(png);
  std::vector<std::uint8_t> bytes;
  // libpng reports errors by longjmp; nothing with a destructor lives between setjmp and the
  // calls that may jump, apart from `bytes`, which is declared before it.
  if (!info || setjmp(png_jmpbuf(png))) {
    png_destroy_write_struct(&png, &info);
    detail::fail("png: encoding failed");
  }
  png_set_write_fn(
      png, &bytes,
      [](png_structp p, png_bytep data, png_size_t length) {
        auto* out = static_cast<std::vector<std::uint8_t>*>(png_get_io_ptr(p));
        out->insert(out->end(), data, data + length);
      },
      nullptr);
  png_set_IHDR(png, info, static_cast<png_uint_32>(image.width),
               static_cast<png_uint_32>(image.height), 8, PNG_COLOR_TYPE_RGB, PNG_INTERLACE_NONE,
               PNG_COMPRESSION_TYPE_DEFAULT, PNG_FILTER_TYPE_DEFAULT);
  png_write_info(png, info);
  for (int y = 0; y < image.height; ++y)
    png_write_row(
        png, const_cast<png_bytep>(image.rgb.data() + 3 * static_cast<std::size_t>(image.width) *
                                                          static_cast<std::size_t>(y)));
  png_write_end(png, nullptr);
  png_destroy_write_struct(&png, &info);
  return bytes;
}

}  // namespace tridex::render
