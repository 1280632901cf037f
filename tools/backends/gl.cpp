#include "tridex/backends/gl_mill.hpp"

#define GL_GLEXT_PROTOTYPES 1
#include <GL/osmesa.h>
#include <GL/gl.h>
#include <GL/glext.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <memory>
#include <vector>

#include "tridex/error.hpp"

namespace tridex::backends {

namespace {

// The tessellated lower surface of one cutter, relative to its tip.
struct CutterCap {
  std::vector<Vec3> vertices;
  std::vector<glm::uvec3> faces;
  std::vector<Vec3> normals;  // per face, pointing out of the cutter (downward-ish)
  struct Edge {
    std::uint32_t a, b;
    int f0, f1;  // adjacent faces; f1 = −1 on the rim
  };
  std::vector<Edge> edges;
};

CutterCap tessellate(const Cutter& cutter, double tolerance) {
  const double half = 0.5 * tolerance, radius = cutter.radius();
  // Profile points (d, h) on the true curve from the axis outward; chords with sagitta ≤ ε/2.
  std::vector<Vec2> profile;
  for (const ProfilePiece& p : cutter.pieces()) {
    if (profile.empty()) profile.emplace_back(p.d0, p.height(p.d0));
    if (!p.is_arc) {
      profile.emplace_back(p.d1, p.height(p.d1));
      continue;
    }
    double a0 = std::asin(std::clamp((p.d0 - p.centre_d) / p.radius, -1.0, 1.0));
    double a1 = std::asin(std::clamp((p.d1 - p.centre_d) / p.radius, -1.0, 1.0));
    double step = half >= p.radius ? 1.0 : 2 * std::acos(1 - half / p.radius);
    int n = std::max(1, static_cast<int>(std::ceil((a1 - a0) / step)));
    for (int k = 1; k <= n; ++k) {
      double a = a0 + (a1 - a0) * k / n;
      profile.emplace_back(k == n ? p.d1 : p.centre_d + p.radius * std::sin(a),
                           p.centre_h - p.radius * std::cos(a));
    }
  }
  // Drop repeated points (a piece starting where the last ended).
  std::vector<Vec2> rings;
  for (const Vec2& q : profile)
    if (rings.empty() || q.x > rings.back().x + 1e-12 * radius) rings.push_back(q);
  const double ring_step = half >= radius ? 2.0 : 2 * std::acos(1 - half / radius);
  const int s = std::max(8, static_cast<int>(std::ceil(2 * 3.141592653589793 / ring_step)));
  CutterCap cap;
  const bool pointed = rings.front().x <= 1e-12 * radius;  // the first ring is the tip itself
  std::vector<std::uint32_t> first_of_ring;
  for (std::size_t k = 0; k < rings.size(); ++k) {
    first_of_ring.push_back(static_cast<std::uint32_t>(cap.vertices.size()));
    if (k == 0 && pointed) {
      cap.vertices.emplace_back(0, 0, rings[0].y);
      continue;
    }
    for (int m = 0; m < s; ++m) {
      double angle = 2 * 3.141592653589793 * m / s;
      cap.vertices.emplace_back(rings[k].x * std::cos(angle), rings[k].x * std::sin(angle),
                                rings[k].y);
    }
  }
  if (!pointed) {  // a flat tip disc: a centre vertex fans it
    cap.vertices.emplace_back(0, 0, rings[0].y);
  }
  const auto centre = static_cast<std::uint32_t>(pointed ? 0 : cap.vertices.size() - 1);
  auto ring_vertex = [&](std::size_t k, int m) {
    return first_of_ring[k] + static_cast<std::uint32_t>(m % s);
  };
  // Faces seen from below counter-clockwise... orientation does not matter (no culling); the
  // normals are made to point down.
  auto add_face = [&](std::uint32_t a, std::uint32_t b, std::uint32_t c) {
    Vec3 n = glm::cross(cap.vertices[b] - cap.vertices[a], cap.vertices[c] - cap.vertices[a]);
    if (glm::dot(n, n) == 0) return;
    if (n.z > 0) n = -n;
    cap.faces.emplace_back(a, b, c);
    cap.normals.push_back(glm::normalize(n));
  };
  const std::size_t first_ring = pointed ? 1 : 0;
  for (int m = 0; m < s; ++m)
    add_face(centre, ring_vertex(first_ring, m), ring_vertex(first_ring, m + 1));
  for (std::size_t k = first_ring; k + 1 < rings.size(); ++k)
    for (int m = 0; m < s; ++m) {
      add_face(ring_vertex(k, m), ring_vertex(k + 1, m), ring_vertex(k + 1, m + 1));
      add_face(ring_vertex(k, m), ring_vertex(k + 1, m + 1), ring_vertex(k, m + 1));
    }
  // Edges with their faces.
  std::vector<std::pair<std::uint64_t, int>> keyed;
  for (std::size_t f = 0; f < cap.faces.size(); ++f) {
    const glm::uvec3& t = cap.faces[f];
    const std::uint32_t v[3] = {t.x, t.y, t.z};
    for (int e = 0; e < 3; ++e) {
      std::uint32_t a = std::min(v[e], v[(e + 1) % 3]), b = std::max(v[e], v[(e + 1) % 3]);
      keyed.emplace_back((std::uint64_t{a} << 32) | b, static_cast<int>(f));
    }
  }
  std::sort(keyed.begin(), keyed.end());
  for (std::size_t k = 0; k < keyed.size();) {
    std::size_t end = k + 1;
    while (end < keyed.size() && keyed[end].first == keyed[k].first) ++end;
    auto a = static_cast<std::uint32_t>(keyed[k].first >> 32),
         b = static_cast<std::uint32_t>(keyed[k].first & 0xFFFFFFFFu);
    cap.edges.push_back({a, b, keyed[k].second, end - k > 1 ? keyed[k + 1].second : -1});
    k = end;
  }
  return cap;
}

struct ContextDeleter {
  void operator()(osmesa_context* c) const { OSMesaDestroyContext(c); }
};

// An OSMesa context with a float depth FBO of side `size`, current on this thread.
class DepthTarget {
 public:
  explicit DepthTarget(int requested_side) {
    context_.reset(OSMesaCreateContextExt(OSMESA_RGBA, 0, 0, 0, nullptr));
    if (!context_) detail::fail("gl: OSMesa could not create an off-screen context");
    if (!OSMesaMakeCurrent(context_.get(), dummy_, GL_UNSIGNED_BYTE, 1, 1))
      detail::fail("gl: OSMesa could not make its context current");
    GLint viewport[2] = {0, 0}, renderbuffer = 0;
    glGetIntegerv(GL_MAX_VIEWPORT_DIMS, viewport);
    glGetIntegerv(GL_MAX_RENDERBUFFER_SIZE, &renderbuffer);
    int limit = std::min({viewport[0], viewport[1], renderbuffer, 4096});
    if (limit < 1) detail::fail("gl: the context reports no usable viewport");
    side_ = requested_side > 0 ? std::min(requested_side, limit) : limit;
    glGenFramebuffers(1, &fbo_);
    glBindFramebuffer(GL_FRAMEBUFFER, fbo_);
    glGenRenderbuffers(1, &depth_);
    glBindRenderbuffer(GL_RENDERBUFFER, depth_);
    glRenderbufferStorage(GL_RENDERBUFFER, GL_DEPTH_COMPONENT32F, side_, side_);
    glFramebufferRenderbuffer(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT, GL_RENDERBUFFER, depth_);
    glDrawBuffer(GL_NONE);
    glReadBuffer(GL_NONE);
    if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE)
      detail::fail("gl: a framebuffer with a 32-bit float depth buffer of ", side_, " x ", side_,
                   " is not supported");
    GLint bits = 0;
    glGetFramebufferAttachmentParameteriv(GL_FRAMEBUFFER, GL_DEPTH_ATTACHMENT,
                                          GL_FRAMEBUFFER_ATTACHMENT_COMPONENT_TYPE, &bits);
    if (bits != GL_FLOAT) detail::fail("gl: the depth attachment is not floating point");
    glMatrixMode(GL_PROJECTION), glLoadIdentity();
    glMatrixMode(GL_MODELVIEW), glLoadIdentity();
    glEnable(GL_DEPTH_TEST);
    glDepthFunc(GL_LESS);
    glDepthMask(GL_TRUE);
    glDisable(GL_CULL_FACE);
    glColorMask(GL_FALSE, GL_FALSE, GL_FALSE, GL_FALSE);
    glClearDepth(1.0);
    glEnableClientState(GL_VERTEX_ARRAY);
  }
  ~DepthTarget() {
    if (!context_) return;
    glDeleteRenderbuffers(1, &depth_);
    glDeleteFramebuffers(1, &fbo_);
  }
  DepthTarget(const DepthTarget&) = delete;
  DepthTarget& operator=(const DepthTarget&) = delete;
  int side() const { return side_; }

