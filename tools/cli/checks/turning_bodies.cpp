// tridex check — shanks, holders and spindle parts of the simultaneous 5-axis moves (issue 34)
// against the final triple dexel (turning_bodies.hpp; docs/design.md, "Simultaneous moves").
#include "checks/turning_bodies.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <optional>

#include "tridex/detail/sweep_distance.hpp"
#include "tridex/gcode/simultaneous.hpp"
#include "tridex/parallel.hpp"
#include "tridex/sweep.hpp"

namespace tridex::cli {

namespace {

// How far beyond `grow` a span's middle pose is searched (mm): a span whose body can move farther
// is split rather than searched in a box grown by all of it (most of a move's poses are several
// millimetres clear: found clear within this, they are skipped as soon as the span's motion is
// less; searching the whole motion's box cost 25 times as much on tilt_turn.ngc).
constexpr double kTbSearch = 3.0;

// A part as a finite frustum about the tool axis: radii r0 at `bottom`, r1 at `top` (mm above
// the tip).
struct TurningPart {
  double r0 = 0, r1 = 0, bottom = 0, top = 0;
};

// The signed distance (negative inside) from `x` to the part at `pose`: a solid of revolution's
// nearest point lies in x's own meridian half-plane, where the part is the trapezoid
// (0, bottom), (r0, bottom), (r1, top), (0, top). Convex in x (the part is convex).
double tb_distance(const TurningPart& p, const ToolPose& pose, const Vec3& x) {
  const Vec3 v = x - pose.tip;
  const double h = glm::dot(v, pose.axis);
  const double d = glm::length(v - h * pose.axis);
  const double best = std::min({detail::segment_distance_2d(d, h, 0, p.bottom, p.r0, p.bottom),
                                detail::segment_distance_2d(d, h, p.r0, p.bottom, p.r1, p.top),
                                detail::segment_distance_2d(d, h, p.r1, p.top, 0, p.top)});
  const bool inside = h >= p.bottom && h <= p.top &&
                      d <= p.r0 + (p.r1 - p.r0) * (h - p.bottom) / (p.top - p.bottom);
  return inside ? -best : best;
}

// The box of the part at `pose` (its two end discs' boxes), grown by `grow`.
Aabb tb_box(const TurningPart& p, const ToolPose& pose, double grow) {
  Aabb box;
  for (const auto& [h, r] : {std::pair(p.bottom, p.r0), std::pair(p.top, p.r1)}) {
    const Vec3 centre = pose.tip + h * pose.axis;
    Vec3 half(0.0);
    for (int i = 0; i < 3; ++i)
      half[i] = r * std::sqrt(std::max(0.0, 1 - pose.axis[i] * pose.axis[i]));
    box.extend(centre - half), box.extend(centre + half);
  }
  return box.inflated(grow);
}

struct TbContact {
  double distance = std::numeric_limits<double>::infinity();  // the least signed distance
  Vec3 where{0.0};
  Vec3 axis{0.0, 0.0, 1.0};
};

// The least signed distance from the material on the Z rays of `d` within the part's box (grown
// by `grow`) to the part at `pose`, where it is below `out.distance` and `grow` (else `out` stays
// as it was): each ray's material searched for its minimum (convex along the ray). A ray farther
// across than the part's widest radius from its axis's shadow on the XY plane (a lower bound of
// the distance from any point of the ray) cannot come nearer.
void tb_contact(const TripleDexel& d, const TurningPart& p, const ToolPose& pose, double grow,
                TbContact& out) {
  const Aabb box = tb_box(p, pose, grow);
  const double h = d.spacing, widest = std::max(p.r0, p.r1);
  const Vec3 a = pose.tip + p.bottom * pose.axis, b = pose.tip + p.top * pose.axis;
  const DexelGrid& g = d.grids[2];
  const int i0 = std::max(0, static_cast<int>(std::ceil((box.min.x - d.origin.x) / h)));
  const int i1 = std::min(g.nu - 1, static_cast<int>(std::floor((box.max.x - d.origin.x) / h)));
  const int j0 = std::max(0, static_cast<int>(std::ceil((box.min.y - d.origin.y) / h)));
  const int j1 = std::min(g.nv - 1, static_cast<int>(std::floor((box.max.y - d.origin.y) / h)));
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      const auto ray = g.ray(i, j);
      if (ray.empty()) continue;
      const double x = d.origin.x + i * h, y = d.origin.y + j * h;
      if (detail::segment_distance_2d(x, y, a.x, a.y, b.x, b.y) - widest >=
          std::min(out.distance, grow))
        continue;
      for (const DexelInterval& s : ray) {
        const double lo = std::max(double(s.enter), box.min.z),
                     hi = std::min(double(s.exit), box.max.z);
        if (!(lo <= hi)) continue;
        auto f = [&](double z) { return tb_distance(p, pose, Vec3(x, y, z)); };
        const double bar = std::min(out.distance, grow);  // only a nearer value counts
        const auto [z, value] = detail::golden_minimum(f, lo, hi, h / 64, bar);
        if (value < bar) out = {value, Vec3(x, y, z), pose.axis};
      }
    }
}

// What one move's parts met: per part, the nearest contact over the poses sampled.
struct TbMoveResult {
  std::vector<TbContact> parts;
  bool capped = false;  // the pose samples reached kMaxPoseSamples before the step asked
};

// The move's parts at poses s_j = j / N, N a power of two such that no point of the body moves
// more than `step` between neighbours (the tip's speed plus the farthest point's distance from
// the tip times the turn rate bound each point's speed: gcode/simultaneous.hpp). Branch and bound
// over the samples, part by part: the middle sample of a span is tested against the material
// within `grow` plus its motion to the span's ends (`margin`, at most kTbSearch), and the span's
// other samples come no nearer than that distance less the margin, so a span that cannot come
// nearer than the nearest contact found (less half a step: the sampling's own error), nor within
// `grow`, is skipped whole. The least distance over all samples, where it is below `grow`, comes
// out within half a step of testing every sample.
TbMoveResult tb_check_move(const gcode::MovePath& path, std::span<const TurningPart> parts,
                           const TripleDexel& result, const SweepMaterial& material, double grow,
                           double step) {
  TbMoveResult out;
  out.parts.resize(parts.size());
  double reach = 0;
  for (const TurningPart& p : parts)
    reach = std::max(reach, std::hypot(std::max(p.r0, p.r1), std::max(p.top, -p.bottom)));
  const PoseBounds bounds = path.bounds();
  const double rate = bounds.tip_speed + reach * bounds.turn_rate;
  long n = 16;
  while (n < kMaxPoseSamples && rate / static_cast<double>(n) > step) n *= 2;
  out.capped = rate / static_cast<double>(n) > step;
  for (std::size_t k = 0; k < parts.size(); ++k) {
    TbContact& best = out.parts[k];
    auto visit = [&](auto& self, long j0, long j1) -> void {
      if (j0 > j1) return;
      const long mid = (j0 + j1) / 2;
      const ToolPose pose = path.at(static_cast<double>(mid) / static_cast<double>(n));
      const double margin =
          rate * static_cast<double>(std::max(mid - j0, j1 - mid)) / static_cast<double>(n);
      if (!material.may_touch(tb_box(parts[k], pose, grow + margin))) return;
      // Searched within `grow` and at most kTbSearch more: nothing nearer bounds the distance.
      const double search = grow + std::min(margin, kTbSearch);
      TbContact here;
      tb_contact(result, parts[k], pose, search, here);
      if (here.distance < best.distance) best = here;
      if (std::min(here.distance, search) - margin >= std::min(best.distance + step / 2, grow))
        return;
      self(self, j0, mid - 1);
      self(self, mid + 1, j1);
    };
    visit(visit, 0, n);
  }
  return out;
}

// The parts of `body` as finite frusta for the move: a shank the table gives no length (it goes
// up to the spindle) ends where no point of it can reach the stock's box from any tip of the move
// (the ends' farthest corner plus half the tip's path: the stock holds all the material).
std::vector<TurningPart> tb_parts(const ToolBody& body, const gcode::Move& m,
                                  const PoseBounds& bounds, const Aabb& stock) {
  double far = 0;
  for (int c = 0; c < 8; ++c) {
    const Vec3 corner((c & 1) ? stock.max.x : stock.min.x, (c & 2) ? stock.max.y : stock.min.y,
                      (c & 4) ? stock.max.z : stock.min.z);
    far = std::max({far, glm::length(corner - m.start), glm::length(corner - m.end)});
  }
  far += bounds.tip_speed / 2;
  std::vector<TurningPart> parts;
  for (const BodyPart& part : body.parts) {
    const BodySection& s = part.shape;
    const double length = std::isfinite(s.length) ? s.length : std::max(far - part.bottom, 1e-3);
    parts.push_back({s.bottom_radius, s.top_radius, part.bottom, part.bottom + length});
  }
  return parts;
}

}  // namespace

