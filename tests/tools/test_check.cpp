// `tridex check`: its distance tree and regions against brute force, and the planted faults of
// issue 7 end to end (a program against its own result, a plunge 0.3 mm too deep in a tilted
// direction, rapids through stock, a non-closed design, an envelope).
#include <doctest/doctest.h>

#include <png.h>

#include <cmath>
#include <cstring>
#include <functional>
#include <random>
#include <set>

#include <nlohmann/json.hpp>

#include "checks/deviation.hpp"
#include "command_harness.hpp"
#include "tridex/geometry.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace test_check {

// ---- references --------------------------------------------------------------------------------

// Distance from p to triangle abc by brute force: the interior via the plane when the foot lies
// inside, else the nearest of the three edges.
double segment_distance(const Vec3& p, const Vec3& a, const Vec3& b) {
  Vec3 ab = b - a;
  double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
  return glm::length(p - (a + t * ab));
}
double triangle_distance(const Vec3& p, const Vec3& a, const Vec3& b, const Vec3& c) {
  Vec3 n = glm::normalize(glm::cross(b - a, c - a));
  Vec3 foot = p - glm::dot(p - a, n) * n;
  bool inside = glm::dot(glm::cross(b - a, foot - a), n) >= 0 &&
                glm::dot(glm::cross(c - b, foot - b), n) >= 0 &&
                glm::dot(glm::cross(a - c, foot - c), n) >= 0;
  if (inside) return std::abs(glm::dot(p - a, n));
  return std::min(
      {segment_distance(p, a, b), segment_distance(p, b, c), segment_distance(p, c, a)});
}

Mesh box_mesh(const Aabb& box) {
  Mesh m;
  for (const Vec3& c : box.corners()) m.positions.emplace_back(c);
  const unsigned faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
  for (const auto& f : faces) {
    m.triangles.emplace_back(f[0], f[1], f[2]);
    m.triangles.emplace_back(f[0], f[2], f[3]);
  }
  return m;
}

// ---- the planted-fault program
// -------------------------------------------------------------------

const char* kStock = "box:0,0,0,20,20,10";
const std::string kTools =
    R"({"1": {"units": "mm", "shape": "cylindrical", "diameter": 6, "length": 20}})";
constexpr double kTilt = 20;  // G68.2 I0 J20 K0: the tool axis is Rx(20°)·z

// One tilted direction: a groove 1 mm deep (lines 9-10), then a plunge (line 13) to `plunge_z`.
// `extra` is inserted after line 6 (so the groove and plunge lines move down by its line count).
std::string program(double plunge_z, const std::string& extra = "") {
  std::ostringstream p;
  p << "%\nG21 G17 G90\nT1 M6\nS8000 M3\nG68.2 X10 Y10 Z10 I0 J" << kTilt << " K0\nG53.1\n"
    << extra << "G0 X-3 Y0\nG0 Z5\nG1 Z-1 F500\nG1 X3\nG0 Z5\nG0 X0 Y4\nG1 Z" << plunge_z
    << "\nG0 Z5\nG28 G91 Z0.\nG69\nM30\n%\n";
  return p.str();
}

// A feature-frame point of the program in the work frame: (10, 10, 10) + Rx(20°)·p.
Vec3 to_work(const Vec3& p) {
  double c = std::cos(glm::radians(kTilt)), s = std::sin(glm::radians(kTilt));
  return Vec3(10, 10, 10) + Vec3(p.x, c * p.y - s * p.z, s * p.y + c * p.z);
}

