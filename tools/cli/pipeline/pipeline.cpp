#include "pipeline/pipeline.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <limits>
#include <set>

#include "checks/machine_run.hpp"
#include "checks/turning_bodies.hpp"
#include "checks/rapid_check.hpp"
#include "errors.hpp"
#include "outputs/output.hpp"
#include "outputs/result_files.hpp"
#include "pipeline/batch_pipe.hpp"
#include "pipeline/plausibility.hpp"
#include "pipeline/reach.hpp"
#include "render.hpp"
#include "tridex/backends/backends.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/intersect_milled.hpp"
#include "tridex/mill.hpp"
#include "tridex/polyhedron.hpp"
#include "tridex/stl.hpp"
#include "tridex/surface.hpp"
#include "tridex/fine_cells.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

Stock load_stock(const StockSpec& spec, const Aabb& cutting_bounds, std::uint64_t max_memory) {
  Stock stock;
  switch (spec.kind) {
    case StockSpec::Kind::box:
    case StockSpec::Kind::automatic: {
      stock.box =
          spec.kind == StockSpec::Kind::box ? spec.box : automatic_stock(cutting_bounds, spec);
      Vec3 size = stock.box.size();
      stock.volume = size.x * size.y * size.z;
      stock.description = {{"kind", spec.kind == StockSpec::Kind::box ? "box" : "auto"},
                           {"min", to_json(stock.box.min)},
                           {"max", to_json(stock.box.max)}};
      break;
    }
    case StockSpec::Kind::mesh: {
      try {
        stock.mesh = read_stl(spec.mesh_path.string(), StlOptions{.require_closed = true,
                                                                  .max_bytes = max_memory,
                                                                  .limit_name = "--max-memory"});
      } catch (const tridex::Error& e) {
        input_error("--stock ", spec.mesh_path.string(), ": ", e.what());
      }
      stock.box = stock.mesh->bounds();
      stock.volume = stock.mesh->signed_volume();
      if (!(stock.volume > 0))
        input_error("--stock ", spec.mesh_path.string(), ": the mesh encloses no volume (",
                    stock.volume, " mm^3); are its triangles inside out?");
      stock.description = {{"kind", "stl"},
                           {"file", spec.mesh_path.string()},
                           {"min", to_json(stock.box.min)},
                           {"max", to_json(stock.box.max)}};
      break;
    }
  }
  return stock;
}

// A move of `group` as the kernel mills it: the tool tip in the group's frame.
CutMove cut_move(const gcode::MoveGroup& group, const gcode::Move& m,
                 const std::map<int, std::uint32_t>& cutter_of_tool) {
  return CutMove{Segment{group.frame.to_local(m.start), group.frame.to_local(m.end)},
                 cutter_of_tool.at(m.tool)};
}

// Mills one group's moves into `map` in program order, checking each rapid with cut_depth against
// what the map holds when the rapid runs (RapidCheck::in_program_order), and each move's shank and
// holder when `bodies` is given (collision_check.hpp).
void mill_in_program_order(ZMap& map, const gcode::MoveGroup& group, std::size_t g,
                           std::span<const Cutter> cutters,
                           const std::map<int, std::uint32_t>& cutter_of_tool,
                           backends::ZMapBackend backend, unsigned threads,
                           std::vector<RapidFinding>& found, BodyCheck* bodies,
                           BodyFindings& body_found) {
  // Heights only fall, so a rapid entirely above the initial top cuts nothing and needs no flush.
  float top = -std::numeric_limits<float>::infinity();
  for (float h : map.heights) top = std::max(top, h);
  std::vector<CutMove> batch;
  auto flush = [&] {
    if (batch.empty()) return;
    // A handful of moves is milled faster than threads start.
    backends::mill_with(backend, map, cutters, batch, batch.size() < 64 ? 1u : threads);
    if (bodies) bodies->milled(map, cutters, batch);
    batch.clear();
  };
  for (const gcode::Move& m : group.moves) {
    CutMove cut = cut_move(group, m, cutter_of_tool);
    if (m.kind == gcode::MoveKind::rapid &&
        std::min(cut.tip.a.z, cut.tip.b.z) < double(top) - kRapidTolerance) {
      flush();
      CutDepth deepest = cut_depth(map, cutters[cut.cutter], cut.tip);
      if (deepest.depth > kRapidTolerance) {
        Vec3 local(map.grid.x(deepest.i), map.grid.y(deepest.j), map.height(deepest.i, deepest.j));
        found.push_back(RapidFinding{m.file, m.line, m.tool, group.axis, deepest.depth,
                                     group.frame.to_world(local), g});
      }
    }
    if (bodies)
      bodies->check(map, m, cut, group.axis, group.frame, g, batch.empty(), flush, body_found);
    batch.push_back(cut);
    if (bodies) bodies->will_mill(map, cutters[cut.cutter], cut);
  }
  flush();
}

std::string describe_box(const Aabb& box) {
  char text[160];
  std::snprintf(text, sizeof text, "%g,%g,%g to %g,%g,%g", box.min.x, box.min.y, box.min.z,
                box.max.x, box.max.y, box.max.z);
  return text;
}

// The kernel's meshes hold float positions, and the surface's vertices stay exact while they lie
// within about 1e5 lattice spacings of the world origin (surface.hpp); beyond that the dexel and
// Z-map arithmetic fails in ways that say nothing to the user. A stock that no move reaches is
// only its own faces: those need a float step (2^-23 of the reach) of at most half a spacing, so
// that neighbouring lattice nodes stay apart in the STL's floats.
constexpr double kMaxReachSpacings = 1e5;
constexpr double kMaxUncutReachSpacings = 0x1p23;

void check_reach(const std::string& what, const Aabb& box, double spacing,
                 double limit = kMaxReachSpacings) {
  double reach = 0;
  for (int a = 0; a < 3; ++a) reach = std::max({reach, std::abs(box.min[a]), std::abs(box.max[a])});
  if (!(reach <= limit * spacing))
    input_error(what, " reaches ", reach,
                " mm from the origin, beyond the coordinates tridex represents exactly at a ",
                "dexel spacing of ", spacing, " mm (", limit * spacing, " mm, ", limit,
                " spacings); move it nearer the origin or use a larger --dexel-cell");
}

