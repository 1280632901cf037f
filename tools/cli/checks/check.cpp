// tridex check — the machined result against the design, rapids that cut, moves outside an
// envelope (issue 7). The result comes from simulate's pipeline (pipeline.hpp, Inui, Chen and
// Umezu, CAD&A 19(4) 2022), with rapids checked in program order.
//
// Deviation: for every vertex of the machined mesh, the distance to the design surface, negative
// when the vertex lies inside the design (material removed that the part needs: a gouge) and
// positive outside (material left: excess); see deviation.hpp for the distance and its sign.
// Out-of-tolerance vertices joined by mesh edges form regions. A gouge region's moves are those
// whose swept cutter reaches its deepest vertices: in a group's frame, p is reached by a move when
// p.z ≥ S(p.x, p.y) − one dexel spacing (S the move's swept lower surface, MoveGeometry), the
// spacing absorbing the surface's resolution.
//
// The design side: a part feature cut away entirely (a thin rib) can leave a machined surface
// that lies on the design everywhere, so points on the design's surface (its vertices and samples
// about two dexel spacings apart, at most 4 million) are measured against the machined surface too
// (signed by the result's triple dexel): a design sample outside the machined solid beyond
// --gouge-tol is material missing, one inside beyond
// --excess-tol is material left. These are counted and bounded, not split into regions.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <iostream>
#include <set>

#include "checks/deviation.hpp"
#include "checks/machine_run.hpp"
#include "checks/reaching_moves.hpp"
#include "commands.hpp"
#include "errors.hpp"
#include "inputs/numbers.hpp"
#include "inputs/stock.hpp"
#include "outputs/html_report.hpp"
#include "outputs/output.hpp"
#include "outputs/result_files.hpp"
#include "pipeline/memory.hpp"
#include "pipeline/pipeline.hpp"
#include "pipeline/shop_summary.hpp"
#include "render.hpp"
#include "tridex/dexel_ops.hpp"
#include "tridex/dexelize.hpp"
#include "tridex/mill.hpp"
#include "tridex/parallel.hpp"
#include "tridex/stl.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

constexpr glm::vec3 kGougeColour{0.86f, 0.16f, 0.14f};
constexpr glm::vec3 kOkColour{0.70f, 0.76f, 0.70f};
constexpr glm::vec3 kExcessColour{0.18f, 0.40f, 0.90f};
constexpr std::size_t kRegionsListed = 100;  // per kind, deepest first
constexpr std::size_t kRegionsWithLines = 20;
constexpr std::size_t kFindingsListed = 1000;   // envelope violations in the report, in line order
constexpr std::size_t kFindingsPrinted = 20;    // of each kind on stdout
constexpr std::size_t kProbesPerRegion = 16;    // deepest vertices tested against the moves
constexpr std::size_t kExcessLinesListed = 20;  // the nearest lines of an excess region
constexpr int kHistogramBins = 20;
constexpr std::size_t kMaxDesignSamples = 4'000'000;

// Runs body(k) for k in [0, n) on `threads` threads (0: every hardware thread), in blocks of 4096.
template <class Body>
void parallel_for(std::size_t n, unsigned threads, const Body& body) {
  constexpr std::size_t kBlock = 4096;
  detail::for_each_chunk((n + kBlock - 1) / kBlock, threads, [&](std::size_t c) {
    for (std::size_t k = c * kBlock; k < std::min(n, (c + 1) * kBlock); ++k) body(k);
  });
}

Json statistics(std::vector<double> values) {
  Json s;
  s["samples"] = values.size();
  if (values.empty()) return s;
  std::sort(values.begin(), values.end());
  double sum = 0, sum2 = 0;
  for (double v : values) sum += v, sum2 += v * v;
  const double n = static_cast<double>(values.size());
  auto percentile = [&](double q) {
    return values[static_cast<std::size_t>(std::round(q / 100 * (n - 1)))];
  };
  s["min_mm"] = values.front();
  s["max_mm"] = values.back();
  s["mean_mm"] = sum / n;
  s["rms_mm"] = std::sqrt(sum2 / n);
  s["percentiles_mm"] = {{"p1", percentile(1)},   {"p5", percentile(5)},   {"p25", percentile(25)},
                         {"p50", percentile(50)}, {"p75", percentile(75)}, {"p95", percentile(95)},
                         {"p99", percentile(99)}};
  // Equal bins over [min, max]; the last bin includes max.
  const double lo = values.front(), hi = values.back(), width = (hi - lo) / kHistogramBins;
  std::vector<long long> counts(kHistogramBins, 0);
  for (double v : values) {
    int bin = width > 0 ? static_cast<int>((v - lo) / width) : 0;
    ++counts[static_cast<std::size_t>(std::clamp(bin, 0, kHistogramBins - 1))];
  }
  Json edges = Json::array();
  for (int b = 0; b <= kHistogramBins; ++b) edges.push_back(lo + b * width);
  s["histogram"] = {{"edges_mm", edges}, {"counts", counts}};
  return s;
}

