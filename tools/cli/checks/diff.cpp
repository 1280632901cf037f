// tridex diff — did my post change the part? (issue 39). Two programs simulated on the same
// stock, dexel lattice and tools (pipeline.hpp); their triple dexels compared ray by ray: where
// one solid has material and the other not for longer than the tolerance along a ray, the span is
// a difference sample. Samples whose lattice nodes touch (26-neighbours) form a region; its volume
// is the larger of the three ray directions' sums (each direction alone misses walls parallel to
// it), its deepest point the middle of its longest span.
//
// Each region is attributed to lines: the moves of the program that removed the material there
// (those whose swept cutter reaches the region's deepest samples, as `check` finds a gouge's
// moves), their counterparts in the other program by the two texts' line alignment
// (line_alignment.hpp), and the changed lines that govern them: the nearest change at or before
// each such line (a G68.2, a tool change, a G20 that moves everything after it) and a change right
// after the last (a tool change moved later). Post mistakes that change no volume come from the
// lint (lint.hpp), counted when program B has them and A does not.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <iostream>
#include <map>
#include <queue>
#include <set>
#include <unordered_map>

#include "checks/deviation.hpp"
#include "checks/line_alignment.hpp"
#include "checks/lint.hpp"
#include "checks/reaching_moves.hpp"
#include "checks/solid_diff.hpp"
#include "commands.hpp"
#include "errors.hpp"
#include "inputs/json_input.hpp"
#include "outputs/html_report.hpp"
#include "outputs/output.hpp"
#include "outputs/result_files.hpp"
#include "pipeline/pipeline.hpp"
#include "render.hpp"
#include "tridex/detail/move_geometry.hpp"
#include "tridex/dexel_ops.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

constexpr std::size_t kDiffRegionsListed = 100;
constexpr std::size_t kDiffRegionsWithLines = 20;
constexpr std::size_t kDiffLinesListed = 200;

// Main-file lines (and their tools) of the moves whose swept cutter reaches one of `probes`, as
// check finds a gouge's moves: p is reached when it lies above the move's swept lower surface in
// the group's frame, within `slack`.
// Moves in subprogram files go to `elsewhere` as "file:line" (the texts aligned are the main
// files'; a called file is the same in both programs, so its lines need no counterpart).
std::map<int, int> reaching_lines(const std::vector<Vec3>& probes, const SimulationResult& r,
                                  double slack, std::set<std::string>& elsewhere) {
  std::map<int, int> lines;  // line -> tool
  for_each_reaching_move(r, probes, slack, [&](const gcode::Move& m) {
    if (m.file == 0)
      lines.emplace(m.line, m.tool);
    else if (elsewhere.size() < kDiffLinesListed)
      elsewhere.insert(r.files.at(static_cast<std::size_t>(m.file)) + ":" + std::to_string(m.line));
  });
  return lines;
}

// The tool of the moves of each main-file line.
std::map<int, int> line_tools(const SimulationResult& r) {
  std::map<int, int> tools;
  for (const gcode::MoveGroup& group : r.groups)
    for (const gcode::Move& m : group.moves)
      if (m.file == 0) tools.emplace(m.line, m.tool);
  return tools;
}

// The changed lines that govern `lines` (header comment): the nearest change at or before each,
// and the first change after the last when no move line lies between.
std::set<int> governing_changes(const std::set<int>& lines, const std::vector<char>& changed,
                                const std::map<int, int>& move_lines) {
  std::set<int> out;
  for (int line : lines)
    if (int c = changed_at_or_before(changed, line); c > 0) out.insert(c);
  if (!lines.empty())
    if (int c = changed_after(changed, *lines.rbegin()); c > 0) {
      auto next_move = move_lines.upper_bound(*lines.rbegin());
      if (next_move == move_lines.end() || next_move->first >= c) out.insert(c);
    }
  return out;
}

struct DiffRun {
  SimulationResult a, b;
  std::string text_a, text_b;
  std::string file_a, file_b;  // the main files, as the findings name them
  LineAlignment alignment;
  std::vector<LintFinding> lint_a, lint_b;  // lint_b: the findings A does not share
  std::optional<LintFinding> error_b;       // B does not run
  double tolerance = 0;
  std::string tolerance_source;
  std::vector<DiffSpan> spans;
  std::vector<DiffRegion> regions;
};

