// tridex regress — a regression folder (issue 39): every program of a folder (or one program)
// simulated with its settings and its solid compared with its stored baseline, as `diff` compares
// two programs (solid_diff.hpp); `--bless` stores the results as the new baselines.
//
// A baseline is the program's triple dexel (NAME.dexel: the exact intervals of every ray, so that
// a rerun with the same settings compares equal to the bit, which a mesh re-dexelized would not:
// the surface rounds corners and thin walls by up to a spacing) and a small JSON (NAME.json: the
// settings it ran with, its stock box, lattice and volume). A rerun cuts the program from the
// baseline's stock box, so that both solids lie on one lattice, as diff cuts B from A's stock.
// Each program runs on its own, so that a batch scheduler can hand each to another machine:
// `tridex regress DIR/one.nc --baseline BASE` reads and writes only one.nc's baseline.
// docs/command-line.md (`tridex regress`) describes the folder, the sidecar and the statuses.
#include <algorithm>
#include <bit>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <set>

#include "checks/reaching_moves.hpp"
#include "checks/solid_diff.hpp"
#include "commands.hpp"
#include "errors.hpp"
#include "inputs/json_input.hpp"
#include "inputs/project.hpp"
#include "outputs/output.hpp"
#include "pipeline/pipeline.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace regress {

constexpr char kMagic[8] = {'T', 'R', 'I', 'D', 'E', 'X', 'D', 'X'};
constexpr std::uint32_t kFormatVersion = 1;
constexpr std::size_t kRegionsWithLines = 20;
constexpr std::size_t kLinesListed = 20;
constexpr std::size_t kRegionsListed = 100;

// ---- the dexel file: magic, version, lattice, then per axis nu, nv, the rays' offsets and the
// intervals (little-endian; the command refuses to build elsewhere) -----------------------------
static_assert(std::endian::native == std::endian::little, "baselines are little-endian");

template <class T>
void put(std::vector<std::uint8_t>& out, const T& value) {
  const auto* bytes = reinterpret_cast<const std::uint8_t*>(&value);
  out.insert(out.end(), bytes, bytes + sizeof(T));
}

std::vector<std::uint8_t> dexel_bytes(const TripleDexel& d) {
  std::vector<std::uint8_t> out(kMagic, kMagic + 8);
  put(out, kFormatVersion);
  for (int a = 0; a < 3; ++a) put(out, d.origin[a]);
  put(out, d.spacing);
  for (int a = 0; a < 3; ++a) put(out, static_cast<std::int32_t>(d.n[a]));
  for (const DexelGrid& g : d.grids) {
    put(out, static_cast<std::int32_t>(g.nu));
    put(out, static_cast<std::int32_t>(g.nv));
    const auto* o = reinterpret_cast<const std::uint8_t*>(g.offsets.data());
    out.insert(out.end(), o, o + g.offsets.size() * sizeof(std::uint32_t));
    const auto* i = reinterpret_cast<const std::uint8_t*>(g.intervals.data());
    out.insert(out.end(), i, i + g.intervals.size() * sizeof(DexelInterval));
  }
  return out;
}

// Reads what dexel_bytes wrote; throws InputError naming the file for anything else.
TripleDexel read_dexel_file(const fs::path& path) {
  const std::string bytes = read_text_file(path, "a tridex baseline (.dexel)");
  std::size_t at = 0;
  auto fail = [&](const char* what) {
    input_error(path.string(), ": not a tridex baseline: ", what);
  };
  auto take = [&](void* to, std::size_t size) {
    if (bytes.size() - at < size) fail("the file is cut short");
    std::memcpy(to, bytes.data() + at, size);
    at += size;
  };
  char magic[8];
  take(magic, 8);
  std::uint32_t version = 0;
  take(&version, 4);
  if (std::memcmp(magic, kMagic, 8) != 0) fail("no TRIDEXDX header");
  if (version != kFormatVersion) fail("another format version; rerun with --bless");
  TripleDexel d;
  for (int a = 0; a < 3; ++a) take(&d.origin[a], 8);
  take(&d.spacing, 8);
  for (int a = 0; a < 3; ++a) {
    std::int32_t n = 0;
    take(&n, 4);
    d.n[a] = n;
  }
  if (!is_finite(d.origin) || !(d.spacing > 0) || glm::any(glm::lessThan(d.n, glm::ivec3(1))))
    fail("a bad lattice");
  for (int a = 0; a < 3; ++a) {
    DexelGrid& g = d.grids[a];
    g.axis = a;
    std::int32_t nu = 0, nv = 0;
    take(&nu, 4), take(&nv, 4);
    if (nu != d.n[TripleDexel::u_axis(a)] || nv != d.n[TripleDexel::v_axis(a)])
      fail("a grid that does not match its lattice");
    const std::size_t rays = static_cast<std::size_t>(nu) * static_cast<std::size_t>(nv);
    if ((bytes.size() - at) / 4 < rays + 1) fail("the file is cut short");
    g.nu = nu, g.nv = nv;
    g.offsets.resize(rays + 1);
    take(g.offsets.data(), (rays + 1) * 4);
    if (g.offsets[0] != 0 || !std::is_sorted(g.offsets.begin(), g.offsets.end()))
      fail("offsets out of order");
    if ((bytes.size() - at) / sizeof(DexelInterval) < g.offsets.back())
      fail("the file is cut short");
    g.intervals.resize(g.offsets.back());
    take(g.intervals.data(), g.intervals.size() * sizeof(DexelInterval));
  }
  if (at != bytes.size()) fail("bytes after the last grid");
  return d;
}

