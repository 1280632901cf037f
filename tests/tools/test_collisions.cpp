// Shank and holder collisions (issue 14): the swept parts' depths and near-miss distances against
// a brute-force reference (the swept solid sampled densely along the move) on random moves in
// tilted frames, and the planted faults end to end through `tridex check`.
#include <doctest/doctest.h>

#include <cmath>
#include <random>

#include <nlohmann/json.hpp>

#include "collision_check.hpp"
#include "command_harness.hpp"
#include "tridex/zmap.hpp"

using namespace tridex;
using namespace tridex::cli;
using namespace tridex::test;
using nlohmann::json;

namespace {

// ---- the brute-force reference -------------------------------------------------------------------

// Height above the section's bottom of its lowest point at distance rho from the axis (+inf
// beyond it), from the section's shape alone.
double section_low(const BodySection& s, double rho) {
  if (rho <= s.bottom_radius) return 0;
  if (s.top_radius > s.bottom_radius && rho <= s.top_radius)
    return (rho - s.bottom_radius) * s.length / (s.top_radius - s.bottom_radius);
  return std::numeric_limits<double>::infinity();
}

double point_segment_2d(Vec2 p, Vec2 a, Vec2 b) {
  Vec2 ab = b - a;
  double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}

// Distance in a meridian plane from the material column at distance rho from the axis (all
// z ≤ top) to the section's cross-section, a trapezoid with its bottom at z = bottom.
double column_distance(const BodySection& s, double bottom, double rho, double top) {
  if (top >= bottom + section_low(s, rho)) return 0;
  const Vec2 corners[4] = {Vec2(-s.bottom_radius, bottom), Vec2(s.bottom_radius, bottom),
                           Vec2(s.top_radius, bottom + s.length), Vec2(-s.top_radius, bottom + s.length)};
  const Vec2 end(rho, top);
  double best = std::numeric_limits<double>::infinity();
  for (int k = 0; k < 4; ++k) {
    best = std::min(best, point_segment_2d(end, corners[k], corners[(k + 1) % 4]));
    // A corner to the column: straight across if it lies below the column's top.
    const Vec2 c = corners[k];
    best = std::min(best, c.y <= top ? std::abs(c.x - rho) : glm::length(c - end));
  }
  return best;
}

struct Reference {
  double depth_low = -std::numeric_limits<double>::infinity();   // sampled: never above the truth
  double depth_high = -std::numeric_limits<double>::infinity();  // widened by a step: never below
  double distance = std::numeric_limits<double>::infinity();     // sampled
  double step = 0;                                                // the tip's travel per sample
};

Reference brute_force(const ZMap& map, const BodyPart& part, const Segment& tip) {
  constexpr int kSamples = 1200;
  Reference ref;
  const Vec3 v = tip.b - tip.a;
  const double e = std::hypot(v.x, v.y) / kSamples, rise = std::abs(v.z) / kSamples;
  ref.step = glm::length(v) / kSamples;
  const BodySection& s = part.shape;
  // Grid points farther than this from the tip's path are out of reach of the part and its growth.
  const double reach = std::max(s.bottom_radius, s.top_radius) + 3;
  const ZMapGrid& g = map.grid;
  const int i0 = std::max(0, int((std::min(tip.a.x, tip.b.x) - reach - g.x0) / g.cell));
  const int i1 = std::min(g.nx - 1, int((std::max(tip.a.x, tip.b.x) + reach - g.x0) / g.cell) + 1);
  const int j0 = std::max(0, int((std::min(tip.a.y, tip.b.y) - reach - g.y0) / g.cell));
  const int j1 = std::min(g.ny - 1, int((std::max(tip.a.y, tip.b.y) + reach - g.y0) / g.cell) + 1);
  for (int k = 0; k <= kSamples; ++k) {
    const Vec3 c = tip.a + (double(k) / kSamples) * v;
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        if (map.is_empty(i, j)) continue;
        const double h = map.height(i, j);
        const double rho = std::hypot(map.grid.x(i) - c.x, map.grid.y(j) - c.y);
        ref.depth_low = std::max(ref.depth_low, h - (c.z + part.bottom + section_low(s, rho)));
        ref.depth_high =
            std::max(ref.depth_high, h - (c.z - rise + part.bottom + section_low(s, std::max(0.0, rho - e))));
        ref.distance = std::min(ref.distance, column_distance(s, c.z + part.bottom, rho, h));
      }
  }
  return ref;
}

}  // namespace

