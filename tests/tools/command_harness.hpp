// Running the built `tridex` command from the tests, and independent references to check it.
#pragma once

// GCC 12 warns falsely on `"text" + std::string + "text"` (bug 105329) under -Werror=restrict.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ == 12
#pragma GCC diagnostic ignored "-Wrestrict"
#endif

#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "tridex/mesh.hpp"

namespace tridex::test {

namespace fs = std::filesystem;

struct CommandResult {
  int status = -1;
  std::string out, err;
};

inline std::string slurp(const fs::path& path) {
  std::ifstream in(path, std::ios::binary);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

inline void write_text(const fs::path& path, const std::string& text) {
  std::ofstream(path, std::ios::binary) << text;
}

// A fresh scratch folder per test case.
inline fs::path scratch(const std::string& name) {
  fs::path dir =
      fs::temp_directory_path() / ("tridex-cmd-" + name + "-" + std::to_string(::getpid()));
  fs::remove_all(dir);
  fs::create_directories(dir);
  return dir;
}

inline std::string quote(const std::string& arg) {
  std::string q = "'";
  for (char c : arg) q += c == '\'' ? std::string("'\\''") : std::string(1, c);
  return q + "'";
}

// Runs `tridex ARGS...` with stdout and stderr captured; the status is the exit code.
inline CommandResult run_tridex(const std::vector<std::string>& args, const fs::path& dir) {
  std::string command = quote(TRIDEX_COMMAND);
  for (const std::string& a : args) command += " " + quote(a);
  fs::path out = dir / ".stdout", err = dir / ".stderr";
  command += " >" + quote(out.string()) + " 2>" + quote(err.string()) + " </dev/null";
  int raw = std::system(command.c_str());
  CommandResult r;
  r.status = WIFEXITED(raw) ? WEXITSTATUS(raw) : -1;
  r.out = slurp(out);
  r.err = slurp(err);
  fs::remove(out);
  fs::remove(err);
  return r;
}

// An independent binary STL reader (80-byte header, count, 50-byte records), welded by exact
// position so that the result is an indexed mesh.
inline Mesh read_binary_stl(const fs::path& path) {
  std::string bytes = slurp(path);
  Mesh mesh;
  if (bytes.size() < 84) return mesh;
  std::uint32_t count;
  std::memcpy(&count, bytes.data() + 80, 4);
  if (bytes.size() != 84 + 50 * static_cast<std::size_t>(count)) return mesh;
  for (std::uint32_t t = 0; t < count; ++t) {
    float v[12];
    std::memcpy(v, bytes.data() + 84 + 50 * static_cast<std::size_t>(t), 48);
    std::uint32_t base = static_cast<std::uint32_t>(mesh.positions.size());
    for (int k = 0; k < 3; ++k)
      mesh.positions.emplace_back(v[3 + 3 * k], v[4 + 3 * k], v[5 + 3 * k]);
    mesh.triangles.emplace_back(base, base + 1, base + 2);
  }
  return mesh;
}

// A closed box as an ASCII STL, outward normals.
inline std::string box_stl_text(double x0, double y0, double z0, double x1, double y1, double z1) {
  const double p[8][3] = {{x0, y0, z0}, {x1, y0, z0}, {x1, y1, z0}, {x0, y1, z0},
                          {x0, y0, z1}, {x1, y0, z1}, {x1, y1, z1}, {x0, y1, z1}};
  const int faces[12][3] = {{0, 2, 1}, {0, 3, 2}, {4, 5, 6}, {4, 6, 7}, {0, 1, 5}, {0, 5, 4},
                            {1, 2, 6}, {1, 6, 5}, {2, 3, 7}, {2, 7, 6}, {3, 0, 4}, {3, 4, 7}};
  std::string text = "solid box\n";
  for (const auto& f : faces) {
    text += "facet normal 0 0 0\nouter loop\n";
    for (int k : f) {
      char line[128];
      std::snprintf(line, sizeof line, "vertex %.6f %.6f %.6f\n", p[k][0], p[k][1], p[k][2]);
      text += line;
    }
    text += "endloop\nendfacet\n";
  }
  return text + "endsolid box\n";
}

}  // namespace tridex::test