// Source lines of the moves whose swept cutter reaches the region's deepest vertices, as
// (Move::file, line) pairs.
std::vector<std::pair<int, int>> gouging_lines(const DeviationRegion& region, const Mesh& mesh,
                                               const std::vector<double>& deviation,
                                               const SimulationResult& r, double slack) {
  std::vector<std::uint32_t> probes = region.vertices;
  std::size_t keep = std::min(kProbesPerRegion, probes.size());
  std::partial_sort(probes.begin(), probes.begin() + static_cast<std::ptrdiff_t>(keep),
                    probes.end(),
                    [&](std::uint32_t a, std::uint32_t b) { return deviation[a] < deviation[b]; });
  probes.resize(keep);
  std::vector<Vec3> points;
  for (std::uint32_t v : probes) points.emplace_back(mesh.positions[v]);
  std::set<std::pair<int, int>> lines;
  for_each_reaching_move(r, points, slack, [&](const gcode::Move& m) {
    lines.insert({m.file, m.line});
  });
  return {lines.begin(), lines.end()};
}

// The moves nearest an excess region (reaching_moves.hpp: nearest_moves), from its highest
// vertices: those whose swept cutter passes within the region's depth and one dexel spacing of
// them (a move that should have removed the material reaches the design there, at most the depth
// below), else the nearest. "lines", "files" (as a gouge's), "tools" and "nearest_mm".
void add_excess_lines(Json& g, const DeviationRegion& region, const Mesh& mesh,
                      const std::vector<double>& deviation, const SimulationResult& r) {
  std::vector<std::uint32_t> probes = region.vertices;
  const std::size_t keep = std::min(kProbesPerRegion, probes.size());
  std::partial_sort(probes.begin(), probes.begin() + static_cast<std::ptrdiff_t>(keep),
                    probes.end(),
                    [&](std::uint32_t a, std::uint32_t b) { return deviation[a] > deviation[b]; });
  probes.resize(keep);
  std::vector<Vec3> points;
  for (std::uint32_t v : probes) points.emplace_back(mesh.positions[v]);
  const double spacing = r.lattice.spacing;
  const std::vector<NearMove> near =
      nearest_moves(r, points, region.depth + spacing, spacing, kExcessLinesListed);
  std::set<std::pair<int, int>> lines;
  std::set<int> tools;
  for (const NearMove& m : near)
    lines.insert({m.move->file, m.move->line}), tools.insert(m.move->tool);
  Json line_list = Json::array(), files = Json::array();
  for (const auto& [file, line] : lines) {
    line_list.push_back(line);
    files.push_back(r.files.at(static_cast<std::size_t>(file)));
  }
  g["lines"] = line_list;
  g["files"] = files;
  g["tools"] = tools;
  if (!near.empty()) g["nearest_mm"] = near.front().gap;
}

Json region_json(const DeviationRegion& region, const Mesh& mesh,
                 const std::vector<double>& deviation) {
  return {{"depth_mm", region.depth},
          {"deepest_point", to_json(Vec3(mesh.positions[region.deepest]))},
          {"deviation_mm", deviation[region.deepest]},
          {"centroid", to_json(region.centroid)},
          {"bbox", {{"min", to_json(region.box.min)}, {"max", to_json(region.box.max)}}},
          {"area_mm2", region.area},
          {"vertices", region.vertices.size()}};
}

// ---- run_check's stages, in the order it runs them -----------------------------------------

// What check reads besides what the pipeline reads: the design and the envelope.
struct CheckInputs {
  std::optional<Aabb> envelope;
  Mesh design;
};

// Inputs that the pipeline does not know, checked before any work.
CheckInputs read_check_inputs(const CheckOptions& options, Progress& progress) {
  CheckInputs in;
  // The rapid check reads each direction's Z-map between batches with the kernel's cut_depth; the
  // GL backend's maps do not agree with it (simulate --zmap-backend gl lists retracts through cut
  // space as rapid cuts), so check keeps to the exact kernel milling.
  if (options.zmap_backend != "cpu")
    input_error("--zmap-backend ", options.zmap_backend,
                ": check needs the kernel's exact milling (cpu) for its rapid check");
  if (!options.envelope.empty()) in.envelope = parse_envelope(options.envelope);
  progress.stage("reading the design " + options.design);
  Mesh& design = in.design;
  try {
    design = read_stl(options.design, StlOptions{.require_closed = true,
                                                 .max_bytes = max_memory_bytes(options.max_memory),
                                                 .limit_name = "--max-memory"});
  } catch (const tridex::Error& e) {
    input_error("--design: ", e.what());
  }
  if (!(design.signed_volume() > 0))
    input_error("--design ", options.design, ": the mesh encloses no volume (",
                design.signed_volume(), " mm^3); are its triangles inside out?");
  return in;
}

