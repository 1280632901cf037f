#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include "tridex/gcode/grouping.hpp"
#include "tridex/gcode/interpreter.hpp"
#include "workload.hpp"

using namespace tridex;

TEST_CASE("the benchmark workload parses into the paper's five directions with four tools each") {
  for (long long segments : {20000LL, 61000LL}) {
    char* text = nullptr;
    std::size_t size = 0;
    std::FILE* out = open_memstream(&text, &size);
    REQUIRE(out);
    long long written = bench::write_workload(out, segments);
    std::fclose(out);
    std::string program(text, size);
    std::free(text);
    CHECK(std::abs(double(written - segments)) <= 0.01 * double(segments));
    std::istringstream in(program);
    gcode::Interpreter interpreter;
    std::vector<gcode::Move> moves;
    interpreter.run(in, "workload.nc", [&](const gcode::Move& m) { moves.push_back(m); });
    long long feeds = 0;
    for (const gcode::Move& m : moves) feeds += m.kind == gcode::MoveKind::feed;
    CHECK(feeds >= written);  // every G01 segment, plus the plunges of the "G1 F" lines
    std::vector<gcode::MoveGroup> groups = gcode::group_by_direction(moves);
    REQUIRE(groups.size() == 5);
    const double c20 = std::cos(glm::radians(20.0)), s20 = std::sin(glm::radians(20.0));
    const Vec3 expected[5] = {Vec3(0, 0, 1), Vec3(c20, 0, s20), Vec3(0, 1, 0), Vec3(-1, 0, 0),
                              Vec3(0, -1, 0)};
    for (int k = 0; k < 5; ++k) {
      INFO("direction ", k, ": (", groups[k].axis.x, ", ", groups[k].axis.y, ", ", groups[k].axis.z,
           ")");
      CHECK(glm::length(groups[k].axis - expected[k]) < 1e-9);
      CHECK(groups[k].tools == std::set<int>{1, 2, 3, 4});
    }
    // Every cutting move stays within reach of the stock (the tool tip within a cutter radius
    // plus the clearance of the box), so the program machines the stock rather than the air.
    const Aabb reach = bench::workload_stock().inflated(12);
    std::size_t outside = 0;
    for (const gcode::Move& m : moves)
      if (m.kind == gcode::MoveKind::feed && (!reach.contains(m.start) || !reach.contains(m.end)))
        ++outside;
    CHECK(outside == 0);
  }
}

TEST_CASE(
    "the workload's variants: sloped roughing, and the ball ends alone with their moves "
    "unchanged") {
  auto write = [](bench::WorkloadVariant variant, long long& written) {
    char* text = nullptr;
    std::size_t size = 0;
    std::FILE* out = open_memstream(&text, &size);
    REQUIRE(out);
    written = bench::write_workload(out, 20000, variant);
    std::fclose(out);
    std::string program(text, size);
    std::free(text);
    return program;
  };
  // The lines of each tool's section of the program (a section starts at its "(… T<n> …)" line).
  auto sections = [](const std::string& program) {
    std::vector<std::pair<int, std::vector<std::string>>> out;
    std::istringstream in(program);
    for (std::string line; std::getline(in, line);) {
      const std::size_t at = line.find(", T");
      if (!line.empty() && line[0] == '(' && at != std::string::npos)
        out.push_back({std::atoi(line.c_str() + at + 3), {}});
      else if (!out.empty())
        out.back().second.push_back(line);
    }
    return out;
  };
  long long levels_count = 0, sloped_count = 0, balls_count = 0;
  const auto levels = sections(write({}, levels_count));
  const auto sloped = sections(write({.sloped_roughing = true}, sloped_count));
  const auto balls = sections(write({.sloped_roughing = true, .balls_only = true}, balls_count));
  REQUIRE(levels.size() == 20);
  REQUIRE(sloped.size() == 20);
  REQUIRE(balls.size() == 10);
  std::size_t b = 0;
  for (std::size_t k = 0; k < sloped.size(); ++k) {
    const int tool = sloped[k].first;
    CHECK(levels[k].first == tool);
    if (tool >= 3) {
      // The finishing passes are the same in every variant.
      CHECK(levels[k].second == sloped[k].second);
      REQUIRE(b < balls.size());
      CHECK(balls[b].first == tool);
      CHECK(balls[b++].second == sloped[k].second);
    } else {
      // Roughing: Z levels go back up to the clearance once per level; the sloped raster once.
      auto rapids_up = [](const std::vector<std::string>& lines) {
        return std::count_if(lines.begin(), lines.end(),
                             [](const std::string& l) { return l.rfind("G0 Z", 0) == 0; });
      };
      CHECK(rapids_up(sloped[k].second) < rapids_up(levels[k].second));
    }
  }
  CHECK(b == balls.size());
  CHECK(balls_count < sloped_count);
}
