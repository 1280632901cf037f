// `tridex moves` end to end: JSON Lines in the work frame, checked against G68.2's rotation
// written out independently on random planes.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "command_reference.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

namespace {

// G68.2's rotation written out independently: R = Rz(a)·Rx(b)·Rz(c), row-major here.
std::array<std::array<double, 3>, 3> euler_zxz(double a, double b, double c) {
  auto rz = [](double t) {
    double r = t * M_PI / 180;
    return std::array<std::array<double, 3>, 3>{
        {{std::cos(r), -std::sin(r), 0}, {std::sin(r), std::cos(r), 0}, {0, 0, 1}}};
  };
  auto rx = [](double t) {
    double r = t * M_PI / 180;
    return std::array<std::array<double, 3>, 3>{
        {{1, 0, 0}, {0, std::cos(r), -std::sin(r)}, {0, std::sin(r), std::cos(r)}}};
  };
  auto mul = [](const auto& p, const auto& q) {
    std::array<std::array<double, 3>, 3> m{};
    for (int i = 0; i < 3; ++i)
      for (int j = 0; j < 3; ++j)
        for (int k = 0; k < 3; ++k) m[i][j] += p[i][k] * q[k][j];
    return m;
  };
  return mul(mul(rz(a), rx(b)), rz(c));
}

Vec3 rotate_by(const std::array<std::array<double, 3>, 3>& m, const Vec3& p) {
  return Vec3(m[0][0] * p.x + m[0][1] * p.y + m[0][2] * p.z,
              m[1][0] * p.x + m[1][1] * p.y + m[1][2] * p.z,
              m[2][0] * p.x + m[2][1] * p.y + m[2][2] * p.z);
}

}  // namespace

TEST_CASE("moves: JSON Lines in the work frame under random G68.2 planes") {
  fs::path dir = scratch("moves");
  std::mt19937 random(5);
  std::uniform_real_distribution<double> angle(-180, 180), tilt(0, 120), offset(-50, 50),
      local(-10, 10);
  for (int trial = 0; trial < 8; ++trial) {
    double a = angle(random), b = tilt(random), c = angle(random);
    Vec3 origin(offset(random), offset(random), offset(random));
    std::vector<Vec3> points;
    std::ostringstream text;
    text.precision(10);
    text << "G21 G90 G17\nT2 M6\nS5000 M3\nG68.2 X" << origin.x << " Y" << origin.y << " Z"
         << origin.z << " I" << a << " J" << b << " K" << c << "\nG53.1\n";
    for (int k = 0; k < 6; ++k) {
      Vec3 p(local(random), local(random), local(random));
      points.push_back(p);
      text << "G1 X" << p.x << " Y" << p.y << " Z" << p.z << " F700\n";
    }
    // A half circle of radius 5 about the last point, in the feature XY plane.
    Vec3 centre = points.back() + Vec3(5, 0, 0), last = points.back() + Vec3(10, 0, 0);
    text << "G3 X" << last.x << " Y" << last.y << " I5 J0\nG69\nM30\n";
    fs::path program = dir / ("p" + std::to_string(trial) + ".ngc");
    write_text(program, text.str());
    CommandResult r = run_tridex({"moves", program.string(), "--arc-tolerance", "0.01"}, dir);
    INFO(r.err);
    REQUIRE(r.status == 0);
    auto R = euler_zxz(a, b, c);
    Vec3 axis(std::sin(a * M_PI / 180) * std::sin(b * M_PI / 180),
              -std::cos(a * M_PI / 180) * std::sin(b * M_PI / 180), std::cos(b * M_PI / 180));
    std::istringstream lines(r.out);
    std::string line;
    std::vector<json> records;
    while (std::getline(lines, line)) records.push_back(json::parse(line));
    // The feed moves, in order; the first comes straight down the tool axis from far away.
    std::vector<json> feeds, arcs;
    for (const json& m : records) {
      for (const char* key : {"line", "kind", "tool", "start", "end", "axis", "feed"})
        REQUIRE(m.contains(key));
      if (m["kind"] == "feed") feeds.push_back(m);
      if (m["kind"] == "arc") arcs.push_back(m);
    }
    REQUIRE(feeds.size() == points.size());
    for (std::size_t k = 0; k < points.size(); ++k) {
      Vec3 expected = origin + rotate_by(R, points[k]);
      Vec3 end = vec(feeds[k]["end"]);
      CHECK(glm::length(end - expected) < 1e-6);
      CHECK(glm::length(vec(feeds[k]["axis"]) - axis) < 1e-9);
      CHECK(feeds[k]["tool"] == 2);
      CHECK(feeds[k]["feed"].get<double>() == doctest::Approx(700));
      CHECK(feeds[k]["line"] == 6 + static_cast<int>(k));
    }
    Vec3 approach = vec(feeds[0]["start"]) - vec(feeds[0]["end"]);
    CHECK(glm::length(approach) > 1000);
    CHECK(glm::dot(glm::normalize(approach), axis) == doctest::Approx(1));
    // Arc pieces: chained, on the circle about the rotated centre, ending at the rotated end.
    REQUIRE(arcs.size() >= 8);
    Vec3 world_centre = origin + rotate_by(R, centre);
    for (std::size_t k = 0; k < arcs.size(); ++k) {
      CHECK(glm::length(vec(arcs[k]["end"]) - world_centre) == doctest::Approx(5).epsilon(1e-6));
      if (k > 0) CHECK(glm::length(vec(arcs[k]["start"]) - vec(arcs[k - 1]["end"])) < 1e-9);
      CHECK(arcs[k]["line"] == 12);
    }
    CHECK(glm::length(vec(arcs.back()["end"]) - (origin + rotate_by(R, last))) < 1e-6);
  }
  fs::remove_all(dir);
}