double gouge_tolerance(const CheckOptions& options) {
  return options.gouge_tol > 0   ? options.gouge_tol
         : options.tolerance > 0 ? options.tolerance
                                 : kShopTolerance;
}

// The pipeline as check runs it: rapids and shanks and holders in program order, the design's
// bounds on the lattice, and the comparison's memory counted up front.
PipelineRequest check_request(const CheckOptions& options, const Mesh& design) {
  PipelineRequest request;
  request.outputs = {{"-o", options.output},
                     {"--report", options.report},
                     {"--png", options.png},
                     {"--ply", options.ply},
                     {"--html", options.html}};
  request.extra_inputs = {options.design};
  request.extra_bounds = {{"--design " + options.design, design.bounds()}};
  request.rapid_check = RapidCheck::in_program_order;
  // After the surface: the design's and the result's distance trees (about 130 bytes a triangle,
  // measured), the deviations and colours of the result's vertices (about half as many as its
  // triangles), and the design samples with their deviations (a point and a double each).
  request.memory_after = [&design](double spacing, double triangles) {
    double samples = static_cast<double>(design.positions.size());
    for (const glm::uvec3& t : design.triangles) {
      Vec3 a(design.positions[t.x]), b(design.positions[t.y]), c(design.positions[t.z]);
      double longest = std::max({glm::length(b - a), glm::length(c - b), glm::length(a - c)});
      samples += std::pow(std::max(1.0, std::ceil(longest / (2 * spacing))), 2);
    }
    samples = std::min(samples, static_cast<double>(kMaxDesignSamples));
    return 130.0 * static_cast<double>(design.triangles.size()) + (130.0 + 12.0) * triangles +
           (sizeof(Vec3) + sizeof(double)) * samples;
  };
  request.body_clearance = options.clearance;
  // The lattice resolves the gouge tolerance (pipeline/resolution.hpp); with --lattice-only a
  // coarser one given is reported, not refused.
  request.resolve_gouges = gouge_tolerance(options);
  request.lattice_only = options.lattice_only;
  // The design and its samples are measured on the lattice: it covers the whole stock.
  request.clip_to_reach = false;
  return request;
}

// What check finds, filled stage by stage and read by the files, the report and the summary.
struct CheckFindings {
  double gouge_tol = 0, excess_tol = 0;  // mm
  std::string tolerance_source;          // where they came from, for the summary and report
  std::vector<double> deviation;         // per vertex of the machined mesh
  std::vector<glm::vec3> colours;        // per vertex: gouge, within tolerance or excess
  std::vector<DeviationRegion> gouges, excesses;
  Json design_side;
  Json gouge_list = Json::array(), excess_list = Json::array();
  Json rapid_list = Json::array();
  Json collision_list = Json::array(), near_list = Json::array(), stick_out = Json::array();
  Json envelope_list = Json::array();
  std::size_t envelope_outside = 0;
  Json travel_list = Json::array();
  // What could not be checked (the verdict does not cover it): said on the verdict line, in the
  // report's "not_checked" and next to the page's verdict.
  std::vector<std::string> not_checked;
};

// A finding's file: the name of Move::file's entry, as --report's "files" and messages give it.
std::string file_name(const SimulationResult& r, int file) {
  return r.files.at(static_cast<std::size_t>(file));
}

// The deviation of the machined surface from the design, its colours and its regions.
// --allowance at `p`: what must be left there at least. Near a box stock's faces, where the design
// meets the stock's side unmachined, no more than the distance to the face can be left.
double allowance_at(const CheckOptions& options, const SimulationResult& r, const Vec3& p) {
  if (options.allowance <= 0 || r.stock.mesh) return options.allowance;
  double least = options.allowance;
  for (int a = 0; a < 3; ++a)
    least =
        std::min({least, std::abs(p[a] - r.stock.box.min[a]), std::abs(p[a] - r.stock.box.max[a])});
  return least;
}

void measure_deviation(const CheckOptions& options, const SimulationResult& r, const Mesh& design,
                       Progress& progress, CheckFindings& f) {
  const Mesh& mesh = r.mesh;
  progress.stage("dexelizing the design");
  TripleDexel design_dexel = dexelize(design, r.lattice, DexelizeOptions{options.threads});
  progress.stage("measuring " + std::to_string(mesh.positions.size()) +
                 " vertices against the design");
  DistanceTree design_tree(design);
  std::vector<double>& deviation = f.deviation;
  deviation.resize(mesh.positions.size());
  parallel_for(mesh.positions.size(), options.threads, [&](std::size_t v) {
    deviation[v] = design_tree.signed_distance(
        Vec3(mesh.positions[v]), [&](const Vec3& p) { return contains(design_dexel, p); });
  });
  std::vector<char> gouge(deviation.size()), excess(deviation.size());
  f.colours.assign(deviation.size(), kOkColour);
  for (std::size_t v = 0; v < deviation.size(); ++v) {
    // --allowance: a machined surface should stand that far outside the design (issue 39); the
    // stock's own faces, where the design meets them, are not machined.
    const double allowance = allowance_at(options, r, Vec3(mesh.positions[v]));
    gouge[v] = deviation[v] < allowance - f.gouge_tol;
    excess[v] = deviation[v] > options.allowance + f.excess_tol;
    if (gouge[v]) f.colours[v] = kGougeColour;
    if (excess[v]) f.colours[v] = kExcessColour;
  }
  f.gouges = deviation_regions(mesh, deviation, gouge);
  f.excesses = deviation_regions(mesh, deviation, excess);
}

