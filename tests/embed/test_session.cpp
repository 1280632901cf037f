// The embedded session (tools/embed/session.hpp, issue 38): the bundled example fed in pieces
// gives simulate's solid, whatever the split; the removed volume against analytic solids; would_cut
// and inside against what the moves leave, worked out by hand, across directions.
#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <random>
#include <sstream>
#include <string>
#include <vector>

#include "errors.hpp"
#include "outputs/result_files.hpp"
#include "pipeline/pipeline.hpp"
#include "session.hpp"
#include "tridex/gcode/diagnostic.hpp"

namespace test_session {

namespace fs = std::filesystem;
using namespace tridex;

const fs::path kExamples = fs::path(TRIDEX_SOURCE_DIR) / "gcode" / "examples";

std::vector<std::string> lines_of(const fs::path& path) {
  std::ifstream in(path);
  std::vector<std::string> lines;
  for (std::string line; std::getline(in, line);) lines.push_back(line + "\n");
  return lines;
}

std::string join(const std::vector<std::string>& lines, std::size_t a, std::size_t b) {
  std::string text;
  for (std::size_t k = a; k < b; ++k) text += lines[k];
  return text;
}

embed::SessionOptions session_options(const Aabb& stock, const std::string& tools, double cell) {
  embed::SessionOptions o;
  o.stock = stock;
  o.tools = tools;
  o.cell = cell;
  return o;
}

bool same_mesh(const Mesh& a, const Mesh& b) {
  return a.positions == b.positions && a.triangles == b.triangles;
}

TEST_CASE("session: the example fed in pieces is simulate's solid, for any split") {
  const fs::path program = kExamples / "mold_3plus2.nc";
  const fs::path tools = kExamples / "mold_3plus2.tools.json";
  cli::SimulateOptions options;
  options.program = program.string();
  options.tools = tools.string();
  options.stock = "box:0,0,0,100,80,50";
  options.dexel_cell = 3;  // coarse: the test's time
  options.quiet = true;
  cli::Progress progress(false);
  const cli::SimulationResult whole = cli::simulate_program(options, progress);
  REQUIRE(whole.groups.size() == 5);

  const std::vector<std::string> lines = lines_of(program);
  const std::size_t n = lines.size();
  std::mt19937 random(38);
  const std::vector<std::vector<std::size_t>> splits = {
      {0, 1, 20, 373, 5962, 21560, 21936, 22300, n},  // at tool changes and tilted planes
      {0, n / 7, n / 3, n / 2 + 11, n - 40, n}};
  for (const std::vector<std::size_t>& cuts : splits) {
    CAPTURE(cuts.size());
    embed::Session s(session_options(Aabb{Vec3(0), Vec3(100, 80, 50)}, tools.string(), 3));
    CHECK(s.zmap_cell() == doctest::Approx(whole.zmap_cell));
    for (std::size_t k = 0; k + 1 < cuts.size(); ++k) s.feed(join(lines, cuts[k], cuts[k + 1]));
    CHECK(s.moves() == whole.segments);
    CHECK(same_mesh(s.mesh(), whole.mesh));
    CHECK(s.removed_volume() == doctest::Approx(whole.stock.volume - whole.volume).epsilon(1e-12));
  }
}

TEST_CASE("session: each question after a piece answers as a whole rebuild, for random splits") {
  // The solid is brought up to date only where a piece changed a map (solid_cache.hpp): after
  // every piece it must be the solid a fresh session makes of the program so far in one piece.
  const fs::path program = kExamples / "mold_3plus2.nc";
  const fs::path tools = kExamples / "mold_3plus2.tools.json";
  const Aabb stock{Vec3(0), Vec3(100, 80, 50)};
  const std::vector<std::string> lines = lines_of(program);
  std::mt19937 random(3838);
  std::uniform_int_distribution<std::size_t> at(1, lines.size() - 1);
  std::vector<std::size_t> cuts = {0, lines.size()};
  for (int k = 0; k < 3; ++k) cuts.push_back(at(random));
  // Short pieces in the +z roughing and at the first tilted plane: a part of a map changes.
  for (std::size_t line : {300, 420, 5990}) cuts.push_back(line);
  std::sort(cuts.begin(), cuts.end());
  cuts.erase(std::unique(cuts.begin(), cuts.end()), cuts.end());
  embed::Session s(session_options(stock, tools.string(), 5));
  double least = 1;
  for (std::size_t k = 0; k + 1 < cuts.size(); ++k) {
    CAPTURE(cuts[k]);
    s.feed(join(lines, cuts[k], cuts[k + 1]));
    const double removed = s.removed_volume();
    least = std::min(least, s.last_rays_redone());
    embed::Session whole(session_options(stock, tools.string(), 5));
    whole.feed(join(lines, 0, cuts[k + 1]));
    CHECK(same_mesh(s.mesh(), whole.mesh()));
    CHECK(removed == whole.removed_volume());
  }
  CHECK(least < 0.6);  // some pieces were not rebuilt whole
}

// A 10 mm flat end mill (T1) and the stock 0..40 x 0..40 x 0..20.
std::string flat_table(const fs::path& dir) {
  const fs::path path = dir / "flat.json";
  std::ofstream(path) << R"({"1": {"units": "mm", "shape": "cylindrical", "length": 50,
                                  "diameter": 10}})";
  return path.string();
}