struct Fixture {
  fs::path dir, tools, design;
  explicit Fixture(const std::string& name)
      : dir(scratch(name)), tools(dir / "tools.json"), design(dir / "design.stl") {
    write_text(tools, kTools);
    // The design is the correct program's own simulated result.
    write_text(dir / "good.nc", program(-2));
    CommandResult made =
        run_tridex({"simulate", (dir / "good.nc").string(), "--tools", tools.string(), "--stock",
                    kStock, "--dexel-cell", "0.1", "-o", design.string(), "-q"},
                   dir);
    INFO(made.err);
    REQUIRE(made.status == 0);
  }
  ~Fixture() { fs::remove_all(dir); }
  CommandResult check(const std::string& text, std::vector<std::string> more = {}) const {
    write_text(dir / "p.nc", text);
    std::vector<std::string> args{"check",        (dir / "p.nc").string(),
                                  "--design",     design.string(),
                                  "--tools",      tools.string(),
                                  "--stock",      kStock,
                                  "--dexel-cell", "0.1",
                                  "--tolerance",  "0.1",
                                  "--report",     (dir / "report.json").string()};
    args.insert(args.end(), more.begin(), more.end());
    return run_tridex(args, dir);
  }
  json report() const { return json::parse(slurp(dir / "report.json")); }
};

std::string cat_warnings(const json& report) {
  std::string all;
  for (const json& w : report["warnings"]) all += w.get<std::string>() + "\n";
  return all;
}

struct Ply {
  std::vector<Vec3> positions;
  std::vector<std::array<int, 3>> colours;
  std::size_t faces = 0;
};

// An independent reader of the binary PLY that `check --ply` writes.
Ply read_ply(const fs::path& path) {
  std::string bytes = slurp(path);
  std::size_t end = bytes.find("end_header\n");
  REQUIRE(end != std::string::npos);
  std::istringstream header(bytes.substr(0, end));
  Ply ply;
  std::size_t vertices = 0;
  for (std::string line; std::getline(header, line);) {
    if (line.rfind("element vertex ", 0) == 0) vertices = std::stoul(line.substr(15));
    if (line.rfind("element face ", 0) == 0) ply.faces = std::stoul(line.substr(13));
  }
  CHECK(bytes.find("format binary_little_endian 1.0") != std::string::npos);
  std::size_t at = end + 11;
  REQUIRE(bytes.size() == at + vertices * 15 + ply.faces * 13);
  for (std::size_t v = 0; v < vertices; ++v, at += 15) {
    float xyz[3];
    std::memcpy(xyz, bytes.data() + at, 12);
    ply.positions.emplace_back(xyz[0], xyz[1], xyz[2]);
    ply.colours.push_back({static_cast<unsigned char>(bytes[at + 12]),
                           static_cast<unsigned char>(bytes[at + 13]),
                           static_cast<unsigned char>(bytes[at + 14])});
  }
  return ply;
}

std::size_t reddish_pixels(const fs::path& path) {
  std::string bytes = slurp(path);
  png_image image;
  std::memset(&image, 0, sizeof image);
  image.version = PNG_IMAGE_VERSION;
  REQUIRE(png_image_begin_read_from_memory(&image, bytes.data(), bytes.size()));
  image.format = PNG_FORMAT_RGB;
  std::vector<std::uint8_t> rgb(PNG_IMAGE_SIZE(image));
  REQUIRE(png_image_finish_read(&image, nullptr, rgb.data(), 0, nullptr));
  std::size_t red = 0;
  for (std::size_t k = 0; k < rgb.size(); k += 3)
    red += rgb[k] > 150 && rgb[k + 1] < 90 && rgb[k + 2] < 90;
  return red;
}