// True when no move can touch the stock. In each direction's frame a cutter removes everything
// above its profile (the Z-map model), so a move reaches the stock only where its path, widened
// by the largest cutter's radius, overlaps the stock across the spindle, and the stock rises above
// its lowest tip. Then the result is the stock itself, and no cut arithmetic happens at its
// coordinates.
// `paths`: the groups' local_paths (reach.hpp).
bool no_move_reaches(const std::vector<gcode::MoveGroup>& groups, std::span<const Aabb> paths,
                     std::span<const Cutter> cutters, const Aabb& stock) {
  double radius = 0;
  for (const Cutter& c : cutters) radius = std::max(radius, c.radius());
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const gcode::MoveGroup& group = groups[g];
    const Aabb& path = paths[g];
    if (path.empty()) continue;
    const Aabb local = local_bounds(group.frame, stock);
    const bool apart = path.min.x - radius > local.max.x || path.max.x + radius < local.min.x ||
                       path.min.y - radius > local.max.y || path.max.y + radius < local.min.y;
    if (!apart && local.max.z >= path.min.z) return false;
  }
  return true;
}

// The files --dump-zmaps writes for the groups: DIR/zmap-<k>-<axis>.stl and .png.
std::vector<fs::path> dump_names(const std::string& directory,
                                 const std::vector<gcode::MoveGroup>& groups) {
  std::vector<fs::path> names;
  for (std::size_t g = 0; g < groups.size(); ++g) {
    fs::path base =
        fs::path(directory) / ("zmap-" + std::to_string(g + 1) + "-" + axis_label(groups[g].axis));
    names.push_back(base.string() + ".stl");
    names.push_back(base.string() + ".png");
  }
  return names;
}

// The dump files are named by the directions, known once the program is read: checked then,
// before any milling, against every input and every other output.
void check_dump_names(const std::string& directory, const std::vector<gcode::MoveGroup>& groups,
                      const std::vector<std::pair<std::string, fs::path>>& outputs,
                      const std::vector<fs::path>& inputs) {
  std::vector<std::pair<std::string, fs::path>> all;
  for (const auto& [option, path] : outputs)
    if (!path.empty()) all.emplace_back(option, path);
  for (const fs::path& name : dump_names(directory, groups)) {
    check_output_path("--dump-zmaps", name, inputs);
    all.emplace_back("--dump-zmaps", name);
  }
  check_distinct_outputs(all);
}

}  // namespace

double fine_cell_bytes(double cells, double rows, double moves, double bands_per_move) {
  constexpr double kSubHeights = 4.0 * ZMapFineCells::kPoints;
  const double per_cell = (kSubHeights + 2 * 4 + 4) + (kSubHeights + 4 + 4);
  const double per_row = 8 + 4;  // refine's row starts, the map's
  // refine's copy of the moves, each move's place in the bands it spans and its box there
  // (lower_fine_cells)
  const double per_move = sizeof(CutMove) + 4 * bands_per_move + sizeof(detail::FineCellBox);
  return per_cell * cells + per_row * rows + per_move * moves;
}

std::string travel_text(const TravelFinding& f) {
  bool linear = f.axis == 'X' || f.axis == 'Y' || f.axis == 'Z';
  char text[160];
  std::snprintf(text, sizeof text,
                linear ? "%c %.6g mm, past the travel's end %.6g" : "%c %.6g°, past its limit %.6g",
                f.axis, f.value, f.limit);
  return text;
}

Json rapid_finding_json(const RapidFinding& f, const std::vector<std::string>& files) {
  return {{"file", files.at(static_cast<std::size_t>(f.file))},
          {"line", f.line},
          {"tool", f.tool},
          {"axis", to_json(f.axis)},
          {"depth_mm", f.depth_mm},
          {"where", to_json(f.where)}};
}

std::string axis_label(const Vec3& axis) {
  static const char* names[] = {"x", "y", "z"};
  for (int a = 0; a < 3; ++a) {
    Vec3 e(0);
    e[a] = 1;
    if (glm::dot(axis, e) > 1 - 1e-9) return std::string("+") + names[a];
    if (glm::dot(axis, e) < -(1 - 1e-9)) return std::string("-") + names[a];
  }
  char text[64];
  std::snprintf(text, sizeof text, "%.3f_%.3f_%.3f", clean(axis.x), clean(axis.y), clean(axis.z));
  return text;
}

