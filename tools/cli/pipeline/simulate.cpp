// tridex simulate — the paper's pipeline from a program to a solid (Inui, Chen and Umezu,
// "Visualization of 3+2 Axis Machining Result by Combining Multiple Z-map Models", CAD&A 19(4)
// 2022, §3), run by pipeline.cpp; this file writes the STL, the picture and the report.
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <iostream>

#include <nlohmann/json.hpp>

#include "commands.hpp"
#include "errors.hpp"
#include "json_text.hpp"
#include "outputs/html_report.hpp"
#include "outputs/output.hpp"
#include "outputs/result_files.hpp"
#include "pipeline/memory.hpp"
#include "pipeline/pipeline.hpp"
#include "pipeline/progress.hpp"
#include "pipeline/shop_summary.hpp"
#include "render.hpp"
#include "tridex/dexel_ops.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

// The stock less the result's volume: the uncut stock's surface volume less the result's
// (pipeline.cpp, surface_volume). Where rounding makes that negative (cuts finer than the lattice
// around a large stock), what the lattice resolves as removed: never a negative removal.
double removed_mm3(const SimulationResult& r) {
  const double removed = r.stock.volume - r.volume;
  return removed >= 0 ? removed : std::max(0.0, r.stock_dexel_volume - r.result_dexel_volume);
}

// "simultaneous 5-axis: N moves (T3: n moves, s sub-steps, band ≤ e mm)", and with --certify
// every tool's worst band against the tolerance.
std::string simultaneous_text(const SimulationResult& r) {
  char text[200];
  std::string out = "simultaneous 5-axis:";
  for (const auto& [tool, s] : r.sweeps) {
    std::snprintf(text, sizeof text, " T%d %lld move%s, %lld sub-steps, band <= %.3g mm;", tool,
                  s.moves, s.moves == 1 ? "" : "s", s.sub_steps, s.band);
    out += text;
  }
  std::snprintf(text, sizeof text, " tolerance %.3g mm", r.sweep_tolerance);
  return out + text;
}

// The JSON report (docs/reports.md), with the run's total time and the rapids that cut.
Json simulate_report(const SimulateOptions& options, const SimulationResult& r,
                     const Json& rapid_findings, double total_s) {
  const ProgramInput& input = r.input;
  const std::vector<gcode::MoveGroup>& groups = r.groups;
  const Stock& stock = r.stock;
  const DexelLattice& lattice = r.lattice;
  const MeshCheck& check = r.mesh_check;
  const double volume = r.volume;
  Json report;
  report["program"] = input.program.string();
  if (input.files.size() != 1 || input.files[0] != input.program) {
    Json files = Json::array();
    for (const fs::path& f : input.files) files.push_back(f.string());
    report["files"] = files;
  }
  report["stock"] = stock.description;
  report["segments"] = r.segments;
  Json group_list = Json::array();
  for (std::size_t g = 0; g < groups.size(); ++g)
    group_list.push_back({{"axis", to_json(groups[g].axis)},
                          {"moves", groups[g].moves.size()},
                          {"tools", groups[g].tools},
                          {"zmap", {r.grids[g].nx, r.grids[g].ny}},
                          {"cell_mm", r.zmap_cell}});
  report["groups"] = group_list;
  report["dexel"] = {{"cell_mm", lattice.spacing},
                     {"res", {lattice.n.x, lattice.n.y, lattice.n.z}}};
  report["backends"] = {{"zmap", options.zmap_backend}, {"dexel", options.dexel_backend}};
  report["memory_estimate_mib"] = r.memory.total() / (1 << 20);
  report["memory_walls_mib"] = r.memory.walls / (1 << 20);
  report["timings_s"] = {{"parse", r.timings.parse},       {"zmap", r.timings.zmap},
                         {"dexelize", r.timings.dexelize}, {"intersect", r.timings.intersect},
                         {"mesh", r.timings.mesh},         {"total", total_s}};
  report["peak_rss_mib"] = peak_rss_mib();
  report["result"] = {{"volume_mm3", volume},
                      {"removed_mm3", removed_mm3(r)},
                      {"dexel_volume_mm3", tridex::volume(r.result)},
                      {"triangles", r.mesh.triangles.size()},
                      {"watertight", check.closed()}};
  report["rapid_cuts"] = rapid_findings;
  report["machining_time"] = machining_time_json(r.machining);
  if (!r.simultaneous.empty()) report["simultaneous"] = sweeps_json(r);  // absent for 3+2
  report["warnings"] = r.warnings;
  return report;
}

// What simulate asks of the pipeline: its outputs checked up front, the HTML page's memory
// counted, and the STL written as soon as the surface is there, beside its check (pipeline.hpp).
PipelineRequest simulate_request(const SimulateOptions& options, Progress& progress) {
  PipelineRequest request;
  request.outputs = {{"-o", options.output},
                     {"--png", options.png},
                     {"--report", options.report},
                     {"--html", options.html}};
  // The page's copy of the surface, encoded, next to the surface itself (measured about 35 bytes
  // a triangle counted).
  if (!options.html.empty())
    request.memory_after = [](double, double triangles) { return 60.0 * triangles; };
  if (!options.output.empty())
    request.surface_ready = [&options, &progress](const Mesh& surface) {
      progress.stage("writing " + options.output);
      write_stl_file(options.output, surface, options.threads);
    };
  return request;
}

}  // namespace

