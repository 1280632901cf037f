#include "tridex/backends/embree_dexelize.hpp"

#include <embree3/rtcore.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/error.hpp"
#include "tridex/polyhedron.hpp"

namespace tridex::backends {

namespace {

struct DeviceDeleter {
  void operator()(RTCDevice d) const { rtcReleaseDevice(d); }
};
struct SceneDeleter {
  void operator()(RTCScene s) const { rtcReleaseScene(s); }
};

struct Hit {
  float t;
  int direction;  // +1 entering, −1 leaving
};

// The intersection context handed to the filter: Embree's own first, then where hits go.
struct CollectContext {
  RTCIntersectContext base;
  std::vector<std::uint32_t>* primitives;
  std::vector<float>* distances;
};

void collect_all(const RTCFilterFunctionNArguments* args) {
  auto* context = reinterpret_cast<CollectContext*>(args->context);
  for (unsigned k = 0; k < args->N; ++k) {
    if (!args->valid[k]) continue;
    context->primitives->push_back(RTCHitN_primID(args->hit, args->N, k));
    context->distances->push_back(RTCRayN_tfar(args->ray, args->N, k));
    args->valid[k] = 0;  // reject: traversal continues to the next hit
  }
}

// One Z-map's polyhedron as an Embree scene, with each triangle's direction sign per axis.
class ZMapScene {
 public:
  ZMapScene(RTCDevice device, const ZMap& map) {
    Mesh mesh = polyhedrize(map);
    box_ = Aabb{};
    for (const glm::vec3& p : mesh.positions) box_.extend(Vec3(p));
    // Which way each triangle faces along x, y and z: bit 2a set when its normal points along
    // −axis a (the ray enters there), bit 2a+1 when along +axis (it leaves).
    facing_.resize(mesh.triangles.size());
    for (std::size_t k = 0; k < mesh.triangles.size(); ++k) {
      const glm::uvec3& t = mesh.triangles[k];
      Vec3 a(mesh.positions[t.x]), b(mesh.positions[t.y]), c(mesh.positions[t.z]);
      Vec3 n = glm::cross(b - a, c - a);
      std::uint8_t f = 0;
      for (int axis = 0; axis < 3; ++axis) {
        if (n[axis] < 0) f = static_cast<std::uint8_t>(f | (1u << (2 * axis)));
        if (n[axis] > 0) f = static_cast<std::uint8_t>(f | (1u << (2 * axis + 1)));
      }
      facing_[k] = f;
    }
    scene_.reset(rtcNewScene(device));
    if (!scene_) detail::fail("embree: could not create a scene");
    rtcSetSceneFlags(scene_.get(), RTC_SCENE_FLAG_ROBUST | RTC_SCENE_FLAG_CONTEXT_FILTER_FUNCTION);
    rtcSetSceneBuildQuality(scene_.get(), RTC_BUILD_QUALITY_LOW);
    RTCGeometry geometry = rtcNewGeometry(device, RTC_GEOMETRY_TYPE_TRIANGLE);
    if (!geometry) detail::fail("embree: could not create a triangle geometry");
    void* vertices = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_VERTEX, 0, RTC_FORMAT_FLOAT3,
                                             sizeof(float) * 3, mesh.positions.size());
    void* indices = rtcSetNewGeometryBuffer(geometry, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                            sizeof(std::uint32_t) * 3, mesh.triangles.size());
    if (!vertices || !indices) {
      rtcReleaseGeometry(geometry);
      detail::fail("embree: could not allocate the buffers of a mesh of ", mesh.triangles.size(),
                   " triangles");
    }
    std::memcpy(vertices, mesh.positions.data(), mesh.positions.size() * sizeof(glm::vec3));
    std::memcpy(indices, mesh.triangles.data(), mesh.triangles.size() * sizeof(glm::uvec3));
    mesh = Mesh{};  // the copy lives in Embree now
    rtcCommitGeometry(geometry);
    rtcAttachGeometry(scene_.get(), geometry);
    rtcReleaseGeometry(geometry);
    rtcCommitScene(scene_.get());
    if (rtcGetDeviceError(device) != RTC_ERROR_NONE)
      detail::fail("embree: building the scene failed");
  }

