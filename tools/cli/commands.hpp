// tridex command — the subcommands and their options (parsed by main.cpp with CLI11).
#pragma once

#include <optional>
#include <string>

namespace tridex::cli {

struct CommonOptions {
  std::string program;          // G-code file or CAMotics project
  double arc_tolerance = 0.001;  // mm
  bool lenient = false;
  bool progress = false;
  bool quiet = false;
};

struct ListOptions : CommonOptions {
  std::string output = "-";  // "-" for stdout
};

struct SimulateOptions : CommonOptions {
  std::string tools;            // --tools FILE (overrides a project's table)
  std::string stock;            // --stock (overrides a project's workpiece); empty: auto
  double zmap_cell = 0;         // 0: stock diagonal / 1000
  double dexel_cell = 0;        // 0: from dexel_res
  int dexel_res = 0;            // 0: the default
  std::string output, png, report, dump_zmaps;
  unsigned threads = 0;         // 0: every hardware thread
  std::string max_memory;       // empty: 80 % of RAM
};

constexpr int kDefaultDexelRes = 320;
constexpr double kDefaultZmapCellFraction = 1.0 / 1000;  // of the stock's diagonal

int run_moves(const ListOptions& options);
int run_groups(const ListOptions& options);
int run_simulate(const SimulateOptions& options);

}  // namespace tridex::cli
