// The test programs the `tridex` command's suites share (a 40 x 30 x 20 stock cut from five
// G68.2 directions, its tool table) and the direct point-membership reference that `simulate`'s
// results are checked against: a point is removed iff some move's swept cutter covers it.
#pragma once

#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <functional>
#include <map>
#include <nlohmann/json.hpp>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "../kernel/edge_sampling.hpp"
#include "command_harness.hpp"
#include "inputs/tool_table.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/mill.hpp"

namespace tridex::test {

// True if `text` holds `prefix`, then one or more digits, then `suffix` (std::regex is avoided:
// GCC 12 warns falsely inside it under the sanitizers).
inline bool has_number_between(const std::string& text, const std::string& prefix,
                               const std::string& suffix) {
  for (std::size_t at = text.find(prefix); at != std::string::npos;
       at = text.find(prefix, at + 1)) {
    std::size_t digits = at + prefix.size(), end = digits;
    while (end < text.size() && std::isdigit(static_cast<unsigned char>(text[end]))) ++end;
    if (end > digits && text.compare(end, suffix.size(), suffix) == 0) return true;
  }
  return false;
}

inline const std::string kTools = R"({
  "1": {"units": "mm", "shape": "cylindrical", "diameter": 6, "length": 20},
  "2": {"units": "mm", "shape": "ballnose", "diameter": 4, "length": 20},
  "3": {"units": "inch", "shape": "bullnose", "diameter": 0.25, "corner-radius": 0.05, "length": 1}
})";

// G68.2 Euler angles (Z-X-Z) and a feature origin on each face of the 40 x 30 x 20 test stock.
struct Direction {
  const char* name;
  Vec3 origin;
  double a, b, c;
};
inline const Direction kDirections[] = {
    {"+Z", {20, 15, 20}, 0, 0, 0},    {"+X tilted 20", {40, 15, 12}, 90, 70, 0},
    {"+Y", {20, 30, 10}, 180, 90, 0}, {"-X", {0, 15, 10}, -90, 90, 0},
    {"-Y", {20, 0, 10}, 0, 90, 0},
};
inline const char* kStock = "box:0,0,0,40,30,20";

// The feature work for one direction, as a CAM post writes it: a flat-end slot with a ramp, a
// ball-end arc groove, a bull-nose plunge.
inline std::string direction_block(const Direction& d) {
  std::ostringstream p;
  p << "G28 G91 Z0.\nG90\nG69\nT1 M6\nS8000 M3\n"
    << "G68.2 X" << d.origin.x << " Y" << d.origin.y << " Z" << d.origin.z << " I" << d.a << " J"
    << d.b << " K" << d.c << "\nG53.1\n"
    << "G0 X-9 Y-2\nG43 Z8 H1\nG1 Z-2 F500\nG1 X7\nG1 Y3 Z-1\nG0 Z8\n"
    << "T2 M6\nG0 X2 Y-3\nG43 Z8 H2\nG1 Z-1.5\nG2 X8 Y3 I0 J6\nG3 X2 Y-3 I-6 J0\nG0 Z8\n"
    << "T3 M6\nG0 X-6 Y4\nG43 Z8 H3\nG1 Z-2.5\nG1 X-3 Y5\nG0 Z8\n"
    << "G28 G91 Z0.\nG69\n";
  return p.str();
}

inline std::string program_of(std::initializer_list<const Direction*> directions) {
  std::string text = "%\nG21 G17 G90\n";
  for (const Direction* d : directions) text += direction_block(*d);
  return text + "M30\n%\n";
}

// ---- the reference: is a world point removed by any move? ------------------------------------

struct Reference {
  std::vector<Cutter> cutters;
  std::vector<detail::MoveGeometry> moves;
  std::vector<Frame> frames;
  std::vector<unsigned> direction;  // per move: the index of its spindle direction
  std::vector<Vec3> axes;           // per direction
  // Moves bucketed by a uniform grid over the stock, each in every cell its removal region
  // (everything within the cutter radius of the segment and above it along the axis) can reach.
  Aabb box;
  double cell = 2;
  glm::ivec3 n;
  std::vector<std::vector<std::uint32_t>> buckets;

