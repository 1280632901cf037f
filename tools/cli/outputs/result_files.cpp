#include "outputs/result_files.hpp"

#include <algorithm>
#include <cstdint>
#include <ostream>
#include <string>

#include "outputs/output.hpp"
#include "tridex/stl.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

void write_stl_file(const fs::path& path, const Mesh& mesh, unsigned threads) {
  AtomicOutput out(path);
  write_stl(out.stream(), mesh, threads);
  out.commit();
}

void write_ply(const fs::path& path, const Mesh& mesh, const std::vector<glm::vec3>& colours) {
  AtomicOutput out(path);
  std::ostream& s = out.stream();
  s << "ply\nformat binary_little_endian 1.0\ncomment tridex check: red gouge, grey within "
       "tolerance, blue excess\n"
    << "element vertex " << mesh.positions.size()
    << "\nproperty float x\nproperty float y\nproperty float z\n"
    << "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    << "element face " << mesh.triangles.size()
    << "\nproperty list uchar int vertex_indices\nend_header\n";
  std::string bytes;
  bytes.reserve(mesh.positions.size() * 15 + mesh.triangles.size() * 13);
  auto put = [&](const void* data, std::size_t size) {
    bytes.append(static_cast<const char*>(data), size);
  };
  for (std::size_t v = 0; v < mesh.positions.size(); ++v) {
    put(&mesh.positions[v], 12);
    for (int c = 0; c < 3; ++c) {
      auto byte = static_cast<std::uint8_t>(std::clamp(colours[v][c], 0.0f, 1.0f) * 255.0f + 0.5f);
      put(&byte, 1);
    }
  }
  for (const glm::uvec3& t : mesh.triangles) {
    std::uint8_t three = 3;
    put(&three, 1);
    for (int k = 0; k < 3; ++k) {
      auto index = static_cast<std::int32_t>(t[k]);
      put(&index, 4);
    }
  }
  s.write(bytes.data(), static_cast<std::streamsize>(bytes.size()));
  out.commit();
}

void write_png_file(const fs::path& path, const render::Image& image) {
  write_file_atomically(path, render::encode_png(image));
}

}  // namespace tridex::cli