TEST_CASE("the distance tree matches brute force, and signs by the face or the inside test") {
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-5, 5);
  Mesh soup;
  for (int t = 0; t < 300; ++t) {
    auto base = static_cast<unsigned>(soup.positions.size());
    Vec3 c(u(rng), u(rng), u(rng));
    for (int k = 0; k < 3; ++k) soup.positions.emplace_back(c + 0.3 * Vec3(u(rng), u(rng), u(rng)));
    soup.triangles.emplace_back(base, base + 1, base + 2);
  }
  cli::DistanceTree tree(soup);
  for (int q = 0; q < 500; ++q) {
    Vec3 p(1.5 * u(rng), 1.5 * u(rng), 1.5 * u(rng));
    double best = std::numeric_limits<double>::infinity();
    for (const glm::uvec3& t : soup.triangles)
      best =
          std::min(best, triangle_distance(p, Vec3(soup.positions[t.x]), Vec3(soup.positions[t.y]),
                                           Vec3(soup.positions[t.z])));
    CHECK(tree.nearest(p).distance == doctest::Approx(best).epsilon(1e-9));
  }
  // A box: the signed distance is the analytic one (negative inside), whichever way it is signed.
  Aabb box{Vec3(-1, -2, -3), Vec3(2, 1, 0.5)};
  Mesh cube = box_mesh(box);
  cli::DistanceTree cube_tree(cube);
  auto inside = [&](const Vec3& p) { return box.contains(p); };
  for (int q = 0; q < 500; ++q) {
    Vec3 p(u(rng), u(rng), u(rng));
    Vec3 outside = glm::max(glm::max(box.min - p, p - box.max), Vec3(0));
    double reference = glm::length(outside) > 0
                           ? glm::length(outside)
                           : -std::min({p.x - box.min.x, box.max.x - p.x, p.y - box.min.y,
                                        box.max.y - p.y, p.z - box.min.z, box.max.z - p.z});
    CHECK(cube_tree.signed_distance(p, inside) == doctest::Approx(reference).epsilon(1e-9));
  }
  CHECK_THROWS_AS(cli::DistanceTree(Mesh{}), tridex::Error);
}

TEST_CASE("deviation regions are the connected components of the selected vertices") {
  // A grid of n x n vertices (two triangles per cell), random selections, against a flood fill.
  const int n = 30;
  Mesh grid;
  for (int j = 0; j < n; ++j)
    for (int i = 0; i < n; ++i) grid.positions.emplace_back(i, j, 0);
  for (int j = 0; j + 1 < n; ++j)
    for (int i = 0; i + 1 < n; ++i) {
      auto v = static_cast<unsigned>(i + n * j);
      grid.triangles.emplace_back(v, v + 1, v + 1 + n);
      grid.triangles.emplace_back(v, v + 1 + n, v + n);
    }
  std::mt19937 rng(11);
  for (int round = 0; round < 20; ++round) {
    std::vector<char> selected(grid.positions.size());
    std::vector<double> deviation(grid.positions.size());
    for (std::size_t v = 0; v < selected.size(); ++v) {
      selected[v] = std::uniform_real_distribution<double>(0, 1)(rng) < 0.45;
      deviation[v] = std::uniform_real_distribution<double>(-1, 1)(rng);
    }
    // Flood fill over the mesh's edges.
    std::vector<std::vector<unsigned>> next(grid.positions.size());
    for (const glm::uvec3& t : grid.triangles)
      for (int e = 0; e < 3; ++e)
        next[t[e]].push_back(t[(e + 1) % 3]), next[t[(e + 1) % 3]].push_back(t[e]);
    std::vector<int> label(selected.size(), -1);
    std::vector<std::size_t> sizes;
    std::vector<double> depths;
    for (unsigned s = 0; s < selected.size(); ++s) {
      if (!selected[s] || label[s] >= 0) continue;
      std::vector<unsigned> stack{s};
      label[s] = static_cast<int>(sizes.size());
      sizes.push_back(0);
      depths.push_back(0);
      while (!stack.empty()) {
        unsigned v = stack.back();
        stack.pop_back();
        ++sizes.back();
        depths.back() = std::max(depths.back(), std::abs(deviation[v]));
        for (unsigned w : next[v])
          if (selected[w] && label[w] < 0) label[w] = label[s], stack.push_back(w);
      }
    }
    std::vector<cli::DeviationRegion> regions = cli::deviation_regions(grid, deviation, selected);
    REQUIRE(regions.size() == sizes.size());
    std::multiset<std::size_t> expected(sizes.begin(), sizes.end()), got;
    double area = 0, expected_area = 0;
    for (const cli::DeviationRegion& r : regions) {
      got.insert(r.vertices.size());
      area += r.area;
      int l = label[r.vertices[0]];
      for (unsigned v : r.vertices) CHECK(label[v] == l);
      CHECK(r.depth == depths[static_cast<std::size_t>(l)]);
    }
    for (std::size_t k = 1; k < regions.size(); ++k)
      CHECK(regions[k - 1].depth >= regions[k].depth);
    CHECK(got == expected);
    // Each triangle (area 1/2) gives a third of its area per selected corner.
    for (const glm::uvec3& t : grid.triangles)
      for (int k = 0; k < 3; ++k) expected_area += selected[t[k]] ? 0.5 / 3 : 0;
    CHECK(area == doctest::Approx(expected_area));
  }
}

