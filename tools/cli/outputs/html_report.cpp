// tridex command — the interactive HTML report; see html_report.hpp. Mesh simplification:
// meshoptimizer's meshopt_simplify (A. Kapoulkine, after Garland and Heckbert, "Surface
// Simplification Using Quadric Error Metrics", SIGGRAPH 1997).
#include "outputs/html_report.hpp"

#include <meshoptimizer.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <fstream>
#include <map>
#include <optional>
#include <set>
#include <stdexcept>
#include <string_view>

#include "json_text.hpp"
#include "outputs/compressed_text.hpp"
#include "outputs/output.hpp"
#include "pipeline/pipeline.hpp"
#include "tridex/detail/move_geometry.hpp"
#include "tridex/gcode/interpreter.hpp"

// The page template and libjs-three's files, embedded at build time (cmake/embed_text.cmake).
extern const char kTridexHtmlTemplate[];
extern const char kTridexThreeJs[];
extern const char kTridexOrbitControlsJs[];

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

// Positions this far from the origin are tridex's stand-in for home returns and reorientations
// ("far along the tool axis"), not programmed points: they are not drawn.
constexpr double kFar = 0.5 * gcode::MachineConfig::kDefaultFar;

template <class T>
std::string base64_of(const std::vector<T>& values) {
  return base64({reinterpret_cast<const std::uint8_t*>(values.data()), values.size() * sizeof(T)});
}

// Points as uint16 per coordinate over `box` (the page's dequantise() inverts it): at most half
// of 1/65535 of the box's side off, 1.5 µm on a 200 mm part.
std::string quantised(const std::vector<glm::vec3>& points, const Aabb& box) {
  std::vector<std::uint16_t> q;
  q.reserve(points.size() * 3);
  for (const glm::vec3& p : points)
    for (int a = 0; a < 3; ++a) {
      const double side = box.max[a] - box.min[a];
      const double t = side > 0 ? (p[a] - box.min[a]) / side : 0;
      q.push_back(static_cast<std::uint16_t>(std::lround(std::clamp(t, 0.0, 1.0) * 65535)));
    }
  return base64_of(q);
}

Json box_json(const Aabb& box) { return {{"min", to_json(box.min)}, {"max", to_json(box.max)}}; }

Aabb bounds_of(const std::vector<glm::vec3>& points) {
  Aabb box;
  for (const glm::vec3& p : points) box.extend(Vec3(p));
  return box;
}

double distance_to_segment(const glm::vec3& p, const glm::vec3& a, const glm::vec3& b) {
  const glm::vec3 ab = b - a;
  const float length2 = glm::dot(ab, ab);
  const float t = length2 > 0 ? std::clamp(glm::dot(p - a, ab) / length2, 0.0f, 1.0f) : 0.0f;
  return glm::length(p - (a + t * ab));
}

// The source lines a listing needs, per file (by name, as the findings' "file" gives it): each
// finding's lines and `context` lines either side.
std::map<std::string, std::set<int>> listed_lines(const Json& report, int context) {
  std::map<std::string, std::set<int>> wanted;
  auto add = [&](const Json& file, const Json& line) {
    if (!file.is_string() || !line.is_number_integer()) return;
    std::set<int>& lines = wanted[file.get<std::string>()];
    for (int k = line.get<int>() - context; k <= line.get<int>() + context; ++k) lines.insert(k);
  };
  for (const char* kind : {"gouges", "excess", "rapid_cuts", "collisions"})
    if (report.contains(kind))
      for (const Json& f : report[kind]) {
        if (f.contains("lines") && f.contains("files"))  // "files"[i]: the file of "lines"[i]
          for (std::size_t i = 0; i < f["lines"].size(); ++i) add(f["files"][i], f["lines"][i]);
        if (f.contains("line")) add(f["file"], f["line"]);
      }
  if (report.contains("regions") && report.contains("file_b"))  // diff's (issue 39)
    for (const Json& g : report["regions"])
      for (const Json& line : g["lines_b"]) add(report["file_b"], line);
  if (report.contains("lint"))
    for (const Json& f : report["lint"]) add(f["file"], f["line"]);
  for (const char* kind : {"envelope", "travel"})
    if (report.contains(kind))
      for (const Json& v : report[kind]["violations"]) add(v["file"], v["line"]);
  if (report.contains("near_misses"))
    for (const Json& v : report["near_misses"]["moves"]) add(v["file"], v["line"]);
  return wanted;
}

