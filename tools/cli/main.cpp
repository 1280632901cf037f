// tridex — the command: `simulate`, `check`, `moves`, `groups` (see README.md for the full story).
//
// Exit status: 0 on success, 2 for bad input (program, tool table, stock, options), 1 for
// anything else. Program errors are printed as file:line:col: message.
#include <CLI/CLI.hpp>

#include <cmath>
#include <cstdio>
#include <iostream>
#include <new>

#include "commands.hpp"
#include "errors.hpp"
#include "outputs/output.hpp"
#include "tridex/gcode/diagnostic.hpp"
#include "tridex/gcode/machine.hpp"

#ifndef TRIDEX_VERSION
#define TRIDEX_VERSION "unknown"
#endif

namespace {

using namespace tridex::cli;

// CLI11's PositiveNumber lets "nan" and "inf" through; every length here must be finite, and at
// most a kilometre (kMaxLengthOption): past any machine, and far from overflow in the grids and
// distances computed from it (--zmap-cell 1e300 made the Z-map's heights infinite).
constexpr double kMaxLengthOption = 1e6;
const CLI::Validator kFinitePositive(
    [](std::string& text) -> std::string {
      double value = 0;
      if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value) || !(value > 0) ||
          value > kMaxLengthOption)
        return "must be a finite positive number of mm up to 1e6, got \"" + text + "\"";
      return {};
    },
    "POSITIVE");

// A distance that may be zero (a clearance).
const CLI::Validator kFiniteNonNegative(
    [](std::string& text) -> std::string {
      double value = 0;
      if (!CLI::detail::lexical_cast(text, value) || !std::isfinite(value) || !(value >= 0) ||
          value > kMaxLengthOption)
        return "must be a finite number of mm from 0 to 1e6, got \"" + text + "\"";
      return {};
    },
    "NONNEGATIVE");

// An option given with an empty value (`--stock ''`, `-o ""`) is a mistake, not the default.
const CLI::Validator kNotEmpty(
    [](std::string& text) -> std::string {
      return text.empty() ? "must not be empty" : std::string();
    },
    "");

