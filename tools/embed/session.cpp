// tridex embedded — the session (session.hpp). The stages follow `tridex simulate`'s
// (tools/cli/pipeline/pipeline.cpp): a change there must be made here too, and the session-vs-
// simulate tests (tests/embed) say when they part.
#include "session.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <span>
#include <sstream>

#include "commands.hpp"
#include "errors.hpp"
#include "outputs/result_files.hpp"
#include "tridex/backends/backends.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/fine_cells.hpp"
#include "tridex/mill.hpp"
#include "tridex/stl.hpp"
#include "tridex/surface.hpp"

namespace tridex::embed {

namespace {

// The name a fed program's diagnostics and moves carry.
const std::string kFedProgram = "<fed>";

// Where a move came from: its line of the fed program, or "a move given directly" (line 0).
std::string where_text(const gcode::Move& m) {
  return m.line > 0 ? kFedProgram + ":" + std::to_string(m.line) : "a move given directly";
}

// Whether the ray p + t·d (t > 0) crosses triangle (a, b, c) (Möller and Trumbore, "Fast, minimum
// storage ray-triangle intersection", JGT 2(1) 1997).
bool ray_crosses(const Vec3& p, const Vec3& d, const Vec3& a, const Vec3& b, const Vec3& c) {
  const Vec3 e1 = b - a, e2 = c - a;
  const Vec3 q = glm::cross(d, e2);
  const double det = glm::dot(e1, q);
  if (std::abs(det) < 1e-300) return false;
  const Vec3 s = p - a;
  const double u = glm::dot(s, q) / det;
  if (u < 0 || u > 1) return false;
  const Vec3 r = glm::cross(s, e1);
  const double v = glm::dot(d, r) / det;
  if (v < 0 || u + v > 1) return false;
  return glm::dot(e2, r) / det > 0;
}

}  // namespace

Session::Session(const SessionOptions& options)
    : options_(options), pool_(std::make_unique<detail::ThreadPool>(options.threads)) {
  const detail::UsePool use(*pool_);
  if (!options.stock_file.empty()) {
    try {  // as simulate reads --stock FILE.stl (pipeline.cpp, load_stock)
      stock_mesh_ = std::make_shared<const Mesh>(
          read_stl(options.stock_file, StlOptions{.require_closed = true}));
    } catch (const tridex::Error& e) {
      cli::input_error("stock ", options.stock_file, ": ", e.what());
    }
    stock_ = stock_mesh_->bounds();
    stock_volume_ = stock_mesh_->signed_volume();
    if (!(stock_volume_ > 0))
      cli::input_error("stock ", options.stock_file, ": the mesh encloses no volume (",
                       stock_volume_, " mm^3); are its triangles inside out?");
  } else {
    stock_ = options.stock;
    const Vec3 box = stock_.size();
    if (!is_finite(stock_.min) || !is_finite(stock_.max) || !(box.x > 0) || !(box.y > 0) ||
        !(box.z > 0))
      cli::input_error(
          "stock: give xmin, ymin, zmin, xmax, ymax, zmax with each max above its min");
    stock_volume_ = box.x * box.y * box.z;
  }
  const Vec3 size = stock_.size();
  if (!(options.cell >= 0) || !std::isfinite(options.cell))
    cli::input_error("cell: the dexel spacing must be a positive number of mm (", options.cell,
                     ")");
  cli::CommonOptions common;
  common.machine = options.machine;
  common.tools = options.tools;
  common.tool_units = options.tool_units;
  common.initial_tool = options.initial_tool;
  common.arc_tolerance = options.arc_tolerance;
  common.lenient = options.lenient;
  input_.machine = cli::load_machine(options.machine);
  cli::apply_tool_options(common, input_);
  interpreter_ = gcode::Interpreter(cli::interpreter_options(common), input_.machine);
  try {  // as simulate sizes the run (pipeline.cpp, size_the_run)
    lattice_ = options.cell > 0 ? DexelLattice::covering(stock_, options.cell)
                                : DexelLattice::covering_resolution(stock_, cli::kDefaultDexelRes);
  } catch (const tridex::Error& e) {
    cli::input_error("dexel resolution: ", e.what());
  }
  zmap_cell_ = std::min(glm::length(size) * cli::kDefaultZmapCellFraction,
                        cli::kDefaultZmapCellOfSpacing * lattice_.spacing);
  cache_ = SolidCache(stock_, stock_mesh_, lattice_, options.threads);
}

std::vector<gcode::Move> Session::run_piece(gcode::Interpreter& interpreter,
                                            std::string_view text) {
  std::vector<gcode::Move> moves;
  std::istringstream in{std::string(text)};
  interpreter.feed(in, kFedProgram, [&](const gcode::Move& m) { moves.push_back(m); });
  return moves;
}

// The cutter of `tool` (loaded from the table when `add`), as simulate's load_cutters finds it.
std::uint32_t Session::cutter_for(int tool, const gcode::Move& m, bool add) {
  if (auto it = cutter_of_tool_.find(tool); it != cutter_of_tool_.end()) return it->second;
  const std::optional<cli::ToolTable>& table = input_.tools;
  if (const cli::ToolSpec* spec = table ? table->find(tool) : nullptr) {
    if (!add) return std::numeric_limits<std::uint32_t>::max();
    cutter_of_tool_[tool] = static_cast<std::uint32_t>(cutters_.size());
    cutters_.push_back(spec->cutter);
    return cutter_of_tool_[tool];
  }
  if (!table)
    cli::input_error(where_text(m), ": tool ", tool,
                     " is used but there is no tool table (give the session a tool table)");
  if (const std::string* why = table->unusable(tool))
    cli::input_error(where_text(m), ": tool ", tool, " is used, but ", *why);
  if (table->zero_diameter().count(tool))
    cli::input_error(where_text(m), ": tool ", tool,
                     " cuts, but its diameter in the tool table is 0 (D0 or no D)");
  cli::input_error(where_text(m), ": tool ", tool, " is used but missing from the tool table ",
                   options_.tools);
}

template <class Commit>
void Session::cut_moves(std::vector<gcode::Move> moves, Commit&& commit) {
  // Tools first, so that a piece that fails changes nothing (simulate's load_initial_tool,
  // load_cutters and drop_toolless_moves, move by move).
  const int initial = input_.machine.initial_tool;
  const bool tool_zero_cuts = input_.tools && input_.tools->find(0);
  std::vector<gcode::Move> cut;
  std::vector<gcode::Move> toolless = toolless_rapids_;
  bool initial_cuts = initial_tool_cuts_;
  long long dropped = 0;
  for (gcode::Move m : moves) {
    // simulate cuts these on their own (cut_simultaneous); the session's maps would take them as
    // fixed-axis moves, a wrong solid: refused, not passed over.
    if (m.pose != gcode::PoseLaw::fixed)
      cli::input_error(where_text(m), ": a simultaneous 5-axis move (the tool turns during it) ",
                       "is not cut by a session yet; simulate the program with `tridex simulate`");
    if (m.tool == 0 && !tool_zero_cuts) {
      const bool rapid = m.kind == gcode::MoveKind::rapid;
      if (initial > 0 && !initial_cuts && !rapid) {
        if (!input_.tools || !input_.tools->find(initial))
          cli::input_error(where_text(m), ": the program cuts before any tool change, with tool ",
                           initial, ", the tool the control starts with, which is not in the ",
                           "tool table");
        initial_cuts = true;
        for (gcode::Move& t : toolless) t.tool = initial, cut.push_back(t);
        toolless.clear();
      }
      if (initial_cuts) {
        m.tool = initial;
      } else if (rapid) {
        toolless.push_back(m);
        ++dropped;
        continue;
      } else {
        cli::input_error(where_text(m), ": a ", gcode::to_string(m.kind),
                         " move with no tool loaded (T… M6)");
      }
    }
    cut.push_back(m);
  }
  std::map<int, const gcode::Move*> first_use;
  for (const gcode::Move& m : cut) first_use.emplace(m.tool, &m);
  for (const auto& [tool, m] : first_use) cutter_for(tool, *m, false);
  // Committed from here on.
  for (const auto& [tool, m] : first_use) cutter_for(tool, *m, true);
  commit();
  toolless_rapids_ = std::move(toolless);
  initial_tool_cuts_ = initial_cuts;
  if (dropped > 0)
    own_warnings_.push_back(
        std::to_string(dropped) +
        " rapid move(s) before the first tool change were not simulated (no tool)");
  warnings_ = own_warnings_;
  for (const gcode::Diagnostic& d : interpreter_.warnings()) warnings_.push_back(d.to_string());
  mill(cut);
}

void Session::feed(std::string_view text) {
  const detail::UsePool use(*pool_);
  gcode::Interpreter trial = interpreter_.clone();
  std::vector<gcode::Move> moves = run_piece(trial, text);
  cut_moves(std::move(moves), [&] { interpreter_ = std::move(trial); });
}

double Session::feed_measured(std::string_view text) {
  const detail::UsePool use(*pool_);
  const double before = removed_volume();
  feed(text);
  return removed_volume() - before;
}

void Session::add_move(const Vec3& start, const Vec3& end, int tool, const Vec3& axis, bool rapid) {
  const detail::UsePool use(*pool_);
  if (!is_finite(start) || !is_finite(end))
    cli::input_error("add_move: the start and end points must be finite");
  const double length = glm::length(axis);
  if (!is_finite(axis) || !(length > 1e-12))
    cli::input_error("add_move: the tool axis must be a finite, non-zero direction");
  if (tool < 0) cli::input_error("add_move: tool ", tool, " is not a tool number");
  gcode::Move m;
  m.kind = rapid ? gcode::MoveKind::rapid : gcode::MoveKind::feed;
  m.tool = tool;
  m.start = start;
  m.end = end;
  m.axis = axis / length;
  cut_moves({m}, [] {});
}

// Step 1, incrementally: each direction's new moves milled into its live map.
void Session::mill(const std::vector<gcode::Move>& moves) {
  std::vector<std::size_t> fed(cuts_.size());
  for (std::size_t g = 0; g < cuts_.size(); ++g) fed[g] = cuts_[g].size();
  for (const gcode::Move& m : moves) {
    const std::size_t g = grouper_.add(m);
    const gcode::MoveGroup& group = grouper_.groups()[g];
    if (g == maps_.size()) {
      ZMapLimits limits;
      limits.max_points = std::numeric_limits<std::size_t>::max();
      maps_.push_back(
          stock_mesh_ ? ZMap::from_mesh(group.frame, *stock_mesh_, zmap_cell_, limits)
                      : ZMap::from_box(group.frame, stock_, zmap_cell_, limits, options_.threads));
      cuts_.emplace_back();
      fed.push_back(0);
    }
    cuts_[g].push_back(CutMove{Segment{group.frame.to_local(m.start), group.frame.to_local(m.end)},
                               cutter_of_tool_.at(m.tool)});
  }
  for (std::size_t g = 0; g < cuts_.size(); ++g) {
    const std::span<const CutMove> batch = std::span<const CutMove>(cuts_[g]).subspan(fed[g]);
    if (batch.empty()) continue;
    backends::mill_with(backends::ZMapBackend::cpu, maps_[g], cutters_, batch,
                        batch.size() < 64 ? 1u : options_.threads);
    cache_.milled(g, maps_[g], cutters_, batch);
  }
  moves_ += static_cast<long long>(moves.size());
  if (!moves.empty()) {
    solid_valid_ = false;
    probes_.clear();
  }
}

// Steps 2-3 where the pieces since changed a map (SolidCache), and the surface (pipeline.cpp:
// intersect_directions, refine_walls, extract_result_surface).
void Session::ensure_solid() {
  if (solid_valid_) return;
  const unsigned threads = options_.threads;
  const TripleDexel& solid = cache_.update(maps_, cutters_, cuts_);
  const TripleDexel& stock_dexel = cache_.stock_dexel();
  mesh_ = extract_surface(solid, {.threads = threads});
  // As simulate's removed_mm3: the uncut stock's surface volume less the solid's, the surfaces'
  // offset from the lattice nodes cancelling (pipeline.cpp, stock_surface_volume). The stock's is
  // measured once: the lattice and the stock stay.
  if (!stock_surface_volume_)
    stock_surface_volume_ = extract_surface(stock_dexel, {.threads = threads}).signed_volume();
  removed_ = *stock_surface_volume_ - mesh_.signed_volume();
  // The surface's rounding never makes a negative removal.
  if (removed_ < 0) removed_ = std::max(0.0, tridex::volume(stock_dexel) - tridex::volume(solid));
  solid_valid_ = true;
}

double Session::removed_volume() {
  const detail::UsePool use(*pool_);
  ensure_solid();
  return removed_;
}

const Mesh& Session::mesh() {
  const detail::UsePool use(*pool_);
  ensure_solid();
  return mesh_;
}

void Session::write_stl(const std::filesystem::path& path) {
  const detail::UsePool use(*pool_);
  ensure_solid();
  cli::write_stl_file(path, mesh_);
}

// The solid's top seen along `axis` (its Z-map from the surface), kept until the next piece.
const ZMap& Session::probe_map(const Vec3& axis) {
  for (const auto& [a, map] : probes_)
    if (glm::dot(a, axis) > 1 - 1e-12) return map;
  Frame frame = Frame::from_axis(axis);
  for (const gcode::MoveGroup& group : grouper_.groups())
    if (glm::dot(group.axis, axis) > 1 - 1e-12) frame = group.frame;
  ZMapLimits limits;
  limits.max_points = std::numeric_limits<std::size_t>::max();
  probes_.emplace_back(axis, ZMap::from_mesh(frame, mesh_, zmap_cell_, limits));
  return probes_.back().second;
}

double Session::would_cut(std::string_view block) {
  const detail::UsePool use(*pool_);
  gcode::Interpreter trial = interpreter_.clone();
  trial.resume();  // a block asked about after the program's end still runs
  const std::vector<gcode::Move> moves = run_piece(trial, block);
  ensure_solid();
  if (mesh_.triangles.empty()) return 0;
  double deepest = 0;
  for (const gcode::Move& m : moves) {
    int tool = m.tool;
    if (tool == 0 && !(input_.tools && input_.tools->find(0))) {
      if (input_.machine.initial_tool <= 0) {
        if (m.kind == gcode::MoveKind::rapid) continue;  // nothing in the spindle: nothing cuts
        cli::input_error(where_text(m), ": a ", gcode::to_string(m.kind),
                         " move with no tool loaded (T… M6)");
      }
      tool = input_.machine.initial_tool;
    }
    std::uint32_t index = cutter_for(tool, m, false);
    const Cutter& cutter =
        index < cutters_.size() ? cutters_[index] : input_.tools->find(tool)->cutter;
    const ZMap& top = probe_map(m.axis);
    const Segment tip{top.grid.frame.to_local(m.start), top.grid.frame.to_local(m.end)};
    deepest = std::max(deepest, cut_depth(top, cutter, tip).depth);
  }
  return deepest > kCutTolerance ? deepest : 0;
}

bool Session::inside(const Vec3& point) {
  const detail::UsePool use(*pool_);
  ensure_solid();
  if (!is_finite(point)) cli::input_error("inside: the point must be finite");
  const Aabb box = mesh_.bounds();
  for (int a = 0; a < 3; ++a)
    if (point[a] < box.min[a] || point[a] > box.max[a]) return false;
  // The parity of the surface's crossings along three skew rays, by majority: a ray that grazes
  // an edge of the lattice-aligned surface miscounts, and no two of these meet the same edge.
  static const std::array<Vec3, 3> rays = {glm::normalize(Vec3(0.5377, 0.3141, 0.7826)),
                                           glm::normalize(Vec3(-0.2718, 0.8413, -0.4669)),
                                           glm::normalize(Vec3(0.6931, -0.5772, -0.4142))};
  int votes = 0;
  for (const Vec3& d : rays) {
    int crossings = 0;
    for (const glm::uvec3& t : mesh_.triangles)
      crossings += ray_crosses(point, d, Vec3(mesh_.positions[t.x]), Vec3(mesh_.positions[t.y]),
                               Vec3(mesh_.positions[t.z]));
    votes += crossings % 2;
  }
  return votes >= 2;
}

std::vector<std::pair<double, double>> Session::extent(const Vec3& point, const Vec3& direction) {
  const detail::UsePool use(*pool_);
  ensure_solid();
  const double length = glm::length(direction);
  if (!is_finite(point) || !is_finite(direction) || !(length > 1e-12))
    cli::input_error("extent: give a finite point and a finite, non-zero direction");
  const Vec3 d = direction / length;
  // The crossings of the line with the surface, entering (the triangle faces against d) or
  // leaving, counted in order: the solid is where more were entered than left. A line that meets
  // an edge or a vertex may count a crossing once too often or too few: then the count does not
  // come back to zero, and the line is moved aside by a hair (1e-6 of a spacing, skew) and asked
  // again, as inside() outvotes such a ray.
  static const std::array<Vec3, 4> aside = {Vec3(0), Vec3(0.5377, 0.3141, 0.7826),
                                            Vec3(-0.2718, 0.8413, -0.4669),
                                            Vec3(0.6931, -0.5772, -0.4142)};
  std::vector<std::pair<double, int>> hits;
  for (const Vec3& nudge : aside) {
    const Vec3 p = point + nudge * (1e-6 * lattice_.spacing);
    hits.clear();
    for (const glm::uvec3& t : mesh_.triangles) {
      const Vec3 a(mesh_.positions[t.x]), b(mesh_.positions[t.y]), c(mesh_.positions[t.z]);
      const Vec3 e1 = b - a, e2 = c - a;
      const Vec3 q = glm::cross(d, e2);
      const double det = glm::dot(e1, q);
      if (std::abs(det) < 1e-300) continue;  // along the line: no crossing
      const Vec3 s = p - a;
      const double u = glm::dot(s, q) / det;
      if (u < 0 || u > 1) continue;
      const Vec3 r = glm::cross(s, e1);
      const double v = glm::dot(d, r) / det;
      if (v < 0 || u + v > 1) continue;
      // det = −(e1 × e2)·d: positive when the outward normal faces against d, the line entering.
      hits.emplace_back(glm::dot(e2, r) / det, det > 0 ? 1 : -1);
    }
    std::sort(hits.begin(), hits.end());
    std::vector<std::pair<double, double>> spans;
    int depth = 0;
    bool sound = true;
    for (const auto& [t, step] : hits) {
      if (depth == 0 && step > 0) spans.emplace_back(t, t);
      depth += step;
      if (depth < 0) sound = false;
      if (depth == 0 && step < 0 && !spans.empty()) spans.back().second = t;
    }
    if (sound && depth == 0) {
      // The hair's offset along d is not undone: it is far below the surface's own rounding.
      spans.erase(std::remove_if(spans.begin(), spans.end(),
                                 [](const auto& span) { return !(span.second > span.first); }),
                  spans.end());
      return spans;
    }
  }
  throw tridex::Error("extent: the surface's crossings along the line do not pair up");
}

}  // namespace tridex::embed