// The design side: samples of the design's surface measured against the machined surface.
void measure_design_side(const CheckOptions& options, const SimulationResult& r, const Mesh& design,
                         Progress& progress, CheckFindings& f) {
  const Mesh& mesh = r.mesh;
  const double spacing = r.lattice.spacing;
  std::vector<Vec3> samples = design_samples(design, 2 * spacing, kMaxDesignSamples);
  std::vector<double> design_deviation;
  if (!mesh.triangles.empty()) {
    progress.stage("measuring the design against the machined surface");
    DistanceTree result_tree(mesh);
    design_deviation.resize(samples.size());
    // Positive where the machined solid holds the design sample (material left outside the
    // design there), negative where it does not (material missing).
    parallel_for(samples.size(), options.threads, [&](std::size_t k) {
      design_deviation[k] = 0.0 - result_tree.signed_distance(samples[k], [&](const Vec3& p) {
        return contains(r.result, p);
      });
    });
  }
  Json& design_side = f.design_side;
  Aabb missing_box, left_box;
  long long missing = 0, left = 0;
  double missing_depth = 0, left_depth = 0;
  for (std::size_t k = 0; k < design_deviation.size(); ++k) {
    const double allowance = allowance_at(options, r, samples[k]);
    if (design_deviation[k] < allowance - f.gouge_tol)
      ++missing, missing_box.extend(samples[k]),
          missing_depth = std::max(missing_depth, -design_deviation[k]);
    if (design_deviation[k] > options.allowance + f.excess_tol)
      ++left, left_box.extend(samples[k]), left_depth = std::max(left_depth, design_deviation[k]);
  }
  if (mesh.triangles.empty())
    missing = static_cast<long long>(samples.size()), missing_box = design.bounds();
  design_side["deviation"] = statistics(design_deviation);
  design_side["missing"] = {{"samples", missing}, {"depth_mm", missing_depth}};
  if (missing)
    design_side["missing"]["bbox"] = {{"min", to_json(missing_box.min)},
                                      {"max", to_json(missing_box.max)}};
  design_side["left"] = {{"samples", left}, {"depth_mm", left_depth}};
  if (left)
    design_side["left"]["bbox"] = {{"min", to_json(left_box.min)}, {"max", to_json(left_box.max)}};
}

// The regions as the report lists them, each of the deepest gouges with the moves that made it.
void list_regions(const SimulationResult& r, Progress& progress, CheckFindings& f) {
  const Mesh& mesh = r.mesh;
  progress.stage("finding the moves that cut " + std::to_string(f.gouges.size()) +
                 " gouge region(s)");
  for (std::size_t k = 0; k < f.gouges.size() && k < kRegionsListed; ++k) {
    Json g = region_json(f.gouges[k], mesh, f.deviation);
    if (k < kRegionsWithLines) {
      // "files"[i] is the file of "lines"[i]: a program with subprogram files repeats line numbers.
      Json lines = Json::array(), files = Json::array();
      for (const auto& [file, line] :
           gouging_lines(f.gouges[k], mesh, f.deviation, r, r.lattice.spacing)) {
        lines.push_back(line);
        files.push_back(file_name(r, file));
      }
      g["lines"] = lines;
      g["files"] = files;
    }
    f.gouge_list.push_back(g);
  }
  for (std::size_t k = 0; k < f.excesses.size() && k < kRegionsListed; ++k) {
    Json g = region_json(f.excesses[k], mesh, f.deviation);
    if (k < kRegionsWithLines) add_excess_lines(g, f.excesses[k], mesh, f.deviation, r);
    f.excess_list.push_back(g);
  }
}

