#include "checks/machine_run.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <filesystem>
#include <map>
#include <optional>
#include <set>

#include "errors.hpp"
#include "tridex/stl.hpp"

namespace tridex::cli {

namespace {

constexpr std::size_t kMachineFindingsListed = 1000;  // of each kind, in the report

MachineBody mr_body(std::string name, std::string group, Link link, int tool,
                    std::shared_ptr<const Mesh> mesh) {
  MachineBody b;
  b.name = std::move(name), b.group = std::move(group), b.link = link, b.tool = tool;
  b.tree = std::make_shared<const TriangleTree>(*mesh);
  b.mesh = std::move(mesh);
  return b;
}

std::shared_ptr<const Mesh> mr_mesh(Mesh mesh) {
  return std::make_shared<const Mesh>(std::move(mesh));
}

Mesh mr_read(const std::string& path, const std::string& what) {
  std::error_code error;
  if (!std::filesystem::is_regular_file(path, error)) input_error(what, ": no such file");
  try {
    Mesh mesh = read_stl(path);
    if (mesh.triangles.empty()) input_error(what, ": the mesh has no triangles");
    return mesh;
  } catch (const tridex::Error& e) {
    input_error(what, ": ", e.what());
  }
}

// Where a machine file's component rides (machine_file.cpp has checked the names).
Link mr_link(const std::string& on, const std::optional<gcode::Kinematics>& kin) {
  if (on == "bed") return {LinkKind::bed, 0};
  if (on == "spindle") return {LinkKind::spindle, 0};
  if (on == "X" || on == "Y" || on == "Z") return {LinkKind::carriage, on[0] - 'X'};
  int depth = 0;
  for (const gcode::RotaryAxis& axis : kin->axes) {
    const bool head = axis.on_head;
    if (axis.letter == on[0]) {
      int d = 0;
      for (const gcode::RotaryAxis& other : kin->axes) {
        if (other.on_head == head) ++d;
        if (&other == &axis) break;
      }
      depth = d;
      return {head ? LinkKind::head : LinkKind::table, depth};
    }
  }
  return {LinkKind::bed, 0};
}

// The tool's length from the tip to the spindle's gauge point (machine_run.hpp): the tool
// table's tool length, else the top of the holder; none when neither is given (the flutes' top
// is not the gauge point: a tool sticks out of a holder tridex is not told of).
std::optional<double> mr_gauge(const SimulationResult& r, int tool) {
  if (auto length = r.input.machine.tool_lengths.find(tool);
      length != r.input.machine.tool_lengths.end() && length->second > 0)
    return length->second;
  auto c = r.cutter_of_tool.find(tool);
  if (c == r.cutter_of_tool.end()) return std::nullopt;
  const ToolBody& body = r.bodies[c->second];
  if (!body.parts.empty()) return body.parts.back().bottom + body.parts.back().shape.length;
  return std::nullopt;
}

// Where the flutes end with neither a shank nor a holder: the gauge point, else the profile's
// top or 6 radii, whichever is higher.
double mr_flutes_top(const SimulationResult& r, int tool, const Cutter& cutter) {
  return mr_gauge(r, tool).value_or(std::max(cutter.profile_height(), 6 * cutter.radius()));
}

// The tool's flutes, shank and holder as meshes in tool coordinates.
void mr_add_tool(MachineCheck& check, const SimulationResult& r, int tool, std::uint32_t c) {
  const Cutter& cutter = r.cutters[c];
  const ToolBody& body = r.bodies[c];
  const double top =
      body.parts.empty() ? mr_flutes_top(r, tool, cutter) : body.parts.front().bottom;
  std::vector<Mesh> flutes;
  // The profile by rings; each piece of the cone between two rings lowered by how far the
  // profile sags below its chord (a ball's lower surface is convex), so that the mesh holds it.
  constexpr int kRings = 6;
  double last_d = 0, last_h = std::min(cutter.lower_height(0), top);
  for (int k = 1; k <= kRings; ++k) {
    const double d = cutter.radius() * k / kRings, h = std::min(cutter.lower_height(d), top);
    double sag = 0;
    for (int i = 1; i < 8; ++i) {
      const double dd = last_d + (d - last_d) * i / 8;
      sag = std::max(sag, last_h + (h - last_h) * i / 8 - std::min(cutter.lower_height(dd), top));
    }
    flutes.push_back(make_frustum_mesh(last_d, d, last_h - sag, h - sag));
    last_d = d, last_h = h;
  }
  if (top > last_h)
    flutes.push_back(make_frustum_mesh(cutter.radius(), cutter.radius(), last_h, top));
  const std::string name = "tool " + std::to_string(tool);
  check.add(
      mr_body(name + " flutes", "tool", {LinkKind::tool, 0}, tool, mr_mesh(merge_meshes(flutes))));
  std::vector<Mesh> holder;
  for (const BodyPart& part : body.parts) {
    const BodySection& s = part.shape;
    Mesh m = make_frustum_mesh(s.bottom_radius, s.top_radius, part.bottom, part.bottom + s.length);
    if (part.name == "shank")
      check.add(mr_body(name + " shank", "tool", {LinkKind::tool, 0}, tool, mr_mesh(std::move(m))));
    else
      holder.push_back(std::move(m));
  }
  if (!holder.empty())
    check.add(mr_body(name + " holder", "tool", {LinkKind::tool, 0}, tool,
                      mr_mesh(merge_meshes(holder))));
}

// At most this many stacked cylinders stand for one spindle part (bodies_against_stock).
constexpr std::size_t kSpindleSlabs = 8;

// A spindle part's envelope of revolution about the spindle axis (its coordinates: the gauge
// point at the origin, +Z up the tool) as stacked cylinders, `gauge` above the tip: between each
// two of its vertices' distinct heights (or kSpindleSlabs equal slabs), a cylinder as wide as
// the farthest vertex of any triangle that reaches into the slab (the distance from an axis is
// convex: a triangle's farthest point is a vertex). A BodyCheck tests each as the material below
// its bottom disc (tool_body.hpp), so the stack holds the part.
std::vector<BodyPart> mr_spindle_envelope(const std::string& name, const Mesh& mesh, double gauge) {
  std::vector<double> heights;
  for (const glm::vec3& p : mesh.positions) heights.push_back(p.z);
  std::sort(heights.begin(), heights.end());
  if (heights.empty()) return {};
  const double lo = heights.front(), hi = heights.back(), merge = 1e-6 * (1 + hi - lo);
  std::vector<double> levels;
  for (double z : heights)
    if (levels.empty() || z > levels.back() + merge) levels.push_back(z);
  if (levels.size() > kSpindleSlabs + 1) {
    levels.clear();
    for (std::size_t k = 0; k <= kSpindleSlabs; ++k)
      levels.push_back(lo + (hi - lo) * static_cast<double>(k) / kSpindleSlabs);
  }
  if (levels.size() == 1) levels.push_back(lo + 1e-3);  // a flat part: one thin slab
  std::vector<double> radius(levels.size() - 1, 0.0);
  for (const glm::uvec3& t : mesh.triangles) {
    double z0 = std::numeric_limits<double>::infinity(), z1 = -z0, r = 0;
    for (int v = 0; v < 3; ++v) {
      const glm::vec3& p = mesh.positions[t[v]];
      z0 = std::min(z0, double(p.z)), z1 = std::max(z1, double(p.z));
      r = std::max(r, std::hypot(double(p.x), double(p.y)));
    }
    for (std::size_t k = 0; k + 1 < levels.size(); ++k)
      if (z1 >= levels[k] - merge && z0 <= levels[k + 1] + merge)
        radius[k] = std::max(radius[k], r);
  }
  std::vector<BodyPart> parts;
  for (std::size_t k = 0; k + 1 < levels.size(); ++k)
    if (radius[k] > 0)
      parts.push_back(BodyPart{name, gauge + levels[k],
                               BodySection{radius[k], radius[k], levels[k + 1] - levels[k]}});
  return parts;
}

}  // namespace

std::vector<ToolBody> bodies_against_stock(const SimulationResult& r) {
  std::vector<ToolBody> bodies = r.bodies;
  std::vector<std::pair<std::string, std::shared_ptr<const Mesh>>> spindle;
  for (const gcode::MachineComponent& c : r.input.machine.components)
    if (c.on == "spindle")
      spindle.emplace_back(
          c.name, c.built ? c.built
                          : mr_mesh(mr_read(
                                c.mesh, "--machine: component \"" + c.name + "\" mesh " + c.mesh)));
  if (spindle.empty()) return bodies;
  for (const auto& [tool, c] : r.cutter_of_tool) {
    const std::optional<double> gauge = mr_gauge(r, tool);
    if (!gauge || c >= bodies.size()) continue;  // not placed: machine_unchecked_text says so
    for (const auto& [name, mesh] : spindle)
      for (BodyPart& part : mr_spindle_envelope(name, *mesh, *gauge))
        bodies[c].parts.push_back(std::move(part));
  }
  return bodies;
}

MachineRun run_machine_check(const std::vector<std::string>& fixtures, const SimulationResult& r) {
  MachineRun run;
  const gcode::MachineConfig& machine = r.input.machine;
  std::vector<std::string> all_fixtures = fixtures;
  for (const auto& f : r.input.fixtures) all_fixtures.push_back(f.string());
  if (all_fixtures.empty() && machine.components.empty()) return run;
  run.active = true;
  MachineCheck check(machine.kinematics, machine.linear_on_head, machine.collision);
  for (const std::string& path : all_fixtures)
    check.add(mr_body(std::filesystem::path(path).filename().string(), "fixture",
                      {LinkKind::work, 0}, -1, mr_mesh(mr_read(path, "--fixture " + path))));
  for (const gcode::MachineComponent& c : machine.components)
    check.add(mr_body(c.name, "component", mr_link(c.on, machine.kinematics), -1,
                      c.built ? c.built
                              : mr_mesh(mr_read(c.mesh, "--machine: component \"" + c.name +
                                                            "\" mesh " + c.mesh))));
  for (const auto& [tool, c] : r.cutter_of_tool) mr_add_tool(check, r, tool, c);
  bool spindle_parts = false;
  for (const MachineBody& b : check.bodies()) spindle_parts |= b.link.kind == LinkKind::spindle;
  for (const MachineBody& b : check.bodies()) {
    run.bodies.push_back(b.name);
    run.groups.push_back(b.group);
    run.meshes.push_back(b.mesh);
  }

  const Vec3 g54 = machine.work_offsets.count(1) ? machine.work_offsets.at(1) : Vec3(0);
  // Pairs in contact on the last move checked: a retract straight up the tool from such a
  // contact is where the machine backs off the crash already reported, not a new one.
  std::set<std::pair<std::string, std::string>> touching;
  auto checked = [&](const MachineMove& move, const gcode::Move& m) {
    const std::size_t first = run.found.collisions.size();
    check.check(move, run.found);
    const Vec3 path = m.end - m.start;
    const bool retract =
        glm::length(path) > 0 && glm::dot(path, m.axis) >= 0.999 * glm::length(path);
    std::set<std::pair<std::string, std::string>> now;
    auto& list = run.found.collisions;
    for (std::size_t k = first; k < list.size();) {
      now.insert({list[k].a, list[k].b});
      if (retract && list[k].t == 0 && touching.count({list[k].a, list[k].b}))
        list.erase(list.begin() + static_cast<std::ptrdiff_t>(k));
      else
        ++k;
    }
    touching = std::move(now);
  };
  std::vector<std::size_t> next(r.groups.size(), 0);
  std::optional<gcode::Move> previous;  // a copy: the groups read moves back by value (MoveList)
  for (const GroupRun& span : r.order)
    for (std::uint64_t k = 0; k < span.moves; ++k) {
      const gcode::Move m = r.groups[span.group].moves[next[span.group]++];
      const std::optional<gcode::Move> before = previous;
      previous = m;
      MachineMove move;
      move.file = m.file, move.line = m.line, move.tool = m.tool;
      const std::optional<double> gauge = mr_gauge(r, m.tool);
      move.gauge = gauge.value_or(0), move.gauge_known = gauge.has_value();
      if (!gauge && spindle_parts) run.spindle_unplaced.insert(m.tool);
      if (!machine.kinematics) {
        move.offset = g54;
        move.from.x = (m.from_far ? m.end : m.start) + g54, move.to.x = m.end + g54;
        checked(move, m);
        continue;
      }
      const gcode::Kinematics& kin = *machine.kinematics;
      move.offset = gcode::tip_in_part(kin, m.machine, m.rotary) - m.end;
      move.to = {m.machine, m.rotary};
      move.from = {gcode::machine_from_part(kin, m.start + move.offset, m.rotary), m.rotary};
      if (m.from_far) {  // the start is a stand-in: the pose it ends at only
        move.from = move.to;
        checked(move, m);
        continue;
      }
      if (before && before->rotary != m.rotary) {
        // The turn before the move, the machine's linear axes standing where the last move ended.
        MachineMove turn = move;
        turn.from = {before->machine, before->rotary};
        turn.to = {before->machine, m.rotary};
        checked(turn, m);
      }
      checked(move, m);
    }
  return run;
}

Json machine_json(const MachineRun& run, const SimulationResult& r) {
  auto state_json = [&](const MachineState& s) {
    Json axes{{"X", s.x.x}, {"Y", s.x.y}, {"Z", s.x.z}};
    if (r.input.machine.kinematics)
      for (const gcode::RotaryAxis& a : r.input.machine.kinematics->axes)
        axes[std::string(1, a.letter)] = s.rotary[std::size_t(gcode::rotary_index(a.letter))];
    return axes;
  };
  auto list = [&](const std::vector<MachineFinding>& findings) {
    Json out = Json::array();
    for (std::size_t k = 0; k < findings.size() && k < kMachineFindingsListed; ++k) {
      const MachineFinding& f = findings[k];
      out.push_back({{"file", r.files.at(static_cast<std::size_t>(f.file))},
                     {"line", f.line},
                     {"tool", f.tool},
                     {"a", f.a},
                     {"b", f.b},
                     {"distance_mm", f.distance},
                     {"along", f.t},
                     {"point", to_json(f.where)},
                     {"axes", state_json(f.state)}});
    }
    return out;
  };
  Json travel = Json::array();
  for (const TravelAlong& t : run.found.travel)
    travel.push_back({{"file", r.files.at(static_cast<std::size_t>(t.file))},
                      {"line", t.line},
                      {"axis", std::string(1, t.axis)},
                      {"value", t.value},
                      {"limit", t.limit},
                      {"along", t.t}});
  const gcode::CollisionSettings& s = r.input.machine.collision;
  return {{"bodies", run.bodies},
          {"clearance_mm", s.clearance},
          {"near_miss_mm", s.near_miss},
          {"collisions", list(run.found.collisions)},
          {"collisions_count", run.found.collisions.size()},
          {"near_misses", list(run.found.near_misses)},
          {"near_misses_count", run.found.near_misses.size()},
          {"travel_along_moves", travel},
          {"spindle_parts_unplaced_tools", run.spindle_unplaced},
          {"moves", run.found.moves},
          {"queries", run.found.queries},
          {"seconds", run.found.seconds}};
}

std::string machine_unchecked_text(const MachineRun& run) {
  if (run.spindle_unplaced.empty()) return {};
  std::string tools;
  for (int t : run.spindle_unplaced) tools += (tools.empty() ? "T" : ", T") + std::to_string(t);
  return "the spindle's parts not tested with " + tools +
         ": no tool length (the tool table's \"tool-length\" or a holder places the gauge point)";
}

HtmlMachine machine_page(const MachineRun& run) {
  HtmlMachine page;
  page.names = run.bodies, page.groups = run.groups;
  for (const auto& mesh : run.meshes) page.meshes.push_back(mesh.get());
  auto poses = [](const std::vector<MachineFinding>& findings) {
    std::vector<std::array<HtmlMachinePose, 2>> out;
    for (std::size_t k = 0; k < findings.size() && k < kMachineFindingsListed; ++k)
      out.push_back({HtmlMachinePose{findings[k].body_a, findings[k].pose_a},
                     HtmlMachinePose{findings[k].body_b, findings[k].pose_b}});
    return out;
  };
  page.collisions = poses(run.found.collisions);
  page.near_misses = poses(run.found.near_misses);
  return page;
}

void print_machine_findings(const MachineRun& run, const SimulationResult& r, std::size_t limit) {
  auto axes_text = [&](const MachineState& s) {
    char text[160];
    std::snprintf(text, sizeof text, "X%.3f Y%.3f Z%.3f", s.x.x, s.x.y, s.x.z);
    std::string out = text;
    if (r.input.machine.kinematics)
      for (const gcode::RotaryAxis& a : r.input.machine.kinematics->axes) {
        std::snprintf(text, sizeof text, " %c%.3f", a.letter,
                      s.rotary[std::size_t(gcode::rotary_index(a.letter))]);
        out += text;
      }
    return out;
  };
  const auto& found = run.found;
  if (const std::string text = machine_unchecked_text(run); !text.empty())
    std::printf("  machine: %s\n", text.c_str());
  for (std::size_t k = 0; k < found.collisions.size() && k < limit; ++k) {
    const MachineFinding& f = found.collisions[k];
    std::printf(
        "  %s:%d: collision: %s and %s meet (distance %.3f mm, %.0f%% along the move, "
        "at %s)\n",
        r.files.at(static_cast<std::size_t>(f.file)).c_str(), f.line, f.a.c_str(), f.b.c_str(),
        f.distance, 100 * f.t, axes_text(f.state).c_str());
  }
  for (std::size_t k = 0; k < found.travel.size() && k < limit; ++k) {
    const TravelAlong& t = found.travel[k];
    std::printf("  %s:%d: %c %.6g mm inside the move, past the travel's end %.6g\n",
                r.files.at(static_cast<std::size_t>(t.file)).c_str(), t.line, t.axis, t.value,
                t.limit);
  }
}

}  // namespace tridex::cli