// Each G-code file of the program (Move::file's table) with its text, line -> text: whole files
// while their total stays within max_source_bytes; of the others the lines around findings, and
// their whole text deflated in chunks of lines (compressed_text.hpp) while the chunks stay within
// max_compressed_source_bytes, so the slider shows the text of any line of any program that fits.
Json source_files(const HtmlPage& page, const HtmlLimits& limits) {
  Json files = Json::array();
  std::uintmax_t budget = limits.max_source_bytes;
  std::size_t compressed_budget = limits.max_compressed_source_bytes;
  std::optional<std::map<std::string, std::set<int>>> wanted;
  for (const std::string& name : page.files) {
    Json file = {{"name", name}, {"source", Json::object()}, {"note", ""}};
    std::error_code error;
    const std::uintmax_t size = fs::file_size(name, error);
    std::ifstream in(name, std::ios::binary);
    if (error || !in) {
      file["note"] = "the file could not be read";
      files.push_back(std::move(file));
      continue;
    }
    const std::set<int>* lines = nullptr;  // those included; null: all
    if (size <= budget) {
      budget -= size;
    } else {
      if (!wanted) wanted = listed_lines(page.report, limits.context);
      lines = &(*wanted)[name];
    }
    Json& source = file["source"];
    std::string text, whole;
    for (int line = 1; std::getline(in, text); ++line) {
      if (!text.empty() && text.back() == '\r') text.pop_back();
      if (lines) (whole += text) += '\n';
      if (lines && !lines->count(line)) continue;
      source[std::to_string(line)] = text;
    }
    if (lines) {
      // The chunks bypass the JSON writer's transcoding: make the text UTF-8 here.
      if (!json_detail::valid_utf8(whole)) whole = latin1_to_utf8(whole);
      CompressedText packed =
          compress_lines(whole, limits.compressed_chunk_lines, compressed_budget);
      for (const std::string& chunk : packed.chunks) compressed_budget -= chunk.size();
      file["chunk_lines"] = packed.lines_per_chunk;
      file["chunks"] = std::move(packed.chunks);
      file["note"] = packed.lines_kept == packed.lines
                         ? "the program is large: its text is kept compressed"
                         : "the page's text budget ends at line " +
                               std::to_string(packed.lines_kept) + " of " +
                               std::to_string(packed.lines);
    }
    files.push_back(std::move(file));
  }
  return files;
}

// A mesh as the page draws it: simplified to `budget` triangles, quantised points, base64.
Json display_mesh_json(const Mesh* mesh, std::span<const double> deviation, double gouge_tol,
                       double excess_tol, std::size_t budget) {
  Json shown_json = {{"triangles", 0}, {"triangles_shown", 0}};
  if (!mesh || mesh->triangles.empty()) return shown_json;
  DisplayMesh shown = simplify_for_display(*mesh, deviation, gouge_tol, excess_tol, budget);
  const Aabb box = bounds_of(shown.positions);
  shown_json["triangles"] = mesh->triangles.size();
  shown_json["triangles_shown"] = shown.indices.size() / 3;
  shown_json["box"] = box_json(box);
  shown_json["positions"] = quantised(shown.positions, box);
  shown_json["indices"] = base64_of(shown.indices);
  if (!shown.deviation.empty()) shown_json["deviation"] = base64_of(shown.deviation);
  return shown_json;
}

Json mesh_json(const HtmlPage& page, const HtmlLimits& limits) {
  double gouge_tol = 0, excess_tol = 0;
  if (!page.deviation.empty()) {
    gouge_tol = page.report.at("tolerances_mm").at("gouge").get<double>();
    excess_tol = page.report.at("tolerances_mm").at("excess").get<double>();
  }
  return display_mesh_json(page.mesh, page.deviation, gouge_tol, excess_tol, limits.max_triangles);
}

Json toolpath_json(const HtmlPage& page, const HtmlLimits& limits) {
  Json path = {{"segments", 0}, {"moves", 0}};
  if (!page.groups) return path;
  Aabb drawn;
  for (const gcode::MoveGroup& group : *page.groups)
    for (const gcode::Move& m : group.moves)
      if (glm::length(m.start) < kFar && glm::length(m.end) < kFar) {
        drawn.extend(m.start);
        drawn.extend(m.end);
      }
  // A tolerance of about a quarter pixel of a 1000-pixel view first, doubled while there are too
  // many segments.
  double tolerance = std::max(1e-6, glm::length(drawn.size()) * limits.path_tolerance);
  DisplayPath thinned = thin_toolpath(*page.groups, page.order, tolerance);
  while (thinned.stops.size() > limits.max_segments)
    thinned = thin_toolpath(*page.groups, page.order, tolerance *= 2);
  path["moves"] = thinned.moves;
  path["segments"] = thinned.stops.size();
  path["tolerance_mm"] = thinned.tolerance;
  path["stop_count"] = thinned.stop_count;
  path["stop_runs"] = base64_of(thinned.stop_runs);
  if (thinned.stops.empty()) return path;
  const Aabb box = bounds_of(thinned.ends);
  path["box"] = box_json(box);
  path["points"] = quantised(thinned.ends, box);
  path["stops"] = base64_of(thinned.stops);
  path["tools"] = base64_of(thinned.tools);
  path["flags"] = base64_of(thinned.flags);
  return path;
}

