#include <doctest/doctest.h>

#include <filesystem>
#include <fstream>
#include <array>
#include <cstring>
#include <random>
#include <set>
#include <sstream>

#include "test_dexel_shapes.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/stl.hpp"

using namespace tridex;
using namespace tridex_test;
namespace fs = std::filesystem;

namespace {

fs::path scratch_dir() {
  fs::path dir = fs::temp_directory_path() / ("tridex_test_stl_" + std::to_string(::getpid()));
  fs::create_directories(dir);
  return dir;
}

void write_bytes(const fs::path& path, const std::string& bytes) {
  std::ofstream out(path, std::ios::binary);
  out.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
}

std::string read_bytes(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), {});
}

// The triangles as sets of corner positions, independent of vertex numbering.
std::multiset<std::array<float, 9>> corner_set(const Mesh& m) {
  std::multiset<std::array<float, 9>> out;
  for (const glm::uvec3& t : m.triangles) {
    std::array<float, 9> c{};
    for (int k = 0; k < 3; ++k)
      for (int e = 0; e < 3; ++e) c[static_cast<std::size_t>(3 * k + e)] = m.positions[t[k]][e];
    out.insert(c);
  }
  return out;
}

}  // namespace

TEST_CASE("STL: binary write then read gives back the same closed mesh") {
  fs::path dir = scratch_dir();
  std::mt19937 rng(12);
  std::uniform_real_distribution<double> unit(-10, 10);
  std::vector<Mesh> shapes{box_mesh(Vec3(unit(rng)), Vec3(11)),
                           sphere_mesh(Vec3(unit(rng), unit(rng), unit(rng)), 3.3),
                           torus_mesh(Vec3(1, 2, 3), 4, 1.5), cylinder_mesh(Vec3(-1), 2, 5)};
  for (std::size_t k = 0; k < shapes.size(); ++k) {
    fs::path path = dir / ("shape" + std::to_string(k) + ".stl");
    write_stl(path.string(), shapes[k]);
    CHECK(fs::file_size(path) == 84 + 50 * shapes[k].triangles.size());
    Mesh back = read_stl(path.string(), {.require_closed = true});
    CHECK(back.positions.size() == shapes[k].positions.size());
    CHECK(corner_set(back) == corner_set(shapes[k]));
    CHECK(check_mesh(back).closed());
    CHECK(back.signed_volume() == doctest::Approx(shapes[k].signed_volume()).epsilon(1e-9));
    // Stored normals follow the vertex order: outward.
    std::string bytes = read_bytes(path);
    for (std::size_t t = 0; t < shapes[k].triangles.size(); t += 7) {
      glm::vec3 n, a, b, c;
      std::memcpy(&n, bytes.data() + 84 + 50 * t, 12);
      std::memcpy(&a, bytes.data() + 84 + 50 * t + 12, 12);
      std::memcpy(&b, bytes.data() + 84 + 50 * t + 24, 12);
      std::memcpy(&c, bytes.data() + 84 + 50 * t + 36, 12);
      CHECK(glm::dot(Vec3(n), glm::cross(Vec3(b - a), Vec3(c - a))) > 0);
    }
  }
  // No temporary files are left behind.
  for (const auto& entry : fs::directory_iterator(dir))
    CHECK(entry.path().string().find(".tmp-") == std::string::npos);
  fs::remove_all(dir);
}