TEST_CASE("swept shank and holder depths and near misses match the sampled swept solid") {
  std::mt19937 random(14);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  int collisions = 0, near = 0, clear = 0, widening = 0;
  for (int trial = 0; trial < 60; ++trial) {
    // A tilted direction's map: a random height field with some points cut through.
    Vec3 axis = glm::normalize(Vec3(unit(random) - 0.5, unit(random) - 0.5, 1.0));
    ZMapGrid grid{Frame::from_axis(axis), -1.0, -1.0, 0.5, 40, 40};
    ZMap map(grid, 0.0f, -20.0f);
    for (float& h : map.heights) h = unit(random) < 0.1 ? -20.0f : static_cast<float>(10 * unit(random));
    BodyPart part;
    part.name = "holder section 1";
    part.bottom = 5 * unit(random);
    const double r0 = 1 + 3 * unit(random);
    const int kind = trial % 3;  // cylinder, widening frustum, narrowing frustum
    part.shape = BodySection{r0, kind == 0 ? r0 : kind == 1 ? r0 + 0.5 + 2.5 * unit(random) : r0 * (0.5 + 0.5 * unit(random)),
                             2 + 6 * unit(random)};
    widening += kind == 1;
    // Moves in the work frame, given to the map in its frame (as the pipeline does).
    Vec3 a_local(3 + 13 * unit(random), 3 + 13 * unit(random), 6 + 8 * unit(random) - part.bottom);
    Vec3 b_local = a_local + Vec3(8 * (unit(random) - 0.5), 8 * (unit(random) - 0.5), 4 * (unit(random) - 0.5));
    if (trial % 5 == 0) b_local = Vec3(a_local.x, a_local.y, b_local.z);  // a plunge
    const Segment tip{grid.frame.to_local(grid.frame.to_world(a_local)), grid.frame.to_local(grid.frame.to_world(b_local))};
    const double clearance = 0.5 + 1.5 * unit(random);
    std::vector<ToolBody> bodies{ToolBody{{part}, 0}};
    BodyCheck check(map, bodies, clearance);
    BodyFindings found;
    gcode::Move move;
    move.line = trial + 1;
    move.tool = 1;
    check.check(map, move, CutMove{tip, 0}, axis, grid.frame, 0, true, [] {}, found);
    const Reference ref = brute_force(map, part, tip);
    INFO("trial ", trial, " kind ", kind, " depth in [", ref.depth_low, ", ", ref.depth_high, "], distance ",
         ref.distance);
    if (!found.collisions.empty()) {
      ++collisions;
      const double depth = found.collisions[0].depth_mm;
      CHECK(depth >= ref.depth_low - 1e-4);
      CHECK(depth <= ref.depth_high + 1e-4);
      CHECK(found.near_misses.empty());
      // The reported point is a grid point with material, in the work frame.
      Vec3 local = grid.frame.to_local(found.collisions[0].where);
      CHECK(std::abs(local.x - grid.x0 - grid.cell * std::round((local.x - grid.x0) / grid.cell)) < 1e-6);
    } else {
      CHECK(ref.depth_low <= kCollisionTolerance + 1e-4);
      const double slack = ref.step + 0.005 * clearance + 2e-3;
      if (!found.near_misses.empty()) {
        ++near;
        CHECK(std::abs(found.near_misses[0].depth_mm - ref.distance) <= slack);
      } else {
        ++clear;
        CHECK(ref.distance >= clearance - slack);
      }
    }
  }
  MESSAGE(collisions, " collisions, ", near, " near misses, ", clear, " clear");
  // The random cases reach every outcome and every shape.
  CHECK(collisions > 5);
  CHECK(near > 3);
  CHECK(clear > 3);
  CHECK(widening > 5);
}