// The playback cells (playback_cells) within the limits: cells as fine as max_playback_cells
// allows, coarser while more than max_playback_removed are removed. Removal stops are shipped as
// 16-bit codes: the stop itself up to 65535 stops, else stop × 65535 / stops (the page maps the
// slider's stop the same way).
Json playback_json(const HtmlPage& page, const HtmlLimits& limits) {
  if (!page.stock || !page.groups || !page.cutter_of_tool || page.stock->box.empty())
    return nullptr;
  const Vec3 size = page.stock->box.size();
  double cell =
      std::cbrt(size.x * size.y * size.z / static_cast<double>(limits.max_playback_cells));
  cell = std::max({cell, 1e-3, std::max({size.x, size.y, size.z}) / 1024});
  Playback p = playback_cells(page, cell);
  for (int attempt = 0; attempt < 4 && p.removed_at.size() > limits.max_playback_removed; ++attempt)
    p = playback_cells(page,
                       cell *= 1.05 * std::cbrt(static_cast<double>(p.removed_at.size()) /
                                                static_cast<double>(limits.max_playback_removed)));
  std::vector<std::uint16_t> codes(p.removed_at.size());
  const std::uint64_t stops = std::max<std::size_t>(p.stop_count, 1);
  for (std::size_t k = 0; k < codes.size(); ++k)
    codes[k] = static_cast<std::uint16_t>(stops <= 65535 ? p.removed_at[k]
                                                         : p.removed_at[k] * 65535ull / stops);
  Json json = {{"box", box_json(p.box)},
               {"n", {p.n[0], p.n[1], p.n[2]}},
               {"cell_mm", p.cell},
               {"stop_count", p.stop_count},
               {"part_mask", base64_of(p.part_mask)},
               {"removed", p.removed_at.size()},
               {"removed_at", base64_of(codes)}};
  if (!p.stock_mask.empty()) json["stock_mask"] = base64_of(p.stock_mask);
  return json;
}

// The tools as the page draws them at the slider: the cutter's radius and each shank or holder
// section (its bottom above the tip, its radii and length; an unbounded one drawn 3 radii long).
Json tools_json(const HtmlPage& page) {
  Json tools = Json::object();
  if (!page.cutter_of_tool) return tools;
  for (const auto& [tool, index] : *page.cutter_of_tool) {
    if (index >= page.cutters.size()) continue;
    Json parts = Json::array();
    if (index < page.bodies.size())
      for (const BodyPart& part : page.bodies[index].parts) {
        const BodySection& s = part.shape;
        const double length = std::isfinite(s.length) ? s.length : 3 * s.bottom_radius;
        parts.push_back({{"name", part.name},
                         {"bottom", part.bottom},
                         {"r0", s.bottom_radius},
                         {"r1", std::isfinite(s.top_radius) ? s.top_radius : s.bottom_radius},
                         {"length", length}});
      }
    const double stick_out = index < page.bodies.size() ? page.bodies[index].stick_out : 0;
    tools[std::to_string(tool)] = {{"radius", page.cutters[index].radius()},
                                   {"name", page.cutters[index].name()},
                                   {"stick_out", stick_out},
                                   {"parts", parts}};
  }
  return tools;
}