 private:
  std::unique_ptr<osmesa_context, ContextDeleter> context_;
  unsigned char dummy_[16]{};
  GLuint fbo_ = 0, depth_ = 0;
  int side_ = 0;
};

}  // namespace

bool gl_available() {
  try {
    DepthTarget target(16);
    return true;
  } catch (const Error&) {
    return false;
  }
}

void gl_mill(ZMap& map, std::span<const Cutter> cutters, std::span<const CutMove> moves,
             const GlMillOptions& options) {
  ZMap::validate(map.grid, {std::numeric_limits<std::size_t>::max()});
  if (map.heights.size() != map.grid.size())
    detail::fail("gl mill: Z-map holds ", map.heights.size(), " heights for ", map.grid.size(),
                 " points");
  const ZMapGrid& g = map.grid;
  const double tolerance = options.tolerance == 0 ? 0.25 * g.cell : options.tolerance;
  detail::require_positive(tolerance, "gl mill tolerance");
  if (options.max_tile < 0)
    detail::fail("gl mill: max tile ", options.max_tile, " must be positive (or 0 for the limit)");
  double z_lo = std::numeric_limits<double>::infinity();
  for (std::size_t k = 0; k < moves.size(); ++k) {
    const CutMove& m = moves[k];
    if (m.cutter >= cutters.size())
      detail::fail("gl mill: move ", k, " uses cutter ", m.cutter, " of ", cutters.size());
    if (!is_finite(m.tip.a) || !is_finite(m.tip.b))
      detail::fail("gl mill: move ", k, " is not finite");
    z_lo = std::min({z_lo, m.tip.a.z, m.tip.b.z});
  }
  if (moves.empty()) return;
  z_lo -=
      1.0 + 0.01 * std::abs(z_lo);  // below every tip: nothing drawn is clipped at the near plane
  std::vector<CutterCap> caps;
  for (const Cutter& c : cutters) caps.push_back(tessellate(c, tolerance));

  DepthTarget target(options.max_tile);
  const int side = target.side();
  std::vector<float> depth(static_cast<std::size_t>(side) * static_cast<std::size_t>(side));
  std::vector<float> batch;
  const std::size_t batch_floats = 3 * 3 * 65536;
  batch.reserve(batch_floats + 4096);
  std::vector<Vec3> moved_a, moved_b;  // a cap at both ends of a move, in NDC
  std::vector<signed char> side_of;    // per face: sign of normal·(b − a)

  for (int j0 = 0; j0 < g.ny; j0 += side)
    for (int i0 = 0; i0 < g.nx; i0 += side) {
      const int w = std::min(side, g.nx - i0), h = std::min(side, g.ny - j0);
      double z_hi = -std::numeric_limits<double>::infinity();
      for (int j = j0; j < j0 + h; ++j)
        for (int i = i0; i < i0 + w; ++i) z_hi = std::max(z_hi, double(map.height(i, j)));
      if (!(z_hi > z_lo)) continue;  // nothing here any move can lower
      z_hi += 1e-6 * std::max(1.0, std::abs(z_hi));
      // Window position of point i is (i − i0) + 0.5: the pixel centre.
      const double sx = 2.0 / (w * g.cell), sy = 2.0 / (h * g.cell), sz = 2.0 / (z_hi - z_lo);
      const double ox = g.x(i0) - 0.5 * g.cell, oy = g.y(j0) - 0.5 * g.cell;
      const double x_lo = ox, x_hi = ox + w * g.cell, y_lo = oy, y_hi = oy + h * g.cell;
      auto ndc = [&](const Vec3& p) {
        return Vec3((p.x - ox) * sx - 1, (p.y - oy) * sy - 1, (p.z - z_lo) * sz - 1);
      };
      auto push = [&](const Vec3& p) {
        batch.push_back(static_cast<float>(p.x)), batch.push_back(static_cast<float>(p.y)),
            batch.push_back(static_cast<float>(p.z));
      };
      auto flush = [&] {
        if (batch.empty()) return;
        glVertexPointer(3, GL_FLOAT, 0, batch.data());
        glDrawArrays(GL_TRIANGLES, 0, static_cast<GLsizei>(batch.size() / 3));
        batch.clear();
      };
      glViewport(0, 0, w, h);
      glClear(GL_DEPTH_BUFFER_BIT);
      for (const CutMove& m : moves) {
        const Cutter& cutter = cutters[m.cutter];
        const double r = cutter.radius();
        if (std::max(m.tip.a.x, m.tip.b.x) + r < x_lo ||
            std::min(m.tip.a.x, m.tip.b.x) - r > x_hi ||
            std::max(m.tip.a.y, m.tip.b.y) + r < y_lo ||
            std::min(m.tip.a.y, m.tip.b.y) - r > y_hi || std::min(m.tip.a.z, m.tip.b.z) >= z_hi)
          continue;
        const CutterCap& cap = caps[m.cutter];
        const Vec3 v = m.tip.b - m.tip.a;
        moved_a.resize(cap.vertices.size()), moved_b.resize(cap.vertices.size());
        for (std::size_t k = 0; k < cap.vertices.size(); ++k) {
          moved_a[k] = ndc(m.tip.a + cap.vertices[k]);
          moved_b[k] = ndc(m.tip.b + cap.vertices[k]);
        }
        side_of.resize(cap.faces.size());
        const double scale = 1e-12 * glm::length(v);
        for (std::size_t f = 0; f < cap.faces.size(); ++f) {
          double d = glm::dot(cap.normals[f], v);
          side_of[f] = static_cast<signed char>(d > scale ? 1 : (d < -scale ? -1 : 0));
          const glm::uvec3& t = cap.faces[f];
          if (side_of[f] <= 0) push(moved_a[t.x]), push(moved_a[t.y]), push(moved_a[t.z]);
          if (side_of[f] >= 0) push(moved_b[t.x]), push(moved_b[t.y]), push(moved_b[t.z]);
        }
        if (glm::dot(v, v) > 0)
          for (const CutterCap::Edge& e : cap.edges) {
            if (e.f1 >= 0 &&
                side_of[static_cast<std::size_t>(e.f0)] == side_of[static_cast<std::size_t>(e.f1)])
              continue;
            push(moved_a[e.a]), push(moved_a[e.b]), push(moved_b[e.b]);
            push(moved_a[e.a]), push(moved_b[e.b]), push(moved_b[e.a]);
          }
        if (batch.size() >= batch_floats) flush();
      }
      flush();
      glFinish();
      glReadPixels(0, 0, w, h, GL_DEPTH_COMPONENT, GL_FLOAT, depth.data());
      if (glGetError() != GL_NO_ERROR)
        detail::fail("gl mill: reading the depth buffer back failed");
      for (int j = 0; j < h; ++j)
        for (int i = 0; i < w; ++i) {
          float d = depth[static_cast<std::size_t>(i) +
                          static_cast<std::size_t>(w) * static_cast<std::size_t>(j)];
          if (!(d < 1.0f)) continue;
          float z = static_cast<float>(z_lo + double(d) * (z_hi - z_lo));
          float& height = map.heights[g.index(i0 + i, j0 + j)];
          height = std::min(height, z);
        }
    }
}

}  // namespace tridex::backends