namespace {

// The pipeline's stages, in the order simulate_program runs them. Each fills its part of the
// SimulationResult; what one stage hands to a later one and the result does not keep travels in
// RunInputs and ParsedProgram.

// What the first stage settles besides r.input: the tool table (--tools, else the project's), the
// stock to load, the memory limit, and every input path that no output may name.
struct RunInputs {
  std::optional<ToolTable> table;
  StockSpec stock_spec;
  std::uint64_t max_memory = 0;
  std::vector<fs::path> inputs;
};

// Inputs and outputs, checked before any work: the program, the stock and the memory limit read,
// every output path writable and naming no input, --dump-zmaps's directory created.
RunInputs check_inputs_and_outputs(const SimulateOptions& options, const PipelineRequest& request,
                                   SimulationResult& r) {
  RunInputs run;
  r.input = resolve_program(options);
  if (!r.input.tools && request.tools) {
    r.input.tools = request.tools;
    apply_tool_options(options, r.input);  // G41/G42 D and G43 H from the table
  }
  const ProgramInput& input = r.input;
  // --tools, else the project's; the input keeps its copy for the summary and the warnings.
  if (r.input.tools) run.table = r.input.tools;
  if (!options.stock.empty())
    run.stock_spec = parse_stock(options.stock);
  else if (input.stock)
    run.stock_spec = *input.stock;
  run.max_memory = max_memory_bytes(options.max_memory);

  std::vector<fs::path>& inputs = run.inputs;
  inputs = files_read(options, input);
  if (run.stock_spec.kind == StockSpec::Kind::mesh) inputs.push_back(run.stock_spec.mesh_path);
  inputs.insert(inputs.end(), request.extra_inputs.begin(), request.extra_inputs.end());
  for (const auto& [option, path] : request.outputs)
    if (!path.empty()) check_output_path(option, path, inputs);
  check_distinct_outputs(request.outputs);
  if (!options.dump_zmaps.empty()) {
    std::error_code error;
    fs::create_directories(options.dump_zmaps, error);
    if (!fs::is_directory(options.dump_zmaps, error))
      input_error("--dump-zmaps ", options.dump_zmaps, ": cannot create the directory");
  }
  return run;
}

// What parsing leaves besides the groups, the program order, the files, the travel findings and
// the machining time in the result: the box of the cutting moves (an automatic stock's), where
// each tool was first selected (for messages) and how many moves are kept (for the memory check).
struct ParsedProgram {
  InterpretResult interpreted;  // its files moved into SimulationResult::files
  Aabb cutting_bounds;
  long long moves_kept = 0;
};

// Parses the program and groups its moves by spindle direction.
ParsedProgram parse_grouped(const SimulateOptions& options, std::uint64_t max_memory,
                            Progress& progress, SimulationResult& r) {
  ParsedProgram parsed;
  const ProgramInput& input = r.input;
  progress.stage("parsing " + input.program.string());
  const Clock::time_point t = Clock::now();
  gcode::DirectionGrouper grouper;
  // simulate must hold every move: grouped by direction (a MoveList holds no spare copies), then
  // as one direction's cutter sweeps while it is milled. What the process already holds (the
  // libraries, a design read) leaves that much less for them.
  MoveBudget budget(max_memory,
                    gcode::MoveList::bytes_per_move(input.machine.kinematics.has_value()) +
                        sizeof(CutMove) + sizeof(void*));
  Aabb& cutting_bounds = parsed.cutting_bounds;
  const std::optional<gcode::Kinematics>& kinematics = input.machine.kinematics;
  // Positions "far along the tool axis" stand in for where the machine takes the tool: no travel.
  const double far = 0.5 * input.machine.far_distance;
  r.machining = MachiningTimer(input.machine);
  // Grouping (and the checks that read each move once) runs on a second thread when there is one,
  // overlapping the interpreter; the budget and the machining time stay on this thread, with the
  // dwells the timer also reads.
  std::optional<gcode::Move> previous;  // the move before, for turning rapids
  BatchPipe<gcode::Move> grouping(
      [&](const gcode::Move& m) {
        if (kinematics) {
          if (previous) note_turning_rapid(*previous, m, r);
          previous = m;
        }
        if (m.pose != gcode::PoseLaw::fixed) {  // the tool turns: cut_simultaneous's
          r.simultaneous.push_back(m);
          if (m.kind != gcode::MoveKind::rapid) {  // a TCP rapid (LinuxCNC's) is no cut
            cutting_bounds.extend(m.start);
            cutting_bounds.extend(m.end);
          }
          return;
        }
        const auto group = static_cast<std::uint32_t>(grouper.add(m));
        if (r.order.empty() || r.order.back().group != group) r.order.push_back({group, 0});
        ++r.order.back().moves;
        if (kinematics && glm::length(m.end) < far)
          for (const gcode::TravelViolation& v :
               gcode::travel_violations(*kinematics, m.machine, m.rotary))
            if (r.travel_count++ < static_cast<long long>(kTravelListed))
              r.travel.push_back({m.file, m.line, v.axis, v.value, v.limit});
        if (m.kind != gcode::MoveKind::rapid) {
          // An approach from "far along the tool axis" is not where the work is.
          if (!m.from_far) cutting_bounds.extend(m.start);
          cutting_bounds.extend(m.end);
        }
      },
      detail::resolve_threads(options.threads) > 1);
  gcode::InterpreterOptions interpreting = interpreter_options(options);
  interpreting.read_ahead = detail::resolve_threads(options.threads) > 1;  // --threads 1: one
  parsed.interpreted = interpret(
      input, interpreting,
      [&](const gcode::Move& m, std::size_t file) {
        budget.keep(m, input.files[file]);
        r.machining.add(m);
        grouping.push(m);
      },
      [&](const gcode::Dwell& d) { r.machining.add(d); }, options.max_moves);
  grouping.finish();
  r.groups = grouper.take();
  r.files = std::move(parsed.interpreted.files);
  r.warnings = parsed.interpreted.warnings;
  r.timings.parse = seconds_since(t);
  parsed.moves_kept = budget.kept();
  return parsed;
}

// Cutters: every tool used must be in the table. Fills r.cutters, r.bodies and r.cutter_of_tool;
// a tool missing is an InputError at the line that first selected it.
void load_cutters(const SimulateOptions& options, const std::optional<ToolTable>& table,
                  const std::map<int, ToolSelection>& tool_first_line, SimulationResult& r) {
  const ProgramInput& input = r.input;
  std::vector<Cutter>& cutters = r.cutters;
  std::map<int, std::uint32_t>& cutter_of_tool = r.cutter_of_tool;
  std::vector<std::set<int>> tool_sets;  // the groups', then the simultaneous moves'
  for (const gcode::MoveGroup& group : r.groups) tool_sets.push_back(group.tools);
  tool_sets.emplace_back();
  for (const gcode::Move& m : r.simultaneous) tool_sets.back().insert(m.tool);
  for (const std::set<int>& group_tools : tool_sets)
    for (int tool : group_tools) {
      if (cutter_of_tool.count(tool)) continue;
      const ToolSpec* spec = table ? table->find(tool) : nullptr;
      if (spec) {
        cutter_of_tool[tool] = static_cast<std::uint32_t>(cutters.size());
        cutters.push_back(spec->cutter);
        r.bodies.push_back(spec->body);
        continue;
      }
      if (tool == 0) continue;  // moves before the first tool change; checked below
      auto where = tool_first_line.find(tool);
      std::string location = where == tool_first_line.end()
                                 ? input.program.string()
                                 : where->second.file + ":" + std::to_string(where->second.line);
      if (!table)
        input_error(location, ": tool ", tool,
                    " is used but there is no tool table (give --tools FILE)");
      if (const std::string* why = table->unusable(tool))
        input_error(location, ": tool ", tool, " is used, but ", *why);
      // LinuxCNC reads a D0 row (a probe, an engraver, a table written before diameters were
      // measured), and so does `moves`; a cut needs the cutter's size.
      if (table->zero_diameter().count(tool))
        input_error(location, ": tool ", tool,
                    " cuts, but its diameter in the tool table is 0 (D0 or no D): give its "
                    "diameter to simulate its cuts");
      input_error(location, ": tool ", tool, " is used but missing from the tool table ",
                  options.tools.empty() ? input.program.string() : options.tools);
    }
}

// The tool a control starts with (MachineConfig::initial_tool: --initial-tool, the machine
// file's "initial_tool", CAMotics' tool 1 for a project): when a feed move comes before any tool
// change, every move before it is cut with that tool, with a warning. A program that selects no
// tool at all (no T word, no M61; LinuxCNC's impeller demo) is cut with T1 when the tool table
// holds one and neither --initial-tool nor the machine file says otherwise, as CAMotics cuts a
// program without a tool change. A program that changes tools before it cuts keeps its
// positioning rapids dropped (drop_toolless_moves).
void load_initial_tool(const std::optional<ToolTable>& table, bool selects_tool,
                       SimulationResult& r) {
  const gcode::MachineConfig& machine = r.input.machine;
  const bool camotics_rule = machine.initial_tool <= 0 && !machine.initial_tool_stated &&
                             !selects_tool && table && table->find(1);
  const int tool = camotics_rule ? 1 : machine.initial_tool;
  if (tool <= 0) return;
  long long toolless = 0;
  bool feeds = false;
  for (const gcode::MoveGroup& group : r.groups)
    for (const gcode::Move& m : group.moves)
      if (m.tool == 0) ++toolless, feeds = feeds || m.kind != gcode::MoveKind::rapid;
  for (const gcode::Move& m : r.simultaneous)  // the moves that turn the tool, too
    if (m.tool == 0) ++toolless, feeds = feeds || m.kind != gcode::MoveKind::rapid;
  if (!feeds) return;
  if (!table || !table->find(tool))
    input_error(r.input.program.string(), ": the program cuts before any tool change, with tool ",
                tool, ", the tool the control starts with, which is ",
                table ? "not in the tool table" : "in no tool table (give --tools FILE)",
                "; give --initial-tool N for another");
  for (gcode::MoveGroup& group : r.groups)
    if (group.tools.erase(0)) {  // a group's tools are its moves' tools
      group.moves.replace_tool(0, tool);
      group.tools.insert(tool);
    }
  for (gcode::Move& m : r.simultaneous)
    if (m.tool == 0) m.tool = tool;
  const std::string source =
      camotics_rule ? "the program selects no tool: T1 of the tool table, as CAMotics does; "
                      "--initial-tool N to choose"
      : machine.initial_tool_stated ? "--initial-tool or the machine file's \"initial_tool\""
                                    : "CAMotics' convention for a project";
  r.warnings.push_back(std::to_string(toolless) +
                       " move(s) before any tool change were cut with tool " +
                       std::to_string(tool) + ", the tool the control starts with (" + source +
                       "); give the program a tool change (T" + std::to_string(tool) +
                       " M6), or --initial-tool 0 to refuse such moves");
}

// Without a tool in the spindle nothing cuts; rapids before the first tool change are only
// positioning and are dropped (with a warning), but a feed move then is an error.
void drop_toolless_moves(SimulationResult& r) {
  std::vector<gcode::MoveGroup>& groups = r.groups;
  long long toolless_rapids = 0;
  if (!r.cutter_of_tool.count(0)) {
    // The program order loses them too: each run keeps the count of its moves that stay.
    std::vector<std::size_t> next(groups.size(), 0);
    for (GroupRun& run : r.order) {
      const gcode::MoveList& moves = groups[run.group].moves;
      const std::size_t end = next[run.group] + run.moves;
      run.moves = static_cast<std::uint64_t>(
          std::count_if(moves.begin() + static_cast<std::ptrdiff_t>(next[run.group]),
                        moves.begin() + static_cast<std::ptrdiff_t>(end),
                        [](const gcode::Move& m) { return m.tool != 0; }));
      next[run.group] = end;
    }
    auto refuse_feed = [&](const gcode::Move& m) {
      if (m.kind != gcode::MoveKind::rapid)
        // The file that holds the move (one of a project's files, or a called subprogram), not
        // the project or the main program.
        input_error(
            r.files.at(static_cast<std::size_t>(m.file)), ":", m.line, ": a ",
            gcode::to_string(m.kind),
            " move with no tool loaded (T… M6; on a machine that loads the tool on T alone, give "
            "--machine a file with \"tool_loads_on_t\": true; for a control that starts with "
            "a tool in the spindle, --initial-tool N)");
    };
    // In place: the groups hold every move of the program, and a copy would double that.
    for (gcode::MoveGroup& group : groups) {
      std::size_t toolless = 0;
      for (const gcode::Move& m : group.moves)
        if (m.tool == 0) refuse_feed(m), ++toolless;
      if (toolless > 0) erase_if(group.moves, [](const gcode::Move& m) { return m.tool == 0; });
      toolless_rapids += static_cast<long long>(toolless);
    }
    // The moves that turn the tool likewise (cut_simultaneous skips a toolless rapid).
    for (const gcode::Move& m : r.simultaneous)
      if (m.tool == 0) refuse_feed(m), ++toolless_rapids;
  }
  if (toolless_rapids > 0)
    r.warnings.push_back(
        std::to_string(toolless_rapids) +
        " rapid move(s) before the first tool change were not simulated (no tool)");
}

std::string clean_number(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%g", v);
  return text;
}

// A box stock much larger than what the moves reach (reach.hpp): the lattice over that part,
// grown by a margin of kReachMarginCells cells, at --dexel-cell or --dexel-res cells along its
// longest side; said in a warning.
void clip_lattice_to_reach(const SimulateOptions& options, int res, SimulationResult& r) {
  const std::optional<Aabb> reach =
      reach_of_moves(r.groups, r.paths, r.simultaneous, r.cutters, r.cutter_of_tool, r.stock.box);
  if (!reach) return;
  const Vec3 size = reach->size();
  const double spacing =
      options.dexel_cell > 0 ? options.dexel_cell : std::max({size.x, size.y, size.z}) / res;
  if (!(spacing > 0)) return;
  const std::optional<Aabb> clipped = clipped_reach(*reach, r.stock.box, spacing);
  if (!clipped) return;
  r.lattice_box = *clipped;
  r.reach_only = true;
  r.lattice = DexelLattice::covering(*clipped, spacing);
  r.warnings.push_back("the lattice covers only the part of the stock the moves reach (" +
                       describe_box(*clipped) + ", " + clean_number(spacing) +
                       " mm dexels); the rest of the stock is uncut and meshed as its faces");
}

// check (PipelineRequest::resolve_gouges, resolution.hpp): the bound of what the lattice can miss
// (r.resolution), the lattice refined when the options left the spacing to tridex and it does not
// resolve the tolerance, and a spacing given that does not refused (exit status 2).
void resolve_tolerance(const SimulateOptions& options, const PipelineRequest& request,
                       const std::function<double(double)>& zmap_cell_for, SimulationResult& r) {
  const double tolerance = request.resolve_gouges;
  const auto bound_at = [&](double spacing) {
    return resolution_bound(r.groups, r.simultaneous, r.cutters, r.cutter_of_tool, spacing,
                            zmap_cell_for(spacing));
  };
  r.resolution = bound_at(r.lattice.spacing);
  if (r.resolution.missable <= tolerance || request.lattice_only) return;
  const double needed = spacing_for_tolerance(
      [&](double spacing) { return bound_at(spacing).missable; }, r.lattice.spacing, tolerance);
  const std::string missed = missable_text(r.resolution, r.cutters, r.cutter_of_tool);
  char spacing_text[96] = "none (the Z-map cell alone is too coarse: a smaller --zmap-cell)";
  if (needed > 0) std::snprintf(spacing_text, sizeof spacing_text, "%.4g mm", needed);
  const bool given = options.dexel_cell > 0 || options.dexel_res > 0;
  std::string option;
  if (options.dexel_cell > 0) option = "--dexel-cell " + clean_number(options.dexel_cell) + ": ";
  if (options.dexel_res > 0) option = "--dexel-res " + std::to_string(options.dexel_res) + ": ";
  if (given || needed == 0)
    input_error(option, "a dexel spacing of ", r.lattice.spacing, " mm can miss a gouge of ",
                missed, " between its samples, more than the gouge tolerance ", tolerance,
                " mm; the spacing that resolves it: ", spacing_text,
                ". Give a finer --dexel-cell, leave --dexel-res/--dexel-cell out to let check "
                "choose, give a looser --tolerance, or --lattice-only to compare on the samples "
                "alone (a design made by tridex on this lattice)");
  r.unrefined_spacing = r.lattice.spacing;
  r.unrefined = r.resolution;
  try {
    r.lattice = DexelLattice::covering(r.lattice_box, needed);
  } catch (const tridex::Error& e) {
    input_error("check at a gouge tolerance of ", tolerance, " mm needs a dexel spacing of ",
                spacing_text, ": ", e.what(), "; give a looser --tolerance");
  }
  r.resolution = bound_at(r.lattice.spacing);
}

std::string refined_memory_message(const PipelineRequest& request, const SimulationResult& r,
                                   std::uint64_t max_memory) {
  char text[256];
  std::snprintf(text, sizeof text,
                "check at a gouge tolerance of %g mm needs a dexel spacing of %.4g mm",
                request.resolve_gouges, r.lattice.spacing);
  char unrefined[64];
  std::snprintf(unrefined, sizeof unrefined, "%.4g mm", r.unrefined_spacing);
  return std::string(text) + " (at " + unrefined + " the lattice can miss a gouge of " +
         missable_text(r.unrefined, r.cutters, r.cutter_of_tool) +
         " between its samples), which needs an estimated " + format_mib(r.memory.total()) +
         ", more than --max-memory " + format_mib(static_cast<double>(max_memory)) +
         "; give a larger --max-memory, a looser --tolerance, or --dexel-res/--dexel-cell with a "
         "--tolerance it resolves";
}

// The stock, the resolutions (the dexel lattice, the Z-map cell and grids), and the memory they
// need, checked against --max-memory before anything big is allocated.
void size_the_run(const SimulateOptions& options, const PipelineRequest& request,
                  const RunInputs& run, const ParsedProgram& parsed, SimulationResult& r) {
  const StockSpec& stock_spec = run.stock_spec;
  const std::uint64_t max_memory = run.max_memory;
  r.paths = local_paths(r.groups, options.threads);
  r.stock = load_stock(stock_spec, parsed.cutting_bounds, max_memory);
  const Stock& stock = r.stock;
  r.lattice_box = stock.box;
  const int res = options.dexel_res > 0 ? options.dexel_res : kDefaultDexelRes;
  try {
    r.lattice = options.dexel_cell > 0 ? DexelLattice::covering(stock.box, options.dexel_cell)
                                       : DexelLattice::covering_resolution(stock.box, res);
    if (!stock.mesh && request.clip_to_reach) clip_lattice_to_reach(options, res, r);
  } catch (const tridex::Error& e) {
    input_error("dexel resolution: ", e.what());
  }
  const Aabb& box = r.lattice_box;
  const double diagonal = glm::length(box.size());
  // A Z-map's polyhedron ramps across the cell where a wall parallel to its spindle drops, and
  // is off by up to a cell at the wall's rims, where it meets the other directions' cuts
  // (docs/design.md, "Known errors"); at most half a dexel spacing keeps those edges within h/2.
  const auto zmap_cell_for = [&](double spacing) {
    return options.zmap_cell > 0
               ? options.zmap_cell
               : std::min(diagonal * kDefaultZmapCellFraction, kDefaultZmapCellOfSpacing * spacing);
  };
  const DexelLattice& lattice = r.lattice;
  const auto check_reaches = [&] {
    // Where no move cuts, the stock's faces are all there is to represent (a wider range).
    check_reach(stock_spec.kind == StockSpec::Kind::mesh
                    ? "--stock " + stock_spec.mesh_path.string()
                    : (r.reach_only ? "the part of the stock the moves reach" : "the stock"),
                box, lattice.spacing,
                no_move_reaches(r.groups, r.paths, r.cutters, stock.box) ? kMaxUncutReachSpacings
                                                                         : kMaxReachSpacings);
    for (const auto& [what, bounds] : request.extra_bounds)
      check_reach(what, bounds, lattice.spacing);
  };
  check_reaches();
  if (request.resolve_gouges > 0) {
    resolve_tolerance(options, request, zmap_cell_for, r);
    if (r.unrefined_spacing > 0) check_reaches();  // a finer lattice reaches less far
  }
  const double zmap_cell = zmap_cell_for(lattice.spacing);
  r.zmap_cell = zmap_cell;
  MemoryShape shape{.threads = static_cast<double>(detail::resolve_threads(options.threads)),
                    .keep_maps = request.keep_maps,
                    .dump_maps = !options.dump_zmaps.empty()};
  for (const gcode::MoveGroup& group : r.groups) {
    try {
      r.grids.push_back(ZMapGrid::covering(group.frame, local_bounds(group.frame, box), zmap_cell));
    } catch (const tridex::Error& e) {
      input_error("--zmap-cell ", zmap_cell, ": ", e.what());
    }
    const double points = static_cast<double>(r.grids.back().nx) * r.grids.back().ny;
    shape.zmap_points += points;
    shape.largest_map = std::max(shape.largest_map, points);
    if (static_cast<double>(group.moves.size()) > shape.largest_group) {
      shape.largest_group = static_cast<double>(group.moves.size());
      shape.group_blocks =
          std::ceil(r.grids.back().nx / 128.0) * std::ceil(r.grids.back().ny / 128.0);
    }
  }
  const glm::dvec3 n(lattice.n);
  shape.rays = n.x * n.y + n.y * n.z + n.z * n.x;
  // What the process holds now (the libraries, every move kept, the meshes read) is alive to the
  // end; the parser's buffers it freed are not, but the peak so far is a floor.
  r.memory = estimate_memory(resident_bytes(), peak_rss_bytes(), shape);
  if (request.memory_after)
    r.memory.after = request.memory_after(lattice.spacing, kTrianglesPerRay * shape.rays);
  const MemoryEstimate& need = r.memory;
  if (need.total() > static_cast<double>(max_memory) && r.unrefined_spacing > 0)
    input_error(refined_memory_message(request, r, max_memory));
  if (need.total() > static_cast<double>(max_memory))
    input_error("the resolution needs an estimated ", format_mib(need.total()),
                " (in use before milling ", format_mib(need.held), " with ", parsed.moves_kept,
                " moves kept, Z-maps ", format_mib(need.zmaps), ", dexels ",
                format_mib(need.dexels), ", surface ", format_mib(need.mesh),
                need.after > 0 ? ", the comparison with the design " + format_mib(need.after)
                               : std::string(),
                "), more than --max-memory ", format_mib(static_cast<double>(max_memory)),
                "; use a larger --zmap-cell or --dexel-cell, or a smaller --dexel-res");
}

// The cutter sweeps of one direction at a time, kept from direction to direction and from
// milling to refining the walls: fresh memory costs a page fault and the zeroing of each page
// (bench/README.md, issue 37), so these buffers are sized once for the largest direction.
struct CutScratch {
  std::vector<CutMove> feeds, rapids;
  std::vector<std::size_t> rapid_moves;
};

// Splits one group's moves into scratch's feeds and rapids (the rapids' indices in group.moves
// kept), as the kernel mills them.
void split_cuts(const gcode::MoveGroup& group, const std::map<int, std::uint32_t>& cutter_of_tool,
                CutScratch& scratch) {
  std::vector<CutMove>& feeds = scratch.feeds;
  std::vector<CutMove>& rapids = scratch.rapids;
  std::vector<std::size_t>& rapid_moves = scratch.rapid_moves;  // their indices in group.moves
  feeds.clear(), rapids.clear(), rapid_moves.clear();
  feeds.reserve(group.moves.size());
  for (auto it = group.moves.begin(); it != group.moves.end(); ++it) {
    const gcode::Move m = *it;
    CutMove cut = cut_move(group, m, cutter_of_tool);
    if (m.kind == gcode::MoveKind::rapid) {
      rapids.push_back(cut);
      rapid_moves.push_back(static_cast<std::size_t>(it - group.moves.begin()));
    } else {
      feeds.push_back(cut);
    }
  }
}

// Mills one group's moves, split by split_cuts into `scratch`, into `map` feed moves first
// (RapidCheck::against_feeds): the rapids are checked against what the feeds leave (when
// `check_rapids`), then milled too.
void mill_against_feeds(ZMap& map, const gcode::MoveGroup& group, std::size_t g,
                        backends::ZMapBackend zmap_backend, bool check_rapids, unsigned threads,
                        const CutScratch& scratch, SimulationResult& r) {
  const std::vector<Cutter>& cutters = r.cutters;
  backends::mill_with(zmap_backend, map, cutters, scratch.feeds, threads);
  for (const RapidCut& found : check_rapids
                                   ? rapid_cuts(map, cutters, scratch.rapids, kRapidTolerance)
                                   : std::vector<RapidCut>{}) {
    const gcode::Move m = group.moves[scratch.rapid_moves[found.index]];
    r.rapid_cuts.push_back(
        RapidFinding{m.file, m.line, m.tool, group.axis, found.depth_mm, m.end, g});
  }
  backends::mill_with(zmap_backend, map, cutters, scratch.rapids, threads);
}

// Group g's Z-map before milling: the stock's top along its spindle.
ZMap initial_map(const SimulationResult& r, std::size_t g, unsigned threads) {
  ZMapLimits limits;
  limits.max_points = std::numeric_limits<std::size_t>::max();  // the memory check above rules
  const Frame& frame = r.groups[g].frame;
  return r.stock.mesh ? ZMap::from_mesh(frame, *r.stock.mesh, r.zmap_cell, limits)
                      : ZMap::from_box(frame, r.lattice_box, r.zmap_cell, limits, threads);
}

// The groups' initial Z-maps, each made on a thread of its own while the caller splits and mills
// the group before it (with more than one thread). A fresh map is mostly page faults and the
// zeroing of its pages (0.1-0.2 s for each of model-D's 100 MB maps), work on one thread that
// left the other core idle between the directions; beside the milling it fills the miller's own
// serial stretches instead (bench/README.md, issue 37). Every map is made alike (from_box's rows
// do not depend on the thread count), so the maps are the same either way. The memory check
// counts every map through the milling already (MemoryEstimate::milling).
class InitialMaps {
 public:
  InitialMaps(const SimulationResult& r, unsigned threads)
      : r_(r), threads_(threads), ahead_(detail::resolve_threads(threads) > 1) {}