// The machine check's bodies and its findings' poses (HtmlMachine); a body is drawn (its mesh
// simplified to its share of the budget, HtmlLimits) when it is a fixture or in a listed finding.
Json machine_page_json(const HtmlMachine& machine, const HtmlLimits& limits) {
  const std::size_t n = machine.meshes.size();
  std::vector<bool> drawn(n, false);
  auto poses = [&](const std::vector<std::array<HtmlMachinePose, 2>>& list) {
    Json out = Json::array();
    for (const auto& pair : list) {
      Json entry = Json::array();
      for (const HtmlMachinePose& p : pair) {
        if (p.body < 0 || static_cast<std::size_t>(p.body) >= n) continue;
        drawn[static_cast<std::size_t>(p.body)] = true;
        // Row by row, [R | o]: THREE.Matrix4.set's order.
        Json m = Json::array();
        for (int r = 0; r < 3; ++r) {
          for (int c = 0; c < 3; ++c) m.push_back(p.frame.rotation[c][r]);
          m.push_back(p.frame.origin[r]);
        }
        entry.push_back({{"body", p.body}, {"matrix", m}});
      }
      out.push_back(std::move(entry));
    }
    return out;
  };
  Json out;
  out["collisions"] = poses(machine.collisions);
  out["near_misses"] = poses(machine.near_misses);
  std::size_t total = 0;
  for (std::size_t k = 0; k < n; ++k) {
    if (k < machine.groups.size() && machine.groups[k] == "fixture") drawn[k] = true;
    if (drawn[k] && machine.meshes[k]) total += machine.meshes[k]->triangles.size();
  }
  Json bodies = Json::array();
  for (std::size_t k = 0; k < n; ++k) {
    const Mesh* mesh = drawn[k] ? machine.meshes[k] : nullptr;
    const std::size_t size = mesh ? mesh->triangles.size() : 0;
    const std::size_t share =
        std::max(limits.min_machine_body_triangles,
                 static_cast<std::size_t>(static_cast<double>(limits.max_machine_triangles) *
                                          static_cast<double>(size) /
                                          static_cast<double>(std::max<std::size_t>(total, 1))));
    Json body = display_mesh_json(mesh, {}, 0, 0, share);
    body["name"] = k < machine.names.size() ? machine.names[k] : "";
    body["group"] = k < machine.groups.size() ? machine.groups[k] : "";
    bodies.push_back(std::move(body));
  }
  out["bodies"] = std::move(bodies);
  return out;
}

std::string html_escaped(std::string_view text) {
  std::string out;
  for (char c : text) {
    switch (c) {
      case '<':
        out += "&lt;";
        break;
      case '>':
        out += "&gt;";
        break;
      case '&':
        out += "&amp;";
        break;
      case '"':
        out += "&quot;";
        break;
      default:
        out += c;
    }
  }
  return out;
}

// ---- playback ------------------------------------------------------------------------------

// Per column (i, j) of centres (x0 + (i + ½)c, y0 + (j + ½)c), the heights where `mesh` crosses
// the vertical line through it, sorted: a point is inside where an odd number lie below it. The
// centres are nudged by an irrational fraction of a cell so that no line meets an edge exactly.
std::vector<std::vector<float>> column_crossings(const Mesh& mesh, double x0, double y0, double c,
                                                 int nx, int ny) {
  std::vector<std::vector<float>> columns(static_cast<std::size_t>(nx) * ny);
  const double nudge_x = 0.5 + 1.37e-5, nudge_y = 0.5 + 2.91e-5;
  auto edge = [](const Vec3& u, const Vec3& v, double px, double py) {
    return (v.x - u.x) * (py - u.y) - (v.y - u.y) * (px - u.x);
  };
  for (const glm::uvec3& t : mesh.triangles) {
    const Vec3 a(mesh.positions[t.x]), b(mesh.positions[t.y]), d(mesh.positions[t.z]);
    const double area = edge(a, b, d.x, d.y);
    if (std::abs(area) < 1e-30) continue;
    const int i0 =
        std::max(0, static_cast<int>(std::ceil((std::min({a.x, b.x, d.x}) - x0) / c - nudge_x)));
    const int i1 = std::min(
        nx - 1, static_cast<int>(std::floor((std::max({a.x, b.x, d.x}) - x0) / c - nudge_x)));
    const int j0 =
        std::max(0, static_cast<int>(std::ceil((std::min({a.y, b.y, d.y}) - y0) / c - nudge_y)));
    const int j1 = std::min(
        ny - 1, static_cast<int>(std::floor((std::max({a.y, b.y, d.y}) - y0) / c - nudge_y)));
    for (int j = j0; j <= j1; ++j)
      for (int i = i0; i <= i1; ++i) {
        const double px = x0 + (i + nudge_x) * c, py = y0 + (j + nudge_y) * c;
        const double w0 = edge(b, d, px, py) / area, w1 = edge(d, a, px, py) / area,
                     w2 = edge(a, b, px, py) / area;
        if (w0 < 0 || w1 < 0 || w2 < 0) continue;
        columns[static_cast<std::size_t>(j) * nx + i].push_back(
            static_cast<float>(w0 * a.z + w1 * b.z + w2 * d.z));
      }
  }
  for (std::vector<float>& column : columns) std::sort(column.begin(), column.end());
  return columns;
}

bool inside_column(const std::vector<float>& crossings, double z) {
  return (std::upper_bound(crossings.begin(), crossings.end(), static_cast<float>(z)) -
          crossings.begin()) %
             2 ==
         1;
}