// ---- the programs and their settings --------------------------------------------------------

bool is_program_name(const fs::path& path) {
  std::string e = path.extension().string();
  std::transform(e.begin(), e.end(), e.begin(),
                 [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
  return e == ".nc" || e == ".ngc" || e == ".tap" || e == ".gcode" || e == ".cnc" ||
         e == ".camotics";
}

// PATH's programs: PATH itself, or the programs of the folder PATH (not its subfolders) sorted by
// name, less the G-code files that a project there lists (they run as part of it).
std::vector<fs::path> programs_of(const fs::path& path) {
  std::error_code error;
  if (!fs::is_directory(path, error)) {
    if (!fs::is_regular_file(path, error))
      input_error(path.string(), ": no such program or folder");
    return {path};
  }
  std::vector<fs::path> found;
  for (const fs::directory_entry& e : fs::directory_iterator(path, error))
    if (e.is_regular_file(error) && is_program_name(e.path())) found.push_back(e.path());
  if (error) input_error(path.string(), ": cannot list the folder (", error.message(), ")");
  std::set<fs::path> in_projects;
  for (const fs::path& p : found)
    if (p.extension() == ".camotics")
      for (const fs::path& f : read_project(p).files) in_projects.insert(fs::weakly_canonical(f));
  std::erase_if(found,
                [&](const fs::path& p) { return in_projects.count(fs::weakly_canonical(p)); });
  std::sort(found.begin(), found.end());
  if (found.empty())
    input_error(path.string(), ": no programs (.nc, .ngc, .tap, .gcode, .cnc, .camotics) in it");
  return found;
}

// NAME.tridex.json beside NAME.nc: the program's own options (docs/command-line.md). Paths in it
// are relative to its folder. Its keys replace the command line's values for this program.
SimulateOptions apply_sidecar(const SimulateOptions& given, const fs::path& program,
                              double& tolerance, Json& settings_from) {
  SimulateOptions o = given;
  o.program = program.string();
  const fs::path sidecar = program.parent_path() / (program.stem().string() + ".tridex.json");
  std::error_code error;
  if (!fs::exists(sidecar, error)) return o;
  settings_from = sidecar.string();
  const nlohmann::json j = read_json_file(sidecar);
  const std::string where = sidecar.string();
  if (!j.is_object()) input_error(where, ": a sidecar must be a JSON object");
  auto path = [&](const nlohmann::json& v, const std::string& key) {
    if (!v.is_string() || v.get<std::string>().empty())
      input_error(where, ": \"", key, "\" must be a file or folder name, got ", json_type_name(v));
    const fs::path p = v.get<std::string>();
    return (p.is_relative() ? sidecar.parent_path() / p : p).string();
  };
  auto number = [&](const nlohmann::json& v, const std::string& key) {
    if (!v.is_number() || !(v.get<double>() > 0) || !(v.get<double>() <= 1e6))
      input_error(where, ": \"", key, "\" must be a positive number, got ", v.dump());
    return v.get<double>();
  };
  for (const auto& [key, v] : j.items()) {
    if (key == "tools") {
      o.tools = path(v, key);
    } else if (key == "machine") {
      const std::string m = v.is_string() ? v.get<std::string>() : std::string();
      o.machine = gcode::MachineConfig::bundled(m) ? m : path(v, key);
    } else if (key == "stock") {
      if (!v.is_string()) input_error(where, ": \"stock\" must be a string as --stock takes");
      const std::string st = v.get<std::string>();
      o.stock = st.rfind("box:", 0) == 0 || st.rfind("auto", 0) == 0 ? st : path(v, key);
    } else if (key == "subprograms") {
      if (!v.is_array()) input_error(where, ": \"subprograms\" must list folders");
      o.subprograms.clear();
      for (const auto& d : v) o.subprograms.push_back(path(d, key));
    } else if (key == "dexel_res") {
      o.dexel_res = static_cast<int>(number(v, key)), o.dexel_cell = 0;
    } else if (key == "dexel_cell") {
      o.dexel_cell = number(v, key), o.dexel_res = 0;
    } else if (key == "zmap_cell") {
      o.zmap_cell = number(v, key);
    } else if (key == "arc_tolerance") {
      o.arc_tolerance = number(v, key);
    } else if (key == "tolerance") {
      tolerance = number(v, key);
    } else if (key == "initial_tool") {
      if (!v.is_number_integer() || v.get<long long>() < 0)
        input_error(where, ": \"initial_tool\" must be a tool number, got ", v.dump());
      o.initial_tool = v.get<int>();
    } else if (key == "tool_units" && v.is_string() && (v == "mm" || v == "inch")) {
      o.tool_units = v.get<std::string>();
    } else if (key == "block_delete" && v.is_string() && (v == "on" || v == "off")) {
      o.block_delete = v.get<std::string>();
    } else if (key == "lenient" && v.is_boolean()) {
      o.lenient = v.get<bool>();
    } else {
      input_error(where, ": unknown key or bad value \"", key, "\": ", v.dump(),
                  " (keys: tools, machine, stock, subprograms, dexel_res, dexel_cell, zmap_cell, "
                  "arc_tolerance, tolerance, initial_tool, tool_units, block_delete, lenient)");
    }
  }
  return o;
}

// What a baseline records of the options a program ran with: a rerun with other values is
// reported as such (and compared all the same where the lattice allows).
Json settings_json(const SimulateOptions& o, double tolerance) {
  return {{"tools", o.tools},           {"machine", o.machine},
          {"stock", o.stock},           {"subprograms", o.subprograms},
          {"dexel_res", o.dexel_res},   {"dexel_cell", o.dexel_cell},
          {"zmap_cell", o.zmap_cell},   {"arc_tolerance", o.arc_tolerance},
          {"tolerance", tolerance},     {"initial_tool", o.initial_tool},
          {"tool_units", o.tool_units}, {"block_delete", o.block_delete},
          {"lenient", o.lenient}};
}

struct Outcome {
  std::string name;  // the program's file name: its baseline's name
  fs::path program;
  std::string status;  // same, changed, new, error
  std::string reason;
  Json regions = Json::array();
  std::size_t region_count = 0;
  double changed_volume = 0;
  Json settings_changed = Json::array();
  Json entry;  // the report's entry
  bool blessed = false;
};

// The regions between the baseline (a) and the new solid (b), each with the new program's lines:
// those whose moves reach it (material the new program removed) or pass nearest (material it
// left, reaching_moves.hpp: nearest_moves), as file:line.
void compare_with_baseline(const TripleDexel& base, const SimulationResult& r, double tolerance,
                           Outcome& out) {
  const std::vector<DiffSpan> spans = solid_differences(base, r.result, tolerance);
  std::vector<DiffRegion> regions = connect_spans(spans, r.result);
  measure_regions(regions, spans, r.result);
  out.region_count = regions.size();
  const double spacing = r.lattice.spacing;
  for (std::size_t k = 0; k < regions.size(); ++k) {
    const DiffRegion& g = regions[k];
    out.changed_volume += g.volume;
    if (k >= kRegionsListed) continue;
    Json region = {{"kind", g.removed ? "removed" : "left"},
                   {"volume_mm3", g.volume},
                   {"depth_mm", g.depth},
                   {"deepest_point", to_json(g.deepest)},
                   {"bbox", {{"min", to_json(g.box.min)}, {"max", to_json(g.box.max)}}}};
    if (k < kRegionsWithLines) {
      std::set<std::pair<int, int>> lines;
      std::set<int> tools;
      if (g.removed) {
        for_each_reaching_move(r, g.probes, 0.25 * spacing, [&](const gcode::Move& m) {
          if (lines.size() < kLinesListed) lines.insert({m.file, m.line}), tools.insert(m.tool);
        });
      } else {
        for (const NearMove& m :
             nearest_moves(r, g.probes, g.depth + spacing, spacing, kLinesListed))
          lines.insert({m.move->file, m.move->line}), tools.insert(m.move->tool);
      }
      Json list = Json::array();
      for (const auto& [file, line] : lines)
        list.push_back(r.files.at(static_cast<std::size_t>(file)) + ":" + std::to_string(line));
      region["lines"] = list;
      region["tools"] = tools;
    }
    out.regions.push_back(region);
  }
}

struct Baseline {
  fs::path dexel, json;
};

Baseline baseline_paths(const fs::path& base, const std::string& name) {
  return {base / (name + ".dexel"), base / (name + ".json")};
}

// One program: run, compare, bless. Bad input of this program (its G-code, its sidecar, its
// baseline) is an "error" outcome, not the end of the run.
Outcome run_one(const RegressOptions& options, const fs::path& program, Progress& progress) {
  Outcome out;
  out.program = program;
  out.name = program.filename().string();
  const Baseline paths = baseline_paths(options.baseline, out.name);
  out.entry = {{"program", program.string()}, {"baseline", paths.json.string()}};
  try {
    double tolerance = options.tolerance;
    Json sidecar = nullptr;
    SimulateOptions o = apply_sidecar(options, program, tolerance, sidecar);
    out.entry["sidecar"] = sidecar;
    const Json settings = settings_json(o, tolerance);
    std::error_code error;
    const bool have = fs::exists(paths.json, error) && fs::exists(paths.dexel, error);
    std::optional<TripleDexel> base;
    Json stored;
    if (have) {
      stored = read_json_file(paths.json);
      if (!stored.is_object() || !stored.contains("stock_box") || !stored.contains("settings"))
        input_error(paths.json.string(), ": not a tridex baseline (no \"stock_box\")");
      base = read_dexel_file(paths.dexel);
      for (const auto& [key, value] : settings.items())
        if (!stored["settings"].contains(key) || stored["settings"][key] != value)
          out.settings_changed.push_back(key);
      // The baseline's stock box: one lattice for both, as diff cuts B from A's stock.
      if (o.stock.empty() || o.stock.rfind("auto", 0) == 0) {
        const Json& box = stored["stock_box"];
        char text[256];
        std::snprintf(text, sizeof text, "box:%.17g,%.17g,%.17g,%.17g,%.17g,%.17g",
                      box["min"][0].get<double>(), box["min"][1].get<double>(),
                      box["min"][2].get<double>(), box["max"][0].get<double>(),
                      box["max"][1].get<double>(), box["max"][2].get<double>());
        o.stock = text;
      }
    }
    PipelineRequest request;
    if (options.bless) request.outputs = {{"--baseline", paths.dexel}, {"--baseline", paths.json}};
    if (!options.report.empty()) request.outputs.push_back({"--report", options.report});
    o.quiet = true;
    const SimulationResult r = simulate_program(o, progress, request);
    const double tol = tolerance > 0 ? tolerance : 0.5 * r.lattice.spacing;
    out.entry["tolerance_mm"] = tol;
    out.entry["volume_mm3"] = r.volume;
    out.entry["warnings"] = r.warnings;
    if (!base) {
      out.status = "new";
      out.reason = "no baseline";
    } else if (!(base->lattice() == r.result.lattice())) {
      out.status = "changed";
      out.reason = "the lattice differs from the baseline's (settings changed: --bless to accept)";
    } else {
      compare_with_baseline(*base, r, tol, out);
      out.status = out.region_count > 0 ? "changed" : "same";
      out.entry["baseline_volume_mm3"] = stored.value("volume_mm3", 0.0);
    }
    if (!out.settings_changed.empty() && out.reason.empty())
      out.reason = "settings differ from the baseline's: " + out.settings_changed.dump();
    if (options.bless) {
      const Json record = {
          {"format", "tridex regress baseline"},
          {"version", kFormatVersion},
          {"program", out.name},
          {"settings", settings},
          {"stock_box", {{"min", to_json(r.stock.box.min)}, {"max", to_json(r.stock.box.max)}}},
          {"lattice",
           {{"origin", to_json(r.lattice.origin)},
            {"spacing", r.lattice.spacing},
            {"n", {r.lattice.n.x, r.lattice.n.y, r.lattice.n.z}}}},
          {"volume_mm3", r.volume}};
      write_file_atomically(paths.dexel, dexel_bytes(r.result));
      write_file_atomically(paths.json, dump_json(record, 2) + "\n");
      out.blessed = true;
    }
  } catch (const gcode::GcodeError& e) {
    out.status = "error", out.reason = e.what();
  } catch (const InputError& e) {
    out.status = "error", out.reason = e.what();
  }
  return out;
}

void print_table(const std::vector<Outcome>& outcomes, bool bless) {
  std::size_t width = 7;
  for (const Outcome& o : outcomes) width = std::max(width, o.name.size());
  std::printf("%-*s  %-8s %7s %12s  %s\n", static_cast<int>(width), "program", "status", "regions",
              "volume_mm3", "lines / reason");
  for (const Outcome& o : outcomes) {
    std::string detail;
    for (const Json& g : o.regions)
      for (const Json& l : g.value("lines", Json::array()))
        if (detail.size() < 120) detail += (detail.empty() ? "" : ", ") + l.get<std::string>();
    if (detail.empty()) detail = o.reason;
    std::string status = o.status == "changed" ? "CHANGED"
                         : o.status == "error" ? "ERROR"
                                               : o.status;
    if (bless && o.blessed && o.status != "same") status += "+";
    std::printf("%-*s  %-8s %7zu %12.4g  %s\n", static_cast<int>(width),
                terminal_safe(o.name).c_str(), status.c_str(), o.region_count, o.changed_volume,
                terminal_safe(detail).c_str());
  }
}

}  // namespace regress

int run_regress(const RegressOptions& options) {
  Progress progress(!options.quiet && (options.progress || stderr_is_terminal()));
  std::error_code error;
  if (options.bless) fs::create_directories(options.baseline, error);
  if (!fs::is_directory(options.baseline, error))
    input_error(
        "--baseline ", options.baseline,
        options.bless ? ": cannot create the folder" : ": no such folder (--bless creates it)");
  const std::vector<fs::path> programs = regress::programs_of(options.program);
  std::set<std::string> names;
  for (const fs::path& p : programs)
    if (!names.insert(p.filename().string()).second)
      input_error(p.string(), ": two programs of one name share a baseline");
  if (!options.report.empty()) check_output_path("--report", options.report, programs);
  std::vector<regress::Outcome> outcomes;
  for (const fs::path& program : programs) {
    progress.stage("running " + program.string());
    outcomes.push_back(regress::run_one(options, program, progress));
  }
  progress.finish();
  int same = 0, changed = 0, fresh = 0, errors = 0;
  Json list = Json::array();
  for (regress::Outcome& o : outcomes) {
    same += o.status == "same", changed += o.status == "changed", fresh += o.status == "new",
        errors += o.status == "error";
    o.entry["status"] = o.status;
    if (!o.reason.empty()) o.entry["reason"] = o.reason;
    o.entry["settings_changed"] = o.settings_changed;
    o.entry["regions_count"] = o.region_count;
    o.entry["changed_volume_mm3"] = o.changed_volume;
    o.entry["regions"] = o.regions;
    o.entry["blessed"] = o.blessed;
    list.push_back(o.entry);
  }
  // New programs count as changes: a result nobody has looked at is not the baseline's.
  const int status = errors                ? kBadInput
                     : options.bless       ? kSuccess
                     : changed + fresh > 0 ? kFindings
                                           : kSuccess;
  const char* verdict = errors ? "error" : changed + fresh > 0 ? "changed" : "same";
  if (!options.report.empty())
    write_file_atomically(options.report, dump_json(Json{{"baseline", options.baseline},
                                                         {"bless", options.bless},
                                                         {"verdict", verdict},
                                                         {"counts",
                                                          {{"programs", outcomes.size()},
                                                           {"same", same},
                                                           {"changed", changed},
                                                           {"new", fresh},
                                                           {"error", errors}}},
                                                         {"programs", list}},
                                                    2) +
                                              "\n");
  if (!options.quiet) {
    regress::print_table(outcomes, options.bless);
    std::printf("%zu program(s): %d same, %d changed, %d new, %d error(s)%s\n", outcomes.size(),
                same, changed, fresh, errors, options.bless ? "; baselines stored" : "");
  }
  for (const regress::Outcome& o : outcomes)
    if (o.status == "error") std::cerr << "tridex: " << terminal_safe(o.reason) << '\n';
  return status;
}

}  // namespace tridex::cli