  // Starts making group g's map (a no-op without a thread to spare, or past the last group).
  void prepare(std::size_t g) {
    if (!ahead_ || g >= r_.groups.size()) return;
    next_.reset();
    making_.start([this, g] { next_.emplace(initial_map(r_, g, 1)); });
  }
  // Group g's map: the one prepare(g) made, or made now.
  ZMap take(std::size_t g) {
    if (!ahead_) return initial_map(r_, g, threads_);
    making_.join();
    ZMap map = std::move(*next_);
    next_.reset();
    return map;
  }

 private:
  const SimulationResult& r_;
  unsigned threads_;
  bool ahead_;
  std::optional<ZMap> next_;  // written by making_'s thread only until the join
  detail::BackgroundTask making_;
};

// Step 1: one milled Z-map per direction (r.maps), its rapids checked as the request asks.
void mill_directions(const SimulateOptions& options, const PipelineRequest& request,
                     Progress& progress, CutScratch& scratch, SimulationResult& r) {
  const Clock::time_point t = Clock::now();
  const std::vector<gcode::MoveGroup>& groups = r.groups;
  std::vector<ZMap>& maps = r.maps;
  maps.reserve(groups.size());
  const backends::ZMapBackend zmap_backend = backends::parse_zmap_backend(options.zmap_backend);
  // gl draws each cutter slightly inside the true one (gl_mill.hpp); cut_depth, which uses the
  // true cutter, then finds "stock" left along every feed, deepest on steep flanks. So the rapid
  // check needs the exact milling.
  const bool check_rapids = zmap_backend == backends::ZMapBackend::cpu;
  if (!check_rapids)
    r.warnings.push_back(
        "rapid moves were not checked for cutting stock: that check needs --zmap-backend cpu");
  // The shanks, holders and spindle parts that check tests against the stock (machine_run.hpp).
  const std::vector<ToolBody> stock_bodies =
      request.body_clearance ? bodies_against_stock(r) : std::vector<ToolBody>{};
  std::size_t most_moves = 0;
  for (const gcode::MoveGroup& group : groups)
    most_moves = std::max(most_moves, group.moves.size());
  scratch.feeds.reserve(most_moves);
  InitialMaps initial(r, options.threads);
  initial.prepare(0);
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const gcode::MoveGroup& group = groups[g];
    progress.stage("milling direction " + std::to_string(g + 1) + "/" +
                   std::to_string(groups.size()) + " (" + axis_label(group.axis) + ", " +
                   std::to_string(group.moves.size()) + " moves)");
    const bool in_order = request.rapid_check == RapidCheck::in_program_order;
    if (!in_order) split_cuts(group, r.cutter_of_tool, scratch);  // while map g is made
    maps.push_back(initial.take(g));
    initial.prepare(g + 1);  // while this group mills
    r.segments += static_cast<long long>(group.moves.size());
    if (in_order) {
      std::optional<BodyCheck> bodies;
      if (request.body_clearance)
        bodies.emplace(maps.back(), stock_bodies, *request.body_clearance);
      mill_in_program_order(maps.back(), group, g, r.cutters, r.cutter_of_tool, zmap_backend,
                            options.threads, r.rapid_cuts, bodies ? &*bodies : nullptr, r.body);
      continue;
    }
    mill_against_feeds(maps.back(), group, g, zmap_backend, check_rapids, options.threads, scratch,
                       r);
  }
  // Only `feeds` goes on to the walls. (Assigning `{}` would keep the capacity: an
  // initializer_list assignment.)
  scratch.rapids = std::vector<CutMove>(), scratch.rapid_moves = std::vector<std::size_t>();
  r.timings.zmap = seconds_since(t);
}