// One direction's columns (in its frame) and, per column, where its height fell: (stop, height)
// in program order, the heights falling.
struct DirectionColumns {
  const Frame* frame = nullptr;
  double x0 = 0, y0 = 0, cell = 1;
  int nx = 0, ny = 0;
  std::vector<std::vector<std::pair<std::uint32_t, float>>> falls;
};

// Mills every move in program order on each direction's columns, recording where heights fall.
std::vector<DirectionColumns> milled_columns(const HtmlPage& page, const Aabb& box, double cell,
                                             std::size_t& stop_count) {
  const std::vector<gcode::MoveGroup>& groups = *page.groups;
  std::vector<DirectionColumns> columns(groups.size());
  std::vector<double> top(groups.size());  // the stock box's highest point in each direction
  for (std::size_t g = 0; g < groups.size(); ++g) {
    DirectionColumns& dc = columns[g];
    dc.frame = &groups[g].frame;
    Aabb local;
    for (const Vec3& corner : box.corners()) local.extend(dc.frame->to_local(corner));
    top[g] = local.max.z;
    dc.x0 = local.min.x, dc.y0 = local.min.y, dc.cell = cell;
    dc.nx = std::max(1, static_cast<int>(std::ceil(local.size().x / cell)));
    dc.ny = std::max(1, static_cast<int>(std::ceil(local.size().y / cell)));
    dc.falls.resize(static_cast<std::size_t>(dc.nx) * dc.ny);
  }
  std::vector<GroupRun> whole;
  if (page.order.empty())
    for (std::size_t g = 0; g < groups.size(); ++g)
      whole.push_back({static_cast<std::uint32_t>(g), groups[g].moves.size()});
  std::vector<std::size_t> next(groups.size(), 0);
  std::optional<std::pair<int, int>> previous;  // the file and line of the move before
  std::uint32_t stop = 0;
  for (const GroupRun& run : page.order.empty() ? std::span<const GroupRun>(whole) : page.order)
    for (std::uint64_t k = 0; k < run.moves; ++k) {
      const gcode::Move m = groups[run.group].moves[next[run.group]++];
      if (previous && *previous != std::pair(m.file, m.line)) ++stop;
      previous = std::pair(m.file, m.line);
      const auto cutter = page.cutter_of_tool->find(m.tool);
      if (cutter == page.cutter_of_tool->end() || cutter->second >= page.cutters.size() ||
          glm::length(m.start) >= kFar || glm::length(m.end) >= kFar)
        continue;
      DirectionColumns& dc = columns[run.group];
      const Segment tip{dc.frame->to_local(m.start), dc.frame->to_local(m.end)};
      // No column falls below the move's lowest tip; a fall above the stock's box is below no
      // cell of it (removal_stop): such moves and columns are skipped, the result is the same.
      const double lowest_tip = std::min(tip.a.z, tip.b.z);
      if (lowest_tip >= top[run.group]) continue;
      const Cutter& c = page.cutters[cutter->second];
      const detail::MoveGeometry geometry(c, tip);
      const double r = c.radius();
      const int i0 = std::max(
          0, static_cast<int>(std::floor((std::min(tip.a.x, tip.b.x) - r - dc.x0) / cell)));
      const int i1 = std::min(
          dc.nx - 1, static_cast<int>(std::floor((std::max(tip.a.x, tip.b.x) + r - dc.x0) / cell)));
      const int j0 = std::max(
          0, static_cast<int>(std::floor((std::min(tip.a.y, tip.b.y) - r - dc.y0) / cell)));
      const int j1 = std::min(
          dc.ny - 1, static_cast<int>(std::floor((std::max(tip.a.y, tip.b.y) + r - dc.y0) / cell)));
      for (int j = j0; j <= j1; ++j)
        for (int i = i0; i <= i1; ++i) {
          auto& falls = dc.falls[static_cast<std::size_t>(j) * dc.nx + i];
          if (!falls.empty() && double(falls.back().second) <= lowest_tip) continue;
          const double z = geometry.lowest(dc.x0 + (i + 0.5) * cell, dc.y0 + (j + 0.5) * cell).z;
          if (z < (falls.empty() ? kFar : double(falls.back().second)))
            falls.push_back({stop, static_cast<float>(z)});
        }
    }
  stop_count = previous ? stop + 1 : 0;
  return columns;
}