  Reference(const std::vector<gcode::Move>& program, const cli::ToolTable& table, const Aabb& stock)
      : box(stock) {
    std::map<int, std::size_t> index;
    for (const auto& [number, spec] : table.tools()) {
      index[number] = cutters.size();
      cutters.push_back(spec.cutter);
    }
    frames.reserve(program.size());
    moves.reserve(program.size());
    for (int a = 0; a < 3; ++a)
      n[a] = std::max(1, static_cast<int>(std::ceil(box.size()[a] / cell)));
    buckets.resize(static_cast<std::size_t>(n.x) * n.y * n.z);
    double reach = glm::length(box.size());
    for (const gcode::Move& m : program) {
      if (m.tool == 0) continue;  // no tool in the spindle
      frames.push_back(Frame::from_axis(m.axis));
      const Frame& f = frames.back();
      auto same = std::find_if(axes.begin(), axes.end(),
                               [&](const Vec3& a) { return glm::length(a - m.axis) < 1e-9; });
      direction.push_back(static_cast<unsigned>(same - axes.begin()));
      if (same == axes.end()) axes.push_back(m.axis);
      const Cutter& cutter = cutters[index.at(m.tool)];
      moves.emplace_back(cutter, Segment{f.to_local(m.start), f.to_local(m.end)});
      Aabb region;
      for (const Vec3& p : {m.start, m.end}) {
        // Clip "far" points to the stock's neighbourhood along the move's own line.
        region.extend(p);
        region.extend(p + reach * f.axis());
      }
      region = region.inflated(cutter.radius());
      glm::ivec3 lo, hi;
      for (int a = 0; a < 3; ++a) {
        lo[a] = std::clamp(static_cast<int>(std::floor((region.min[a] - box.min[a]) / cell)), 0,
                           n[a] - 1);
        hi[a] = std::clamp(static_cast<int>(std::floor((region.max[a] - box.min[a]) / cell)), 0,
                           n[a] - 1);
        if (region.max[a] < box.min[a] || region.min[a] > box.max[a]) lo[a] = 1, hi[a] = 0;
      }
      for (int k = lo.z; k <= hi.z; ++k)
        for (int j = lo.y; j <= hi.y; ++j)
          for (int i = lo.x; i <= hi.x; ++i)
            buckets[static_cast<std::size_t>(i + n.x * (j + n.y * k))].push_back(
                static_cast<std::uint32_t>(moves.size() - 1));
    }
  }

  // 0 outside the stock, 1 kept, otherwise 2 << d for each direction d whose moves remove p.
  unsigned label(const Vec3& p) const {
    if (!in_stock(p)) return 0;
    glm::ivec3 c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp(static_cast<int>(std::floor((p[a] - box.min[a]) / cell)), 0, n[a] - 1);
    unsigned l = 0;
    for (std::uint32_t m : buckets[static_cast<std::size_t>(c.x + n.x * (c.y + n.y * c.z))]) {
      const unsigned bit = 2u << direction[m];
      if (l & bit) continue;
      Vec3 q = frames[m].to_local(p);
      if (q.z >= moves[m].lowest_above(q.x, q.y)) l |= bit;
    }
    return l == 0 ? 1 : l;
  }
  bool removed(const Vec3& p) const {
    glm::ivec3 c;
    for (int a = 0; a < 3; ++a)
      c[a] = std::clamp(static_cast<int>(std::floor((p[a] - box.min[a]) / cell)), 0, n[a] - 1);
    for (std::uint32_t m : buckets[static_cast<std::size_t>(c.x + n.x * (c.y + n.y * c.z))]) {
      Vec3 q = frames[m].to_local(p);
      if (q.z >= moves[m].lowest_above(q.x, q.y)) return true;
    }
    return false;
  }
  // The stock: the box itself unless a test gives another solid inside it.
  std::function<bool(const Vec3&)> solid;
  bool in_stock(const Vec3& p) const { return box.contains(p) && (!solid || solid(p)); }
  bool kept(const Vec3& p) const { return in_stock(p) && !removed(p); }
};

using tridex::test::MeshInside;

struct Simulated {
  nlohmann::json report;
  Mesh mesh;
};

