#include "checks/collision_check.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

namespace tridex::cli {

namespace {

constexpr int kTile = 16;        // grid points along a tile's side
constexpr int kBisections = 14;  // the closest distance to clearance / 2^14

Segment raised(const Segment& tip, double by) {
  return Segment{tip.a + Vec3(0, 0, by), tip.b + Vec3(0, 0, by)};
}

}  // namespace

void record_body_finding(std::vector<BodyFinding>& list, BodyFinding f, bool keep_larger) {
  for (auto it = list.rbegin(); it != list.rend() && it->line == f.line && it->file == f.file; ++it)
    if (it->part == f.part && it->tool == f.tool && it->group == f.group) {
      if (keep_larger ? f.depth_mm > it->depth_mm : f.depth_mm < it->depth_mm) *it = f;
      return;
    }
  list.push_back(std::move(f));
}

BodyCheck::BodyCheck(const ZMap& map, std::span<const ToolBody> bodies, double clearance)
    : bodies_(bodies), clearance_(clearance) {
  for (const ToolBody& body : bodies) {
    plain_.emplace_back();
    grown_.emplace_back();
    for (const BodyPart& part : body.parts) {
      plain_.back().push_back(part_surface(part, 0));
      grown_.back().push_back(part_surface(part, clearance));
    }
  }
  tiles_x_ = (map.grid.nx + kTile - 1) / kTile;
  tiles_y_ = (map.grid.ny + kTile - 1) / kTile;
  tile_top_.assign(static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tiles_y_),
                   -std::numeric_limits<float>::infinity());
  tile_pending_.assign(tile_top_.size(), 0);
  refresh_tiles(map, 0, map.grid.nx - 1, 0, map.grid.ny - 1);
  // Heights only fall: the stock's top now bounds the material for good.
  for (float top : tile_top_) map_top_ = std::max(map_top_, double(top));
}

void BodyCheck::will_mill(const ZMap& map, const Cutter& cutter, const CutMove& move) {
  const PointRange points = footprint_points(map.grid, cutter.radius(), move.tip);
  if (points.empty()) return;
  for (int tj = points.j0 / kTile; tj <= points.j1 / kTile; ++tj)
    for (int ti = points.i0 / kTile; ti <= points.i1 / kTile; ++ti)
      tile_pending_[static_cast<std::size_t>(ti) +
                    static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tj)] = 1;
}

void BodyCheck::refresh_tiles(const ZMap& map, int i0, int i1, int j0, int j1) {
  const ZMapGrid& g = map.grid;
  for (int tj = j0 / kTile; tj <= j1 / kTile; ++tj)
    for (int ti = i0 / kTile; ti <= i1 / kTile; ++ti) {
      float top = -std::numeric_limits<float>::infinity();
      for (int j = tj * kTile; j < std::min(g.ny, (tj + 1) * kTile); ++j)
        for (int i = ti * kTile; i < std::min(g.nx, (ti + 1) * kTile); ++i)
          if (!map.is_empty(i, j)) top = std::max(top, map.height(i, j));
      const std::size_t t = static_cast<std::size_t>(ti) +
                            static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tj);
      tile_top_[t] = top;
      tile_pending_[t] = 0;
    }
}

void BodyCheck::milled(const ZMap& map, std::span<const Cutter> cutters,
                       std::span<const CutMove> batch) {
  if (batch.empty()) return;
  const ZMapGrid& g = map.grid;
  double x0 = std::numeric_limits<double>::infinity(), x1 = -x0, y0 = x0, y1 = -x0;
  for (const CutMove& m : batch) {
    const double r = cutters[m.cutter].radius();
    x0 = std::min({x0, m.tip.a.x - r, m.tip.b.x - r}),
    x1 = std::max({x1, m.tip.a.x + r, m.tip.b.x + r});
    y0 = std::min({y0, m.tip.a.y - r, m.tip.b.y - r}),
    y1 = std::max({y1, m.tip.a.y + r, m.tip.b.y + r});
  }
  const double i0 = std::max(0.0, std::floor((x0 - g.x0) / g.cell)),
               i1 = std::min(g.nx - 1.0, std::ceil((x1 - g.x0) / g.cell));
  const double j0 = std::max(0.0, std::floor((y0 - g.y0) / g.cell)),
               j1 = std::min(g.ny - 1.0, std::ceil((y1 - g.y0) / g.cell));
  if (i0 > i1 || j0 > j1) return;
  refresh_tiles(map, static_cast<int>(i0), static_cast<int>(i1), static_cast<int>(j0),
                static_cast<int>(j1));
}