// The program's own findings: rapids that cut, shanks and holders in the material or near it, the
// stick-out each tool needs, moves outside the envelope or the machine's travel.
void list_program_findings(const SimulationResult& r, const std::optional<Aabb>& envelope,
                           CheckFindings& f) {
  for (const RapidFinding& finding : r.rapid_cuts)
    f.rapid_list.push_back(rapid_finding_json(finding, r.files));
  // ---- shanks and holders -------------------------------------------------------------------
  auto body_json = [&](const BodyFinding& finding, const char* measure) {
    return Json{{"file", file_name(r, finding.file)},
                {"line", finding.line},
                {"tool", finding.tool},
                {"part", finding.part},
                {measure, finding.depth_mm},
                {"point", to_json(finding.where)},
                {"axis", to_json(finding.axis)}};
  };
  for (std::size_t k = 0; k < r.body.collisions.size() && k < kFindingsListed; ++k)
    f.collision_list.push_back(body_json(r.body.collisions[k], "depth_mm"));
  for (std::size_t k = 0; k < r.body.near_misses.size() && k < kFindingsListed; ++k)
    f.near_list.push_back(body_json(r.body.near_misses[k], "distance_mm"));
  // The stick-out a program needs: the holder's lower surface rises with the stick-out, so the
  // deepest holder collision of a tool in a direction is what it must grow by.
  for (const auto& [key, depth] : r.body.holder_depth) {
    const auto& [tool, group] = key;
    const ToolBody& body = r.bodies[r.cutter_of_tool.at(tool)];
    f.stick_out.push_back({{"tool", tool},
                           {"axis", to_json(r.groups[group].axis)},
                           {"stick_out_mm", body.stick_out},
                           {"needed_mm", body.stick_out + depth + kCollisionTolerance}});
  }

  if (envelope) {
    // Positions "far along the tool axis" (home returns, reorientations) are tridex's stand-in for
    // where the machine takes the tool, not programmed points.
    const double far = 0.5 * gcode::MachineConfig::kDefaultFar;
    struct Outside {  // what the finding lists of a move (the groups read moves back by value)
      int file, line;
      Vec3 end;
    };
    std::vector<Outside> outside;
    for (const gcode::MoveGroup& group : r.groups)
      for (const gcode::Move& m : group.moves)
        if (glm::length(m.end) < far && !envelope->contains(m.end))
          outside.push_back({m.file, m.line, m.end});
    std::stable_sort(outside.begin(), outside.end(), [](const Outside& a, const Outside& b) {
      return std::pair(a.file, a.line) < std::pair(b.file, b.line);
    });
    f.envelope_outside = outside.size();
    for (std::size_t k = 0; k < outside.size() && k < kFindingsListed; ++k)
      f.envelope_list.push_back({{"file", file_name(r, outside[k].file)},
                                 {"line", outside[k].line},
                                 {"tip", to_json(outside[k].end)}});
  }

  // Machine travel (the kinematics' "travel" and rotary limits): a finding per axis and move.
  for (const TravelFinding& finding : r.travel)
    f.travel_list.push_back({{"file", file_name(r, finding.file)},
                             {"line", finding.line},
                             {"axis", std::string(1, finding.axis)},
                             {"value", finding.value},
                             {"limit", finding.limit}});
}

bool check_failed(const SimulationResult& r, const CheckFindings& f, const MachineRun& machine) {
  if (!machine.found.collisions.empty() || !machine.found.travel.empty()) return true;
  const bool design_side_finding = f.design_side["missing"]["samples"].get<long long>() > 0 ||
                                   f.design_side["left"]["samples"].get<long long>() > 0;
  return !f.gouges.empty() || !f.excesses.empty() || design_side_finding || !f.rapid_list.empty() ||
         f.envelope_outside > 0 || r.travel_count > 0 || !r.body.collisions.empty();
}

// -o, --ply and --png: the machined mesh, plain and coloured by deviation.
void write_result_files(const CheckOptions& options, SimulationResult& r, const CheckFindings& f,
                        Progress& progress) {
  const Mesh& mesh = r.mesh;
  if (!options.output.empty()) {
    progress.stage("writing " + options.output);
    write_stl_file(options.output, mesh, options.threads);
  }
  if (!options.ply.empty()) {
    progress.stage("writing " + options.ply);
    write_ply(options.ply, mesh, f.colours);
  }
  if (!options.png.empty()) {
    progress.stage("rendering " + options.png);
    if (mesh.triangles.empty()) {
      r.warnings.push_back("no material is left: " + options.png + " was not written");
    } else {
      render::MeshRenderOptions view;
      view.vertex_colours = f.colours;
      render::Image image = render::render_mesh(mesh, view);
      char gouge_label[64], excess_label[64], ok_label[64];
      std::snprintf(gouge_label, sizeof gouge_label, "gouge < -%.3g mm", f.gouge_tol);
      std::snprintf(ok_label, sizeof ok_label, "within tolerance");
      std::snprintf(excess_label, sizeof excess_label, "excess > +%.3g mm", f.excess_tol);
      render::draw_legend(
          image,
          {{kGougeColour, gouge_label}, {kOkColour, ok_label}, {kExcessColour, excess_label}});
      write_file_atomically(options.png, render::encode_png(image));
    }
  }
}

// What the lattice resolves (pipeline/resolution.hpp): the deepest gouge it can miss between its
// samples (null: a whole cut), the spacing, and the spacing before it was refined for the
// tolerance.
Json resolution_json(const CheckOptions& options, const SimulationResult& r) {
  Json j;
  j["missable_gouge_mm"] =
      std::isfinite(r.resolution.missable) ? Json(r.resolution.missable) : Json(nullptr);
  j["tool"] = r.resolution.tool;
  j["dexel_cell_mm"] = r.lattice.spacing;
  j["zmap_cell_mm"] = r.zmap_cell;
  if (r.unrefined_spacing > 0) j["refined_from_mm"] = r.unrefined_spacing;
  j["lattice_only"] = options.lattice_only;
  return j;
}

