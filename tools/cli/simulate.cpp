// tridex simulate — the paper's pipeline from a program to a solid (Inui, Chen and Umezu,
// "Visualization of 3+2 Axis Machining Result by Combining Multiple Z-map Models", CAD&A 19(4)
// 2022, §3): parse -> group moves by spindle direction -> one Z-map per direction, milled with
// the direction's moves (Step 1) -> each Z-map dexelized on one triple-dexel lattice (Step 2)
// -> stock ∩ M_1 ∩ … ∩ M_N (Step 3) -> surface -> STL, picture, report.
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>
#include <map>
#include <sstream>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "errors.hpp"
#include "json_text.hpp"
#include "memory.hpp"
#include "output.hpp"
#include "program_input.hpp"
#include "rapid_check.hpp"
#include "progress.hpp"
#include "render.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/gcode/grouping.hpp"
#include "tridex/machine.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/mill.hpp"
#include "tridex/polyhedron.hpp"
#include "tridex/stl.hpp"
#include "tridex/surface.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

// A rapid deeper than this below the feed-only surface is reported (mm): well above the
// rounding of float heights, well below any real collision.
constexpr double kRapidTolerance = 0.005;

double seconds_since(Clock::time_point start) {
  return std::chrono::duration<double>(Clock::now() - start).count();
}

// The stock as the pipeline needs it: a box, or a closed mesh and its bounds.
struct Stock {
  Aabb box;                  // bounds (the box itself for a box stock)
  std::optional<Mesh> mesh;  // a mesh stock
  double volume = 0;
  Json description;
};

Stock load_stock(const StockSpec& spec, const Aabb& cutting_bounds) {
  Stock stock;
  switch (spec.kind) {
    case StockSpec::Kind::box:
    case StockSpec::Kind::automatic: {
      stock.box = spec.kind == StockSpec::Kind::box ? spec.box : automatic_stock(cutting_bounds, spec);
      Vec3 size = stock.box.size();
      stock.volume = size.x * size.y * size.z;
      stock.description = {{"kind", spec.kind == StockSpec::Kind::box ? "box" : "auto"},
                           {"min", to_json(stock.box.min)}, {"max", to_json(stock.box.max)}};
      break;
    }
    case StockSpec::Kind::mesh: {
      try {
        stock.mesh = read_stl(spec.mesh_path.string(), StlOptions{.require_closed = true});
      } catch (const tridex::Error& e) {
        input_error("--stock ", spec.mesh_path.string(), ": ", e.what());
      }
      stock.box = stock.mesh->bounds();
      stock.volume = stock.mesh->signed_volume();
      if (!(stock.volume > 0))
        input_error("--stock ", spec.mesh_path.string(), ": the mesh encloses no volume (",
                    stock.volume, " mm^3); are its triangles inside out?");
      stock.description = {{"kind", "stl"}, {"file", spec.mesh_path.string()},
                           {"min", to_json(stock.box.min)}, {"max", to_json(stock.box.max)}};
      break;
    }
  }
  return stock;
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

void write_png_file(const fs::path& path, const render::Image& image) {
  write_file_atomically(path, render::encode_png(image));
}

void write_stl_file(const fs::path& path, const Mesh& mesh) {
  AtomicOutput out(path);
  write_stl(out.stream(), mesh);
  out.commit();
}

}  // namespace

