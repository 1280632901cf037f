// tridex command — plausibility warnings (issue 31): setups that run without an error but are
// most likely not what the user meant, each warning naming what to give to silence it. A new
// user otherwise gets a "pass" for a wrong setup: an inch program read in millimetres, a stock
// made up from the moves, a tool table read in the wrong units, a start tool assumed.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include "commands.hpp"
#include "pipeline/pipeline.hpp"

namespace tridex::cli {

// Whether a G-code file has a G20 or G21 word outside comments (parentheses, ';'): a lexical
// scan, G020 and "G 21" included; it stops at the first one.
bool program_sets_units(const std::filesystem::path& file);

// The warnings about the setup, appended to r.warnings, in this order:
//   - no G20/G21 in the program and no machine file "units": the units it was read in, and the
//     extent of its cutting moves against the stock's (an inch program read in mm is tiny);
//   - the stock made up from the moves (--stock auto, the default): its box;
//   - a LinuxCNC .tbl whose units nothing stated ("linear_units", --tool-units), or one read in
//     inches whose diameters look metric (any above 2 in);
//   - a tool wider than the stock, or than twice the moves' extent.
// `cutting` is the box of the cutting moves (work frame).
void warn_implausible_setup(const SimulateOptions& options, const Aabb& cutting,
                            SimulationResult& r);

}  // namespace tridex::cli