// --report's JSON (and the --html page's figures).
Json check_report(const CheckOptions& options, const SimulationResult& r,
                  const std::optional<Aabb>& envelope, const CheckFindings& f, bool failed,
                  double deviation_s, double total_s) {
  const Mesh& mesh = r.mesh;
  Json report;
  report["program"] = r.input.program.string();
  report["design"] = options.design;
  report["verdict"] = failed ? "fail" : "pass";
  report["tolerances_mm"] = {{"gouge", f.gouge_tol}, {"excess", f.excess_tol}};
  report["tolerance_source"] = f.tolerance_source;
  if (options.allowance > 0) report["allowance_mm"] = options.allowance;
  report["stock"] = r.stock.description;
  report["segments"] = r.segments;
  report["dexel"] = {{"cell_mm", r.lattice.spacing},
                     {"res", {r.lattice.n.x, r.lattice.n.y, r.lattice.n.z}}};
  report["backends"] = {{"zmap", options.zmap_backend}, {"dexel", options.dexel_backend}};
  report["resolution"] = resolution_json(options, r);
  report["deviation"] = statistics(f.deviation);
  report["gouges"] = f.gouge_list;
  report["excess"] = f.excess_list;
  report["design_side"] = f.design_side;
  report["rapid_cuts"] = f.rapid_list;
  report["collisions"] = f.collision_list;
  report["collisions_count"] = r.body.collisions.size();
  report["near_misses"] = {{"clearance_mm", options.clearance},
                           {"count", r.body.near_misses.size()},
                           {"moves", f.near_list}};
  report["stick_out"] = f.stick_out;
  report["machining_time"] = machining_time_json(r.machining);
  if (envelope)
    report["envelope"] = {
        {"box", {{"min", to_json(envelope->min)}, {"max", to_json(envelope->max)}}},
        {"outside", f.envelope_outside},
        {"violations", f.envelope_list}};
  if (r.input.machine.kinematics)
    report["travel"] = {{"outside", r.travel_count}, {"violations", f.travel_list}};
  report["result"] = {{"volume_mm3", r.volume},
                      {"triangles", mesh.triangles.size()},
                      {"watertight", r.mesh_check.closed()}};
  report["timings_s"] = {{"parse", r.timings.parse},       {"zmap", r.timings.zmap},
                         {"dexelize", r.timings.dexelize}, {"intersect", r.timings.intersect},
                         {"mesh", r.timings.mesh},         {"collisions", r.body.seconds},
                         {"deviation", deviation_s},       {"total", total_s}};
  report["memory_estimate_mib"] = r.memory.total() / (1 << 20);
  report["memory_walls_mib"] = r.memory.walls / (1 << 20);
  report["peak_rss_mib"] = peak_rss_mib();
  report["warnings"] = r.warnings;
  return report;
}

// --report and --html.
void write_reports(const CheckOptions& options, const SimulationResult& r, const Mesh& design,
                   const Json& report, const CheckFindings& f, const MachineRun& machine,
                   Progress& progress) {
  if (!options.report.empty()) {
    progress.stage("writing " + options.report);
    write_file_atomically(options.report, dump_json(report, 2) + "\n");
  }
  if (!options.html.empty()) {
    progress.stage("writing " + options.html);
    const HtmlMachine machine_parts = machine_page(machine);
    write_html_report(options.html,
                      {.title = "tridex check: " + r.input.program.filename().string() +
                                " against " + fs::path(options.design).filename().string(),
                       .report = report,
                       .mesh = &r.mesh,
                       .deviation = f.deviation,
                       .design = &design,
                       .groups = &r.groups,
                       .order = r.order,
                       .files = r.files,
                       .stock = &r.stock,
                       .cutters = r.cutters,
                       .bodies = r.bodies,
                       .cutter_of_tool = &r.cutter_of_tool,
                       .machine = machine.active ? &machine_parts : nullptr});
  }
}

// The excess regions with the lines nearest them, as the gouges: "excess 0.300 mm around (x, y,
// z), nearest lines p.nc:12, p.nc:14 (T1, 0.05 mm away)".
void print_excess_lines(const Json& excess_list) {
  std::size_t printed = 0;
  for (const Json& g : excess_list)
    if (g.contains("lines") && printed++ < kFindingsPrinted) {
      std::string lines, tools;
      for (std::size_t i = 0; i < g["lines"].size() && i < 10; ++i)
        lines += (lines.empty() ? "" : ", ") + g["files"][i].get<std::string>() + ":" +
                 std::to_string(g["lines"][i].get<int>());
      if (g["lines"].size() > 10) lines += ", … (" + std::to_string(g["lines"].size()) + " in all)";
      for (const Json& t : g["tools"]) tools += (tools.empty() ? "T" : ", T") + t.dump();
      const Json& c = g["centroid"];
      std::printf(
          "  excess %.3f mm around (%.3f, %.3f, %.3f), nearest lines %s (%s, %.3f mm "
          "away)\n",
          g["depth_mm"].get<double>(), c[0].get<double>(), c[1].get<double>(), c[2].get<double>(),
          lines.empty() ? "?" : terminal_safe(lines).c_str(), tools.c_str(),
          g.value("nearest_mm", 0.0));
    }
}