int run_simulate(const SimulateOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  Progress progress(!options.quiet && (options.progress || stderr_is_terminal()));
  SimulationResult r = simulate_program(options, progress, simulate_request(options, progress));
  const ProgramInput& input = r.input;
  const std::vector<gcode::MoveGroup>& groups = r.groups;
  const DexelLattice& lattice = r.lattice;
  const Mesh& mesh = r.mesh;
  const MeshCheck& check = r.mesh_check;
  const double volume = r.volume;
  const long long segments = r.segments;
  std::vector<std::string>& warnings = r.warnings;
  Json rapid_findings = Json::array();
  for (const RapidFinding& f : r.rapid_cuts)
    rapid_findings.push_back(rapid_finding_json(f, r.files));
  if (!rapid_findings.empty()) {
    std::string lines;
    for (std::size_t k = 0; k < rapid_findings.size() && k < 10; ++k)
      lines += (k ? ", " : "") + rapid_findings[k]["file"].get<std::string>() + ":" +
               std::to_string(rapid_findings[k]["line"].get<int>());
    warnings.push_back(std::to_string(rapid_findings.size()) +
                       " rapid move(s) cut material that no feed move removes (at " + lines +
                       (rapid_findings.size() > 10 ? ", …" : "") +
                       "; see \"rapid_cuts\" in the report)");
  }
  if (r.travel_count > 0) {
    const TravelFinding& f = r.travel.front();
    warnings.push_back(std::to_string(r.travel_count) +
                       " position(s) outside the machine's travel (first " +
                       r.files.at(static_cast<std::size_t>(f.file)) + ":" + std::to_string(f.line) +
                       ": " + travel_text(f) + "; `tridex check` lists each)");
  }

  // ---- outputs ------------------------------------------------------------------------------
  bool png_written = !options.png.empty();
  if (!options.png.empty()) {
    progress.stage("rendering " + options.png);
    if (mesh.triangles.empty()) {
      warnings.push_back("no material is left: " + options.png + " was not written");
      png_written = false;
    } else {
      write_file_atomically(options.png, render::encode_png(render::render_mesh(mesh)));
    }
  }
  const double total_s =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  if (!check.closed())
    warnings.push_back("the result mesh is not watertight (" +
                       std::to_string(check.boundary_edges) + " boundary, " +
                       std::to_string(check.non_manifold_edges) + " non-manifold edges)");

  const Json report = simulate_report(options, r, rapid_findings, total_s);
  if (!options.report.empty()) {
    progress.stage("writing " + options.report);
    write_file_atomically(options.report, dump_json(report, 2) + "\n");
  }
  if (!options.html.empty()) {
    progress.stage("writing " + options.html);
    write_html_report(options.html,
                      {.title = "tridex simulate: " + input.program.filename().string(),
                       .report = report,
                       .mesh = &mesh,
                       .deviation = {},
                       .groups = &groups,
                       .order = r.order,
                       .files = r.files,
                       .stock = &r.stock,
                       .cutters = r.cutters,
                       .bodies = r.bodies,
                       .cutter_of_tool = &r.cutter_of_tool});
  }
  progress.finish();
  if (options.certify) {  // on stdout even with --quiet: it is what was asked for
    std::printf("certify: sweep tolerance %.6g mm (a tenth of the dexel spacing)\n",
                r.sweep_tolerance);
    for (const auto& [tool, s] : r.sweeps)
      std::printf(
          "certify: tool %d: %lld simultaneous move%s, %lld sub-steps, worst band e = "
          "%.6g mm%s\n",
          tool, s.moves, s.moves == 1 ? "" : "s", s.sub_steps, s.band,
          s.band <= r.sweep_tolerance ? "" : " (OVER the tolerance)");
    if (r.sweeps.empty()) std::printf("certify: no simultaneous moves\n");
  }

  if (!options.quiet) {
    for (const std::string& w : warnings) std::cerr << "warning: " << terminal_safe(w) << '\n';
    std::string written;
    // Only what was written: a picture of nothing is not.
    for (const std::string& path :
         {options.output, png_written ? options.png : std::string(), options.report, options.html})
      if (!path.empty()) written += (written.empty() ? " -> " : ", ") + path;
    std::printf(
        "%s: %lld segment%s in %zu direction%s, %d x %d x %d dexels; %.1f mm^3 left, %.1f mm^3 "
        "removed, %zu triangles, %s%s; %.2f s\n",
        input.program.filename().string().c_str(), segments, segments == 1 ? "" : "s",
        groups.size(), groups.size() == 1 ? "" : "s", lattice.n.x, lattice.n.y, lattice.n.z, volume,
        removed_mm3(r), mesh.triangles.size(), check.closed() ? "watertight" : "NOT watertight",
        written.c_str(), total_s);
    std::printf("  %s\n", machining_time_text(r.machining).c_str());
    std::printf("  %s\n  %s\n", tools_text(r).c_str(), directions_text(r).c_str());
    if (!r.simultaneous.empty()) std::printf("  %s\n", simultaneous_text(r).c_str());
  }
  return kSuccess;
}

}  // namespace tridex::cli