void attribute_region(DiffRegion& region, DiffRun& run, const std::map<int, int>& tools_a,
                      const std::map<int, int>& tools_b) {
  // The probes lie inside the region, so the moves that cut it reach them; the slack absorbs
  // the Z-map's grid only.
  const double slack = 0.25 * run.a.lattice.spacing;
  const SimulationResult& cutter = region.removed ? run.b : run.a;
  const std::map<int, int> cut =
      reaching_lines(region.probes, cutter, slack, region.removed ? region.sub_b : region.sub_a);
  std::set<int>& own = region.removed ? region.lines_b : region.lines_a;
  std::set<int>& other = region.removed ? region.lines_a : region.lines_b;
  const std::vector<int>& map = region.removed ? run.alignment.b_to_a : run.alignment.a_to_b;
  for (const auto& [line, tool] : cut) {
    own.insert(line);
    if (line < static_cast<int>(map.size()) && map[static_cast<std::size_t>(line)] > 0)
      other.insert(map[static_cast<std::size_t>(line)]);
  }
  region.changed_a = governing_changes(region.lines_a, run.alignment.changed_a, tools_a);
  region.changed_b = governing_changes(region.lines_b, run.alignment.changed_b, tools_b);
  for (int line : region.lines_a)
    if (auto t = tools_a.find(line); t != tools_a.end()) region.tools_a.insert(t->second);
  for (int line : region.lines_b)
    if (auto t = tools_b.find(line); t != tools_b.end()) region.tools_b.insert(t->second);
  region.lines_a.insert(region.changed_a.begin(), region.changed_a.end());
  region.lines_b.insert(region.changed_b.begin(), region.changed_b.end());
}

// Each line's normalized text (line_alignment.hpp), line k at k - 1.
std::vector<std::string> text_lines(std::string_view text) {
  std::vector<std::string> lines;
  std::size_t at = 0;
  while (at <= text.size()) {
    std::size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    lines.push_back(normalized_block(text.substr(at, end - at)));
    at = end + 1;
  }
  return lines;
}

// The lint of both programs; B's findings that A shares (same kind, aligned line) are dropped.
void lint_both(DiffRun& run, const gcode::MachineConfig& machine) {
  LintSettings settings;
  settings.decimal_point_input = machine.decimal_point_input;
  settings.linuxcnc = machine.dialect == gcode::Dialect::linuxcnc;
  settings.expect_g43 = program_uses_g43(run.text_a);
  settings.strict = true;
  run.lint_a = lint_text(run.text_a, run.file_a, settings);
  std::vector<LintFinding> all_b = lint_text(run.text_b, run.file_b, settings);
  // Shared: the same kind at the aligned line, or on a block of the same text (a moved block).
  const std::vector<std::string> lines_a = text_lines(run.text_a), lines_b = text_lines(run.text_b);
  std::set<std::pair<std::string, int>> at_line;
  std::set<std::pair<std::string, std::string>> on_text;
  for (const LintFinding& f : run.lint_a) {
    if (f.line < static_cast<int>(run.alignment.a_to_b.size()))
      at_line.insert({f.code, run.alignment.a_to_b[static_cast<std::size_t>(f.line)]});
    if (f.line >= 1 && f.line <= static_cast<int>(lines_a.size()))
      on_text.insert({f.code, lines_a[static_cast<std::size_t>(f.line - 1)]});
  }
  for (LintFinding& f : all_b) {
    const bool shared = at_line.count({f.code, f.line}) ||
                        (f.line >= 1 && f.line <= static_cast<int>(lines_b.size()) &&
                         on_text.count({f.code, lines_b[static_cast<std::size_t>(f.line - 1)]}));
    if (!shared) run.lint_b.push_back(std::move(f));
  }
}

Json diff_lines_json(const std::set<int>& lines) {
  Json out = Json::array();
  for (int line : lines)
    if (out.size() < kDiffLinesListed) out.push_back(line);
  return out;
}

Json diff_region_json(const DiffRegion& region) {
  return {{"kind", region.removed ? "removed_by_b" : "left_by_b"},
          {"volume_mm3", region.volume},
          {"depth_mm", region.depth},
          {"deepest_point", to_json(region.deepest)},
          {"bbox", {{"min", to_json(region.box.min)}, {"max", to_json(region.box.max)}}},
          {"lines_a", diff_lines_json(region.lines_a)},
          {"lines_b", diff_lines_json(region.lines_b)},
          {"changed_lines_a", diff_lines_json(region.changed_a)},
          {"changed_lines_b", diff_lines_json(region.changed_b)},
          {"tools_a", region.tools_a},
          {"tools_b", region.tools_b},
          {"subprogram_lines_a", region.sub_a},
          {"subprogram_lines_b", region.sub_b}};
}