fs::path scratch(const char* name) {
  fs::path dir = fs::temp_directory_path() / ("tridex_test_session_" + std::string(name));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

// Facing from +z down to `z` across the whole stock (passes 8 mm apart, 10 mm tool).
std::string facing(double z) {
  std::ostringstream g;
  g << "G0 X-10 Y-8\nG0 Z" << z + 5 << "\nG1 Z" << z << " F500\n";
  for (int row = 0; row <= 6; ++row)
    g << "G1 X" << (row % 2 ? -10 : 50) << "\nG1 Y" << -8 + 8 * (row + 1) << "\n";
  g << "G0 Z30\n";
  return g.str();
}

// Facing from -x (tool axis -x: G68.2 I-90 J90, as the example's -x side) down to world x = `x`.
std::string side_facing(double x) {
  std::ostringstream g;
  g << "G68.2 X0 Y20 Z10 I-90 J90 K0\nG53.1\nG0 X-40 Y-40\nG0 Z5\nG1 Z" << -x << " F500\n";
  for (int row = 0; row <= 10; ++row)
    g << "G1 X" << (row % 2 ? -40 : 40) << "\nG1 Y" << -40 + 8 * (row + 1) << "\n";
  // Back upright: G69 alone keeps the tool along -x (docs/gcode.md).
  g << "G0 Z30\nG68.2 X0 Y0 Z0 I0 J0 K0\nG53.1\nG69\n";
  return g.str();
}

const char* kStart = "G21 G90 G17\nT1 M6\nS8000 M3\n";

TEST_CASE("session: removed volume against analytic solids, piece by piece") {
  const fs::path dir = scratch("volume");
  embed::Session s(session_options(Aabb{Vec3(0), Vec3(40, 40, 20)}, flat_table(dir), 0.5));
  s.feed(kStart);
  CHECK(s.removed_volume() == doctest::Approx(0).epsilon(1e-9));
  s.feed(facing(15));  // 40 x 40 x 5
  CHECK(s.removed_volume() == doctest::Approx(8000).epsilon(5e-4));
  s.feed(side_facing(12));  // 12 x 40 x 15 more
  CHECK(s.removed_volume() == doctest::Approx(8000 + 7200).epsilon(5e-4));
  // A slot 10 wide, 3 deep along y at x = 20: its walls parallel to the spindle lie inside cells.
  s.feed("G0 X26 Y-10\nG1 Z12 F300\nG1 Y50\nG0 Z30\n");
  CHECK(s.removed_volume() == doctest::Approx(15200 + 10 * 40 * 3).epsilon(2e-3));
}

TEST_CASE("session: would_cut and inside see every direction's cuts") {
  const fs::path dir = scratch("queries");
  embed::Session s(session_options(Aabb{Vec3(0), Vec3(40, 40, 20)}, flat_table(dir), 0.5));
  s.feed(kStart);
  s.feed(facing(15));
  s.feed(side_facing(12));
  // A plunge from +z: material under the whole disc down to it, above 15 none.
  CHECK(s.would_cut("G0 X20 Y20\nG1 Z10 F300") == doctest::Approx(5).epsilon(0.01));
  CHECK(s.would_cut("G0 X20 Y20\nG1 Z16 F300") == 0);
  CHECK(s.would_cut("G0 X-20 Y20\nG1 Z2 F300") == 0);  // beside the stock
  // Over the band the -x facing removed (x < 12): a +z Z-map alone still holds material there.
  CHECK(s.would_cut("G0 X6 Y20\nG1 Z2 F300") == 0);
  CHECK(s.would_cut("G0 X8 Y20\nG1 Z2 F300") == doctest::Approx(13).epsilon(0.01));
  // Asking cut nothing and left the interpreter where it was.
  CHECK(s.removed_volume() == doctest::Approx(15200).epsilon(5e-4));
  // inside against the solid worked out by hand, at random points off its faces.
  std::mt19937 random(38);
  std::uniform_real_distribution<double> u(-5, 45);
  int checked = 0;
  for (int k = 0; k < 400; ++k) {
    const Vec3 p(u(random), u(random), u(random) * 0.5);
    const bool in = p.x > 12 && p.x < 40 && p.y > 0 && p.y < 40 && p.z > 0 && p.z < 15;
    const double margin = std::min({std::abs(p.x - 12), std::abs(p.x - 40), std::abs(p.y),
                                    std::abs(p.y - 40), std::abs(p.z), std::abs(p.z - 15)});
    if (margin < 0.5) continue;  // within a dexel spacing of a face
    CAPTURE(p);
    CHECK(s.inside(p) == in);
    ++checked;
  }
  CHECK(checked > 300);
}

TEST_CASE("session: the stock's extent along a line, against the solid and against inside") {
  const fs::path dir = scratch("extent");
  embed::Session s(session_options(Aabb{Vec3(0), Vec3(40, 40, 20)}, flat_table(dir), 0.5));
  s.feed(kStart);
  s.feed(facing(15));
  s.feed(side_facing(12));  // left: 12..40 x 0..40 x 0..15
  using Spans = std::vector<std::pair<double, double>>;
  auto near = [](const Spans& got, const Spans& want) {
    if (got.size() != want.size()) return false;
    for (std::size_t k = 0; k < got.size(); ++k)
      if (std::abs(got[k].first - want[k].first) > 0.05 ||
          std::abs(got[k].second - want[k].second) > 0.05)
        return false;
    return true;
  };
  CHECK(near(s.extent(Vec3(20, 20, 0), Vec3(0, 0, 1)), {{0, 15}}));    // the height at 20, 20
  CHECK(near(s.extent(Vec3(20, 20, 0), Vec3(0, 0, -2)), {{-15, 0}}));  // any length, sign
  CHECK(near(s.extent(Vec3(0, 20, 5), Vec3(1, 0, 0)), {{12, 40}}));
  CHECK(near(s.extent(Vec3(30, -10, 5), Vec3(0, 1, 0)), {{10, 50}}));
  CHECK(s.extent(Vec3(6, 20, 0), Vec3(0, 0, 1)).empty());  // the -x facing took it all
  // Skew lines against inside() at points along them, away from the surface.
  std::mt19937 random(383);
  std::uniform_real_distribution<double> u(-1, 1), w(0, 40);
  int checked = 0;
  for (int line = 0; line < 12; ++line) {
    const Vec3 p(w(random), w(random), w(random) * 0.5);
    const Vec3 d = glm::normalize(Vec3(u(random), u(random), u(random)));
    const Spans spans = s.extent(p, d);
    CAPTURE(p);
    CAPTURE(d);
    for (double t = -60; t <= 60; t += 1.7) {
      bool in = false;
      double margin = 1e9;
      for (const auto& [a, b] : spans) {
        in = in || (t > a && t < b);
        margin = std::min({margin, std::abs(t - a), std::abs(t - b)});
      }
      if (margin < 0.5) continue;  // within a dexel spacing of the surface
      CHECK(s.inside(p + t * d) == in);
      ++checked;
    }
  }
  CHECK(checked > 500);
  CHECK_THROWS_AS(s.extent(Vec3(0), Vec3(0)), cli::InputError);
}

TEST_CASE("session: moves given directly cut as the same moves in G-code; removal per piece") {
  const fs::path dir = scratch("direct");
  const std::string table = flat_table(dir);
  const Aabb stock{Vec3(0), Vec3(40, 40, 20)};
  const std::string program = std::string(kStart) + facing(15) + side_facing(12) +
                              "G0 X26 Y-10\nG1 Z12 F300\nG1 Y50\nG0 Z30\n";
  embed::Session by_gcode(session_options(stock, table, 1));
  const double removed = by_gcode.feed_measured(program);
  CHECK(removed == doctest::Approx(15200 + 10 * 40 * 3).epsilon(2e-3));
  CHECK(removed == by_gcode.removed_volume());
  const long long cut = by_gcode.moves();
  CHECK(by_gcode.feed_measured("G0 X20 Y20 Z30\n") == 0);  // in the air
  // The same moves, as the interpreter makes them, given one by one.
  gcode::Interpreter interpreter;
  std::vector<gcode::Move> moves;
  std::istringstream in(program);
  interpreter.feed(in, "direct", [&](const gcode::Move& m) { moves.push_back(m); });
  embed::Session direct(session_options(stock, table, 1));
  int tilted = 0;
  for (const gcode::Move& m : moves) {
    if (m.tool == 0) continue;  // before T1 M6: simulate does not cut them either
    direct.add_move(m.start, m.end, m.tool, m.axis * 3.0, m.kind == gcode::MoveKind::rapid);
    tilted += m.axis.z < 0.5;
  }
  CHECK(tilted > 10);
  CHECK(direct.moves() == cut);
  CHECK(same_mesh(direct.mesh(), by_gcode.mesh()));
  CHECK_THROWS_AS(direct.add_move(Vec3(0), Vec3(1), 7, Vec3(0, 0, 1)), cli::InputError);
  CHECK_THROWS_AS(direct.add_move(Vec3(0), Vec3(1), 1, Vec3(0)), cli::InputError);
  CHECK(direct.moves() == cut);
}

TEST_CASE("session: the same solid on 1 and on 3 kept threads") {
  const fs::path dir = scratch("threads");
  const std::string table = flat_table(dir);
  const std::vector<std::string> pieces = {kStart, facing(15), side_facing(12),
                                           "G0 X26 Y-10\nG1 Z12 F300\nG1 Y50\nG0 Z30\n"};
  embed::SessionOptions one = session_options(Aabb{Vec3(0), Vec3(40, 40, 20)}, table, 0.5);
  embed::SessionOptions three = one;
  one.threads = 1, three.threads = 3;
  embed::Session a(one), b(three);
  for (const std::string& piece : pieces) {
    a.feed(piece), b.feed(piece);
    CHECK(a.removed_volume() == b.removed_volume());
  }
  CHECK(same_mesh(a.mesh(), b.mesh()));
}

// A ramp 40 x 40, 20 high at x = 0 down to 4 at x = 40, as a closed, outward STL.
fs::path ramp_stl(const fs::path& dir) {
  Mesh m;
  for (const Vec3& p : {Vec3(0, 0, 0), Vec3(40, 0, 0), Vec3(40, 40, 0), Vec3(0, 40, 0),
                        Vec3(0, 0, 20), Vec3(40, 0, 4), Vec3(40, 40, 4), Vec3(0, 40, 20)})
    m.positions.emplace_back(p);
  const Vec3 centre(20, 20, 6);
  auto quad = [&](unsigned a, unsigned b, unsigned c, unsigned d) {
    for (glm::uvec3 t : {glm::uvec3(a, b, c), glm::uvec3(a, c, d)}) {
      const Vec3 p0(m.positions[t.x]), p1(m.positions[t.y]), p2(m.positions[t.z]);
      if (glm::dot(glm::cross(p1 - p0, p2 - p0), p0 - centre) < 0) std::swap(t.y, t.z);
      m.triangles.push_back(t);
    }
  };
  quad(0, 1, 2, 3), quad(4, 5, 6, 7), quad(0, 1, 5, 4), quad(1, 2, 6, 5), quad(2, 3, 7, 6),
      quad(3, 0, 4, 7);
  const fs::path path = dir / "ramp.stl";
  cli::write_stl_file(path, m);
  return path;
}

TEST_CASE("session: a mesh stock, fed in pieces, is simulate's solid on that STL") {
  const fs::path dir = scratch("mesh_stock");
  const std::string table = flat_table(dir);
  const fs::path stock = ramp_stl(dir);
  const std::string program = std::string(kStart) + facing(14) + side_facing(10) +
                              "G0 X26 Y-10\nG1 Z6 F300\nG1 Y50\nG0 Z30\n";
  const fs::path file = dir / "ramp.nc";
  std::ofstream(file) << program;
  cli::SimulateOptions options;
  options.program = file.string();
  options.tools = table;
  options.stock = stock.string();
  options.dexel_cell = 1;
  options.quiet = true;
  cli::Progress progress(false);
  const cli::SimulationResult whole = cli::simulate_program(options, progress);
  embed::SessionOptions o = session_options(Aabb{}, table, 1);
  o.stock_file = stock.string();
  embed::Session s(o);
  const std::vector<std::string> lines = lines_of(file);
  s.feed(join(lines, 0, 12));
  CHECK(s.removed_volume() > 0);  // the top of the ramp above z 14
  s.feed(join(lines, 12, 30));
  s.removed_volume();  // brought up to date in between
  s.feed(join(lines, 30, lines.size()));
  CHECK(same_mesh(s.mesh(), whole.mesh));
  CHECK(s.removed_volume() == doctest::Approx(whole.stock.volume - whole.volume).epsilon(1e-12));
  o.stock_file = (dir / "none.stl").string();
  CHECK_THROWS_AS(embed::Session{o}, cli::InputError);
}

TEST_CASE("session: a piece that fails changes nothing; state carries over") {
  const fs::path dir = scratch("errors");
  embed::Session s(session_options(Aabb{Vec3(0), Vec3(40, 40, 20)}, flat_table(dir), 1));
  s.feed(kStart);
  s.feed("G0 X20 Y20 Z25\nF400\n");
  CHECK_THROWS_AS(s.feed("G1 Z10\nT7 M6\nG1 Z5\n"), cli::InputError);  // T7: not in the table
  CHECK_THROWS_AS(s.feed("G1 Z10\nG1 Q\n"), gcode::GcodeError);
  CHECK(s.moves() == 1);
  CHECK(s.removed_volume() == 0);
  s.feed("G1 Z18\n");  // F400 from an earlier piece
  CHECK(s.removed_volume() == doctest::Approx(25 * 3.14159265 * 2).epsilon(0.05));  // cell 1
  // A simultaneous 5-axis move is refused (the session cuts fixed-axis moves only), naming its
  // line.
  embed::SessionOptions five = session_options(Aabb{Vec3(-20), Vec3(20, 20, 0)}, "", 2);
  five.machine = "ac-trunnion";
  five.tools = flat_table(dir);
  embed::Session turning(five);
  turning.feed("G21 G90 G17\nT1 M6\nS9000 M3\nG0 X-12 Y8 Z5 A0 C0\nG1 Z-0.5 F400\n");
  const long long before = turning.moves();
  try {
    turning.feed("G1 X12 A8 C20 F600\n");
    FAIL("a simultaneous move was cut");
  } catch (const cli::InputError& e) {
    CHECK(std::string(e.what()).find("<fed>:6: a simultaneous 5-axis move") != std::string::npos);
  }
  CHECK(turning.moves() == before);
  CHECK_THROWS_AS(embed::Session(session_options(Aabb{Vec3(0), Vec3(0, 40, 20)}, "", 0)),
                  cli::InputError);
  CHECK_THROWS_AS(embed::Session(session_options(Aabb{Vec3(0), Vec3(40, 40, 20)},
                                                 (dir / "none.json").string(), 0)),
                  cli::InputError);
}

}  // namespace test_session
