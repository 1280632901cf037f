// tridex command — simultaneous 5-axis moves (Move::pose ≠ fixed): each move's pose from the
// machine's kinematics (gcode/simultaneous.hpp), sub-stepped with a certified band and cut from
// the triple dexel after the Z-maps' intersection (tridex/sweep.hpp; docs/design.md,
// "Simultaneous moves"). Removal commutes with the intersection, so the order does not matter.
#include <algorithm>
#include <chrono>
#include <limits>
#include <string>

#include "errors.hpp"
#include "pipeline/pipeline.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/gcode/simultaneous.hpp"
#include "tridex/sweep.hpp"

namespace tridex::cli {

namespace {

// A sweep needs a finite cutter: up to the flutes' top where the tool table gives a shank (its
// bottom), else the cutting part and two diameters above it (docs/design.md says why a cutter
// taller than the material it can reach changes nothing).
SweepCutter sweep_cutter_of(const Cutter& cutter, const ToolBody& body) {
  const double profile = cutter.profile_height();
  double height = profile + 4 * cutter.radius();
  if (!body.parts.empty() && body.parts.front().bottom > profile)
    height = body.parts.front().bottom;
  return {cutter, height};
}

// The box of the cutter at `pose`: a cylinder of its radius from the tip up its axis to its height.
Aabb cutter_box(const SweepCutter& cutter, const ToolPose& pose) {
  const Vec3 top = pose.tip + cutter.height * pose.axis;
  const double radius = cutter.cutter.radius();
  Vec3 grow(0.0);
  for (int i = 0; i < 3; ++i)
    grow[i] = radius * std::sqrt(std::max(0.0, 1 - pose.axis[i] * pose.axis[i]));
  return Aabb{glm::min(pose.tip, top) - grow, glm::max(pose.tip, top) + grow};
}

// The deepest the cutter reaches into the material of the Z rays of `d` at `pose` (0: none),
// each ray's material searched for the cutter's least signed distance (convex along the ray):
// its minimum with `deepest`, else the first value found at or below 0 (convex_minimum).
double pose_depth(const TripleDexel& d, const SweepCutter& cutter, const ToolPose& pose,
                  const Aabb& box, double precision, Vec3& where, bool deepest = false) {
  const double h = d.spacing;
  const DexelGrid& g = d.grids[2];
  const int i0 = std::max(0, static_cast<int>(std::ceil((box.min.x - d.origin.x) / h)));
  const int i1 = std::min(g.nu - 1, static_cast<int>(std::floor((box.max.x - d.origin.x) / h)));
  const int j0 = std::max(0, static_cast<int>(std::ceil((box.min.y - d.origin.y) / h)));
  const int j1 = std::min(g.nv - 1, static_cast<int>(std::floor((box.max.y - d.origin.y) / h)));
  double depth = 0;
  for (int i = i0; i <= i1; ++i)
    for (int j = j0; j <= j1; ++j) {
      const double x = d.origin.x + i * h, y = d.origin.y + j * h;
      for (const DexelInterval& s : g.ray(i, j)) {
        const double lo = std::max(double(s.enter), box.min.z),
                     hi = std::min(double(s.exit), box.max.z);
        if (!(lo < hi)) continue;
        auto f = [&](double z) { return cutter.distance(pose.tip, pose.axis, Vec3(x, y, z)); };
        const std::pair<double, double> best = deepest
                                                   ? detail::golden_minimum(f, lo, hi, precision)
                                                   : detail::convex_minimum(f, lo, hi, precision);
        if (-best.second > depth) depth = -best.second, where = Vec3(x, y, best.first);
      }
    }
  return depth;
}

// The deepest `cutter` reaches into the material of `d` along `path`, at poses no cutter point
// moves more than half a spacing between (so a cut of a spacing or more is not missed).
double path_depth(const TripleDexel& d, const SweepMaterial& material, const SweepCutter& cutter,
                  const gcode::MovePath& path, bool deepest, Vec3& where) {
  const double h = d.spacing;
  const PoseBounds bounds = path.bounds();
  const double rate = bounds.tip_speed + cutter.reach() * bounds.turn_rate;
  long samples = 16;
  while (samples < kMaxSubSteps && rate / static_cast<double>(samples) > h / 2) samples *= 2;
  double depth = 0;
  for (long k = 0; k <= samples; ++k) {
    const ToolPose pose = path.at(static_cast<double>(k) / static_cast<double>(samples));
    const Aabb box = cutter_box(cutter, pose);
    if (!material.may_touch(box)) continue;
    depth = std::max(depth, pose_depth(d, cutter, pose, box, h / 8, where, deepest));
  }
  return depth;
}

// check: the simultaneous rapids `rapids` (indices into r.simultaneous with their sweep steps),
// in program order, each measured against r.result before its own removal: by then r.result
// holds the stock less every 3+2 cut, every simultaneous feed and the rapids before it, a subset
// of what stood when it ran (removal is monotone), so a rapid found cutting it surely cut stock.
void check_simultaneous_rapids(const SimulateOptions& options, SimulationResult& r,
                               std::span<const SweepCutter> cutters,
                               const std::vector<std::pair<std::size_t, SweepPlan>>& rapids) {
  const SweepMaterial material(r.result);
  for (const auto& [k, plan] : rapids) {
    const gcode::Move& m = r.simultaneous[k];
    const gcode::MovePath path(*r.input.machine.kinematics, m);
    Vec3 where(0.0);
    const double depth =
        path_depth(r.result, material, cutters[r.cutter_of_tool.at(m.tool)], path, true, where);
    if (depth > kRapidTolerance)
      r.rapid_cuts.push_back(RapidFinding{m.file, m.line, m.tool, m.axis, depth, where, 0});
    if (!plan.steps.empty())
      sweep_remove(r.result, cutters, plan.steps, options.threads, r.sweep_tolerance / 100);
  }
}

}  // namespace

void cut_simultaneous(const SimulateOptions& options, SimulationResult& r, bool checked) {
  const auto start = std::chrono::steady_clock::now();
  const std::optional<gcode::Kinematics>& kinematics = r.input.machine.kinematics;
  if (!kinematics) detail::fail("cut_simultaneous: simultaneous moves without kinematics");
  r.sweep_tolerance = r.lattice.spacing / 10;
  std::vector<SweepCutter> cutters;
  std::vector<SweepShape> shapes;
  for (std::size_t c = 0; c < r.cutters.size(); ++c) {
    cutters.push_back(sweep_cutter_of(r.cutters[c], r.bodies[c]));
    // A bull nose's torus as inscribed chords, their sagitta a quarter of the band (sweep.hpp).
    cutters.back().chord = r.sweep_tolerance / 4;
    shapes.push_back(sweep_shape(cutters.back()));
  }
  // Sub-steps that cannot reach the material left after the 3+2 cuts are dropped (sweep.hpp).
  const SweepMaterial material(r.result);
  auto may_touch = [&](const Aabb& box) { return material.may_touch(box); };
  std::vector<SweepStep> steps;
  std::vector<std::pair<std::size_t, SweepPlan>> rapids;  // checked apart, in program order
  long long capped = 0;
  for (const gcode::Move& m : r.simultaneous) {
    auto it = r.cutter_of_tool.find(m.tool);
    if (it == r.cutter_of_tool.end()) continue;  // before any tool (dropped as the groups' are)
    const gcode::MovePath path(*kinematics, m);
    const std::size_t c = it->second;
    const SweepPlan plan =
        plan_sweep_parts([&](double s) { return path.at(s); }, path.bounds(), cutters[c], shapes[c],
                         r.sweep_tolerance, static_cast<std::uint32_t>(c), may_touch);
    SweepSummary& summary = r.sweeps[m.tool];
    ++summary.moves;
    summary.sub_steps += static_cast<long long>(plan.steps.size());
    summary.band = std::max(summary.band, plan.band);
    if (plan.band > r.sweep_tolerance) ++capped;
    if (checked && m.kind == gcode::MoveKind::rapid)
      rapids.emplace_back(static_cast<std::size_t>(&m - r.simultaneous.data()), plan);
    else
      steps.insert(steps.end(), plan.steps.begin(), plan.steps.end());
  }
  if (capped)
    r.warnings.push_back(std::to_string(capped) + " simultaneous move" + (capped == 1 ? "" : "s") +
                         " needed more than " + std::to_string(kMaxSubSteps) +
                         " sub-steps: their band exceeds " + std::to_string(r.sweep_tolerance) +
                         " mm (see the report's \"simultaneous\")");
  sweep_remove(r.result, cutters, steps, options.threads, r.sweep_tolerance / 100);
  if (!rapids.empty()) check_simultaneous_rapids(options, r, cutters, rapids);
  r.result_dexel_volume = tridex::volume(r.result);
  r.sweep_seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

SimultaneousReach simultaneous_reach(const SimulationResult& r, const gcode::Move& m,
                                     std::span<const Vec3> points, double precision) {
  SimultaneousReach out;
  auto it = r.cutter_of_tool.find(m.tool);
  if (it == r.cutter_of_tool.end() || !r.input.machine.kinematics || points.empty()) return out;
  const SweepCutter cutter = sweep_cutter_of(r.cutters[it->second], r.bodies[it->second]);
  const gcode::MovePath path(*r.input.machine.kinematics, m);
  const PoseBounds bounds = path.bounds();
  // The signed distance to the cutter at pose s changes by at most this per unit s (a cutter
  // point at most `reach` from the tip moves by at most tip speed + reach · turn rate).
  const double rate = bounds.tip_speed + cutter.reach() * bounds.turn_rate;
  long samples = 16;
  while (samples < kMaxSubSteps && rate / (2.0 * static_cast<double>(samples)) > precision)
    samples *= 2;
  const double margin = rate / (2.0 * static_cast<double>(samples));
  // A cheap rejection first: each point's distance to the box of the tip's whole path, less the
  // cutter's reach, bounds its distance to the sweep from below.
  Aabb tips;
  for (long j = 0; j <= samples; ++j)
    tips.extend(path.at(static_cast<double>(j) / static_cast<double>(samples)).tip);
  const double slack = margin + bounds.tip_speed / static_cast<double>(samples);
  double best = std::numeric_limits<double>::infinity();
  std::vector<std::size_t> near;
  for (std::size_t k = 0; k < points.size(); ++k) {
    const Vec3 q = glm::clamp(points[k], tips.min, tips.max);
    const double floor = glm::length(points[k] - q) - cutter.reach() - slack;
    if (floor > 0)
      best = std::min(best, floor);
    else
      near.push_back(k);
  }
  for (long j = 0; j <= samples && !near.empty(); ++j) {
    const ToolPose pose = path.at(static_cast<double>(j) / static_cast<double>(samples));
    for (std::size_t k : near)
      best = std::min(best, cutter.distance(pose.tip, pose.axis, points[k]) - margin);
  }
  out.gap = best;
  out.valid = true;
  return out;
}

void note_turning_rapid(const gcode::Move& before, const gcode::Move& after, SimulationResult& r) {
  const std::array<double, 3> start_rotary =
      after.pose == gcode::PoseLaw::fixed ? after.rotary : after.rotary_start;
  if (after.from_far || before.rotary == start_rotary || after.tool != before.tool) return;
  gcode::Move turn = after;
  turn.kind = gcode::MoveKind::rapid;
  turn.pose = gcode::PoseLaw::joints;
  turn.feed = 0;
  turn.start = before.end;
  turn.end = after.start;
  turn.rotary_start = before.rotary;
  turn.rotary = start_rotary;
  turn.machine = before.machine;
  r.turning_rapids.push_back(turn);
}

void check_turning_rapids(SimulationResult& r) {
  if (r.turning_rapids.empty() || !r.input.machine.kinematics) return;
  const SweepMaterial material(r.result);
  for (const gcode::Move& m : r.turning_rapids) {
    auto it = r.cutter_of_tool.find(m.tool);
    if (it == r.cutter_of_tool.end()) continue;
    const SweepCutter cutter = sweep_cutter_of(r.cutters[it->second], r.bodies[it->second]);
    const gcode::MovePath path(*r.input.machine.kinematics, m);
    Vec3 where(0.0);
    const double depth = path_depth(r.result, material, cutter, path, false, where);
    if (depth > kRapidTolerance)
      r.rapid_cuts.push_back(RapidFinding{m.file, m.line, m.tool, m.axis, depth, where, 0});
  }
}

Json sweeps_json(const SimulationResult& r) {
  Json by_tool = Json::object();
  long long moves = 0, sub_steps = 0;
  double band = 0;
  for (const auto& [tool, s] : r.sweeps) {
    by_tool[std::to_string(tool)] = {
        {"moves", s.moves}, {"sub_steps", s.sub_steps}, {"band_mm", s.band}};
    moves += s.moves, sub_steps += s.sub_steps, band = std::max(band, s.band);
  }
  return {{"moves", moves},
          {"sub_steps", sub_steps},
          {"band_mm", band},
          {"tolerance_mm", r.sweep_tolerance},
          {"seconds", r.sweep_seconds},
          {"by_tool", by_tool}};
}

}  // namespace tridex::cli
