#include "pipeline/plausibility.hpp"

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <fstream>

#include "inputs/tool_table.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

std::string size_text(const Vec3& size) {
  char text[96];
  std::snprintf(text, sizeof text, "%.3g x %.3g x %.3g mm", size.x, size.y, size.z);
  return text;
}

std::string box_text(const Aabb& box) {
  char text[160];
  std::snprintf(text, sizeof text, "%g,%g,%g,%g,%g,%g", box.min.x, box.min.y, box.min.z, box.max.x,
                box.max.y, box.max.z);
  return text;
}

bool stock_is_automatic(const SimulationResult& r) {
  return r.stock.description.contains("kind") && r.stock.description["kind"] == "auto";
}

void warn_units(const Aabb& cutting, SimulationResult& r) {
  const gcode::MachineConfig& machine = r.input.machine;
  if (machine.units_stated) return;
  for (const fs::path& file : r.input.files)
    if (program_sets_units(file)) return;
  std::string text = r.input.program.string() +
                     ": the program sets no units (no G20 or G21): " + "read in " +
                     (machine.inch_at_start ? "inches" : "mm") + ", the machine's units at start";
  if (!cutting.empty() && !stock_is_automatic(r)) {
    const Vec3 moves = cutting.size(), stock = r.stock.box.size();
    text += "; its cutting moves span " + size_text(moves) + " against a " + size_text(stock) +
            " stock";
    const double reach = std::max(moves.x, moves.y), width = std::max(stock.x, stock.y);
    if (!machine.inch_at_start && reach * 10 < width)
      text += " (an inch program read in mm?)";
    else if (machine.inch_at_start && reach > 5 * width)
      text += " (a metric program read in inches?)";
  }
  r.warnings.push_back(text +
                       "; give G20 or G21 in the program, or \"units\" in a machine file, to say");
}

void warn_automatic_stock(SimulationResult& r) {
  if (!stock_is_automatic(r)) return;
  r.warnings.push_back("no stock given: a box made up from the cutting moves, " +
                       box_text(r.stock.box) + " (" + size_text(r.stock.box.size()) +
                       "); give --stock box:XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX (or an STL, or a " +
                       "project's workpiece) to say what the part is cut from");
}

// A .tbl's units: LinuxCNC reads it in the machine's units ([TRAJ]LINEAR_UNITS), which tridex
// cannot know unless told.
void warn_tbl_units(const SimulateOptions& options, SimulationResult& r) {
  if (options.tools.empty() || ascii_lower(fs::path(options.tools).extension().string()) != ".tbl")
    return;
  const gcode::MachineConfig& machine = r.input.machine;
  const double unit = machine.tool_table_in_inches ? 25.4 : 1.0;
  const char* units = machine.tool_table_in_inches ? "inches" : "mm";
  if (!machine.linear_units_stated)
    r.warnings.push_back(options.tools + ": nothing states the tool table's units: read in " +
                         units + " (as LinuxCNC's rs274 reads a .tbl with no INI); give " +
                         "--tool-units mm|inch or \"linear_units\" in a machine file to say");
  if (!machine.tool_table_in_inches || !r.input.tools) return;
  std::string metric;
  for (const auto& [number, spec] : r.input.tools->tools())
    if (spec.diameter_mm / unit > 2) {
      char text[96];
      std::snprintf(text, sizeof text, "%sT%d D%g (%.4g mm)", metric.empty() ? "" : ", ", number,
                    spec.diameter_mm / unit, spec.diameter_mm);
      metric += text;
    }
  if (!metric.empty())
    r.warnings.push_back(options.tools + ": read in inches, its diameters look metric (" + metric +
                         "); give --tool-units mm or \"linear_units\": \"mm\" in a machine file " +
                         "if the table is in mm");
}

// A tool out of proportion: wider than the stock across the spindle, or than twice the extent
// of the moves.
void warn_tool_sizes(const Aabb& cutting, SimulationResult& r) {
  const Vec3 stock = r.stock.box.size(), moves = cutting.empty() ? Vec3(0) : cutting.size();
  const double stock_width = std::max({stock.x, stock.y, stock.z});
  const double reach = std::max(moves.x, moves.y);
  for (const auto& [tool, index] : r.cutter_of_tool) {
    const double diameter = 2 * r.cutters[index].radius();
    std::string against;
    // A stock given bounds the work; one made up from the moves says nothing, so the moves do.
    if (!stock_is_automatic(r) && diameter > stock_width)
      against = "wider than the " + size_text(stock) + " stock";
    else if (stock_is_automatic(r) && reach > 0 && diameter > 2 * reach)
      against = "more than twice the " + size_text(moves) + " its moves span";
    if (against.empty()) continue;
    char text[64];
    std::snprintf(text, sizeof text, "tool %d is a %.4g mm cutter, ", tool, diameter);
    r.warnings.push_back(text + against +
                         ": check the tool table's units (--tool-units, \"units\" of a JSON "
                         "table) and its diameters");
  }
}

}  // namespace

bool program_sets_units(const fs::path& file) {
  std::ifstream in(file, std::ios::binary);
  std::string line;
  while (std::getline(in, line)) {
    int depth = 0;
    std::string words;  // the line without comments and blanks, upper case
    for (char c : line) {
      if (c == ';' && depth == 0) break;
      if (c == '(') ++depth;
      if (depth == 0 && !std::isspace(static_cast<unsigned char>(c)))
        words += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
      if (c == ')' && depth > 0) --depth;
    }
    for (std::size_t g = words.find('G'); g != std::string::npos; g = words.find('G', g + 1)) {
      std::size_t k = g + 1;
      while (k < words.size() && words[k] == '0') ++k;
      const bool twenty =
          k + 2 <= words.size() && words[k] == '2' && (words[k + 1] == '0' || words[k + 1] == '1');
      const bool ends =
          k + 2 == words.size() ||
          (!std::isdigit(static_cast<unsigned char>(words[k + 2])) && words[k + 2] != '.');
      if (twenty && ends) return true;
    }
  }
  return false;
}

void warn_implausible_setup(const SimulateOptions& options, const Aabb& cutting,
                            SimulationResult& r) {
  warn_units(cutting, r);
  warn_automatic_stock(r);
  warn_tbl_units(options, r);
  warn_tool_sizes(cutting, r);
}

}  // namespace tridex::cli
