// tridex command — the simulation pipeline shared by `simulate` and `check` (Inui, Chen and Umezu,
// "Visualization of 3+2 Axis Machining Result by Combining Multiple Z-map Models", CAD&A 19(4)
// 2022, §3): parse -> group moves by spindle direction -> one Z-map per direction, milled with the
// direction's moves (Step 1) -> stock ∩ M_1 ∩ … ∩ M_N on one triple-dexel lattice (Steps 2-3)
// -> surface. The callers write the outputs; the pipeline only checks their paths up front.
#pragma once

#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <functional>
#include <map>
#include <optional>
#include <span>
#include <string>
#include <utility>
#include <vector>

#include "checks/collision_check.hpp"
#include "commands.hpp"
#include "inputs/program_input.hpp"
#include "json_text.hpp"
#include "checks/machining_time.hpp"
#include "pipeline/memory.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/resolution.hpp"
#include "tridex/cutter.hpp"
#include "tridex/dexel.hpp"
#include "tridex/gcode/grouping.hpp"
#include "tridex/mesh.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/zmap.hpp"

namespace tridex::cli {

// The stock as the pipeline needs it: a box, or a closed mesh and its bounds.
struct Stock {
  Aabb box;                  // bounds (the box itself for a box stock)
  std::optional<Mesh> mesh;  // a mesh stock
  double volume = 0;
  Json description;
};

// How rapids are checked for cutting material (docs/design.md: a rapid that touches stock is a
// finding).
enum class RapidCheck {
  // Against the direction's Z-map milled by its feed moves alone: rapids through material that no
  // feed move of the direction removes (what `simulate` reports).
  against_feeds,
  // In program order: the direction's moves are milled in batches between rapids (mill() does not
  // depend on order within a batch) and each rapid is checked with cut_depth before it is milled.
  // Exact for a program with one spindle direction. With several, material that another direction
  // removed earlier still counts, so a rapid may be reported that a machine runs safely, but none
  // that meets material is missed — in particular every rapid that meets the final solid.
  in_program_order,
};

struct PipelineRequest {
  std::vector<std::pair<std::string, std::filesystem::path>>
      outputs;                                      // (option, path), checked first
  std::vector<std::filesystem::path> extra_inputs;  // never overwritten either
  // The tool table of a program that has none of its own (no --tools, not a project with tools):
  // diff's B runs with a project A's table (issue 39).
  std::optional<ToolTable> tools;
  // Other geometry that must lie within the exact range on the lattice (check's design), with
  // its name for the message.
  std::vector<std::pair<std::string, Aabb>> extra_bounds;
  RapidCheck rapid_check = RapidCheck::against_feeds;
  // With in_program_order: the tools' shanks and holders against the stock (collision_check.hpp),
  // near misses within this clearance (mm); none: not checked.
  std::optional<double> body_clearance;
  bool keep_maps = false;  // keep the milled Z-maps (otherwise released after Step 3)
  // Fine cells at walls parallel to a spindle (fine_cells.hpp); off only to measure what they
  // cost and gain (bench/tools: BM_simulate_fine_cells).
  bool fine_cells = true;
  // What the caller allocates after the surface, in bytes, given the lattice spacing and the
  // estimated triangle count of the surface (check: the design's and the result's distance
  // trees, the deviations, the design samples); counted in the up-front memory check.
  std::function<double(double spacing, double triangles)> memory_after;
  // check (issue 31): the gouge tolerance the lattice must resolve, mm (resolution.hpp); 0: none.
  // Without --dexel-res/--dexel-cell the spacing is made fine enough for it, within
  // --max-memory; a spacing given that cannot resolve it is refused unless `lattice_only`.
  double resolve_gouges = 0;
  bool lattice_only = false;  // --lattice-only: the bound is reported, not enforced
  // A box stock much larger than the toolpath: the lattice over the part the moves reach
  // (reach.hpp). check keeps the whole stock: it measures the design on the lattice.
  bool clip_to_reach = true;
  // Called with the result's surface once it is extracted, before the pipeline returns (simulate
  // writes its STL there): with more than one thread, while the surface's check runs beside it
  // (SimulationResult::mesh_check is not yet known). What it throws ends the run.
  std::function<void(const Mesh&)> surface_ready;
};

// A rapid that cuts: `depth_mm` below the material along the spindle at `where` (work frame).
struct RapidFinding {
  int file = 0;  // Move::file: an index into SimulationResult::files
  int line = 0;
  int tool = 0;
  Vec3 axis{0, 0, 1};
  double depth_mm = 0;
  Vec3 where{0};
  std::size_t group = 0;
};

// A move that ends outside the machine's travel (the kinematics' "travel" in machine
// coordinates, or a rotary axis's limits): `check` lists these as findings, `simulate` warns.
struct TravelFinding {
  int file = 0;  // Move::file: an index into SimulationResult::files
  int line = 0;
  char axis = 'X';
  double value = 0;  // mm (X Y Z, machine coordinates) or degrees (A B C)
  double limit = 0;  // the end of the travel it passed
};
constexpr std::size_t kTravelListed = 1000;  // findings kept in the result; all are counted

struct PipelineTimings {
  double parse = 0, zmap = 0, dexelize = 0, intersect = 0, mesh = 0;
};

// The program's order across the groups (the groups keep it only within each): runs of moves
// that follow each other in execution order and fall in one group.
struct GroupRun {
  std::uint32_t group = 0;
  std::uint64_t moves = 0;
};

// The simultaneous 5-axis moves of one tool (simultaneous.cpp): how many, their sub-steps, and
// the largest band e of the sweep's certificate (sweep.hpp), mm.
struct SweepSummary {
  long long moves = 0, sub_steps = 0;
  double band = 0;
};

struct SimulationResult {
  ProgramInput input;
  std::vector<gcode::MoveGroup> groups;  // moves in program order within each group
  std::vector<GroupRun> order;           // the groups' moves in program order: what follows what
  std::vector<Aabb> paths;               // each group's tool tips in its frame (local_paths)
  std::vector<std::string> files;        // Move::file's table (InterpretResult::files)
  std::vector<Cutter> cutters;
  std::vector<ToolBody> bodies;                 // the non-cutting parts, parallel to cutters
  std::map<int, std::uint32_t> cutter_of_tool;  // tool number -> index into cutters
  Stock stock;
  double zmap_cell = 0;
  std::vector<ZMapGrid> grids;  // one per group
  std::vector<ZMap> maps;       // milled, one per group (empty unless keep_maps)
  DexelLattice lattice;
  // The box the lattice, the Z-maps and r.result cover: the stock's, or the part of a box stock
  // the moves reach (`reach_only`, reach.hpp); r.mesh is the whole stock's surface either way.
  Aabb lattice_box;
  bool reach_only = false;
  // With PipelineRequest::resolve_gouges: the deepest gouge the lattice can miss, and the spacing
  // the options gave before it was refined for the tolerance (0: not refined).
  ResolutionBound resolution, unrefined;
  double unrefined_spacing = 0;
  MemoryEstimate memory;
  TripleDexel result;
  Mesh mesh;
  MeshCheck mesh_check;
  // The result's volume: the stock's less what was removed, measured as the uncut stock's surface
  // volume less the result's (the surfaces' offset from the lattice nodes cancels: pipeline.cpp,
  // surface_volume). The mesh's own enclosed volume differs by that offset times the uncut faces.
  double volume = 0;
  double stock_surface_volume = 0;  // the uncut stock's surface on the lattice, mm³
  // The stock's and the result's volume on the dexel lattice: what the lattice resolves as
  // removed, never negative (the surface's volume may exceed the stock's by its rounding when
  // the cuts are finer than the lattice).
  double stock_dexel_volume = 0, result_dexel_volume = 0;
  long long segments = 0;
  std::vector<RapidFinding> rapid_cuts;
  std::vector<TravelFinding> travel;  // the first kTravelListed, in program order
  long long travel_count = 0;
  BodyFindings body;  // collisions and near misses of shanks and holders (body_clearance only)
  MachiningTimer machining;  // the program's machining time
  std::vector<std::string> warnings;
  PipelineTimings timings;
  // Moves whose tool turns (Move::pose ≠ fixed), in program order: in no group, cut on the triple
  // dexel after the groups' Z-maps (cut_simultaneous), summarised by tool.
  std::vector<gcode::Move> simultaneous;
  // The turns of the rotaries between moves in raw form (G0 with rotary words, not swept: an
  // indexing move), each as the joints move it makes from the move before to the move after
  // (note_turning_rapid), with the line of the move after it.
  std::vector<gcode::Move> turning_rapids;
  std::map<int, SweepSummary> sweeps;
  double sweep_tolerance = 0;  // mm: the band asked of each sub-step
  double sweep_seconds = 0;
};

// Cuts r.simultaneous from r.result (simultaneous.cpp): each move sub-stepped so that its band
// stays within a tenth of the dexel spacing (or the sub-step cap, with a warning), its sweeps
// subtracted ray by ray; fills r.sweeps and the result's dexel volume. `checked` (check): the
// rapids among them are removed last, in program order, each first measured against r.result (the
// stock less every other cut before it and the later feeds': a subset of what stood when it ran)
// and listed in r.rapid_cuts where its cutter meets that material.
void cut_simultaneous(const SimulateOptions& options, SimulationResult& r, bool checked);
// Between consecutive moves `before` and `after` of a run with kinematics: when the rotaries
// turned in between (a G0 with rotary words in raw form: the interpreter emits no move for the
// turn and keeps the linear axes' machine coordinates) and `after` does not come from far along
// the tool (TCP, DWO and tilted-plane indexing leave the tool far), the turn as a rapid joints
// move in r.turning_rapids, at `after`'s line.
void note_turning_rapid(const gcode::Move& before, const gcode::Move& after, SimulationResult& r);
// check (RapidCheck::in_program_order): each turning rapid whose cutter, over its poses, meets
// material of the final result (so surely material at the time of the turn) is a rapid cut, its
// depth the deepest the cutter reaches into that material, at poses no cutter point moves more
// than half a spacing between (so a cut of a spacing or more is not missed).
void check_turning_rapids(SimulationResult& r);
// How near a simultaneous move of r.simultaneous passes to `points` (simultaneous.cpp), for
// check's gouge and excess attribution: `gap` bounds from below the least signed distance of a
// point to the cutter over the move's poses (≤ 0: the cutter reached it), within `precision`
// (the poses are sampled densely enough that the distance between samples cannot drop by more).
// `valid` is false for a move with no cutter (before any tool).
struct SimultaneousReach {
  bool valid = false;
  double gap = 0;
};
SimultaneousReach simultaneous_reach(const SimulationResult& r, const gcode::Move& m,
                                     std::span<const Vec3> points, double precision);
// The JSON of r.sweeps for the report and `--certify`.
Json sweeps_json(const SimulationResult& r);

// A rapid deeper than this below the material is reported (mm): well above the rounding of float
// heights, well below any real collision.
constexpr double kRapidTolerance = 0.005;

// Runs the pipeline. Throws InputError (exit status 2) for bad input, including an output path of
// `request` that cannot be written or names an input; writes --dump-zmaps if asked.
SimulationResult simulate_program(const SimulateOptions& options, Progress& progress,
                                  const PipelineRequest& request = {});

// Bytes at refine_steep_cells's peak for `cells` fine cells over maps with `rows` cell rows in
// all, while it holds `moves` moves of one direction, each listed in about `bands_per_move` of
// its row bands: per cell the sub-heights, index and highest sub-point being built (108 bytes,
// the index up to twice over while it grows), the sorted copy set_fine_cells makes of both
// (108), and each move as a CutMove and its places in the bands.
double fine_cell_bytes(double cells, double rows, double moves, double bands_per_move);

std::string axis_label(const Vec3& axis);
// "X 612.5 mm, past the travel's end 600" / "A -130°, past its limit -120".
std::string travel_text(const TravelFinding& finding);

// A rapid into the stock as simulate's and check's reports list it (`files`:
// SimulationResult::files).
Json rapid_finding_json(const RapidFinding& finding, const std::vector<std::string>& files);

}  // namespace tridex::cli