TEST_CASE("check: a program against its own result passes (exit 0), with a PLY and a picture") {
  Fixture f("check-own");
  fs::path ply = f.dir / "own.ply", png = f.dir / "own.png";
  CommandResult r = f.check(program(-2), {"--ply", ply.string(), "--png", png.string()});
  INFO(r.err);
  INFO(r.out);
  CHECK(r.status == 0);
  json report = f.report();
  CHECK(report["verdict"] == "pass");
  CHECK(report["gouges"].empty());
  CHECK(report["excess"].empty());
  CHECK(report["rapid_cuts"].empty());  // the retracts (lines 11, 14) only pass through cut space
  CHECK(report["tolerances_mm"]["gouge"] == 0.1);
  CHECK(std::abs(report["deviation"]["min_mm"].get<double>()) <= 0.1);
  CHECK(std::abs(report["deviation"]["max_mm"].get<double>()) <= 0.1);
  CHECK(report["design_side"]["missing"]["samples"] == 0);
  long long counted = 0;
  for (long long c : report["deviation"]["histogram"]["counts"]) counted += c;
  CHECK(counted == report["deviation"]["samples"].get<long long>());
  Ply mesh = read_ply(ply);
  CHECK(mesh.positions.size() == report["deviation"]["samples"].get<std::size_t>());
  CHECK(mesh.faces == report["result"]["triangles"].get<std::size_t>());
  for (const auto& c : mesh.colours)
    CHECK((c[0] < 200 && c[2] < 200));  // neither gouge red nor excess blue
  CHECK(reddish_pixels(png) < 400);     // the legend's swatch (14 x 14 pixels) only
}

TEST_CASE(
    "check: a plunge 0.3 mm too deep in a tilted direction is a gouge of 0.3 mm at its place and "
    "line") {
  Fixture f("check-gouge");
  fs::path ply = f.dir / "gouge.ply", png = f.dir / "gouge.png";
  CommandResult r = f.check(program(-2.3), {"--ply", ply.string(), "--png", png.string()});
  INFO(r.err);
  INFO(r.out);
  CHECK(r.status == 3);
  json report = f.report();
  CHECK(report["verdict"] == "fail");
  REQUIRE(report["gouges"].size() == 1);
  const json& gouge = report["gouges"][0];
  CHECK(gouge["depth_mm"].get<double>() ==
        doctest::Approx(0.3).epsilon(0.1 / 0.3));  // within a dexel cell
  CHECK(gouge["lines"] == json::array({13}));
  CHECK(r.out.find("p.nc:13") != std::string::npos);
  // The deepest point lies on the faulty hole's floor: in the feature frame within the tool's
  // radius of (0, 4) and about 2.3 deep; the region's centre near the floor's centre.
  Vec3 deepest(gouge["deepest_point"][0].get<double>(), gouge["deepest_point"][1].get<double>(),
               gouge["deepest_point"][2].get<double>());
  Vec3 floor_centre = to_work(Vec3(0, 4, -2.3)), axis = to_work(Vec3(0, 0, 1)) - to_work(Vec3(0));
  Vec3 offset = deepest - floor_centre;
  CHECK(std::abs(glm::dot(offset, axis)) <= 0.3 + 0.15);
  CHECK(glm::length(offset - glm::dot(offset, axis) * axis) <= 3 + 0.15);
  Vec3 centroid(gouge["centroid"][0].get<double>(), gouge["centroid"][1].get<double>(),
                gouge["centroid"][2].get<double>());
  CHECK(glm::length(centroid - floor_centre) < 1.0);
  // The floor is a disc of radius 3 (area 28.3 mm²) and the extra wall is short.
  CHECK(gouge["area_mm2"].get<double>() > 20);
  CHECK(gouge["area_mm2"].get<double>() < 40);
  CHECK(report["deviation"]["min_mm"].get<double>() ==
        doctest::Approx(-gouge["depth_mm"].get<double>()));
  CHECK(report["excess"].empty());
  // From the design's side the correct floor is material missing, 0.3 mm from the machined one.
  CHECK(report["design_side"]["missing"]["depth_mm"].get<double>() ==
        doctest::Approx(0.3).epsilon(0.1 / 0.3));
  Ply mesh = read_ply(ply);
  std::size_t red = 0;
  for (std::size_t v = 0; v < mesh.positions.size(); ++v)
    if (mesh.colours[v][0] > 200 && mesh.colours[v][1] < 90) {
      ++red;
      CHECK(glm::length(mesh.positions[v] - floor_centre) < 3 + 0.5);
    }
  CHECK(red == gouge["vertices"].get<std::size_t>());
  CHECK(reddish_pixels(png) > 1000);
}

