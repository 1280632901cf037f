// tridex command — CAMotics project files (.camotics, JSON).
//
// From a project tridex takes the program file(s) ("files", relative to the project's folder),
// the tool table ("tools", the same schema as --tools) and the workpiece ("workpiece":
// {"automatic": bool, "margin": percent, "bounds": {"min": [x,y,z], "max": [x,y,z]}}, in mm as
// CAMotics stores it). Options given on the command line take precedence. tridex's own key
// "fixtures" lists STL files (relative to the project's folder) that hold the part, in the work
// frame, for check's machine check (--fixture adds to them).
#pragma once

#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "inputs/stock.hpp"
#include "inputs/tool_table.hpp"

namespace tridex::cli {

struct Project {
  std::vector<std::filesystem::path> files;
  std::optional<ToolTable> tools;
  std::optional<StockSpec> stock;
  std::vector<std::filesystem::path> fixtures;  // "fixtures": STL files, for check (issue 33)
};

// True if `path` looks like a CAMotics project (its extension, or a leading '{').
bool is_project_file(const std::filesystem::path& path);
// Throws InputError naming the file and the key for any fault (json_input.hpp).
Project read_project(const std::filesystem::path& path);
// The same from parsed JSON; `path` names the project and its folder holds the program files.
Project project_from_json(const nlohmann::json& json, const std::filesystem::path& path);

}  // namespace tridex::cli