// --dump-zmaps: each direction's milled Z-map as STL and as a height picture.
void dump_zmaps(const std::string& directory, const SimulationResult& r, Progress& progress) {
  const std::vector<fs::path> names = dump_names(directory, r.groups);
  for (std::size_t g = 0; g < r.maps.size(); ++g) {
    progress.stage("writing Z-map " + std::to_string(g + 1) + " to " + directory);
    write_stl_file(names[2 * g], polyhedrize(r.maps[g]));
    write_png_file(names[2 * g + 1], render::render_heights(r.maps[g]));
  }
}

// Every move of `group` as the kernel mills it, in order, into `moves`, converted on `threads`
// threads: on one, the conversion of each direction's moves left the other core idle between
// the directions' refinements (bench/README.md, issue 37).
void cut_moves(const gcode::MoveGroup& group, const std::map<int, std::uint32_t>& cutter_of_tool,
               unsigned threads, std::vector<CutMove>& moves) {
  const std::size_t n = group.moves.size();
  moves.resize(n);
  constexpr std::size_t kChunk = std::size_t{1} << 16;
  detail::for_each_chunk((n + kChunk - 1) / kChunk, threads, [&](std::size_t c) {
    for (std::size_t k = c * kChunk; k < std::min(n, (c + 1) * kChunk); ++k)
      moves[k] = cut_move(group, group.moves[k], cutter_of_tool);
  });
}