inline Simulated simulate(const fs::path& dir, const fs::path& program, const fs::path& tools,
                          const std::string& stock, int dexel_res, double zmap_cell) {
  fs::path stl = dir / "result.stl", report = dir / "report.json";
  CommandResult r = run_tridex(
      {"simulate", program.string(), "--tools", tools.string(), "--stock", stock, "--dexel-res",
       std::to_string(dexel_res), "--zmap-cell", std::to_string(zmap_cell), "-o", stl.string(),
       "--report", report.string(), "--quiet"},
      dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  CHECK(r.out.empty());  // --quiet
  Simulated s;
  s.report = nlohmann::json::parse(slurp(report));
  s.mesh = read_binary_stl(stl);
  return s;
}

// The result against the reference: watertight, the same volume within what the dexel spacing
// h allows on the cut surfaces, and the same membership at points at least 2h from any change
// of the reference classification.
inline void check_against_reference(const Simulated& s, const Reference& ref, std::uint32_t seed) {
  const nlohmann::json& result = s.report["result"];
  CHECK(result["watertight"].get<bool>());
  Mesh welded = weld_vertices(s.mesh);
  CHECK(check_mesh(welded).closed());
  double volume = result["volume_mm3"].get<double>();
  CHECK(s.mesh.signed_volume() == doctest::Approx(volume).epsilon(1e-4));
  const double h = s.report["dexel"]["cell_mm"].get<double>();

  // Volume on a jittered regular grid of spacing g; the cut-surface area from the number of
  // neighbouring samples that differ (each face of the surface is crossed by ≤ √3·A/g² pairs,
  // ≥ A/g²: the estimate over-counts by at most √3).
  std::mt19937 random(seed);
  std::uniform_real_distribution<double> unit(0, 1);
  const Aabb& box = ref.box;
  const double g = 0.5;
  glm::ivec3 n = glm::ivec3(glm::floor(box.size() / g));
  Vec3 jitter(unit(random) * g, unit(random) * g, unit(random) * g);
  std::vector<char> kept(static_cast<std::size_t>(n.x) * n.y * n.z);
  auto at = [&](int i, int j, int k) -> char& {
    return kept[static_cast<std::size_t>(i + n.x * (j + n.y * k))];
  };
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) at(i, j, k) = ref.kept(box.min + jitter + g * Vec3(i, j, k));
  std::vector<char> in_stock(kept.size());
  auto stock_at = [&](int i, int j, int k) -> char& {
    return in_stock[static_cast<std::size_t>(i + n.x * (j + n.y * k))];
  };
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i)
        stock_at(i, j, k) = ref.in_stock(box.min + jitter + g * Vec3(i, j, k));
  // Pairs of neighbouring samples that differ: on any surface of the result, and on the surfaces
  // the program cut (both samples in the stock).
  std::size_t kept_count = 0, stock_count = 0, differing = 0, differing_cut = 0;
  auto pair = [&](int i, int j, int k, int i2, int j2, int k2) {
    if (at(i, j, k) == at(i2, j2, k2)) return;
    ++differing;
    if (stock_at(i, j, k) && stock_at(i2, j2, k2)) ++differing_cut;
  };
  for (int k = 0; k < n.z; ++k)
    for (int j = 0; j < n.y; ++j)
      for (int i = 0; i < n.x; ++i) {
        kept_count += at(i, j, k) ? 1 : 0;
        stock_count += stock_at(i, j, k) ? 1 : 0;
        if (i + 1 < n.x) pair(i, j, k, i + 1, j, k);
        if (j + 1 < n.y) pair(i, j, k, i, j + 1, k);
        if (k + 1 < n.z) pair(i, j, k, i, j, k + 1);
      }
  Vec3 size = box.size();
  double stock_volume = size.x * size.y * size.z;
  // Samples cover n·g along each side; scale the kept fraction to the whole box.
  double reference_volume =
      stock_volume * static_cast<double>(kept_count) / static_cast<double>(kept.size());
  double reference_stock =
      stock_volume * static_cast<double>(stock_count) / static_cast<double>(kept.size());
  // The surface lies within h of the true one (exact dexel crossings), so the volume is within
  // h/2 · area on average; the sampled reference adds about g³·√(samples on the surface)/2.
  double cut_area = static_cast<double>(differing) * g * g;
  double sampling = 0.5 * g * g * g * std::sqrt(static_cast<double>(differing));
  double tolerance = 0.5 * h * cut_area + 4 * sampling;
  INFO("reference volume " << reference_volume << ", result " << volume << ", tolerance "
                           << tolerance << " (cut area about " << cut_area << " mm^2, h " << h
                           << ")");
  CHECK(std::abs(volume - reference_volume) <= tolerance);
  // The program cuts something well above what the cut surfaces alone would let pass.
  double cut_tolerance = 0.5 * h * static_cast<double>(differing_cut) * g * g +
                         2 * g * g * g * std::sqrt(static_cast<double>(differing_cut));
  CHECK(reference_stock - reference_volume > 3 * cut_tolerance);

  // Point membership wherever the reference classification does not change within h.
  MeshInside inside(s.mesh, 1.0);
  int compared = 0, wrong = 0;
  for (int trial = 0; trial < 4000; ++trial) {
    Vec3 p = box.min + Vec3(unit(random), unit(random), unit(random)) * box.size();
    bool reference = ref.kept(p), clear = true;
    for (int a = 0; a < 3 && clear; ++a)
      for (double sign : {-1.0, 1.0}) {
        Vec3 q = p;
        q[a] += sign * h;
        if (ref.kept(q) != reference) clear = false;
      }
    if (!clear) continue;
    ++compared;
    if (inside.inside(p) != reference) {
      ++wrong;
      if (wrong <= 5)
        MESSAGE("mismatch at " << p.x << ", " << p.y << ", " << p.z << ": reference kept "
                               << reference);
    }
  }
  CHECK(compared > 1000);
  CHECK(wrong == 0);
}

// A JSON array of three numbers as a point.
inline Vec3 vec(const nlohmann::json& j) {
  return Vec3(j[0].get<double>(), j[1].get<double>(), j[2].get<double>());
}

}  // namespace tridex::test