Json diff_report(const DiffOptions& options, const DiffRun& run, bool different) {
  Json report;
  report["program_a"] = options.program;
  report["program_b"] = options.program_b;
  report["verdict"] = different ? "different" : "same";
  report["tolerance_mm"] = run.tolerance;
  report["tolerance_source"] = run.tolerance_source;
  report["stock"] = run.a.stock.description;
  report["dexel"] = {{"cell_mm", run.a.lattice.spacing},
                     {"res", {run.a.lattice.n.x, run.a.lattice.n.y, run.a.lattice.n.z}}};
  report["volume_a_mm3"] = run.a.volume;
  if (!run.error_b) report["volume_b_mm3"] = run.b.volume;
  Json regions = Json::array();
  for (std::size_t k = 0; k < run.regions.size() && k < kDiffRegionsListed; ++k)
    regions.push_back(diff_region_json(run.regions[k]));
  report["regions"] = regions;
  report["regions_count"] = run.regions.size();
  Json lint = Json::array();
  for (const LintFinding& f : run.lint_b) lint.push_back(lint_json(f));
  if (run.error_b) {
    Json e = lint_json(*run.error_b);
    if (int c = changed_at_or_before(run.alignment.changed_b, run.error_b->line); c > 0)
      e["changed_line"] = c;
    lint.push_back(e);
  }
  report["lint"] = lint;
  Json lint_a = Json::array();
  for (const LintFinding& f : run.lint_a) lint_a.push_back(lint_json(f));
  report["lint_a"] = lint_a;
  int changed_a = 0, changed_b = 0;
  for (char c : run.alignment.changed_a) changed_a += c;
  for (char c : run.alignment.changed_b) changed_b += c;
  report["changed_lines"] = {{"a", changed_a}, {"b", changed_b}};
  report["warnings_a"] = run.a.warnings;
  report["warnings_b"] = run.b.warnings;
  return report;
}

std::string diff_lines_text(const std::string& file, const std::set<int>& lines) {
  std::string out;
  std::size_t count = 0;
  for (int line : lines)
    if (count++ < 12) out += (out.empty() ? "" : ", ") + file + ":" + std::to_string(line);
  if (count > 12) out += ", … (" + std::to_string(count) + " in all)";
  return out.empty() ? "none" : out;
}

void print_diff(const DiffRun& run, bool different) {
  std::printf("%s vs %s: %zu region(s) differ beyond %g mm (%s), %zu lint finding(s)%s: %s\n",
              run.file_a.c_str(), run.file_b.c_str(), run.regions.size(), run.tolerance,
              run.tolerance_source.c_str(), run.lint_b.size(),
              run.error_b ? ", B does not run" : "", different ? "DIFFERENT" : "same");
  for (std::size_t k = 0; k < run.regions.size() && k < kDiffRegionsWithLines; ++k) {
    const DiffRegion& g = run.regions[k];
    std::printf("  %s %.4g mm3, %.3f mm deep at (%.3f, %.3f, %.3f)\n",
                g.removed ? "removed by B" : "left by B", g.volume, g.depth, g.deepest.x,
                g.deepest.y, g.deepest.z);
    std::printf("    changed: %s; %s\n", diff_lines_text(run.file_b, g.changed_b).c_str(),
                diff_lines_text(run.file_a, g.changed_a).c_str());
    std::printf("    B lines %s\n    A lines %s\n", diff_lines_text(run.file_b, g.lines_b).c_str(),
                diff_lines_text(run.file_a, g.lines_a).c_str());
  }
  for (const LintFinding& f : run.lint_b)
    std::printf("  %s\n", terminal_safe(lint_text_line(f)).c_str());
  if (run.error_b) std::printf("  %s\n", terminal_safe(lint_text_line(*run.error_b)).c_str());
}

// B on A's stock: the same box (an automatic stock is A's), the same file, so the same lattice.
DiffOptions options_for_b(const DiffOptions& options, const SimulationResult& a) {
  DiffOptions b = options;
  b.program = options.program_b;
  if (a.stock.mesh) {
    b.stock = a.stock.description["file"].get<std::string>();
  } else {
    char box[256];
    std::snprintf(box, sizeof box, "box:%.17g,%.17g,%.17g,%.17g,%.17g,%.17g", a.stock.box.min.x,
                  a.stock.box.min.y, a.stock.box.min.z, a.stock.box.max.x, a.stock.box.max.y,
                  a.stock.box.max.z);
    b.stock = box;
  }
  return b;
}