// Walls parallel to a spindle are placed inside their cells: the steep cells take finer heights
// from the moves (fine_cells.hpp). How many cells are steep is known only now: their sub-grids
// are checked against --max-memory before any is allocated.
void refine_walls(const SimulateOptions& options, std::uint64_t max_memory,
                  std::vector<CutMove>& moves, SimulationResult& r) {
  std::vector<ZMap>& maps = r.maps;
  const std::vector<gcode::MoveGroup>& groups = r.groups;
  std::vector<std::vector<std::uint32_t>> steep(maps.size());
  std::size_t steep_cells = 0;
  double rows = 0, most_moves = 0;
  for (std::size_t g = 0; g < maps.size(); ++g) {
    steep[g] = tridex::steep_cells(maps[g], WallOptions{}.steep_slope, options.threads);
    steep_cells += steep[g].size();
    rows += maps[g].grid.ny;
    most_moves = std::max(most_moves, static_cast<double>(groups[g].moves.size()));
  }
  // A move is listed in the bands its swept box spans: its width plus one band at each end
  // for the short moves of most programs.
  double widest = 0;
  for (const Cutter& c : r.cutters) widest = std::max(widest, 2 * c.radius());
  const double bands_per_move = 2 + widest / (kWallBandRows * r.zmap_cell);
  const double before = r.memory.total();
  r.memory.walls =
      fine_cell_bytes(static_cast<double>(steep_cells), rows, most_moves, bands_per_move);
  r.memory.fine = fine_cell_bytes(static_cast<double>(steep_cells), rows, 0, 0);
  if (r.memory.total() > static_cast<double>(max_memory))
    input_error("the walls need finer heights in ", steep_cells,
                " steep Z-map cells: an estimated ", format_mib(r.memory.walls), " next to ",
                format_mib(r.memory.zmaps), " of Z-maps (", format_mib(before),
                " in all without them), more than --max-memory ",
                format_mib(static_cast<double>(max_memory)),
                "; use a larger --zmap-cell or --dexel-cell, or a smaller --dexel-res");
  // One buffer for every direction (milling's): its pages are touched once.
  moves.reserve(static_cast<std::size_t>(most_moves));
  for (std::size_t g = 0; g < maps.size(); ++g) {
    cut_moves(groups[g], r.cutter_of_tool, options.threads, moves);
    refine_steep_cells(maps[g], r.cutters, moves, {.threads = options.threads},
                       std::move(steep[g]));
  }
}