TEST_CASE("check: a hole left out is excess, from the machined side and from the design's") {
  Fixture f("check-excess");
  CommandResult r = f.check(program(5));  // the "plunge" stays above the stock
  INFO(r.err);
  INFO(r.out);
  CHECK(r.status == 3);
  json report = f.report();
  CHECK(report["gouges"].empty());
  CHECK(report["rapid_cuts"].empty());
  REQUIRE(!report["excess"].empty());
  // Over the hole's floor (feature z = -2, radius 3 around (0, 4)) the material left is the
  // groove's floor (z = -1, where y ≤ 3) or else the top face (z = -y·tan 20°, below -1.09 for
  // y > 3): at most 1 mm above the floor, from the groove. Within a dexel cell (0.1 mm).
  double deepest = 0;
  for (double y = 1; y <= 7; y += 0.001)
    deepest = std::max(deepest, (y <= 3 ? -1.0 : -y * std::tan(glm::radians(kTilt))) + 2);
  const json& excess = report["excess"][0];
  CHECK(excess["depth_mm"].get<double>() == doctest::Approx(deepest).epsilon(0.1 / deepest));
  // Its lines (issue 39): the moves nearest it, the plunge that stopped above the hole (line 13)
  // among them, and the groove beside it (line 10).
  const std::string lines = excess["lines"].dump();
  CHECK(lines.find("13") != std::string::npos);
  CHECK(lines.find("10") != std::string::npos);
  Vec3 centroid(excess["centroid"][0].get<double>(), excess["centroid"][1].get<double>(),
                excess["centroid"][2].get<double>());
  CHECK(glm::length(centroid - to_work(Vec3(0, 4, -1))) < 2.5);
  // The hole's floor and wall, seen from the design, lie inside the machined solid.
  CHECK(report["design_side"]["left"]["samples"].get<long long>() > 0);
  CHECK(report["design_side"]["left"]["depth_mm"].get<double>() ==
        doctest::Approx(deepest).epsilon(0.1 / deepest));
  CHECK(report["design_side"]["missing"]["samples"] == 0);
}

