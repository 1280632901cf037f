// tridex embedded — a session: a stock and a tool table, a program fed in pieces as a controller or
// a CAM system produces it, and questions about the stock as it stands (docs/embedding.md).
//
// Moves are milled into one live Z-map per spindle direction as they are read (Step 1 of Inui,
// Chen and Umezu, CAD&A 19(4) 2022, §3, incrementally: a Z-map's milling is a minimum over the
// moves, so pieces give the same heights as the whole program). The solid (Steps 2-3) is brought
// up to date when a question needs it, only where the pieces since changed a map (SolidCache),
// and its surface made again: the same stages as `tridex simulate`
// (tools/cli/pipeline/pipeline.cpp), so the session's solid equals simulate's on the same
// program, stock, tools and --dexel-cell.
#pragma once

#include <cstddef>
#include <filesystem>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <string_view>
#include <vector>

#include "inputs/program_input.hpp"
#include "solid_cache.hpp"
#include "tridex/cutter.hpp"
#include "tridex/dexel.hpp"
#include "tridex/gcode/grouping.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "tridex/mill.hpp"
#include "tridex/mesh.hpp"
#include "tridex/parallel.hpp"
#include "tridex/zmap.hpp"

namespace tridex::embed {

struct SessionOptions {
  Aabb stock;              // the stock box, work frame (mm)
  std::string stock_file;  // or a closed STL as the stock (as --stock FILE.stl), bounds and all
  std::string tools;       // tool table file, as --tools (CAMotics JSON, Fusion, .tbl)
  std::string machine;     // as --machine: a bundled name or a machine file; empty: default
  double cell = 0;         // dexel spacing (mm), as --dexel-cell; 0: --dexel-res's default
  unsigned threads = 0;    // every call's threads, kept by the session (0: every hardware thread)
  std::string tool_units;  // as --tool-units: a .tbl's units (empty: the machine's)
  int initial_tool = -1;   // as --initial-tool (-1: the machine's)
  double arc_tolerance = 0.001;  // mm
  bool lenient = false;
};

class Session {
 public:
  // Throws cli::InputError (a bad stock, cell, tool table or machine).
  explicit Session(const SessionOptions& options);

  // Runs one more piece of the program and mills its moves. A piece that fails (GcodeError,
  // InputError: a tool missing from the table, a feed move with no tool) leaves the session as
  // it was, interpreter state included.
  void feed(std::string_view text);
  // feed(), and the mm³ that piece removed (the removed volume after it less before it: the
  // solid is brought up to date before and after, at the cost of two questions).
  double feed_measured(std::string_view text);
  // One straight move given directly, not as G-code (issue 38): from `start` to `end` (tool tip,
  // mm, the work frame: the part's coordinates, as the stock and a program's moves), cut by tool
  // `tool` of the table with its spindle along `axis` (tip towards holder; normalized here). A
  // rapid cuts as a feed does (simulate cuts rapids too). The interpreter's state is untouched.
  // Throws cli::InputError (a tool missing from the table, a zero or non-finite axis or point).
  void add_move(const Vec3& start, const Vec3& end, int tool, const Vec3& axis, bool rapid = false);

  // mm³ removed so far: the uncut stock's surface volume less the solid's, as simulate's
  // "removed_mm3" (docs/reports.md). A piece's removal is the difference across its feed().
  double removed_volume();
  // The depth (mm, along each move's spindle) the block's moves would cut into the stock as it
  // stands, every direction's cuts counted, without cutting it or changing the interpreter's
  // state; 0 when they cut nothing (within kCutTolerance).
  double would_cut(std::string_view block);
  // Whether a point (work frame) lies inside the stock as it stands (the solid's surface).
  bool inside(const Vec3& point);
  // The stock's extent along the line point + t·direction (t in mm along the unit direction):
  // the intervals [t_in, t_out] of the line inside the solid's surface, ascending. The height at
  // (x, y) is the last t_out from (x, y, 0) along +z; any axis and any line work alike.
  std::vector<std::pair<double, double>> extent(const Vec3& point, const Vec3& direction);
  const Mesh& mesh();
  void write_stl(const std::filesystem::path& path);

  const std::vector<std::string>& warnings() const { return warnings_; }
  long long moves() const { return moves_; }
  double dexel_spacing() const { return lattice_.spacing; }
  double zmap_cell() const { return zmap_cell_; }
  // The share of the result's rays the last question intersected again (1: all), for the tests.
  double last_rays_redone() const { return cache_.last_rays_redone(); }

  static constexpr double kCutTolerance = 0.005;  // mm: simulate's rapid tolerance

 private:
  std::vector<gcode::Move> run_piece(gcode::Interpreter& interpreter, std::string_view text);
  // Resolves the moves' tools (simulate's rules for moves before any tool change) and mills them;
  // changes nothing when that throws. `commit` then runs first (the interpreter's new state).
  template <class Commit>
  void cut_moves(std::vector<gcode::Move> moves, Commit&& commit);
  std::uint32_t cutter_for(int tool, const gcode::Move& m, bool add);
  void mill(const std::vector<gcode::Move>& moves);
  void ensure_solid();
  const ZMap& probe_map(const Vec3& axis);

  SessionOptions options_;
  // The session's threads, started once: every call's parallel work runs on them (UsePool).
  std::unique_ptr<detail::ThreadPool> pool_;
  cli::ProgramInput input_;
  gcode::Interpreter interpreter_;
  Aabb stock_;
  std::shared_ptr<const Mesh> stock_mesh_;  // a mesh stock, or null for the box
  double stock_volume_ = 0;
  DexelLattice lattice_;
  double zmap_cell_ = 0;
  std::vector<Cutter> cutters_;
  std::map<int, std::uint32_t> cutter_of_tool_;
  gcode::DirectionGrouper grouper_;
  std::vector<ZMap> maps_;                    // live, one per direction (grouper_'s groups)
  std::vector<std::vector<CutMove>> cuts_;    // every move of each direction (the fine cells)
  std::vector<gcode::Move> toolless_rapids_;  // before any tool, cut if the initial tool is
  bool initial_tool_cuts_ = false;
  long long moves_ = 0;
  std::vector<std::string> own_warnings_;  // the session's; warnings_ adds the interpreter's
  std::vector<std::string> warnings_;

  // The solid as it stands, kept until the next piece.
  SolidCache cache_;
  bool solid_valid_ = false;
  Mesh mesh_;
  std::optional<double> stock_surface_volume_;  // the uncut stock's surface, once measured
  double removed_ = 0;
  std::vector<std::pair<Vec3, ZMap>> probes_;  // the solid's top along each axis asked
};

}  // namespace tridex::embed