// The volume of the surface extract_surface gives the uncut stock on r's lattice (stitched into
// the stock's box on a reach lattice, as the result's is). Each crossing stays a few float steps
// (crossing_margin) off the lattice nodes, and a box stock's faces lie a hair off node planes
// (DexelLattice::covering), so an uncut face stands about 3e-4 mm proud: over a whole stock,
// -0.85 % of a small groove's removal. The result's surface carries the same offset, so the
// difference of the two surfaces' volumes is the removal without it (docs/reports.md). A box
// stock's comes in closed form (box_surface_volume, within 1e-8 of the extracted surface's on
// full and reach lattices: float noise), as extracting it took as long as the result's surface
// on the paper-scale workload; a mesh stock's is extracted.
double stock_surface_volume(const TripleDexel& stock, unsigned threads, const SimulationResult& r) {
  if (!r.stock.mesh) {
    const Vec3 size = r.lattice_box.size();
    return r.stock.volume - size.x * size.y * size.z + box_surface_volume(r.lattice, r.lattice_box);
  }
  Mesh mesh = extract_surface(stock, {.threads = threads});
  if (r.reach_only) mesh = stitch_into_stock(mesh, r.lattice_box, r.stock.box, r.lattice.spacing);
  return mesh.signed_volume();
}

// Steps 2 and 3: the stock as a triple dexel, cut by every direction's Z-map (r.result).
// intersect_milled() fuses the two steps ray by ray (each ray of the stock clipped by each Z-map's
// polyhedron in turn, never storing M_i), so "intersect" times them together.
void intersect_directions(const SimulateOptions& options, const PipelineRequest& request,
                          std::uint64_t max_memory, Progress& progress, CutScratch& scratch,
                          SimulationResult& r) {
  Clock::time_point t = Clock::now();
  const Stock& stock = r.stock;
  std::vector<ZMap>& maps = r.maps;
  // The intersection needs only the cuts: what a direction left uncut is raised above the stock,
  // so that the stock's faces and silhouette come from W0 exactly (see raise_uncut). A kept map
  // stays as milled; the raised copy is the one intersected.
  std::vector<ZMap> kept_maps;
  if (request.keep_maps) kept_maps = maps;
  for (std::size_t g = 0; g < maps.size(); ++g) {
    if (stock.mesh)
      raise_uncut(maps[g], *stock.mesh, options.threads);
    else
      raise_uncut(maps[g], r.lattice_box, options.threads);
  }
  if (request.fine_cells) refine_walls(options, max_memory, scratch.feeds, r);
  scratch.feeds = std::vector<CutMove>();  // freed, not only cleared
  progress.stage("dexelizing the stock");
  TripleDexel stock_dexel = stock.mesh
                                ? dexelize(*stock.mesh, r.lattice, DexelizeOptions{options.threads})
                                : TripleDexel::box(r.lattice, r.lattice_box);
  r.stock_surface_volume = stock_surface_volume(stock_dexel, options.threads, r);
  r.timings.dexelize = seconds_since(t);
  progress.stage("dexelizing and intersecting " + std::to_string(maps.size()) + " Z-maps");
  t = Clock::now();
  r.result = backends::machine_with(backends::parse_dexel_backend(options.dexel_backend),
                                    stock_dexel, maps, options.threads);
  r.timings.intersect = seconds_since(t);
  // The result is the stock less the cuts: the same volume means no move reached the stock (a
  // stock given far from where the program works, say). Not an error, but surely not meant.
  r.stock_dexel_volume = tridex::volume(stock_dexel);
  r.result_dexel_volume = tridex::volume(r.result);
  if (r.result_dexel_volume >= r.stock_dexel_volume * (1 - 1e-12)) {
    // Only when no move can reach the stock is "nothing was cut" a fact; otherwise the cuts are
    // finer than the lattice resolves (a large stock around a small toolpath), and saying so
    // tells the user what to change.
    if (no_move_reaches(r.groups, r.paths, r.cutters, stock.box))
      r.warnings.push_back("nothing was cut: no move reaches the stock (" +
                           describe_box(stock.box) +
                           "); the result is the whole stock: check --stock against the "
                           "program's work offsets and units");
    else
      r.warnings.push_back("the moves reach the stock (" + describe_box(stock.box) +
                           ") but remove less than the dexel spacing of " +
                           std::to_string(r.lattice.spacing) +
                           " mm resolves: give a smaller --dexel-cell, or a stock nearer the "
                           "toolpath");
  }
  stock_dexel = TripleDexel{};
  maps = std::move(kept_maps);
  maps.shrink_to_fit();
}