TEST_CASE("check: rapids through material are reported with their line, in program order") {
  Fixture f("check-rapid");
  // Line 8 rapids 0.5 mm into the stock where the groove (lines 12-13) cuts later: no gouge, but a
  // crash on a real machine, which simulate's feeds-first check cannot see.
  CommandResult r = f.check(program(-2, "G0 X-3 Y0\nG0 Z-0.5\nG0 Z5\n"));
  INFO(r.err);
  INFO(r.out);
  CHECK(r.status == 3);
  json report = f.report();
  CHECK(report["gouges"].empty());
  REQUIRE(report["rapid_cuts"].size() == 1);
  CHECK(report["rapid_cuts"][0]["line"] == 8);
  CHECK(report["rapid_cuts"][0]["depth_mm"].get<double>() > 0.3);
  CHECK(r.out.find("p.nc:8: rapid cuts") != std::string::npos);

  // A rapid through material no move removes: a rapid and a gouge, both at line 8.
  r = f.check(program(-2, "G0 X5 Y-5\nG0 Z-1.5\nG0 Z5\n"));
  CHECK(r.status == 3);
  report = f.report();
  REQUIRE(report["rapid_cuts"].size() == 1);
  CHECK(report["rapid_cuts"][0]["line"] == 8);
  REQUIRE(!report["gouges"].empty());
  CHECK(report["gouges"][0]["lines"] == json::array({8}));
}

TEST_CASE("check and simulate: positions outside the machine's travel") {
  Fixture f("check-travel");
  // The bundled B/C trunnion with a Z travel that the program's retracts leave, in machine
  // coordinates (the tilt puts the part's points elsewhere on the machine than in the work frame).
  write_text(
      f.dir / "m.json",
      R"({"kinematics": {"profile": "bc-trunnion", "travel": {"X": [-200, 200], "Z": [-50, 5]}}})");
  std::string machine = (f.dir / "m.json").string();
  CommandResult r = f.check(program(-2), {"--machine", machine});
  INFO(r.err);
  CHECK(r.status == 3);
  json report = f.report();
  // The reference: every move of `tridex moves` whose machine position ends past a travel end,
  // leaving out the positions "far along the tool axis" that stand in for home returns.
  fs::path moves = f.dir / "moves.jsonl";
  REQUIRE(
      run_tridex({"moves", (f.dir / "p.nc").string(), "--machine", machine, "-o", moves.string()},
                 f.dir)
          .status == 0);
  std::vector<std::pair<int, double>> expected;  // (line, machine z)
  std::istringstream in(slurp(moves));
  for (std::string line; std::getline(in, line);) {
    json m = json::parse(line);
    Vec3 end(m["end"][0].get<double>(), m["end"][1].get<double>(), m["end"][2].get<double>());
    double x = m["machine"][0].get<double>(), z = m["machine"][2].get<double>();
    CHECK(std::abs(x) < 200);
    if (glm::length(end) < 5000 && (z > 5 || z < -50))
      expected.emplace_back(m["line"].get<int>(), z);
  }
  REQUIRE(!expected.empty());
  REQUIRE(report["travel"]["outside"].get<std::size_t>() == expected.size());
  const json& violations = report["travel"]["violations"];
  REQUIRE(violations.size() == expected.size());
  for (std::size_t k = 0; k < expected.size(); ++k) {
    CHECK(violations[k]["line"].get<int>() == expected[k].first);
    CHECK(violations[k]["axis"] == "Z");
    CHECK(violations[k]["value"].get<double>() == doctest::Approx(expected[k].second));
    CHECK(violations[k]["limit"].get<double>() == 5.0);
    CHECK(violations[k]["file"] == (f.dir / "p.nc").string());
  }
  CHECK(r.out.find("past the travel's end 5") != std::string::npos);
  // Within the travel: no finding, and the report still says how many were outside (none).
  write_text(f.dir / "wide.json",
             R"({"kinematics": {"profile": "bc-trunnion", "travel": {"Z": [-50, 500]}}})");
  CHECK(f.check(program(-2), {"--machine", (f.dir / "wide.json").string()}).status == 0);
  CHECK(f.report()["travel"]["outside"] == 0);
  // simulate: one warning that counts them and names the first.
  fs::path sim_report = f.dir / "sim.json";
  CommandResult s = run_tridex(
      {"simulate", (f.dir / "p.nc").string(), "--tools", f.tools.string(), "--stock", kStock,
       "--dexel-cell", "0.2", "--machine", machine, "--report", sim_report.string(), "-q"},
      f.dir);
  REQUIRE(s.status == 0);
  std::string warning = cat_warnings(json::parse(slurp(sim_report)));
  CHECK_MESSAGE(
      warning.find(std::to_string(expected.size()) +
                   " position(s) outside the machine's travel (first " + (f.dir / "p.nc").string() +
                   ":" + std::to_string(expected[0].first) + ": Z ") != std::string::npos,
      warning);
  // A bad travel is an input error naming the key.
  write_text(f.dir / "bad.json",
             R"({"kinematics": {"profile": "bc-trunnion", "travel": {"Z": [5, -5]}}})");
  CommandResult bad = f.check(program(-2), {"--machine", (f.dir / "bad.json").string()});
  CHECK(bad.status == 2);
  CHECK(bad.err.find("kinematics.travel.Z") != std::string::npos);
}

