// libFuzzer harness over the STL reader (binary and ASCII), clang
// -fsanitize=fuzzer,address,undefined (run.sh). Any input must read into a mesh with valid indices
// and finite float positions, or throw tridex::Error; with a memory limit, nothing may allocate
// beyond it. Crashes become named cases in tests/tools/test_bad_input.cpp with their input under
// tests/data/.
#include <unistd.h>

#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <fstream>
#include <string>

#include "tridex/stl.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  // read_stl takes a path: the input goes to a file of this process's own.
  static const std::string path = "/tmp/tridex-fuzz-stl-" + std::to_string(::getpid()) + ".stl";
  {
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), static_cast<std::streamsize>(size));
  }
  try {
    // require_closed runs the reader, the weld and check_mesh: everything a stock or design meets.
    tridex::Mesh mesh =
        tridex::read_stl(path, tridex::StlOptions{.require_closed = true, .max_bytes = 64 << 20});
    for (const glm::vec3& p : mesh.positions)
      if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z)) std::abort();
    for (const glm::uvec3& t : mesh.triangles)
      if (t.x >= mesh.positions.size() || t.y >= mesh.positions.size() ||
          t.z >= mesh.positions.size())
        std::abort();
  } catch (const tridex::Error&) {
  }
  return 0;
}
