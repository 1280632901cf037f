// tridex command — tool tables in the CAMotics JSON schema.
//
// An object keyed by tool number; each tool has "shape", "diameter", "length" and "units"
// ("mm"/"metric" or "inch"/"imperial"; default mm), as CAMotics writes them, plus tridex's
// "bullnose" shape with "corner-radius". Shapes map onto tridex cutters (tridex/cutter.hpp):
//   cylindrical  flat end of radius D/2
//   ballnose     ball end of radius D/2
//   bullnose     bull nose of radius D/2 and corner radius "corner-radius"
//   conical      a sharp cone reaching D/2 at height "length" (half-angle atan(D / 2L))
//   snubnose     a flat tip of diameter "snub_diameter", widening to D/2 at height "length"
//   spheroid     the lower half of an ellipsoid of radius D/2 and height "length", as a fine
//                convex polyline (64 pieces)
// "description" and unknown keys are ignored, so that CAMotics tables load unchanged.
//
// The parts that do not cut (tridex/tool_body.hpp), all optional, in the tool's units:
//   "flute-length"    the cutting length; above it the shank (none given: the flutes go on up)
//   "shank-diameter"  the shank's diameter (default: "diameter")
//   "stick-out"       the length out of the holder, tip to holder face
//   "holder"          its sections from the holder face up, each {"bottom-diameter",
//                     "top-diameter", "length"} (a cylinder when the diameters agree, else a
//                     cone frustum); needs "stick-out"
//
// "tool-length" (or "tool_length"), optional, is the tool's length from the spindle's gauge point
// to the tip, for tool length offsets (G43 H; gcode/README.md "Tool length offsets"); it may be
// negative (measured from a master tool). CAMotics' "length" is the cutting shape's, not this.
//
// The third format, a LinuxCNC tool table (.tbl), is read by from_tbl: one tool a line,
// `T1 P1 Z0.511 D0.125 ;comment`, T the tool number, Z its length, D its diameter (a flat end
// mill), in the machine's units (LinuxCNC's [TRAJ]LINEAR_UNITS, the machine file's
// "linear_units"): inches unless it says mm, as rs274 run standalone reads them; the comment is its
// description. X/Y offsets other than 0 are an error (tridex does not simulate them); P, the
// pocket, and the other axes' offsets and lathe entries (I J Q) are ignored. A tool without D keeps
// its length (for G43) but cannot cut.
//
// The second format, Autodesk Fusion's tool library export (`{"data": [tool, ...]}`), is read by
// from_fusion_json: each tool's "post-process"."number" is its number, "unit" "millimeters" or
// "inches", "type" "flat end mill", "face mill", "ball end mill" or "bull nose end mill" (other
// entries — drills, holders, probes, turning tools — are skipped), and "geometry" DC (cutting
// diameter), LCF (flute length), LB (length below the holder: the stick-out), OAL (overall
// length), SFDM (shank diameter) and RE (corner radius, bull nose), with "holder"."segments" of
// {"height", "lower-diameter", "upper-diameter"} from the holder face up.
#pragma once

#include <filesystem>
#include <map>
#include <set>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "tridex/cutter.hpp"
#include "tridex/tool_body.hpp"

namespace tridex::cli {

struct ToolSpec {
  int number = 0;
  std::string shape;  // the table's shape name, lower case
  double diameter_mm = 0;
  double length_mm = 0;  // 0 when the table gives none
  double corner_radius_mm = 0;
  double snub_diameter_mm = 0;
  double flute_length_mm = 0;       // 0 when the table gives none (flutes all the way up)
  double shank_diameter_mm = 0;     // 0: the cutting diameter
  double stick_out_mm = 0;          // 0 when the table gives none
  std::vector<BodySection> holder;  // bottom (holder face) first; radii and lengths in mm
  std::string description;
  Cutter cutter = Cutter::flat(1);
  ToolBody body;  // the shank and holder parts, from the fields above
};

class ToolTable {
 public:
  // Parses a table; `source` names it in error messages. Throws InputError naming the tool and key.
  static ToolTable from_json(const nlohmann::json& table, const std::string& source);
  // Parses a Fusion tool library (`{"data": [...]}`); throws InputError naming the tool and field.
  static ToolTable from_fusion_json(const nlohmann::json& library, const std::string& source);
  // Parses a LinuxCNC tool table; throws InputError naming source:line:column and the word.
  // `unit_mm`: millimetres per table unit (25.4: inches).
  static ToolTable from_tbl(const std::string& text, const std::string& source,
                            double unit_mm = 25.4);
  // Reads any format (a .tbl file name: LinuxCNC, in `tbl_unit_mm`; a Fusion library is an object
  // with a "data" list).
  static ToolTable read(const std::filesystem::path& path, double tbl_unit_mm = 25.4);

  const ToolSpec* find(int number) const {
    auto it = tools_.find(number);
    return it == tools_.end() ? nullptr : &it->second;
  }
  const std::map<int, ToolSpec>& tools() const { return tools_; }
  bool empty() const { return tools_.empty(); }
  // Tool lengths (mm, gauge point to tip) of the tools whose entry gives one; every entry of a
  // LinuxCNC .tbl gives one (no Z: 0, as LinuxCNC reads it).
  const std::map<int, double>& tool_lengths() const { return tool_lengths_; }
  // The tools of a LinuxCNC table with D0 or no D: in the table, with no cutter (tools() lacks
  // them), a diameter of 0 for G41/G42.
  const std::set<int>& zero_diameter() const { return zero_diameter_; }
  // Why a tool the table holds cannot cut (a Fusion probe, a form mill), naming it and its type;
  // nullptr for a tool that can, or that the table does not hold.
  const std::string* unusable(int number) const {
    auto it = unusable_.find(number);
    return it == unusable_.end() ? nullptr : &it->second;
  }

 private:
  std::map<int, ToolSpec> tools_;
  std::map<int, double> tool_lengths_;
  std::set<int> zero_diameter_;
  std::map<int, std::string> unusable_;
};

// The cutter a tool description stands for (the mapping above); throws InputError.
Cutter make_cutter(const ToolSpec& spec, const std::string& where);

// The shank and holder parts of a tool description, checked (flutes within the stick-out, the
// holder above a positive stick-out); throws InputError naming `where` and the key.
ToolBody make_body(const ToolSpec& spec, const std::string& where);

// `text` with its ASCII letters lowered: units, shapes, types and extensions match in any case.
std::string ascii_lower(std::string text);

}  // namespace tridex::cli
