// tridex command — `--html OUT.html` of simulate and check (issues 15 and 32): one self-contained
// page with the machined part in a three.js view (for check, the design as a translucent ghost
// over it on request), the toolpath with a slider over the program that plays the cut back (the
// stock still to be cut and the tool at each step: Playback below), the findings grouped by
// cause (choosing one turns the camera so that its spot is in view and lists its G-code lines)
// and the report's figures in the shop's words. docs/reports.md describes the page and its test
// contract (data-finding, window.tridexView). three.js and its
// OrbitControls (Debian's libjs-three, found by CMake) and the page template (html_report.html) are
// embedded in the command and inlined into every page, so the page opens offline and makes no
// request.
//
// Large results are made small enough to open quickly: the part is simplified with meshoptimizer
// (Kapoulkine's edge collapse under quadric error, meshopt_simplify) to a triangle budget, keeping
// every triangle that touches an out-of-tolerance vertex and the border around them, so the
// deviation colours stay where they were; the toolpath is thinned to what the page can show (runs
// of moves within a tolerance of one straight segment become that segment). Points are quantised
// to 16 bits over their box and stored base64.
#pragma once

#include <array>
#include <cstddef>
#include <cstdint>
#include <filesystem>
#include <map>
#include <span>
#include <string>
#include <vector>

#include "json_text.hpp"
#include "pipeline/pipeline.hpp"
#include "tridex/gcode/grouping.hpp"
#include "tridex/cutter.hpp"
#include "tridex/mesh.hpp"
#include "tridex/tool_body.hpp"