// The first stop at which a direction's column through `p` falls below it; UINT32_MAX: none.
std::uint32_t removal_stop(const std::vector<DirectionColumns>& columns, const Vec3& p) {
  std::uint32_t first = UINT32_MAX;
  for (const DirectionColumns& dc : columns) {
    const Vec3 q = dc.frame->to_local(p);
    const int i = static_cast<int>(std::floor((q.x - dc.x0) / dc.cell)),
              j = static_cast<int>(std::floor((q.y - dc.y0) / dc.cell));
    if (i < 0 || j < 0 || i >= dc.nx || j >= dc.ny) continue;
    const auto& falls = dc.falls[static_cast<std::size_t>(j) * dc.nx + i];
    const auto below = std::partition_point(falls.begin(), falls.end(),
                                            [&](const auto& f) { return double(f.second) >= q.z; });
    if (below != falls.end()) first = std::min(first, below->first);
  }
  return first;
}

}  // namespace

std::string base64(std::span<const std::uint8_t> bytes) {
  static constexpr char kDigits[] =
      "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::string out;
  out.reserve((bytes.size() + 2) / 3 * 4);
  std::size_t i = 0;
  for (; i + 3 <= bytes.size(); i += 3) {
    const std::uint32_t v =
        std::uint32_t{bytes[i]} << 16 | std::uint32_t{bytes[i + 1]} << 8 | bytes[i + 2];
    for (int shift = 18; shift >= 0; shift -= 6) out += kDigits[(v >> shift) & 63];
  }
  if (const std::size_t rest = bytes.size() - i; rest > 0) {
    const std::uint32_t v =
        std::uint32_t{bytes[i]} << 16 | (rest > 1 ? std::uint32_t{bytes[i + 1]} << 8 : 0);
    out += kDigits[(v >> 18) & 63];
    out += kDigits[(v >> 12) & 63];
    out += rest > 1 ? kDigits[(v >> 6) & 63] : '=';
    out += '=';
  }
  return out;
}

DisplayMesh simplify_for_display(const Mesh& mesh, std::span<const double> deviation,
                                 double gouge_tol, double excess_tol, std::size_t max_triangles) {
  if (!deviation.empty() && deviation.size() != mesh.positions.size())
    throw std::logic_error("simplify_for_display: one deviation per vertex expected");
  std::vector<std::uint32_t> locked, free;
  auto out_of_tolerance = [&](std::uint32_t v) {
    return !deviation.empty() && (deviation[v] < -gouge_tol || deviation[v] > excess_tol);
  };
  for (const glm::uvec3& t : mesh.triangles) {
    const bool keep = out_of_tolerance(t.x) || out_of_tolerance(t.y) || out_of_tolerance(t.z);
    for (int k = 0; k < 3; ++k) (keep ? locked : free).push_back(t[k]);
  }
  std::vector<std::uint32_t> indices;
  {
    // Locked triangles stay; the free part is simplified with its border locked (so it still
    // meets them), under a rising error bound (relative to the mesh's extent) until it fits. The
    // first bound, 5e-4 (0.1 mm on a 200 mm part, a quarter pixel of a 500-pixel view of it),
    // mostly merges the flat faces that a dexel surface tiles finely and their sub-cell ripple.
    // When the locked triangles alone take half the budget, everything is simplified.
    unsigned options = meshopt_SimplifyLockBorder;
    if (locked.size() / 3 >= max_triangles / 2) {
      free.insert(free.end(), locked.begin(), locked.end());
      locked.clear();
      options = 0;
    }
    const std::size_t target = (max_triangles - locked.size() / 3) * 3;
    std::vector<std::uint32_t> simplified(free.size());
    for (float error : {5e-4f, 2e-3f, 8e-3f, 3e-2f, 1e-1f, 1.0f}) {
      const std::size_t goal = error == 5e-4f ? 0 : target;  // as far as the first bound allows
      simplified.resize(meshopt_simplify(simplified.data(), free.data(), free.size(),
                                         &mesh.positions[0].x, mesh.positions.size(),
                                         sizeof(glm::vec3), goal, error, options));
      if (simplified.size() <= target) break;
      simplified.resize(free.size());
    }
    if (simplified.size() > target)  // the locked border alone is over the budget
      simplified.resize(meshopt_simplifySloppy(simplified.data(), free.data(), free.size(),
                                               &mesh.positions[0].x, mesh.positions.size(),
                                               sizeof(glm::vec3), target, 1.0f, nullptr));
    indices = std::move(locked);
    indices.insert(indices.end(), simplified.begin(), simplified.end());
  }
  // Only the vertices still used, renumbered in order of first use.
  DisplayMesh shown;
  std::vector<std::uint32_t> renumbered(mesh.positions.size(), UINT32_MAX);
  for (std::uint32_t& v : indices) {
    if (renumbered[v] == UINT32_MAX) {
      renumbered[v] = static_cast<std::uint32_t>(shown.positions.size());
      shown.positions.push_back(mesh.positions[v]);
      if (!deviation.empty()) shown.deviation.push_back(static_cast<float>(deviation[v]));
    }
    v = renumbered[v];
  }
  shown.indices = std::move(indices);
  return shown;
}