void check_turning_bodies(SimulationResult& r, std::span<const ToolBody> bodies, double clearance,
                          unsigned threads) {
  const auto start = std::chrono::steady_clock::now();
  const std::optional<gcode::Kinematics>& kinematics = r.input.machine.kinematics;
  // The moves whose tool turns, then the raw-form rapid turns between moves (note_turning_rapid).
  std::vector<const gcode::Move*> moves;
  for (const gcode::Move& m : r.simultaneous) moves.push_back(&m);
  for (const gcode::Move& m : r.turning_rapids) moves.push_back(&m);
  if (moves.empty() || !kinematics) return;
  const SweepMaterial material(r.result);
  const double step = r.lattice.spacing / 2;
  std::vector<TbMoveResult> results(moves.size());
  std::vector<std::vector<TurningPart>> parts_of(moves.size());
  detail::for_each_chunk(moves.size(), threads, [&](std::size_t k) {
    const gcode::Move& m = *moves[k];
    auto it = r.cutter_of_tool.find(m.tool);
    if (it == r.cutter_of_tool.end() || it->second >= bodies.size()) return;
    const ToolBody& body = bodies[it->second];
    if (body.parts.empty()) return;
    const gcode::MovePath path(*kinematics, m);
    parts_of[k] = tb_parts(body, m, path.bounds(), r.stock.box);
    results[k] = tb_check_move(path, parts_of[k], r.result, material, clearance, step);
  });
  long long capped = 0;
  const std::size_t no_group = r.groups.size();  // in no direction's group
  for (std::size_t k = 0; k < results.size(); ++k) {
    const gcode::Move& m = *moves[k];
    capped += results[k].capped;
    for (std::size_t p = 0; p < results[k].parts.size(); ++p) {
      const TbContact& c = results[k].parts[p];
      const std::string& name = bodies[r.cutter_of_tool.at(m.tool)].parts[p].name;
      if (-c.distance > kCollisionTolerance)
        record_body_finding(r.body.collisions,
                            {m.file, m.line, m.tool, name, -c.distance, c.where, c.axis, no_group},
                            true);
      else if (clearance > 0 && c.distance <= clearance)
        record_body_finding(
            r.body.near_misses,
            {m.file, m.line, m.tool, name, std::max(0.0, c.distance), c.where, c.axis, no_group},
            false);
    }
  }
  if (capped)
    r.warnings.push_back(std::to_string(capped) + " simultaneous move(s) needed more than " +
                         std::to_string(kMaxPoseSamples) +
                         " poses for the shank and holder check: a body point moves more than " +
                         std::to_string(step) + " mm between the poses tested");
  r.body.seconds += std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace tridex::cli
