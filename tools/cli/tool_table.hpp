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
#pragma once

#include <filesystem>
#include <map>
#include <string>

#include <nlohmann/json_fwd.hpp>

#include "tridex/cutter.hpp"

namespace tridex::cli {

struct ToolSpec {
  int number = 0;
  std::string shape;          // the table's shape name, lower case
  double diameter_mm = 0;
  double length_mm = 0;       // 0 when the table gives none
  double corner_radius_mm = 0;
  double snub_diameter_mm = 0;
  std::string description;
  Cutter cutter = Cutter::flat(1);
};

class ToolTable {
 public:
  // Parses a table; `source` names it in error messages. Throws InputError naming the tool and key.
  static ToolTable from_json(const nlohmann::json& table, const std::string& source);
  static ToolTable read(const std::filesystem::path& path);

  const ToolSpec* find(int number) const {
    auto it = tools_.find(number);
    return it == tools_.end() ? nullptr : &it->second;
  }
  const std::map<int, ToolSpec>& tools() const { return tools_; }
  bool empty() const { return tools_.empty(); }

 private:
  std::map<int, ToolSpec> tools_;
};

// The cutter a tool description stands for (the mapping above); throws InputError.
Cutter make_cutter(const ToolSpec& spec, const std::string& where);

}  // namespace tridex::cli