TEST_CASE("STL: a binary file whose header begins with 'solid' is read as binary") {
  fs::path dir = scratch_dir();
  Mesh cube = box_mesh(Vec3(0), Vec3(1));
  std::ostringstream out;
  write_stl(out, cube);
  std::string bytes = out.str();
  std::memcpy(bytes.data(), "solid cube", 10);
  write_bytes(dir / "solid_header.stl", bytes);
  Mesh back = read_stl((dir / "solid_header.stl").string(), {.require_closed = true});
  CHECK(corner_set(back) == corner_set(cube));
  // Truncated by a few bytes: an error naming the file, for both header kinds.
  write_bytes(dir / "truncated.stl", bytes.substr(0, bytes.size() - 7));
  CHECK_THROWS_WITH_AS(read_stl((dir / "truncated.stl").string()), doctest::Contains("truncated"),
                       Error);
  std::string plain = out.str();
  write_bytes(dir / "truncated2.stl", plain.substr(0, plain.size() - 50));
  CHECK_THROWS_WITH_AS(read_stl((dir / "truncated2.stl").string()), doctest::Contains("truncated"),
                       Error);
  write_bytes(dir / "short.stl", std::string(40, '\x01'));
  CHECK_THROWS_WITH_AS(read_stl((dir / "short.stl").string()), doctest::Contains("too short"),
                       Error);
  CHECK_THROWS_WITH_AS(read_stl((dir / "missing.stl").string()), doctest::Contains("cannot open"),
                       Error);
  fs::remove_all(dir);
}

TEST_CASE("STL: ASCII fixtures, CRLF and exponents; open meshes rejected when asked") {
  std::string data = TRIDEX_TEST_DATA;
  Mesh cube = read_stl(data + "/stl/cube_ascii.stl", {.require_closed = true});
  CHECK(cube.positions.size() == 8);
  CHECK(cube.triangles.size() == 12);
  CHECK(cube.signed_volume() == doctest::Approx(8.0));
  Mesh open = read_stl(data + "/stl/open_cube_ascii.stl");
  CHECK(check_mesh(open).boundary_edges == 3);
  CHECK_THROWS_WITH_AS(read_stl(data + "/stl/open_cube_ascii.stl", {.require_closed = true}),
                       doctest::Contains("3 boundary edges"), Error);
}

TEST_CASE("STL: malformed ASCII names the line") {
  fs::path dir = scratch_dir();
  const std::string good =
      "solid t\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\nvertex 0 1 "
      "0\nendloop\nendfacet\nendsolid t\n";
  write_bytes(dir / "good.stl", good);
  CHECK(read_stl((dir / "good.stl").string()).triangles.size() == 1);
  struct Case {
    std::string from, to, message;
  };
  for (const Case& c :
       {Case{"vertex 0 1 0\n", "", "line 6"}, Case{"vertex 1 0 0", "vertex 1 x 0", "line 5"},
        Case{"vertex 1 0 0", "vertex 1 nan 0", "line 5"},
        Case{"endsolid t\n", "", "without 'endsolid'"}, Case{"outer loop", "outer", "line 4"},
        Case{"endfacet", "endface", "line 8"}}) {
    std::string text = good;
    text.replace(text.find(c.from), c.from.size(), c.to);
    write_bytes(dir / "bad.stl", text);
    CHECK_THROWS_WITH_AS(read_stl((dir / "bad.stl").string()), doctest::Contains(c.message.c_str()),
                         Error);
  }
  fs::remove_all(dir);
}

TEST_CASE("STL: writing into a missing directory fails cleanly; an invalid mesh is refused") {
  fs::path dir = scratch_dir();
  Mesh cube = box_mesh(Vec3(0), Vec3(1));
  CHECK_THROWS_AS(write_stl((dir / "no_such_dir" / "x.stl").string(), cube), Error);
  Mesh bad = cube;
  bad.triangles.emplace_back(0u, 1u, 99u);
  CHECK_THROWS_AS(write_stl((dir / "bad.stl").string(), bad), Error);
  CHECK(!fs::exists(dir / "bad.stl"));
  for (const auto& entry : fs::directory_iterator(dir))
    CHECK(entry.path().string().find(".tmp-") == std::string::npos);
  // An existing file is replaced whole.
  write_stl((dir / "x.stl").string(), sphere_mesh(Vec3(0), 1));
  write_stl((dir / "x.stl").string(), cube);
  CHECK(fs::file_size(dir / "x.stl") == 84 + 50 * 12);
  fs::remove_all(dir);
}
