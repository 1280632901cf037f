// tridex command — the workpiece: `--stock box:…`, `--stock FILE.stl` or `--stock auto[:MARGIN]`.
#pragma once

#include <filesystem>
#include <optional>
#include <string>

#include "tridex/geometry.hpp"

namespace tridex::cli {

// The largest coordinate (mm) a stock box, an envelope or a project's workpiece may have, and the
// largest margin: far past any machine (the lattice refuses a stock beyond 2^23 spacings with its
// own message), and within the float range of the kernel's Z-map heights (3.4e38: ±1e200 made the
// Z-map heights infinite). Values beyond are bad input (exit status 2), not a failure of the run.
constexpr double kMaxStockCoordinate = 1e30;
// A project's automatic margin, percent of the cutting moves' box.
constexpr double kMaxMarginPercent = 1e4;

struct StockSpec {
  enum class Kind { box, mesh, automatic };
  Kind kind = Kind::automatic;
  Aabb box;                         // Kind::box: the stock, mm, work frame
  std::filesystem::path mesh_path;  // Kind::mesh: a closed STL
  // Kind::automatic: the margin added on every side of the box around the cutting moves, in mm;
  // unset means 5 % of each side (the CAMotics default), and then the top gets no margin.
  std::optional<double> margin_mm;
  std::optional<double> margin_percent;  // from a CAMotics project ("margin", percent)
};

// Parses the option text; throws InputError naming the option and the offending part.
StockSpec parse_stock(const std::string& text);

// "XMIN,YMIN,ZMIN,XMAX,YMAX,ZMAX" (the part after "box:"), min below max on every axis; throws
// InputError naming `option`.
Aabb parse_box(const std::string& numbers, const std::string& option);
// `check --envelope box:…`.
Aabb parse_envelope(const std::string& text);

// The automatic stock around `cutting_bounds` (the tool-tip box of the cutting moves), following
// CAMotics: the top is the highest cut or z = 0 whichever is higher when the cuts go below 0, at
// least 2 mm thick, then a margin on every side but the top when it is a percentage.
Aabb automatic_stock(const Aabb& cutting_bounds, const StockSpec& spec);

std::string describe(const StockSpec& spec);

}  // namespace tridex::cli