namespace tridex::cli {

struct HtmlLimits {
  std::size_t max_triangles = 250'000;  // shown of the part (a budget; see simplify_for_display)
  std::size_t max_design_triangles = 100'000;  // of check's design ghost (drawn translucent)
  std::size_t max_segments = 1'000'000;        // of the toolpath after thinning
  double path_tolerance = 1.0 / 4000;  // thinning, as a fraction of the toolpath's box diagonal
  std::uintmax_t max_source_bytes = 4 << 20;  // the whole program text is inlined up to this size
  // Beyond it, each file's text deflated in chunks of lines, up to this many bytes (base64) in all:
  // the paper-scale program's 144 MB of G-code take 34 MB.
  std::size_t max_compressed_source_bytes = std::size_t{48} << 20;
  std::size_t compressed_chunk_lines = 32768;
  int context = 3;  // neighbouring lines shown around a finding's line
  // Playback (the stock as it stands at the slider): cells of the stock's box, at most this many,
  // and of them at most max_playback_removed removed ones (coarser cells until both hold). Each
  // removed cell costs 2 bytes, each cell 1 or 2 bits: at most 0.6 MB of page (docs/reports.md).
  std::size_t max_playback_cells = 1 << 20;
  std::size_t max_playback_removed = 150'000;
  // The machine check's bodies drawn (the fixtures, and those of a listed finding): at most this
  // many triangles in all, each body's share by its size and at least min_machine_body_triangles
  // (simplify_for_display). A machine of 100 k triangles costs the page about 1 MB at most.
  std::size_t max_machine_triangles = 60'000;
  std::size_t min_machine_body_triangles = 500;
};

// check's machine check (issue 33): its bodies (fixtures, the machine's components, the tools'
// parts, each in its own coordinates) and, per finding of the report's machine.collisions and
// machine.near_misses (in their order), the pair's two bodies and their frames at the finding's
// pose (body coordinates to the work frame, where the page draws everything).
struct HtmlMachinePose {
  int body = -1;
  Frame frame;
};
struct HtmlMachine {
  std::vector<std::string> names, groups;  // groups: "fixture", "component", "tool"
  std::vector<const Mesh*> meshes;
  std::vector<std::array<HtmlMachinePose, 2>> collisions, near_misses;
};

struct HtmlPage {
  std::string title;
  Json report;                        // the report as --report writes it
  const Mesh* mesh = nullptr;         // the machined part; null or empty: none left
  std::span<const double> deviation;  // check: signed deviation per mesh vertex
  const Mesh* design = nullptr;       // check: the design, shown as a ghost on request
  const std::vector<gcode::MoveGroup>* groups = nullptr;
  std::span<const GroupRun> order;  // the groups' moves in program order (pipeline.hpp)
  std::vector<std::string> files;   // Move::file's table: the G-code files, listed
  // Playback and the tool drawn at the slider: the raw stock, the cutters and their shanks and
  // holders (parallel), and which cutter each tool number is. Absent: no playback, no tool drawn.
  const Stock* stock = nullptr;
  std::span<const Cutter> cutters;
  std::span<const ToolBody> bodies;
  const std::map<int, std::uint32_t>* cutter_of_tool = nullptr;
  const HtmlMachine* machine = nullptr;  // check with fixtures or machine components
};

// Writes the page atomically (output.hpp).
void write_html_report(const std::filesystem::path& path, const HtmlPage& page,
                       const HtmlLimits& limits = {});

// ---- the pieces, for the tests -------------------------------------------------------------

std::string base64(std::span<const std::uint8_t> bytes);

// The page's data (the JSON inside its tridex-data block).
Json html_page_data(const HtmlPage& page, const HtmlLimits& limits);

struct DisplayMesh {
  std::vector<glm::vec3> positions;
  std::vector<std::uint32_t> indices;  // three per triangle
  std::vector<float> deviation;        // per position when the input had one
};

// At most `max_triangles`: meshopt_simplify with the out-of-tolerance triangles and the border
// around them locked (everything free only if those alone take half the budget), first within an
// error of 5e-4 of the mesh's extent (merging flat faces), then with rising bounds until the
// budget is met. Kept vertices keep their positions and deviations exactly.
DisplayMesh simplify_for_display(const Mesh& mesh, std::span<const double> deviation,
                                 double gouge_tol, double excess_tol, std::size_t max_triangles);

struct DisplayPath {
  std::vector<glm::vec3> ends;       // two per segment, in program (execution) order
  std::vector<std::uint32_t> stops;  // per segment: the last program stop it stands for
  std::vector<std::uint16_t> tools;  // per segment
  std::vector<std::uint8_t> flags;   // per segment: direction (group) index | 128 for rapids
  // The program's stops in execution order: a stop is a move whose (file, line) differs from the
  // move before it. Stored as runs (file, first line, count) of stops in one file on consecutive
  // lines (a straight program is one run a file, a loop repeats its runs).
  std::vector<std::uint32_t> stop_runs;
  std::size_t stop_count = 0;
  std::size_t moves = 0;
  double tolerance = 0;  // mm, what the thinning used
};

// The moves of all groups in program order (`order`; empty: each group in turn), each run of moves
// of one kind, tool and direction that joins end to start and stays within `tolerance` (mm) of the
// straight segment from its first start to its last end drawn as that segment, carrying the run's
// last stop. Positions "far along the tool axis" (tridex's stand-in for home returns) are left out
// of the drawing; their lines are still stops.
DisplayPath thin_toolpath(const std::vector<gcode::MoveGroup>& groups,
                          std::span<const GroupRun> order, double tolerance);

// The in-process stock for playback: cells of `cell` mm over the stock's box, each either outside
// the stock, inside the final part (the result mesh), or removed at a program stop (the stop index
// of thin_toolpath's slider). A cell's removal stop is the first stop whose move lowers, in some
// direction's frame, the swept cutter's lowest point (detail::MoveGeometry, as the Z-maps are
// milled) below the cell's centre on the direction's column of `cell` mm through it; a cell no
// move reaches that way (rounding at the part's skin) is removed at the last stop, so that the
// last stop shows the final part exactly and stop 0 the raw stock less what its moves cut.
struct Playback {
  Aabb box;  // the cells' box: the stock's bounds
  std::array<int, 3> n{};
  double cell = 0;
  std::vector<std::uint8_t> stock_mask;   // bit per cell (x fastest, then y, z); empty: all stock
  std::vector<std::uint8_t> part_mask;    // bit per cell: inside the result mesh
  std::vector<std::uint32_t> removed_at;  // per stock cell not in the part, in cell order
  std::size_t stop_count = 0;
};
Playback playback_cells(const HtmlPage& page, double cell);

}  // namespace tridex::cli
