#include "inputs/project.hpp"

#include <fstream>

#include <nlohmann/json.hpp>

#include "errors.hpp"
#include "inputs/json_input.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

bool is_project_file(const fs::path& path) {
  if (path.extension() == ".camotics") return true;
  std::ifstream in(path, std::ios::binary);
  char c = 0;
  while (in.get(c))
    if (!std::isspace(static_cast<unsigned char>(c))) return c == '{';
  return false;
}

namespace {

Vec3 read_point(const nlohmann::json& value, const std::string& where) {
  if (!value.is_array() || value.size() != 3) input_error(where, ": expected [x, y, z]");
  Vec3 p;
  for (int a = 0; a < 3; ++a) {
    const auto& v = value[static_cast<std::size_t>(a)];
    if (!v.is_number()) input_error(where, ": coordinate ", a, " is not a number");
    p[a] = v.get<double>();
  }
  if (!is_finite(p) || glm::any(glm::greaterThan(glm::abs(p), Vec3(kMaxStockCoordinate))))
    input_error(where, ": coordinates must be finite and within ±", kMaxStockCoordinate, " mm");
  return p;
}

}  // namespace

Project read_project(const fs::path& path) { return project_from_json(read_json_file(path), path); }

Project project_from_json(const nlohmann::json& json, const fs::path& path) {
  if (!json.is_object()) input_error(path.string(), ": a CAMotics project must be a JSON object");
  const std::string source = path.string();
  Project project;
  fs::path folder = path.parent_path();
  auto files = json.find("files");
  if (files == json.end() || !files->is_array() || files->empty())
    input_error(source, ": \"files\" must list the program file(s)");
  for (const auto& f : *files) {
    // CAMotics writes plain strings; some versions write {"path": ...}.
    std::string name;
    if (f.is_string())
      name = f.get<std::string>();
    else if (f.is_object() && f.contains("path") && f["path"].is_string())
      name = f["path"].get<std::string>();
    else
      input_error(source, ": \"files\" entries must be file names, got ", json_type_name(f));
    if (name.empty() || name.find('\0') != std::string::npos)
      input_error(source, ": \"files\" holds an empty or invalid file name");
    fs::path file = name;
    if (file.is_relative()) file = folder / file;
    std::error_code error;
    if (!fs::is_regular_file(file, error))
      input_error(source, ": program file ", file.string(), " does not exist");
    project.files.push_back(file);
  }
  if (auto tools = json.find("tools"); tools != json.end())
    project.tools = ToolTable::from_json(*tools, source + ": \"tools\"");
  if (auto fixtures = json.find("fixtures"); fixtures != json.end()) {
    if (!fixtures->is_array())
      input_error(source, ": \"fixtures\" must list STL files, got ", json_type_name(*fixtures));
    for (const auto& f : *fixtures) {
      if (!f.is_string() || f.get<std::string>().empty())
        input_error(source, ": \"fixtures\" entries must be file names, got ", json_type_name(f));
      fs::path file = f.get<std::string>();
      if (file.is_relative()) file = folder / file;
      std::error_code error;
      if (!fs::is_regular_file(file, error))
        input_error(source, ": fixture ", file.string(), " does not exist");
      project.fixtures.push_back(file);
    }
  }
  if (auto work = json.find("workpiece"); work != json.end()) {
    if (!work->is_object()) input_error(source, ": \"workpiece\" must be an object");
    StockSpec stock;
    bool automatic = true;
    if (auto flag = work->find("automatic"); flag != work->end()) {
      if (!flag->is_boolean())
        input_error(source, ": workpiece \"automatic\" must be true or false, got ",
                    json_type_name(*flag), flag->is_string() ? " " + flag->dump() : std::string());
      automatic = flag->get<bool>();
    }
    if (auto margin = work->find("margin"); margin != work->end()) {
      if (!margin->is_number() || !(margin->get<double>() >= 0) ||
          !(margin->get<double>() <= kMaxMarginPercent))
        input_error(source, ": workpiece \"margin\" must be a number (percent) from 0 to ",
                    kMaxMarginPercent, ", got ",
                    margin->is_number() ? margin->dump() : json_type_name(*margin));
      stock.margin_percent = margin->get<double>();
    }
    auto bounds = work->find("bounds");
    if (!automatic) {
      if (bounds == work->end() || !bounds->is_object())
        input_error(source, ": a workpiece that is not automatic needs \"bounds\"");
      stock.kind = StockSpec::Kind::box;
      auto corner = [&](const char* key) {
        auto found = bounds->find(key);
        return read_point(found == bounds->end() ? nlohmann::json() : *found,
                          source + ": workpiece bounds " + key);
      };
      stock.box = Aabb{corner("min"), corner("max")};
      for (int a = 0; a < 3; ++a)
        if (!(stock.box.min[a] < stock.box.max[a]))
          input_error(source, ": workpiece bounds min must be below max on every axis");
    }
    project.stock = stock;
  }
  return project;
}

}  // namespace tridex::cli
