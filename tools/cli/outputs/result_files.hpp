// tridex command — the machined result and pictures as files: binary STL, binary PLY coloured per
// vertex, PNG. Each is written whole or not at all (output.hpp).
#pragma once

#include <filesystem>
#include <vector>

#include "render.hpp"
#include "tridex/mesh.hpp"

namespace tridex::cli {

// `threads` format the records (tridex::write_stl; 0: every hardware thread).
void write_stl_file(const std::filesystem::path& path, const Mesh& mesh, unsigned threads = 1);

// Binary little-endian PLY: float x y z and uchar red green blue per vertex (`colours`, one per
// position, 0-1), uchar-counted int index lists per face.
void write_ply(const std::filesystem::path& path, const Mesh& mesh,
               const std::vector<glm::vec3>& colours);

void write_png_file(const std::filesystem::path& path, const render::Image& image);

}  // namespace tridex::cli