DisplayPath thin_toolpath(const std::vector<gcode::MoveGroup>& groups,
                          std::span<const GroupRun> order, double tolerance) {
  struct Ref {  // a move by place: the groups read their moves back by value (MoveList)
    std::uint32_t group;
    std::size_t index;
  };
  // The moves in program order: the groups keep it within each, `order` across them.
  std::vector<GroupRun> whole;
  if (order.empty())
    for (std::size_t g = 0; g < groups.size(); ++g)
      whole.push_back({static_cast<std::uint32_t>(g), groups[g].moves.size()});
  std::vector<Ref> moves;
  std::vector<std::size_t> next(groups.size(), 0);
  for (const GroupRun& run : order.empty() ? std::span<const GroupRun>(whole) : order) {
    if (run.group >= groups.size() || next[run.group] + run.moves > groups[run.group].moves.size())
      throw std::logic_error("thin_toolpath: the program order does not match the groups");
    for (std::uint64_t k = 0; k < run.moves; ++k) moves.push_back({run.group, next[run.group]++});
  }

  DisplayPath path;
  path.moves = moves.size();
  path.tolerance = tolerance;
  constexpr std::size_t kLongestRun = 64;  // bounds the quadratic check of a run
  std::vector<glm::vec3> run;              // the run's points: its start, then each move's end
  struct First {                           // what the run's first move gives it
    std::uint8_t group;
    int tool;
    bool rapid;
  } first{};
  std::uint32_t run_stop = 0;  // the stop of the run's last move
  auto flush = [&] {
    if (run.size() < 2) return;
    path.ends.push_back(run.front());
    path.ends.push_back(run.back());
    path.stops.push_back(run_stop);
    path.tools.push_back(static_cast<std::uint16_t>(std::clamp(first.tool, 0, 65535)));
    path.flags.push_back(static_cast<std::uint8_t>(first.group | (first.rapid ? 128 : 0)));
    run.clear();
  };
  std::optional<std::pair<int, int>> previous;  // the file and line of the move before
  for (const Ref& ref : moves) {
    const gcode::Move m = groups[ref.group].moves[ref.index];
    const auto group = static_cast<std::uint8_t>(ref.group % 128);
    if (!previous || *previous != std::pair(m.file, m.line)) {
      // A new stop: it extends the last run when it is the next line of the same file.
      std::vector<std::uint32_t>& runs = path.stop_runs;
      const auto file = static_cast<std::uint32_t>(m.file),
                 line = static_cast<std::uint32_t>(m.line);
      if (!runs.empty() && runs[runs.size() - 3] == file &&
          runs[runs.size() - 2] + runs.back() == line)
        ++runs.back();
      else
        runs.insert(runs.end(), {file, line, 1});
      ++path.stop_count;
    }
    previous = std::pair(m.file, m.line);
    if (glm::length(m.start) >= kFar || glm::length(m.end) >= kFar) {
      flush();
      continue;
    }
    const glm::vec3 start(m.start), end(m.end);
    bool joins = !run.empty() && run.size() < kLongestRun && first.group == group &&
                 first.tool == m.tool && first.rapid == (m.kind == gcode::MoveKind::rapid) &&
                 glm::length(run.back() - start) <= 1e-6f;
    if (joins)
      for (std::size_t k = 1; k < run.size() && joins; ++k)
        joins = distance_to_segment(run[k], run.front(), end) <= tolerance;
    if (!joins) {
      flush();
      first = {group, m.tool, m.kind == gcode::MoveKind::rapid};
      run.push_back(start);
    }
    run.push_back(end);
    run_stop = static_cast<std::uint32_t>(path.stop_count - 1);
  }
  flush();
  return path;
}