  // The spans of the lattice ray through (pu, pv) along `axis` inside the polyhedron, in
  // world coordinates along the axis, appended to `out` (sorted, disjoint, float).
  void spans(int axis, double pu, double pv, std::vector<DexelInterval>& out) const {
    const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
    if (pu < box_.min[u] || pu > box_.max[u] || pv < box_.min[v] || pv > box_.max[v]) return;
    thread_local std::vector<std::uint32_t> primitives;
    thread_local std::vector<float> distances;
    thread_local std::vector<Hit> hits;
    primitives.clear(), distances.clear(), hits.clear();
    const double start = box_.min[axis] - 1, length = box_.max[axis] - box_.min[axis] + 2;
    RTCRayHit query{};
    float origin[3];
    origin[axis] = static_cast<float>(start), origin[u] = static_cast<float>(pu),
    origin[v] = static_cast<float>(pv);
    query.ray.org_x = origin[0], query.ray.org_y = origin[1], query.ray.org_z = origin[2];
    query.ray.dir_x = axis == 0 ? 1.f : 0.f, query.ray.dir_y = axis == 1 ? 1.f : 0.f,
    query.ray.dir_z = axis == 2 ? 1.f : 0.f;
    query.ray.tnear = 0, query.ray.tfar = static_cast<float>(length);
    query.ray.mask = 0xFFFFFFFFu, query.ray.flags = 0;
    query.hit.geomID = RTC_INVALID_GEOMETRY_ID, query.hit.primID = RTC_INVALID_GEOMETRY_ID;
    CollectContext context{};
    rtcInitIntersectContext(&context.base);
    context.base.filter = collect_all;
    context.primitives = &primitives, context.distances = &distances;
    rtcIntersect1(scene_.get(), &context.base, &query);
    for (std::size_t k = 0; k < primitives.size(); ++k) {
      std::uint8_t f = facing_[primitives[k]];
      int direction = (f >> (2 * axis) & 1u) ? 1 : ((f >> (2 * axis + 1) & 1u) ? -1 : 0);
      if (direction != 0) hits.push_back({distances[k] + origin[axis], direction});
    }
    std::sort(hits.begin(), hits.end(), [](const Hit& a, const Hit& b) { return a.t < b.t; });
    // Merge the hits of one crossing (several triangles around an edge or vertex).
    const float merge =
        4 * std::numeric_limits<float>::epsilon() *
        static_cast<float>(std::max({std::abs(box_.min[axis]), std::abs(box_.max[axis]), 1.0}));
    std::size_t ray_start = out.size();
    bool inside = false;
    float enter = 0;
    for (std::size_t k = 0; k < hits.size();) {
      float t = hits[k].t;
      int net = 0;
      for (; k < hits.size() && hits[k].t - t <= merge; ++k) net += hits[k].direction;
      if (net > 0 && !inside)
        inside = true, enter = t;
      else if (net < 0 && inside)
        inside = false, detail::push_span(out, ray_start, enter, t);
    }
  }

 private:
  std::unique_ptr<RTCSceneTy, SceneDeleter> scene_;
  std::vector<std::uint8_t> facing_;
  Aabb box_;
};

std::unique_ptr<RTCDeviceTy, DeviceDeleter> make_device(unsigned threads) {
  std::string config = "threads=" + std::to_string(detail::resolve_threads(threads));
  std::unique_ptr<RTCDeviceTy, DeviceDeleter> device(rtcNewDevice(config.c_str()));
  if (!device) detail::fail("embree: could not create a device (", config, ")");
  return device;
}

Vec3 ray_position(const DexelLattice& lattice, int axis, std::size_t r) {
  const int u = TripleDexel::u_axis(axis), v = TripleDexel::v_axis(axis);
  const auto nu = static_cast<std::size_t>(lattice.n[u]);
  Vec3 p(0);
  p[u] = lattice.origin[u] + lattice.spacing * static_cast<double>(r % nu);
  p[v] = lattice.origin[v] + lattice.spacing * static_cast<double>(r / nu);
  return p;
}

}  // namespace

TripleDexel embree_dexelize(const ZMap& map, const DexelLattice& lattice, unsigned threads) {
  detail::require_lattice(lattice, "embree dexelize");
  detail::require_solid_zmap(map, "embree dexelize");
  auto device = make_device(threads);
  const ZMapScene scene(device.get(), map);
  TripleDexel result;
  result.origin = lattice.origin, result.spacing = lattice.spacing, result.n = lattice.n;
  for (int axis = 0; axis < 3; ++axis)
    result.grids[axis] = detail::build_grid(
        lattice, axis, threads, [&](std::size_t r, std::vector<DexelInterval>& out) {
          Vec3 p = ray_position(lattice, axis, r);
          scene.spans(axis, p[TripleDexel::u_axis(axis)], p[TripleDexel::v_axis(axis)], out);
        });
  return result;
}

TripleDexel embree_machine(const TripleDexel& stock, std::span<const ZMap> milled,
                           unsigned threads) {
  validate(stock);
  for (const ZMap& map : milled) detail::require_solid_zmap(map, "embree machine");
  auto device = make_device(threads);
  const DexelLattice lattice = stock.lattice();
  TripleDexel result = stock;
  for (const ZMap& map : milled) {
    const ZMapScene scene(device.get(), map);
    for (int axis = 0; axis < 3; ++axis) {
      const DexelGrid& current = result.grids[axis];
      result.grids[axis] = detail::build_grid(
          lattice, axis, threads, [&](std::size_t r, std::vector<DexelInterval>& out) {
            std::span<const DexelInterval> now = current.ray(r);
            if (now.empty()) return;
            thread_local std::vector<DexelInterval> cut;
            cut.clear();
            Vec3 p = ray_position(lattice, axis, r);
            scene.spans(axis, p[TripleDexel::u_axis(axis)], p[TripleDexel::v_axis(axis)], cut);
            detail::intersect_ray(now, cut, out);
          });
    }
  }
  return result;
}

}  // namespace tridex::backends