TEST_CASE("check: moves outside the envelope, bad designs and bad options") {
  Fixture f("check-envelope");
  // Feature-frame z = 5 is above work z = 14 for every retract of the program (y ≥ -3).
  CommandResult r = f.check(program(-2), {"--envelope", "box:-50,-50,-50,50,50,14"});
  INFO(r.err);
  CHECK(r.status == 3);
  json report = f.report();
  std::set<int> lines;
  for (const json& v : report["envelope"]["violations"]) {
    lines.insert(v["line"].get<int>());
    CHECK(v["tip"][2].get<double>() > 14);
  }
  // The reference: the lines of the interpreted moves (`tridex moves`) whose tip ends above
  // z = 14, leaving out the positions "far along the tool axis" that stand in for home returns.
  fs::path moves = f.dir / "moves.jsonl";
  REQUIRE(run_tridex({"moves", (f.dir / "p.nc").string(), "-o", moves.string()}, f.dir).status ==
          0);
  std::set<int> expected;
  std::istringstream in(slurp(moves));
  for (std::string line; std::getline(in, line);) {
    json m = json::parse(line);
    Vec3 end(m["end"][0].get<double>(), m["end"][1].get<double>(), m["end"][2].get<double>());
    if (glm::length(end) < 5000 && end.z > 14) expected.insert(m["line"].get<int>());
  }
  CHECK(expected.count(8) == 1);  // the first retract, at least
  CHECK(lines == expected);
  CHECK(f.check(program(-2), {"--envelope", "box:-50,-50,-50,50,50,50"}).status == 0);
  CHECK(f.check(program(-2), {"--envelope", "box:1,2,3"}).status == 2);
  CHECK(f.check(program(-2), {"--envelope", "box:0,0,0,-1,1,1"}).status == 2);

  // A design that is not closed is an error that says so.
  fs::path open = f.dir / "open.stl";
  write_text(open,
             "solid open\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 0\n   "
             "vertex 0 1 0\n"
             "  endloop\n endfacet\nendsolid open\n");
  write_text(f.dir / "p.nc", program(-2));
  r = run_tridex({"check", (f.dir / "p.nc").string(), "--design", open.string(), "--tools",
                  f.tools.string(), "--stock", kStock, "--report", (f.dir / "never.json").string()},
                 f.dir);
  CHECK(r.status == 2);
  CHECK(r.err.find("not closed") != std::string::npos);
  CHECK(!fs::exists(f.dir / "never.json"));
  // Options: --tolerance excludes the split tolerances; --design is required; an output over an
  // input is refused; the rapid check needs the exact Z-map milling.
  CHECK(f.check(program(-2), {"--gouge-tol", "0.2"}).status == 2);
  CHECK(
      run_tridex({"check", (f.dir / "p.nc").string(), "--tools", f.tools.string()}, f.dir).status ==
      2);
  CHECK(f.check(program(-2), {"--ply", f.design.string()}).status == 2);
  CHECK(f.check(program(-2), {"--zmap-backend", "gl"}).status == 2);
}

}  // namespace test_check