// The stock's volume less the removal measured surface against surface (surface_volume).
void result_volume(SimulationResult& r) {
  r.volume = r.stock.volume - (r.stock_surface_volume - r.mesh.signed_volume());
}

// The surface of the result (r.mesh), checked for watertightness, and the result's volume. With
// PipelineRequest::surface_ready and a thread to spare, the surface goes to it while the check
// runs beside (simulate's STL write): both are long passes over the whole surface, and one of
// them alone left a core idle (bench/README.md, issue 37).
void extract_result_surface(const SimulateOptions& options, const PipelineRequest& request,
                            Progress& progress, SimulationResult& r) {
  progress.stage("extracting the surface");
  const Clock::time_point t = Clock::now();
  r.mesh = extract_surface(r.result, {.threads = options.threads});
  if (r.reach_only)
    r.mesh = stitch_into_stock(r.mesh, r.lattice_box, r.stock.box, r.lattice.spacing);
  auto check = [&] {
    r.mesh_check = check_mesh(r.mesh, options.threads);
    r.timings.mesh = seconds_since(t);
    result_volume(r);
  };
  if (request.surface_ready && detail::resolve_threads(options.threads) > 1) {
    detail::BackgroundTask checking;  // waits for the check if the write throws
    checking.start(check);
    request.surface_ready(r.mesh);
    checking.join();
  } else {
    check();
    if (request.surface_ready) request.surface_ready(r.mesh);
  }
}

}  // namespace

SimulationResult simulate_program(const SimulateOptions& options, Progress& progress,
                                  const PipelineRequest& request) {
  SimulationResult r;
  const RunInputs run = check_inputs_and_outputs(options, request, r);
  ParsedProgram parsed = parse_grouped(options, run.max_memory, progress, r);
  check_outputs_not_read(request.outputs, parsed.interpreted.read);  // the subprograms it called
  // The dump files are named by the directions, known only now.
  if (!options.dump_zmaps.empty())
    check_dump_names(options.dump_zmaps, r.groups, request.outputs, run.inputs);
  load_initial_tool(run.table, parsed.interpreted.selects_tool, r);
  load_cutters(options, run.table, parsed.interpreted.tool_first_line, r);
  drop_toolless_moves(r);
  size_the_run(options, request, run, parsed, r);
  warn_implausible_setup(options, parsed.cutting_bounds, r);
  CutScratch scratch;
  mill_directions(options, request, progress, scratch, r);
  if (!options.dump_zmaps.empty()) {
    scratch.feeds =
        std::vector<CutMove>();  // the dump's polyhedra take the room (MemoryEstimate::dump)
    dump_zmaps(options.dump_zmaps, r, progress);
  }
  intersect_directions(options, request, run.max_memory, progress, scratch, r);
  if (!r.simultaneous.empty()) cut_simultaneous(options, r, request.body_clearance.has_value());
  // The simultaneous moves' shanks and holders against the final solid (turning_bodies.hpp).
  if ((!r.simultaneous.empty() || !r.turning_rapids.empty()) && request.body_clearance)
    check_turning_bodies(r, bodies_against_stock(r), *request.body_clearance, options.threads);
  if (request.rapid_check == RapidCheck::in_program_order) check_turning_rapids(r);
  extract_result_surface(options, request, progress, r);
  return r;
}

}  // namespace tridex::cli
