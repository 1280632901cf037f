// Running the built `tridex` command from the tests, and independent references to check it.
#pragma once

// GCC 12 warns falsely on `"text" + std::string + "text"` (bug 105329) under -Werror=restrict.
#if defined(__GNUC__) && !defined(__clang__) && __GNUC__ == 12
#pragma GCC diagnostic ignored "-Wrestrict"
#endif

#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
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

}  // namespace tridex::test