void add_common(CLI::App& command, CommonOptions& options) {
  command
      .add_option("PROGRAM", options.program,
                  "G-code file (.nc, .ngc, .tap, .gcode, any name) or CAMotics project (.camotics)")
      ->required()
      ->check(kNotEmpty);
  command
      .add_option("--arc-tolerance", options.arc_tolerance,
                  "largest chord error of linearised arcs, mm (default 0.001)")
      ->check(kFinitePositive);
  command
      .add_option("--max-blocks", options.max_blocks,
                  "stop with exit status 2 after this many executed blocks (bounds M98 ... L "
                  "loops; default " +
                      std::to_string(kDefaultMaxBlocks) + ")")
      ->check(CLI::PositiveNumber);
  command
      .add_option("--max-moves", options.max_moves,
                  "stop with exit status 2 after this many generated moves, arc chords included "
                  "(bounds loops of arcs; default " +
                      std::to_string(kDefaultMaxMoves) + ")")
      ->check(CLI::PositiveNumber);
  command.add_flag("--lenient", options.lenient,
                   "unsupported G-code words become warnings and are skipped");
  command
      .add_option("--block-delete", options.block_delete,
                  "the control's block delete switch: on skips the blocks that start with '/', off "
                  "runs them\n"
                  "(default on)")
      ->check(CLI::IsMember({"on", "off"}));
  command
      .add_option("--machine", options.machine,
                  std::string("machine file (JSON) or bundled machine: ") +
                      tridex::gcode::bundled_machine_names() + " (README: Machine files)")
      ->check(kNotEmpty);
  command
      .add_option("--subprograms", options.subprograms,
                  "folder of subprogram files (O9810.nc, name.ngc) that M98/G65/o-call may "
                  "call (repeatable)")
      ->check(kNotEmpty);
  command
      .add_option("--tools", options.tools,
                  "tool table, JSON in the CAMotics schema, a Fusion tool library or a LinuxCNC "
                  ".tbl (overrides a project's\n"
                  "tools; G41/G42 D offset by half a tool's diameter, G43 H by its tool length)")
      ->check(kNotEmpty);
  command
      .add_option("--tool-units", options.tool_units,
                  "units of a LinuxCNC .tbl tool table, mm or inch (default: the machine file's\n"
                  "\"linear_units\", else inch as rs274 reads it, with a warning)")
      ->check(CLI::IsMember({"mm", "inch"}));
  command
      .add_option(
          "--initial-tool", options.initial_tool,
          "the tool in the spindle when the program starts: moves before the first tool\n"
          "change cut with it (0: none; default: the machine file's \"initial_tool\", else\n"
          "1 for a CAMotics project, as CAMotics runs it, else none)")
      ->check(CLI::Range(0, 1'000'000'000));
  command.add_flag("--progress", options.progress,
                   "show progress on stderr even when it is not a terminal");
  command.add_flag("-q,--quiet", options.quiet, "print nothing but errors")->excludes("--progress");
}

void add_max_memory(CLI::App& command, std::string& max_memory) {
  command
      .add_option(
          "--max-memory", max_memory,
          "refuse a run whose estimated memory (the moves it keeps, the Z-maps, dexels and mesh)\n"
          "exceeds this (e.g. 4G; default 80 % of RAM)")
      ->check(kNotEmpty);
}

// simulate's options, shared by check.
void add_simulate(CLI::App& command, SimulateOptions& options) {
  add_common(command, options);
  command
      .add_option("--stock", options.stock,
                  "box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX | FILE.stl | auto[:MARGIN] (default auto: the "
                  "box around\n"
                  "the cutting moves plus MARGIN mm, or 5 % of each side without one)")
      ->check(kNotEmpty);
  command
      .add_option(
          "--zmap-cell", options.zmap_cell,
          "Z-map grid spacing, mm (default: stock diagonal / 1000, at most half the dexel spacing)")
      ->check(kFinitePositive);
  auto* dexel_cell =
      command.add_option("--dexel-cell", options.dexel_cell, "triple-dexel spacing, mm")
          ->check(kFinitePositive);
  command
      .add_option("--dexel-res", options.dexel_res,
                  "triple-dexel cells along the stock's longest side (default " +
                      std::to_string(kDefaultDexelRes) +
                      ": the bundled example in seconds on 2 cores)")
      ->check(CLI::Range(1, 1 << 20))
      ->excludes(dexel_cell);
  command
      .add_option("--dump-zmaps", options.dump_zmaps,
                  "write each direction's milled Z-map to DIR as STL and as a height picture")
      ->check(kNotEmpty);
  command
      .add_option("--threads", options.threads, "worker threads (default: every hardware thread)")
      ->check(CLI::Range(0u, 4096u));
  command.add_flag("--certify", options.certify,
                   "print, per tool, the simultaneous 5-axis moves and the worst band e (mm) "
                   "their sweeps\nstay within");
  command
      .add_option("--zmap-backend", options.zmap_backend,
                  "Step 1: cpu (the kernel's exact milling, default) or gl (the swept cutters "
                  "drawn into an\n"
                  "OSMesa float depth buffer)")
      ->check(CLI::IsMember({"cpu", "gl"}));
  command
      .add_option(
          "--dexel-backend", options.dexel_backend,
          "Steps 2-3: scan (scan conversion onto the ray grids, default), tree (the paper's grid\n"
          "AABB tree) or embree (Embree 3 ray casting)")
      ->check(CLI::IsMember({"scan", "tree", "embree"}));
  command
      .add_option("--html", options.html,
                  "write an interactive HTML report: the part in 3D, the toolpath, the findings "
                  "and the figures\n"
                  "(one file that opens offline in a browser)")
      ->check(kNotEmpty);
  add_max_memory(command, options.max_memory);
}

// issue 39: `diff` (simulate's options for both programs) and `lint`.
// issue 39 also adds `moves --diff B`.
std::pair<CLI::App*, CLI::App*> add_diff_and_lint(CLI::App& app, DiffOptions& diff,
                                                  LintOptions& lint, CLI::App& mov,
                                                  ListOptions& moves) {
  mov.add_option("--diff", moves.diff,
                 "align the moves with program B's by geometry and order: one JSON line per "
                 "change\n(moved, added, removed, changed) and a summary; exit status 3 on any")
      ->check(kNotEmpty);

  CLI::App* dif = app.add_subcommand(
      "diff",
      "simulate two programs on A's stock, lattice and tools and compare the solids: regions that\n"
      "differ with their lines in each program, and the post lint of B; exit status 3 when they\n"
      "differ");
  add_simulate(*dif, diff);
  dif->add_option("PROGRAM_B", diff.program_b, "the program to compare with PROGRAM")
      ->required()
      ->check(kNotEmpty);
  dif->add_option("--tolerance", diff.tolerance,
                  "a span of material longer than this along a dexel ray is a difference, mm\n"
                  "(default: half the dexel spacing)")
      ->check(kFinitePositive);
  dif->add_option("--report", diff.report, "write the JSON report of the comparison")
      ->check(kNotEmpty);
  dif->add_option("--png", diff.png,
                  "write a picture of B's result coloured where it differs from A's")
      ->check(kNotEmpty);
  CLI::App* lnt = app.add_subcommand(
      "lint",
      "post-processor mistakes at file:line: units changed mid-program, G43 H missing or not\n"
      "the tool's, integer coordinates, arc centres of the other G90.1/G91.1 mode; exit status 3\n"
      "when any is found");
  add_common(*lnt, lint);
  lnt->add_option("--report", lint.report, "write the findings as JSON")->check(kNotEmpty);
  return {dif, lnt};
}

// issue 39: `regress` (a regression folder).
CLI::App* add_regress(CLI::App& app, RegressOptions& regress) {
  CLI::App* reg = app.add_subcommand(
      "regress",
      "run every program of a folder (or one program) and compare each solid with its stored\n"
      "baseline; --bless stores new baselines; exit status 3 when any changed or is new");
  add_simulate(*reg, regress);
  reg->add_option("--baseline", regress.baseline,
                  "the folder of baselines (NAME.dexel and NAME.json per program)")
      ->required()
      ->check(kNotEmpty);
  reg->add_flag("--bless", regress.bless, "store the results as the new baselines");
  reg->add_option("--tolerance", regress.tolerance,
                  "a span of material longer than this along a dexel ray is a difference, mm\n"
                  "(default: half the dexel spacing)")
      ->check(kFinitePositive);
  reg->add_option("--report", regress.report, "write the JSON report of every program")
      ->check(kNotEmpty);
  return reg;
}

// check's options for what it looks for beyond the design: the envelope, the shank's and the
// holder's clearance, the roughing allowance, the fixtures.
void add_check_findings(CLI::App& chk, CheckOptions& check) {
  chk.add_option(
         "--envelope", check.envelope,
         "box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX: every move whose tool tip ends outside is a finding")
      ->check(kNotEmpty);
  chk.add_option(
         "--clearance", check.clearance,
         "report moves whose shank or holder comes closer than this to the stock, mm (0: none)")
      ->check(kFiniteNonNegative);
  chk.add_option("--allowance", check.allowance,
                 "stock to leave on the design, mm: the surface must stand this far outside it,\n"
                 "within the tolerances (a roughing program; default 0)")
      ->check(kFiniteNonNegative);
  chk.add_option("--fixture", check.fixtures,
                 "a fixture (vise, clamp) as STL in the work frame, never cut: the tool and the "
                 "machine's parts are\nchecked against it along every move (repeatable)")
      ->check(kNotEmpty);
}

}  // namespace

int main(int argc, char** argv) {
  remove_temporaries_on_signals();
  CLI::App app{
      "tridex: simulate 3+2-axis milling (G68.2 tilted planes) from a G-code program to a\n"
      "watertight STL, a picture and a report. Method: Inui, Chen and Umezu, CAD&A 19(4) 2022.",
      "tridex"};
  app.set_version_flag("--version", "tridex " TRIDEX_VERSION);
  app.require_subcommand(1);
  app.footer(
      "Exit status: 0 success, 2 bad input (program, tool table, stock, options), 1 other "
      "failure;\n"
      "`check` exits 3 when it finds a gouge, excess, a rapid into material, a move outside the "
      "envelope\n"
      "or a shank or holder in the material.\n"
      "Run `tridex COMMAND --help` for a command's options.");

  SimulateOptions simulate;
  CLI::App* sim = app.add_subcommand(
      "simulate", "mill the program into its stock and write the machined solid");
  add_simulate(*sim, simulate);
  sim->add_option("-o,--output", simulate.output, "write the result as binary STL")
      ->check(kNotEmpty);
  sim->add_option("--png", simulate.png, "write a shaded picture of the result (off-screen OSMesa)")
      ->check(kNotEmpty);
  sim->add_option("--report", simulate.report, "write the JSON report")->check(kNotEmpty);

  CheckOptions check;
  CLI::App* chk = app.add_subcommand(
      "check",
      "compare the machined result with a design: gouges, excess, rapids into stock, envelope,\n"
      "shank and holder collisions;\n"
      "exit status 3 when anything is found");
  add_simulate(*chk, check);
  chk->add_option("--design", check.design, "the designed part, a closed STL")
      ->required()
      ->check(kNotEmpty);
  auto* tolerance = chk->add_option("--tolerance", check.tolerance,
                                    "gouge and excess tolerance, mm (default 0.02)")
                        ->check(kFinitePositive);
  chk->add_option("--gouge-tol", check.gouge_tol,
                  "material removed inside the design beyond this is a gouge, mm")
      ->check(kFinitePositive)
      ->excludes(tolerance);
  chk->add_option("--excess-tol", check.excess_tol,
                  "material left outside the design beyond this is excess, mm")
      ->check(kFinitePositive)
      ->excludes(tolerance);
  chk->add_flag(
      "--lattice-only", check.lattice_only,
      "with --dexel-res/--dexel-cell: compare on the lattice's samples even where it "
      "cannot resolve\nthe gouge tolerance (a design made by tridex on the same lattice)");
  add_check_findings(*chk, check);
  chk->add_option("-o,--output", check.output, "write the machined result as binary STL")
      ->check(kNotEmpty);
  chk->add_option("--report", check.report, "write the JSON report of the check")->check(kNotEmpty);
  chk->add_option("--png", check.png, "write a picture coloured by deviation, with a legend")
      ->check(kNotEmpty);
  chk->add_option("--ply", check.ply,
                  "write the machined mesh as PLY with per-vertex colour by deviation")
      ->check(kNotEmpty);

  ListOptions moves;
  CLI::App* mov =
      app.add_subcommand("moves", "print the interpreted moves as JSON Lines, one object per move");
  add_common(*mov, moves);
  mov->add_option("-o,--output", moves.output, "write to a file instead of stdout")
      ->check(kNotEmpty);

  ListOptions groups;
  CLI::App* grp = app.add_subcommand("groups", "print the spindle-direction groups as JSON");
  add_common(*grp, groups);
  add_max_memory(*grp, groups.max_memory);
  grp->add_option("-o,--output", groups.output, "write to a file instead of stdout")
      ->check(kNotEmpty);

  DiffOptions diff;
  LintOptions lint;
  const auto [dif, lnt] = add_diff_and_lint(app, diff, lint, *mov, moves);
  RegressOptions regress;
  CLI::App* reg = add_regress(app, regress);

  try {
    app.parse(argc, argv);
  } catch (const CLI::ParseError& e) {
    if (e.get_exit_code() == 0) return app.exit(e);  // --help, --version
    std::cerr << "tridex: " << terminal_safe(e.what())
              << "\n(run `tridex --help` or `tridex COMMAND --help`)\n";
    return kBadInput;
  }

  try {
    if (sim->parsed()) return run_simulate(simulate);
    if (chk->parsed()) return run_check(check);
    if (mov->parsed()) return run_moves(moves);
    if (grp->parsed()) return run_groups(groups);
    if (dif->parsed()) return run_diff(diff);
    if (lnt->parsed()) return run_lint(lint);
    if (reg->parsed()) return run_regress(regress);
  } catch (const tridex::gcode::GcodeError& e) {
    std::cerr << terminal_safe(e.what()) << '\n';
    return kBadInput;
  } catch (const InputError& e) {
    std::cerr << "tridex: " << terminal_safe(e.what()) << '\n';
    return kBadInput;
  } catch (const std::bad_alloc&) {
    std::cerr << "tridex: out of memory (lower the resolution or --max-memory)\n";
    return kFailure;
  } catch (const std::exception& e) {
    std::cerr << "tridex: " << terminal_safe(e.what()) << '\n';
    return kFailure;
  }
  return kFailure;
}