int run_simulate(const SimulateOptions& options) {
  const Clock::time_point start = Clock::now();
  Progress progress(!options.quiet && (options.progress || stderr_is_terminal()));

  // ---- inputs and outputs, checked before any work ---------------------------------------
  ProgramInput input = resolve_program(options.program);
  std::optional<ToolTable> table;
  if (!options.tools.empty()) table = ToolTable::read(options.tools);
  else if (input.tools) table = std::move(input.tools);
  StockSpec stock_spec;
  if (!options.stock.empty()) stock_spec = parse_stock(options.stock);
  else if (input.stock) stock_spec = *input.stock;
  std::uint64_t max_memory = options.max_memory.empty()
                                 ? physical_memory_bytes() / 10 * 8
                                 : parse_memory(options.max_memory);

  std::vector<fs::path> inputs(input.files.begin(), input.files.end());
  inputs.push_back(input.program);
  if (!options.tools.empty()) inputs.push_back(options.tools);
  if (stock_spec.kind == StockSpec::Kind::mesh) inputs.push_back(stock_spec.mesh_path);
  if (!options.output.empty()) check_output_path("-o", options.output, inputs);
  if (!options.png.empty()) check_output_path("--png", options.png, inputs);
  if (!options.report.empty()) check_output_path("--report", options.report, inputs);
  if (!options.dump_zmaps.empty()) {
    std::error_code error;
    fs::create_directories(options.dump_zmaps, error);
    if (!fs::is_directory(options.dump_zmaps, error))
      input_error("--dump-zmaps ", options.dump_zmaps, ": cannot create the directory");
  }

  // ---- parse, grouped by spindle direction ------------------------------------------------
  progress.stage("parsing " + input.program.string());
  Clock::time_point t = Clock::now();
  gcode::InterpreterOptions interpreter_options;
  interpreter_options.arc_tolerance = options.arc_tolerance;
  interpreter_options.lenient = options.lenient;
  gcode::DirectionGrouper grouper;
  Aabb cutting_bounds;
  const double far = 0.5 * gcode::MachineConfig::kDefaultFar;
  InterpretResult parsed = interpret(input, interpreter_options, [&](const gcode::Move& m, std::size_t) {
    grouper.add(m);
    if (m.kind != gcode::MoveKind::rapid) {
      // An approach from "far along the tool axis" is not where the work is.
      if (glm::length(m.start) < far) cutting_bounds.extend(m.start);
      cutting_bounds.extend(m.end);
    }
  });
  std::vector<gcode::MoveGroup> groups = grouper.take();
  std::vector<std::string> warnings = parsed.warnings;
  const double parse_s = seconds_since(t);

  // ---- cutters: every tool used must be in the table --------------------------------------
  std::vector<Cutter> cutters;
  std::map<int, std::uint32_t> cutter_of_tool;
  long long toolless_rapids = 0;
  for (const gcode::MoveGroup& group : groups)
    for (int tool : group.tools) {
      if (cutter_of_tool.count(tool)) continue;
      const ToolSpec* spec = table ? table->find(tool) : nullptr;
      if (spec) {
        cutter_of_tool[tool] = static_cast<std::uint32_t>(cutters.size());
        cutters.push_back(spec->cutter);
        continue;
      }
      if (tool == 0) continue;  // moves before the first tool change; checked below
      auto where = parsed.tool_first_line.find(tool);
      std::string location = where == parsed.tool_first_line.end()
                                 ? input.program.string()
                                 : where->second.file + ":" + std::to_string(where->second.line);
      if (!table)
        input_error(location, ": tool ", tool, " is used but there is no tool table (give --tools FILE)");
      input_error(location, ": tool ", tool, " is used but missing from the tool table ",
                  options.tools.empty() ? input.program.string() : options.tools);
    }
  // Without a tool in the spindle nothing cuts; rapids before the first tool change are only
  // positioning and are skipped, but a feed move then is an error.
  if (!cutter_of_tool.count(0))
    for (gcode::MoveGroup& group : groups) {
      std::vector<gcode::Move> kept;
      kept.reserve(group.moves.size());
      for (const gcode::Move& m : group.moves) {
        if (m.tool != 0) kept.push_back(m);
        else if (m.kind == gcode::MoveKind::rapid) ++toolless_rapids;
        else
          input_error(input.files.size() == 1 ? input.files[0].string() : input.program.string(), ":",
                      m.line, ": a ", gcode::to_string(m.kind), " move with no tool loaded (T… M6)");
      }
      group.moves = std::move(kept);
    }
  if (toolless_rapids > 0)
    warnings.push_back(std::to_string(toolless_rapids) +
                       " rapid move(s) before the first tool change were not simulated (no tool)");

  // ---- stock, resolutions, and the memory they need ---------------------------------------
  Stock stock = load_stock(stock_spec, cutting_bounds);
  const double diagonal = glm::length(stock.box.size());
  const double zmap_cell = options.zmap_cell > 0 ? options.zmap_cell : diagonal * kDefaultZmapCellFraction;
  DexelLattice lattice;
  try {
    lattice = options.dexel_cell > 0
                  ? DexelLattice::covering(stock.box, options.dexel_cell)
                  : DexelLattice::covering_resolution(stock.box, options.dexel_res > 0 ? options.dexel_res : kDefaultDexelRes);
  } catch (const tridex::Error& e) {
    input_error("dexel resolution: ", e.what());
  }
  std::vector<ZMapGrid> grids;
  double zmap_points = 0;
  for (const gcode::MoveGroup& group : groups) {
    try {
      grids.push_back(ZMapGrid::covering(group.frame, local_bounds(group.frame, stock.box), zmap_cell));
    } catch (const tridex::Error& e) {
      input_error("--zmap-cell ", zmap_cell, ": ", e.what());
    }
    zmap_points += static_cast<double>(grids.back().nx) * grids.back().ny;
  }
  MemoryEstimate need = estimate_memory(zmap_points, lattice.n.x, lattice.n.y, lattice.n.z);
  if (need.total() > static_cast<double>(max_memory))
    input_error("the resolution needs an estimated ", format_mib(need.total()), " (Z-maps ",
                format_mib(need.zmaps), ", dexels ", format_mib(need.dexels), ", mesh ",
                format_mib(need.mesh), "), more than --max-memory ",
                format_mib(static_cast<double>(max_memory)),
                "; use a larger --zmap-cell or --dexel-cell, or a smaller --dexel-res");

  // ---- Step 1: one milled Z-map per direction ---------------------------------------------
  t = Clock::now();
  std::vector<ZMap> maps;
  maps.reserve(groups.size());
  ZMapLimits limits;
  limits.max_points = std::numeric_limits<std::size_t>::max();  // the memory check above rules
  long long segments = 0;
  Json rapid_findings = Json::array();
  for (std::size_t g = 0; g < groups.size(); ++g) {
    const gcode::MoveGroup& group = groups[g];
    progress.stage("milling direction " + std::to_string(g + 1) + "/" + std::to_string(groups.size()) +
                   " (" + axis_label(group.axis) + ", " + std::to_string(group.moves.size()) + " moves)");
    maps.push_back(stock.mesh ? ZMap::from_mesh(group.frame, *stock.mesh, zmap_cell, limits)
                              : ZMap::from_box(group.frame, stock.box, zmap_cell, limits));
    // Feed moves first; the rapids are checked against what the feeds leave, then milled too.
    std::vector<CutMove> feeds, rapids;
    std::vector<const gcode::Move*> rapid_moves;
    feeds.reserve(group.moves.size());
    for (const gcode::Move& m : group.moves) {
      CutMove cut{Segment{group.frame.to_local(m.start), group.frame.to_local(m.end)}, cutter_of_tool.at(m.tool)};
      if (m.kind == gcode::MoveKind::rapid) {
        rapids.push_back(cut);
        rapid_moves.push_back(&m);
      } else {
        feeds.push_back(cut);
      }
    }
    segments += static_cast<long long>(group.moves.size());
    mill(maps.back(), cutters, feeds, MillOptions{options.threads});
    for (const RapidCut& found : rapid_cuts(maps.back(), cutters, rapids, kRapidTolerance)) {
      const gcode::Move& m = *rapid_moves[found.index];
      rapid_findings.push_back({{"line", m.line}, {"tool", m.tool}, {"axis", to_json(group.axis)},
                                {"depth_mm", found.depth_mm}});
    }
    mill(maps.back(), cutters, rapids, MillOptions{options.threads});
  }
  if (!rapid_findings.empty()) {
    std::string lines;
    for (std::size_t k = 0; k < rapid_findings.size() && k < 10; ++k)
      lines += (k ? ", " : "") + std::to_string(rapid_findings[k]["line"].get<int>());
    warnings.push_back(std::to_string(rapid_findings.size()) +
                       " rapid move(s) cut material that no feed move removes (lines " + lines +
                       (rapid_findings.size() > 10 ? ", …" : "") + "; see \"rapid_cuts\" in the report)");
  }
  const double zmap_s = seconds_since(t);

  if (!options.dump_zmaps.empty()) {
    for (std::size_t g = 0; g < maps.size(); ++g) {
      progress.stage("writing Z-map " + std::to_string(g + 1) + " to " + options.dump_zmaps);
      fs::path base = fs::path(options.dump_zmaps) /
                      ("zmap-" + std::to_string(g + 1) + "-" + axis_label(groups[g].axis));
      write_stl_file(base.string() + ".stl", polyhedrize(maps[g]));
      write_png_file(base.string() + ".png", render::render_heights(maps[g]));
    }
  }

  // ---- Steps 2 and 3: the stock as a triple dexel, cut by every direction's Z-map ---------
  // machine() fuses the two steps ray by ray (each ray of the stock clipped by each Z-map's
  // polyhedron in turn, never storing M_i), so "intersect" times them together.
  t = Clock::now();
  // The intersection needs only the cuts: what a direction left uncut is raised above the stock,
  // so that the stock's faces and silhouette come from W0 exactly (see raise_uncut).
  for (std::size_t g = 0; g < maps.size(); ++g)
    raise_uncut(maps[g], stock.mesh ? ZMap::from_mesh(groups[g].frame, *stock.mesh, zmap_cell, limits)
                                    : ZMap::from_box(groups[g].frame, stock.box, zmap_cell, limits));
  progress.stage("dexelizing the stock");
  TripleDexel stock_dexel = stock.mesh ? dexelize(*stock.mesh, lattice, DexelizeOptions{options.threads})
                                       : TripleDexel::box(lattice, stock.box);
  const double dexelize_s = seconds_since(t);
  progress.stage("dexelizing and intersecting " + std::to_string(maps.size()) + " Z-maps");
  t = Clock::now();
  TripleDexel result = machine(stock_dexel, maps, options.threads);
  const double intersect_s = seconds_since(t);
  stock_dexel = TripleDexel{};
  maps.clear();
  maps.shrink_to_fit();

  // ---- surface ------------------------------------------------------------------------------
  progress.stage("extracting the surface");
  t = Clock::now();
  Mesh mesh = extract_surface(result);
  MeshCheck check = check_mesh(mesh);
  const double mesh_s = seconds_since(t);
  const double volume = mesh.signed_volume();

  // ---- outputs ------------------------------------------------------------------------------
  if (!options.output.empty()) {
    progress.stage("writing " + options.output);
    write_stl_file(options.output, mesh);
  }
  if (!options.png.empty()) {
    progress.stage("rendering " + options.png);
    if (mesh.triangles.empty()) {
      warnings.push_back("no material is left: " + options.png + " was not written");
    } else {
      write_png_file(options.png, render::render_mesh(mesh));
    }
  }
  const double total_s = seconds_since(start);
  if (!check.closed())
    warnings.push_back("the result mesh is not watertight (" + std::to_string(check.boundary_edges) +
                       " boundary, " + std::to_string(check.non_manifold_edges) + " non-manifold edges)");

  Json report;
  report["program"] = input.program.string();
  if (input.files.size() != 1 || input.files[0] != input.program) {
    Json files = Json::array();
    for (const fs::path& f : input.files) files.push_back(f.string());
    report["files"] = files;
  }
  report["stock"] = stock.description;
  report["segments"] = segments;
  Json group_list = Json::array();
  for (std::size_t g = 0; g < groups.size(); ++g)
    group_list.push_back({{"axis", to_json(groups[g].axis)},
                          {"moves", groups[g].moves.size()},
                          {"tools", groups[g].tools},
                          {"zmap", {grids[g].nx, grids[g].ny}},
                          {"cell_mm", zmap_cell}});
  report["groups"] = group_list;
  report["dexel"] = {{"cell_mm", lattice.spacing}, {"res", {lattice.n.x, lattice.n.y, lattice.n.z}}};
  report["memory_estimate_mib"] = need.total() / (1 << 20);
  report["timings_s"] = {{"parse", parse_s}, {"zmap", zmap_s}, {"dexelize", dexelize_s},
                         {"intersect", intersect_s}, {"mesh", mesh_s}, {"total", total_s}};
  report["peak_rss_mib"] = peak_rss_mib();
  report["result"] = {{"volume_mm3", volume},
                      {"removed_mm3", stock.volume - volume},
                      {"dexel_volume_mm3", tridex::volume(result)},
                      {"triangles", mesh.triangles.size()},
                      {"watertight", check.closed()}};
  report["rapid_cuts"] = rapid_findings;
  report["warnings"] = warnings;
  if (!options.report.empty()) {
    progress.stage("writing " + options.report);
    write_file_atomically(options.report, report.dump(2) + "\n");
  }
  progress.finish();

  if (!options.quiet) {
    for (const std::string& w : warnings) std::cerr << "warning: " << w << '\n';
    std::string written;
    for (const std::string& path : {options.output, options.png, options.report})
      if (!path.empty()) written += (written.empty() ? " -> " : ", ") + path;
    std::printf("%s: %lld segments in %zu directions, %d x %d x %d dexels; %.1f mm^3 left, %.1f mm^3 "
                "removed, %zu triangles, %s%s; %.2f s\n",
                input.program.filename().string().c_str(), segments, groups.size(), lattice.n.x,
                lattice.n.y, lattice.n.z, volume, stock.volume - volume, mesh.triangles.size(),
                check.closed() ? "watertight" : "NOT watertight", written.c_str(), total_s);
  }
  return kSuccess;
}

}  // namespace tridex::cli