// --png and --html: B's surface coloured by its signed distance to A's (deviation.hpp, A's solid
// deciding the sign where the faces cannot), as check colours the result by the design: red where
// B removed A's material beyond the tolerance, blue where it left material A removed; the page
// lists the regions as findings with their lines in B and shows A's surface as the ghost.
void write_diff_pictures(const DiffOptions& options, DiffRun& run, const Json& report,
                         Progress& progress) {
  if (run.error_b) {
    std::fprintf(stderr, "warning: B does not run: no --png or --html written\n");
    return;
  }
  const Mesh& mesh = run.b.mesh;
  std::vector<double> deviation(mesh.positions.size(), 0.0);
  std::vector<glm::vec3> colours(mesh.positions.size(), glm::vec3(0.70f, 0.76f, 0.70f));
  if (!mesh.triangles.empty() && !run.a.mesh.triangles.empty()) {
    progress.stage("measuring B's surface against A's");
    const DistanceTree a_tree(run.a.mesh);
    for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
      deviation[v] = a_tree.signed_distance(
          Vec3(mesh.positions[v]), [&](const Vec3& p) { return contains(run.a.result, p); });
      if (deviation[v] < -run.tolerance) colours[v] = glm::vec3(0.86f, 0.16f, 0.14f);
      if (deviation[v] > run.tolerance) colours[v] = glm::vec3(0.18f, 0.40f, 0.90f);
    }
  }
  if (!options.png.empty()) {
    progress.stage("rendering " + options.png);
    if (mesh.triangles.empty()) {
      std::fprintf(stderr, "warning: B leaves no material: %s was not written\n",
                   options.png.c_str());
    } else {
      render::MeshRenderOptions view;
      view.vertex_colours = colours;
      render::Image image = render::render_mesh(mesh, view);
      char removed[64], left[64];
      std::snprintf(removed, sizeof removed, "removed by B > %.3g mm", run.tolerance);
      std::snprintf(left, sizeof left, "left by B > %.3g mm", run.tolerance);
      render::draw_legend(image, {{glm::vec3(0.86f, 0.16f, 0.14f), removed},
                                  {glm::vec3(0.70f, 0.76f, 0.70f), "the same"},
                                  {glm::vec3(0.18f, 0.40f, 0.90f), left}});
      write_file_atomically(options.png, render::encode_png(image));
    }
  }
  if (!options.html.empty()) {
    progress.stage("writing " + options.html);
    Json page_report = report;
    page_report["program"] = run.file_b;
    page_report["tolerances_mm"] = {{"gouge", run.tolerance}, {"excess", run.tolerance}};
    // The page's legend and summary read check's deviation figures: B's surface against A's.
    if (!deviation.empty()) {
      const auto [lo, hi] = std::minmax_element(deviation.begin(), deviation.end());
      double sum = 0, sum2 = 0;
      for (double d : deviation) sum += d, sum2 += d * d;
      const double n = static_cast<double>(deviation.size());
      page_report["deviation"] = {{"samples", deviation.size()},
                                  {"min_mm", *lo},
                                  {"max_mm", *hi},
                                  {"mean_mm", sum / n},
                                  {"rms_mm", std::sqrt(sum2 / n)}};
    }
    write_html_report(options.html,
                      {.title = "tridex diff: " + fs::path(run.file_b).filename().string() +
                                " against " + fs::path(run.file_a).filename().string(),
                       .report = page_report,
                       .mesh = &mesh,
                       .deviation = deviation,
                       .design = &run.a.mesh,
                       .groups = &run.b.groups,
                       .order = run.b.order,
                       .files = run.b.files,
                       .stock = &run.b.stock,
                       .cutters = run.b.cutters,
                       .bodies = run.b.bodies,
                       .cutter_of_tool = &run.b.cutter_of_tool});
  }
}

}  // namespace