CutDepth BodyCheck::contact_depth(const ZMap& map, const Cutter& surface, const Segment& tip,
                                  bool* stale) const {
  const ZMapGrid& g = map.grid;
  const PointRange points = footprint_points(g, surface.radius(), tip);
  CutDepth deepest;
  if (points.empty()) return deepest;
  const int ia = points.i0, ib = points.i1, ja = points.j0, jb = points.j1;
  // The swept surface lies nowhere below the tip's lowest point: a tile whose highest material
  // is not above it cannot be reached.
  const double floor_z = std::min(tip.a.z, tip.b.z);
  std::optional<detail::MoveGeometry> geometry;
  for (int tj = ja / kTile; tj <= jb / kTile; ++tj)
    for (int ti = ia / kTile; ti <= ib / kTile; ++ti) {
      const std::size_t t = static_cast<std::size_t>(ti) +
                            static_cast<std::size_t>(tiles_x_) * static_cast<std::size_t>(tj);
      if (double(tile_top_[t]) <= floor_z) continue;
      if (!geometry) geometry.emplace(surface, tip);
      for (int j = std::max(ja, tj * kTile); j <= std::min(jb, tj * kTile + kTile - 1); ++j)
        for (int i = std::max(ia, ti * kTile); i <= std::min(ib, ti * kTile + kTile - 1); ++i) {
          if (map.is_empty(i, j) || double(map.height(i, j)) <= floor_z) continue;
          double depth = map.height(i, j) - geometry->lowest_above(g.x(i), g.y(j));
          if (depth > deepest.depth) deepest = {depth, i, j};
          if (stale && depth > 0 && tile_pending_[t]) *stale = true;
        }
    }
  return deepest;
}

void BodyCheck::check(const ZMap& map, const gcode::Move& move, const CutMove& cut,
                      const Vec3& axis, const Frame& frame, std::size_t group, bool up_to_date,
                      const std::function<void()>& flush, BodyFindings& found) {
  if (cut.cutter >= bodies_.size()) return;
  const ToolBody& body = bodies_[cut.cutter];
  const auto start = std::chrono::steady_clock::now();
  for (std::size_t k = 0; k < body.parts.size(); ++k) {
    const BodyPart& part = body.parts[k];
    const Cutter& grown = grown_[cut.cutter][k];
    // Above all the material (a spindle's parts mostly are): nothing to search.
    if (std::min(cut.tip.a.z, cut.tip.b.z) + part.bottom - clearance_ >= map_top_) continue;
    bool stale = false;
    if (contact_depth(map, grown, raised(cut.tip, part.bottom - clearance_),
                      up_to_date ? nullptr : &stale)
            .depth <= 0)
      continue;
    // Every test below reaches a subset of these points (a smaller growth reaches less): where
    // none lies under a pending move, the map's heights there are the true ones.
    if (stale) {
      // The map may still hold what the pending moves remove: mill them and look again.
      const auto paused = std::chrono::steady_clock::now();
      flush();
      up_to_date = true;
      found.seconds -=
          std::chrono::duration<double>(std::chrono::steady_clock::now() - paused).count();
      if (contact_depth(map, grown, raised(cut.tip, part.bottom - clearance_)).depth <= 0) continue;
    }
    const CutDepth plain = contact_depth(map, plain_[cut.cutter][k], raised(cut.tip, part.bottom));
    auto located = [&](const CutDepth& d) {
      return frame.to_world(Vec3(map.grid.x(d.i), map.grid.y(d.j), map.height(d.i, d.j)));
    };
    if (plain.depth > kCollisionTolerance) {
      record_body_finding(found.collisions,
                          BodyFinding{move.file, move.line, move.tool, part.name, plain.depth,
                                      located(plain), axis, group},
                          true);
      // The holder's own sections only (the spindle's parts follow them: machine_run.hpp).
      if (body.has_holder() && part.bottom >= body.stick_out &&
          part.name.starts_with("holder section")) {
        double& deepest = found.holder_depth[{move.tool, group}];
        deepest = std::max(deepest, plain.depth);
      }
      continue;
    }
    if (!(clearance_ > 0)) continue;
    // A near miss: the smallest growth that reaches the material is the closest distance.
    double lo = 0, hi = clearance_;
    CutDepth closest = contact_depth(map, grown, raised(cut.tip, part.bottom - clearance_));
    if (plain.depth > 0) {
      hi = 0, closest = plain;
    } else {
      for (int step = 0; step < kBisections; ++step) {
        const double mid = 0.5 * (lo + hi);
        CutDepth d =
            contact_depth(map, part_surface(part, mid), raised(cut.tip, part.bottom - mid));
        if (d.depth > 0)
          hi = mid, closest = d;
        else
          lo = mid;
      }
    }
    record_body_finding(
        found.near_misses,
        BodyFinding{move.file, move.line, move.tool, part.name, hi, located(closest), axis, group},
        false);
  }
  found.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace tridex::cli
