// tridex command — the subcommands and their options (parsed by main.cpp with CLI11).
#pragma once

#include <optional>
#include <string>
#include <vector>

namespace tridex::cli {

// Above the blocks of all but the largest real programs (a 20-million-line file is hundreds of MB
// of G-code), low enough that a few bytes of nested M98 ... L9999 (10^8 blocks and more) stop
// with a message instead of running on without bound.
constexpr long long kDefaultMaxBlocks = 20'000'000;

// Moves (chords of arcs and cycles included) a run may generate: one block can expand into
// millions of chords, so --max-blocks alone does not bound the work of a loop of arcs. Far above
// real programs (a 20-million-line file of moves), low enough that such a loop stops in minutes.
constexpr long long kDefaultMaxMoves = 200'000'000;

struct CommonOptions {
  std::string program;           // G-code file or CAMotics project
  double arc_tolerance = 0.001;  // mm
  bool lenient = false;
  std::string block_delete = "on";       // --block-delete on|off: the operator's switch
  std::string machine;                   // --machine FILE|NAME (empty: the default machine)
  std::vector<std::string> subprograms;  // --subprograms DIR (repeatable)
  std::string tools;       // --tools FILE (overrides a project's table; G41/G42 D read it)
  std::string tool_units;  // --tool-units mm|inch: a .tbl's units (empty: the machine's)
  int initial_tool = -1;   // --initial-tool N (-1: the machine file's, else 1 for a project)
  bool progress = false;
  bool quiet = false;
  long long max_blocks = kDefaultMaxBlocks;  // --max-blocks: executed blocks before exit status 2
  long long max_moves = kDefaultMaxMoves;    // --max-moves: generated moves before exit status 2
  std::string max_memory;  // --max-memory (simulate, check, groups); empty: 80 % of RAM
};

struct ListOptions : CommonOptions {
  std::string output = "-";  // "-" for stdout
  std::string diff;          // moves --diff B: the moves aligned with B's (issue 39)
};

struct SimulateOptions : CommonOptions {
  std::string stock;      // --stock (overrides a project's workpiece); empty: auto
  double zmap_cell = 0;   // 0: stock diagonal / 1000, at most half the dexel spacing
  double dexel_cell = 0;  // 0: from dexel_res
  int dexel_res = 0;      // 0: the default
  std::string output, png, report, dump_zmaps;
  std::string html;                    // --html OUT.html: the interactive report (html_report.hpp)
  unsigned threads = 0;                // 0: every hardware thread
  std::string zmap_backend = "cpu";    // --zmap-backend: cpu | gl (tools/backends)
  std::string dexel_backend = "scan";  // --dexel-backend: scan | tree | embree
  bool certify = false;  // --certify: print the sweeps' worst band e per tool (simultaneous moves)
};

// A small safety distance (mm): shanks and holders closer than this to the stock are near misses.
constexpr double kDefaultClearance = 1.0;

// `check`: simulate's options (--report and --png are the check's own report and picture; -o still
// writes the machined solid) and the design to compare with.
struct CheckOptions : SimulateOptions {
  std::string design;                    // --design PART.stl (closed)
  double tolerance = 0;                  // --tolerance: both tolerances; 0: kShopTolerance
  double gouge_tol = 0;                  // --gouge-tol (overrides --tolerance)
  double excess_tol = 0;                 // --excess-tol (overrides --tolerance)
  std::string ply;                       // --ply OUT.ply: the machined mesh coloured by deviation
  std::string envelope;                  // --envelope box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX
  double clearance = kDefaultClearance;  // --clearance: near misses of shanks and holders, mm
  double allowance = 0;                  // --allowance: stock to leave on the design, mm (issue 39)
  std::vector<std::string> fixtures;     // --fixture FILE.stl (repeatable; machine_run.hpp)
  // --lattice-only: a --dexel-res/--dexel-cell that cannot resolve the gouge tolerance is used
  // anyway, the verdict holding on the lattice's samples (pipeline/resolution.hpp)
  bool lattice_only = false;
};

// `diff` (issue 39): simulate's options for both programs (PROGRAM is A), B's solid compared
// with A's on A's stock and lattice.
struct DiffOptions : SimulateOptions {
  std::string program_b;
  double tolerance = 0;  // --tolerance, mm; 0: half the dexel spacing
};

// `regress` (issue 39): PROGRAM is a folder of programs or one program; simulate's options are
// every program's defaults (a NAME.tridex.json sidecar overrides them for NAME.nc).
struct RegressOptions : SimulateOptions {
  std::string baseline;  // --baseline BASE: NAME.dexel and NAME.json per program
  bool bless = false;    // --bless: store the results as the new baselines
  double tolerance = 0;  // --tolerance, mm; 0: half the dexel spacing
};

// `lint`: the post lint of a program (checks/lint.hpp).
struct LintOptions : CommonOptions {
  std::string report;  // --report FILE: the findings as JSON
};

// check's default verdict tolerance, mm: a shop's usual ±0.02 mm on a milled surface (ISO 2768-f
// allows ±0.05 mm on features up to 6 mm; a finish pass is held well inside it).
constexpr double kShopTolerance = 0.02;

constexpr int kDefaultDexelRes = 320;
constexpr double kDefaultZmapCellFraction = 1.0 / 1000;  // of the stock's diagonal
constexpr double kDefaultZmapCellOfSpacing = 0.5;        // at most this many dexel spacings

int run_moves(const ListOptions& options);
int run_groups(const ListOptions& options);
int run_simulate(const SimulateOptions& options);
int run_check(const CheckOptions& options);
int run_diff(const DiffOptions& options);
int run_moves_diff(const ListOptions& options);
int run_lint(const LintOptions& options);
int run_regress(const RegressOptions& options);

}  // namespace tridex::cli