// "resolution: dexel spacing 0.1385 mm (refined from 0.3125 mm for the tolerance), Z-map cell
// 0.06925 mm: a gouge can go deeper than the samples show by at most 0.02 mm (tool 4, …)".
std::string resolution_text(const CheckOptions& options, const SimulationResult& r) {
  char text[160];
  std::snprintf(text, sizeof text, "resolution: dexel spacing %.4g mm", r.lattice.spacing);
  std::string line = text;
  if (r.unrefined_spacing > 0) {
    std::snprintf(text, sizeof text, " (refined from %.4g mm for the tolerance)",
                  r.unrefined_spacing);
    line += text;
  }
  std::snprintf(text, sizeof text,
                ", Z-map cell %.4g mm: a gouge can go deeper than the samples "
                "show by %s",
                r.zmap_cell, std::isfinite(r.resolution.missable) ? "at most " : "");
  line += text;
  line += missable_text(r.resolution, r.cutters, r.cutter_of_tool);
  if (options.lattice_only && r.resolution.missable > gouge_tolerance(options))
    line += " (--lattice-only: the verdict holds on the lattice's samples)";
  return line;
}

// The warnings on stderr, then the verdict line and the first findings of each kind on stdout.
void print_summary(const CheckOptions& options, const SimulationResult& r, const Json& report,
                   const CheckFindings& f, bool failed, double total_s) {
  for (const std::string& w : r.warnings) std::cerr << "warning: " << terminal_safe(w) << '\n';
  const Json& d = report["deviation"];
  char range[96] = "not measured (no material left)";
  if (d.contains("min_mm"))
    std::snprintf(range, sizeof range, "%.4g .. %.4g mm", d["min_mm"].get<double>(),
                  d["max_mm"].get<double>());
  std::printf(
      "%s vs %s: deviation %s; %zu gouge and %zu excess region(s) beyond -%g/+%g mm, design "
      "samples %lld missing and %lld left, %zu rapid(s) cutting material, %zu move(s) outside the "
      "envelope, %lld outside the machine's travel, %zu shank/holder collision(s), %zu near "
      "miss(es) within %g mm: %s; %.2f s\n",
      r.input.program.filename().string().c_str(),
      fs::path(options.design).filename().string().c_str(), range, f.gouges.size(),
      f.excesses.size(), f.gouge_tol, f.excess_tol,
      f.design_side["missing"]["samples"].get<long long>(),
      f.design_side["left"]["samples"].get<long long>(), f.rapid_list.size(), f.envelope_outside,
      r.travel_count, r.body.collisions.size(), r.body.near_misses.size(), options.clearance,
      failed ? "FAIL" : "pass", total_s);
  std::printf("  %s\n", machining_time_text(r.machining).c_str());
  std::string unchecked;
  for (const std::string& text : f.not_checked) unchecked += "; NOT CHECKED: " + text;
  if (f.gouge_tol == f.excess_tol)
    std::printf("  verdict: %s at ±%g mm (%s)%s\n", failed ? "FAIL" : "pass", f.gouge_tol,
                f.tolerance_source.c_str(), unchecked.c_str());
  else
    std::printf("  verdict: %s at -%g/+%g mm (%s)%s\n", failed ? "FAIL" : "pass", f.gouge_tol,
                f.excess_tol, f.tolerance_source.c_str(), unchecked.c_str());
  std::printf("  %s\n", resolution_text(options, r).c_str());
  std::printf("  %s\n  %s\n", tools_text(r).c_str(), directions_text(r).c_str());
  std::size_t printed = 0;
  for (const Json& g : f.gouge_list)
    if (g.contains("lines") && printed++ < kFindingsPrinted) {
      std::string lines;
      std::size_t count = 0;
      for (std::size_t i = 0; i < g["lines"].size(); ++i)
        if (count++ < 10)
          lines += (lines.empty() ? "" : ", ") + g["files"][i].get<std::string>() + ":" +
                   std::to_string(g["lines"][i].get<int>());
      if (count > 10) lines += ", … (" + std::to_string(count) + " in all)";
      const Json& c = g["centroid"];
      std::printf("  gouge %.3f mm around (%.3f, %.3f, %.3f), lines %s\n",
                  g["depth_mm"].get<double>(), c[0].get<double>(), c[1].get<double>(),
                  c[2].get<double>(), lines.empty() ? "?" : lines.c_str());
    }
  print_excess_lines(f.excess_list);
  const Json& rapid_list = f.rapid_list;
  for (std::size_t k = 0; k < rapid_list.size() && k < kFindingsPrinted; ++k)
    std::printf("  %s:%d: rapid cuts %.3f mm of material\n",
                rapid_list[k]["file"].get<std::string>().c_str(), rapid_list[k]["line"].get<int>(),
                rapid_list[k]["depth_mm"].get<double>());
  const Json& envelope_list = f.envelope_list;
  for (std::size_t k = 0; k < envelope_list.size() && k < kFindingsPrinted; ++k)
    std::printf("  %s:%d: tool tip %s outside the envelope\n",
                envelope_list[k]["file"].get<std::string>().c_str(),
                envelope_list[k]["line"].get<int>(), envelope_list[k]["tip"].dump().c_str());
  for (std::size_t k = 0; k < r.travel.size() && k < kFindingsPrinted; ++k)
    std::printf("  %s:%d: %s\n", file_name(r, r.travel[k].file).c_str(), r.travel[k].line,
                travel_text(r.travel[k]).c_str());
  for (std::size_t k = 0; k < r.body.collisions.size() && k < kFindingsPrinted; ++k) {
    const BodyFinding& b = r.body.collisions[k];
    std::printf(
        "  %s:%d: tool %d's %s is %.3f mm into the stock at (%.3f, %.3f, %.3f), spindle %s\n",
        file_name(r, b.file).c_str(), b.line, b.tool, b.part.c_str(), b.depth_mm, b.where.x,
        b.where.y, b.where.z, axis_label(b.axis).c_str());
  }
  for (const Json& s : f.stick_out)
    std::printf("  tool %d along %s needs a stick-out of %.3f mm (it has %.3f)\n",
                s["tool"].get<int>(), s["axis"].dump().c_str(), s["needed_mm"].get<double>(),
                s["stick_out_mm"].get<double>());
  if (rapid_list.size() > kFindingsPrinted || f.envelope_outside > kFindingsPrinted ||
      r.travel_count > static_cast<long long>(kFindingsPrinted) ||
      r.body.collisions.size() > kFindingsPrinted)
    std::printf("  (more in the report)\n");
}

}  // namespace

