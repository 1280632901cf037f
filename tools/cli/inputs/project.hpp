// tridex command — CAMotics project files (.camotics, JSON).
//
// From a project tridex takes the program file(s) ("files", relative to the project's folder),
// the tool table ("tools", the same schema as --tools) and the workpiece ("workpiece":
// {"automatic": bool, "margin": percent, "bounds": {"min": [x,y,z], "max": [x,y,z]}}, in mm as
// CAMotics stores it). Options given on the command line take precedence.
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
};

// True if `path` looks like a CAMotics project (its extension, or a leading '{').
bool is_project_file(const std::filesystem::path& path);
// Throws InputError naming the file and the key for any fault (json_input.hpp).
Project read_project(const std::filesystem::path& path);
// The same from parsed JSON; `path` names the project and its folder holds the program files.
Project project_from_json(const nlohmann::json& json, const std::filesystem::path& path);

}  // namespace tridex::cli