int run_diff(const DiffOptions& options) {
  Progress progress(!options.quiet && (options.progress || stderr_is_terminal()));
  PipelineRequest request;
  if (!options.report.empty()) request.outputs.push_back({"--report", options.report});
  request.extra_inputs = {options.program, options.program_b};
  request.clip_to_reach = false;  // A's and B's moves reach apart: one lattice over the stock
  DiffRun run;
  for (const auto& [option, path] :
       {std::pair<std::string, std::string>{"--png", options.png}, {"--html", options.html}})
    if (!path.empty()) request.outputs.push_back({option, path});
  run.a = simulate_program(options, progress, request);
  const DiffOptions for_b = options_for_b(options, run.a);
  if (options.tools.empty()) request.tools = run.a.input.tools;  // a project A's table for B
  run.file_a = run.a.input.files.at(0).string();
  run.text_a = read_text_file(run.a.input.files.at(0), "a G-code file");
  const ProgramInput input_b = resolve_program(for_b);
  run.file_b = input_b.files.at(0).string();
  run.text_b = read_text_file(input_b.files.at(0), "a G-code file");
  run.alignment = align_lines(run.text_a, run.text_b);
  lint_both(run, run.a.input.machine);
  try {
    run.b = simulate_program(for_b, progress, request);
  } catch (const gcode::GcodeError& e) {
    run.error_b = lint_error_finding(e.where.file, e.where.line, e.where.message);
  } catch (const InputError& e) {  // B names a tool the table lacks, runs past --max-moves, …
    const std::string message = e.what();
    const std::size_t at = message.find(run.file_b + ":");  // "bug.nc:63: tool 7 is …"
    const int line =
        at == std::string::npos ? 0 : std::atoi(message.c_str() + at + run.file_b.size() + 1);
    run.error_b = LintFinding{run.file_b, line, "program_error", message};
  }
  run.tolerance = options.tolerance > 0 ? options.tolerance : 0.5 * run.a.lattice.spacing;
  run.tolerance_source = options.tolerance > 0 ? "given" : "half the dexel spacing; --tolerance";
  if (!run.error_b) {
    if (!(run.a.result.lattice() == run.b.result.lattice()))
      throw std::runtime_error("diff: the two programs ran on different lattices");
    progress.stage("comparing the solids");
    run.spans = solid_differences(run.a.result, run.b.result, run.tolerance);
    run.regions = connect_spans(run.spans, run.a.result);
    measure_regions(run.regions, run.spans, run.a.result);
    const std::map<int, int> tools_a = line_tools(run.a), tools_b = line_tools(run.b);
    for (std::size_t k = 0; k < run.regions.size() && k < kDiffRegionsWithLines; ++k)
      attribute_region(run.regions[k], run, tools_a, tools_b);
  }
  const bool different = !run.regions.empty() || !run.lint_b.empty() || run.error_b;
  Json report = diff_report(options, run, different);
  if (!run.error_b && !run.b.files.empty()) report["file_b"] = run.b.files.front();
  if (!options.report.empty()) {
    progress.stage("writing " + options.report);
    write_file_atomically(options.report, dump_json(report, 2) + "\n");
  }
  if (!options.png.empty() || !options.html.empty())
    write_diff_pictures(options, run, report, progress);
  progress.finish();
  if (!options.quiet) print_diff(run, different);
  return different ? kFindings : kSuccess;
}

}  // namespace tridex::cli

namespace tridex::cli {

// tridex lint: the post lint of the program's files, and the interpreter's verdict on it.
int run_lint(const LintOptions& options) {
  const ProgramInput input = resolve_program(options);
  if (!options.report.empty())
    check_output_path("--report", options.report, files_read(options, input));
  LintSettings settings;
  settings.decimal_point_input = input.machine.decimal_point_input;
  settings.linuxcnc = input.machine.dialect == gcode::Dialect::linuxcnc;
  std::vector<LintFinding> findings;
  for (const fs::path& file : input.files) {
    std::vector<LintFinding> own =
        lint_text(read_text_file(file, "a G-code file"), file.string(), settings);
    findings.insert(findings.end(), own.begin(), own.end());
  }
  try {
    interpret(
        input, interpreter_options(options), [](const gcode::Move&, std::size_t) {}, {},
        options.max_moves);
  } catch (const gcode::GcodeError& e) {
    findings.push_back(lint_error_finding(e.where.file, e.where.line, e.where.message));
  }
  if (!options.report.empty()) {
    Json list = Json::array();
    for (const LintFinding& f : findings) list.push_back(lint_json(f));
    write_file_atomically(options.report,
                          dump_json(Json{{"program", options.program},
                                         {"verdict", findings.empty() ? "clean" : "findings"},
                                         {"findings", list}},
                                    2) +
                              "\n");
  }
  if (!options.quiet) {
    for (const LintFinding& f : findings)
      std::printf("%s\n", terminal_safe(lint_text_line(f)).c_str());
    std::printf("%s: %zu lint finding(s)\n", options.program.c_str(), findings.size());
  }
  return findings.empty() ? kSuccess : kFindings;
}

}  // namespace tridex::cli