int run_check(const CheckOptions& options) {
  const Clock::time_point start = Clock::now();
  Progress progress(!options.quiet && (options.progress || stderr_is_terminal()));
  const CheckInputs in = read_check_inputs(options, progress);
  SimulationResult r = simulate_program(options, progress, check_request(options, in.design));
  CheckFindings f;
  f.gouge_tol = gouge_tolerance(options);
  f.excess_tol = options.excess_tol > 0  ? options.excess_tol
                 : options.tolerance > 0 ? options.tolerance
                                         : kShopTolerance;
  f.tolerance_source = options.gouge_tol > 0 || options.excess_tol > 0 || options.tolerance > 0
                           ? "given"
                           : "the default shop tolerance; --tolerance to change";

  const Clock::time_point t = Clock::now();
  measure_deviation(options, r, in.design, progress, f);
  measure_design_side(options, r, in.design, progress, f);
  list_regions(r, progress, f);
  const double deviation_s = seconds_since(t);
  list_program_findings(r, in.envelope, f);

  write_result_files(options, r, f, progress);
  if (!r.mesh_check.closed())
    r.warnings.push_back("the result mesh is not watertight (" +
                         std::to_string(r.mesh_check.boundary_edges) + " boundary, " +
                         std::to_string(r.mesh_check.non_manifold_edges) + " non-manifold edges)");
  const MachineRun machine = run_machine_check(options.fixtures, r);
  if (const std::string text = machine_unchecked_text(machine); !text.empty()) {
    r.warnings.push_back(text);
    f.not_checked.push_back(text);
  }
  const bool failed = check_failed(r, f, machine);
  const double total_s = seconds_since(start);
  Json report = check_report(options, r, in.envelope, f, failed, deviation_s, total_s);
  if (!f.not_checked.empty()) report["not_checked"] = f.not_checked;
  if (machine.active || !machine.found.travel.empty()) report["machine"] = machine_json(machine, r);
  write_reports(options, r, in.design, report, f, machine, progress);
  progress.finish();
  if (!options.quiet) {
    print_summary(options, r, report, f, failed, total_s);
    if (machine.active)
      std::printf(
          "  machine: %zu collision(s), %zu near miss(es) within %g mm, %zu limit(s) passed "
          "inside moves; %lld moves, %lld distance queries, %.2f s\n",
          machine.found.collisions.size(), machine.found.near_misses.size(),
          r.input.machine.collision.near_miss, machine.found.travel.size(), machine.found.moves,
          machine.found.queries, machine.found.seconds);
    print_machine_findings(machine, r, kFindingsPrinted);
  }
  return failed ? kFindings : kSuccess;
}

}  // namespace tridex::cli
