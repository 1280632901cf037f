// `tridex groups` end to end: one group per spindle direction, with its frame, moves and tools.
#include <doctest/doctest.h>

#include <algorithm>
#include <cmath>
#include <nlohmann/json.hpp>
#include <random>

#include "command_reference.hpp"

using namespace tridex;
using namespace tridex::test;
using nlohmann::json;

TEST_CASE("groups: one group per spindle direction with its moves and tools") {
  fs::path dir = scratch("groups");
  fs::path program = dir / "five.nc", out = dir / "groups.json";
  write_text(program, program_of({&kDirections[0], &kDirections[1], &kDirections[2],
                                  &kDirections[3], &kDirections[4], &kDirections[2]}));
  CommandResult r = run_tridex({"groups", program.string(), "-o", out.string()}, dir);
  INFO(r.err);
  REQUIRE(r.status == 0);
  json doc = json::parse(slurp(out));
  REQUIRE(doc["groups"].size() == 5);  // +Y appears twice in the program but is one direction
  CommandResult moves = run_tridex({"moves", program.string()}, dir);
  long long lines = std::count(moves.out.begin(), moves.out.end(), '\n');
  CHECK(doc["segments"].get<long long>() == lines);
  long long total = 0;
  for (std::size_t g = 0; g < 5; ++g) {
    const Direction& d = kDirections[g];
    const json& group = doc["groups"][g];
    double a = d.a * M_PI / 180, b = d.b * M_PI / 180;
    Vec3 axis(std::sin(a) * std::sin(b), -std::cos(a) * std::sin(b), std::cos(b));
    CHECK(glm::length(vec(group["axis"]) - axis) < 1e-9);
    CHECK(glm::length(vec(group["frame"]["z"]) - axis) < 1e-9);
    CHECK(group["tools"] == json::array({1, 2, 3}));
    total += group["moves"].get<long long>();
    long long by_kind = 0;
    for (const auto& [kind, count] : group["by_kind"].items()) by_kind += count.get<long long>();
    CHECK(by_kind == group["moves"].get<long long>());
    CHECK(group["by_kind"]["arc"].get<long long>() > 0);
  }
  CHECK(total == lines);
  CHECK(doc["groups"][2]["moves"].get<long long>() > doc["groups"][3]["moves"].get<long long>());
  fs::remove_all(dir);
}