Playback playback_cells(const HtmlPage& page, double cell) {
  Playback p;
  if (!page.stock || !page.groups || !page.cutter_of_tool || page.stock->box.empty()) return p;
  p.box = page.stock->box;
  p.cell = cell;
  for (int a = 0; a < 3; ++a)
    p.n[a] = std::max(1, static_cast<int>(std::ceil(p.box.size()[a] / cell - 1e-9)));
  const std::size_t nx = p.n[0], ny = p.n[1], nz = p.n[2], cells = nx * ny * nz;
  const std::vector<DirectionColumns> columns = milled_columns(page, p.box, cell, p.stop_count);
  const std::uint32_t last = static_cast<std::uint32_t>(std::max<std::size_t>(p.stop_count, 1) - 1);
  std::vector<std::vector<float>> part, stock;
  if (page.mesh)
    part = column_crossings(*page.mesh, p.box.min.x, p.box.min.y, cell, p.n[0], p.n[1]);
  if (page.stock->mesh)
    stock = column_crossings(*page.stock->mesh, p.box.min.x, p.box.min.y, cell, p.n[0], p.n[1]);
  p.part_mask.assign((cells + 7) / 8, 0);
  if (!stock.empty()) p.stock_mask.assign((cells + 7) / 8, 0);
  for (std::size_t k = 0, index = 0; k < nz; ++k)
    for (std::size_t j = 0; j < ny; ++j)
      for (std::size_t i = 0; i < nx; ++i, ++index) {
        const Vec3 centre =
            p.box.min + cell * Vec3(static_cast<double>(i) + 0.5, static_cast<double>(j) + 0.5,
                                    static_cast<double>(k) + 0.5);
        const std::size_t column = j * nx + i;
        if (!stock.empty()) {
          if (!inside_column(stock[column], centre.z)) continue;
          p.stock_mask[index / 8] |= static_cast<std::uint8_t>(1 << (index % 8));
        }
        if (!part.empty() && inside_column(part[column], centre.z)) {
          p.part_mask[index / 8] |= static_cast<std::uint8_t>(1 << (index % 8));
          continue;
        }
        p.removed_at.push_back(std::min(removal_stop(columns, centre), last));
      }
  return p;
}

Json html_page_data(const HtmlPage& page, const HtmlLimits& limits) {
  Json data;
  data["title"] = page.title;
  data["report"] = page.report;
  data["mesh"] = mesh_json(page, limits);
  data["toolpath"] = toolpath_json(page, limits);
  if (page.design)
    data["design"] = display_mesh_json(page.design, {}, 0, 0, limits.max_design_triangles);
  Json directions = Json::array();
  if (page.groups)
    for (const gcode::MoveGroup& g : *page.groups) {
      Json tools = Json::array();
      for (int t : g.tools) tools.push_back(t);
      // The machine's rotary positions of the direction's first move, when it has a kinematic
      // model: the page names the direction by them (else by G68.2 angles).
      Json rotary = Json::object();
      if (!g.moves.empty())
        for (int a = 0; a < 3; ++a)
          if (g.moves.front().rotary_axes & (1 << a))
            rotary[std::string(1, "ABC"[a])] = g.moves.front().rotary[static_cast<std::size_t>(a)];
      directions.push_back({{"axis", to_json(g.axis)},
                            {"label", axis_label(g.axis)},
                            {"rotary", rotary},
                            {"moves", g.moves.size()},
                            {"tools", tools}});
    }
  data["directions"] = directions;
  data["playback"] = playback_json(page, limits);
  data["tools"] = tools_json(page);
  if (page.machine) data["machine"] = machine_page_json(*page.machine, limits);
  data["files"] = source_files(page, limits);
  data["context"] = limits.context;
  data["listing_lines"] = 20;  // of a finding's lines, the first this many are listed
  Json messages = Json::array();
  if (data["mesh"]["triangles_shown"] == 0)
    messages.push_back(
        "No material is left: the machined result has no triangles, so there is no part to show.");
  if (!page.groups || data["toolpath"]["moves"] == 0)
    messages.push_back("The program has no moves: there is no toolpath to show.");
  data["messages"] = messages;
  return data;
}

void write_html_report(const fs::path& path, const HtmlPage& page, const HtmlLimits& limits) {
  // The data goes inside a <script> element: no '<' may appear in it ("</script>" would end the
  // element), and JSON allows "\u003c" wherever a '<' could be (inside strings).
  std::string data = dump_json(html_page_data(page, limits));
  std::string escaped;
  escaped.reserve(data.size());
  for (char c : data) c == '<' ? escaped += "\\u003c" : escaped += c;

  const std::string_view page_template = kTridexHtmlTemplate;
  const std::array<std::pair<std::string_view, std::string_view>, 4> fills = {
      {{"@TITLE@", {}},
       {"@DATA@", escaped},
       {"@THREE@", kTridexThreeJs},
       {"@ORBIT@", kTridexOrbitControlsJs}}};
  const std::string title = html_escaped(page.title);
  AtomicOutput out(path);
  std::size_t at = 0;
  for (const auto& [marker, text] : fills) {
    const std::size_t found = page_template.find(marker, at);
    if (found == std::string_view::npos)
      throw std::logic_error("html_report.html lacks " + std::string(marker));
    out.stream() << page_template.substr(at, found - at)
                 << (marker == "@TITLE@" ? std::string_view(title) : text);
    at = found + marker.size();
  }
  out.stream() << page_template.substr(at);
  out.commit();
}

}  // namespace tridex::cli
