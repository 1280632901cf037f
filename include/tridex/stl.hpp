// tridex — STL input and output.
//
// Reading accepts binary and ASCII STL. A file is binary when its size is exactly
// 84 + 50·(the triangle count in its header), whatever its first bytes say (many binary files
// begin with "solid"); otherwise it must be ASCII ("solid … facet normal … outer loop, three
// vertex lines, endloop, endfacet … endsolid"). Corners are welded (mesh_check.hpp) so that
// triangles share vertices, and with StlOptions::require_closed the result must pass check_mesh.
// Writing is binary, with facet normals from the vertex order, through a temporary file in the
// target's directory that is renamed over the target only once complete.
#pragma once

#include <atomic>
#include <bit>
#include <cctype>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <istream>
#include <limits>
#include <ostream>
#include <string>
#include <string_view>
#include <system_error>
#include <vector>

#include <glm/glm.hpp>

#include "tridex/error.hpp"
#include "tridex/mesh.hpp"
#include "tridex/mesh_check.hpp"
#include "tridex/parallel.hpp"

#if defined(_WIN32)
#include <process.h>
#define TRIDEX_GETPID _getpid
#else
#include <unistd.h>
#define TRIDEX_GETPID getpid
#endif

namespace tridex {

struct StlOptions {
  bool require_closed = false;  // throw unless the welded mesh is closed (check_mesh)
  // Refuse, before allocating, a file whose triangles would need more than this many bytes to
  // read and weld (kStlBytesPerTriangle each; an ASCII file's text besides). 0: no limit.
  std::uint64_t max_bytes = 0;
  const char* limit_name = "the memory limit";  // for the message, e.g. "--max-memory"
};

// Memory that reading one triangle takes at its peak: the soup's three corners and indices (48
// bytes), the weld's remap and hash index, and the welded mesh (weld_vertices).
inline constexpr std::uint64_t kStlBytesPerTriangle = 128;

namespace detail {

inline std::uint32_t load_u32_le(const unsigned char* p) {
  return std::uint32_t{p[0]} | (std::uint32_t{p[1]} << 8) | (std::uint32_t{p[2]} << 16) |
         (std::uint32_t{p[3]} << 24);
}

inline float load_f32_le(const unsigned char* p) { return std::bit_cast<float>(load_u32_le(p)); }

inline void store_u32_le(unsigned char* p, std::uint32_t v) {
  for (int k = 0; k < 4; ++k) p[k] = static_cast<unsigned char>(v >> (8 * k));
}

inline void store_f32_le(unsigned char* p, float f) {
  store_u32_le(p, std::bit_cast<std::uint32_t>(f));
}

inline void add_stl_corner(Mesh& mesh, const glm::vec3& p, const std::string& path,
                           std::size_t triangle) {
  if (!std::isfinite(p.x) || !std::isfinite(p.y) || !std::isfinite(p.z))
    fail("STL ", path, ": triangle ", triangle, " has a coordinate that is not finite");
  mesh.positions.push_back(p);
}

inline Mesh read_stl_binary(std::istream& in, const std::string& path, std::uint32_t count) {
  Mesh soup;
  soup.positions.reserve(3 * static_cast<std::size_t>(count));
  soup.triangles.reserve(count);
  const std::size_t batch = 1 << 16;
  std::vector<unsigned char> buffer(50 * std::min<std::size_t>(batch, count));
  for (std::size_t done = 0; done < count;) {
    std::size_t n = std::min<std::size_t>(batch, count - done);
    in.read(reinterpret_cast<char*>(buffer.data()), static_cast<std::streamsize>(50 * n));
    if (static_cast<std::size_t>(in.gcount()) != 50 * n)
      fail("STL ", path, ": binary file is truncated in triangle ",
           done + static_cast<std::size_t>(in.gcount()) / 50);
    for (std::size_t k = 0; k < n; ++k) {
      const unsigned char* record = buffer.data() + 50 * k + 12;  // skip the stored normal
      auto base = static_cast<std::uint32_t>(soup.positions.size());
      for (int c = 0; c < 3; ++c)
        add_stl_corner(soup,
                       glm::vec3(load_f32_le(record + 12 * c), load_f32_le(record + 12 * c + 4),
                                 load_f32_le(record + 12 * c + 8)),
                       path, done + k);
      soup.triangles.emplace_back(base, base + 1, base + 2);
    }
    done += n;
  }
  return soup;
}

// A tokenizer over ASCII STL text that knows its line number for messages.
class StlText {
 public:
  StlText(std::string text, const std::string& path) : text_(std::move(text)), path_(path) {}

  bool at_end() {
    skip_space();
    return pos_ >= text_.size();
  }

  // The next whitespace-separated word; word_line() is the line it is on.
  std::string_view word() {
    skip_space();
    word_line_ = line_;
    std::size_t start = pos_;
    while (pos_ < text_.size() && !std::isspace(static_cast<unsigned char>(text_[pos_]))) ++pos_;
    return std::string_view(text_).substr(start, pos_ - start);
  }

  void expect(std::string_view keyword) {
    std::string_view w = word();
    if (w != keyword)
      fail("STL ", path_, ": line ", word_line_, ": expected '", keyword, "' but found '",
           w.empty() ? std::string_view("end of file") : w, "'");
  }

  float number() {
    std::string_view w = word();
    double value = 0;
    const char* first = w.data();
    if (!w.empty() && *first == '+') ++first;  // from_chars does not take a leading '+'
    auto [end, error] = std::from_chars(first, w.data() + w.size(), value);
    if (w.empty() || (error != std::errc() && error != std::errc::result_out_of_range) ||
        end != w.data() + w.size() || std::isnan(value) ||
        (error == std::errc() && std::isinf(value)))
      fail("STL ", path_, ": line ", word_line_, ": expected a finite number but found '",
           w.empty() ? std::string_view("end of file") : w, "'");
    // from_chars leaves the value alone when out of range; strtod gives ±HUGE_VAL for an overflow
    // and 0 or a subnormal for an underflow, which is harmless.
    if (error == std::errc::result_out_of_range)
      value = std::strtod(std::string(w).c_str(), nullptr);
    // Positions are float: a value beyond its range would become infinite.
    if (std::abs(value) > double(std::numeric_limits<float>::max()))
      fail("STL ", path_, ": line ", word_line_, ": ", w,
           " is beyond the range of an STL coordinate (float, ±", std::numeric_limits<float>::max(),
           ")");
    return static_cast<float>(value);
  }

  void skip_line() {
    while (pos_ < text_.size() && text_[pos_] != '\n') ++pos_;
  }

  std::size_t line() const { return line_; }
  std::size_t word_line() const { return word_line_; }

 private:
  void skip_space() {
    while (pos_ < text_.size() && std::isspace(static_cast<unsigned char>(text_[pos_]))) {
      if (text_[pos_] == '\n') ++line_;
      ++pos_;
    }
  }

  std::string text_;
  std::string path_;
  std::size_t pos_ = 0, line_ = 1, word_line_ = 1;
};

inline Mesh read_stl_ascii(std::string text, const std::string& path, const StlOptions& options) {
  const std::uint64_t text_bytes = text.size();
  StlText in(std::move(text), path);
  Mesh soup;
  in.expect("solid");
  in.skip_line();  // the solid's name, possibly empty or with spaces
  for (;;) {
    if (in.at_end()) fail("STL ", path, ": line ", in.line(), ": file ends without 'endsolid'");
    std::string_view w = in.word();
    std::size_t line = in.word_line();
    if (w == "endsolid") {
      in.skip_line();
      if (in.at_end()) break;
      in.expect("solid");  // several solids in one file: read them all
      in.skip_line();
      continue;
    }
    if (w != "facet")
      fail("STL ", path, ": line ", line, ": expected 'facet' or 'endsolid' but found '", w, "'");
    in.expect("normal");
    for (int k = 0; k < 3; ++k) in.number();  // recomputed from the vertex order when written
    in.expect("outer");
    in.expect("loop");
    auto base = static_cast<std::uint32_t>(soup.positions.size());
    for (int c = 0; c < 3; ++c) {
      in.expect("vertex");
      float x = in.number(), y = in.number(), z = in.number();
      soup.positions.emplace_back(x, y, z);
    }
    in.expect("endloop");
    in.expect("endfacet");
    soup.triangles.emplace_back(base, base + 1, base + 2);
    if (soup.positions.size() > 0xFFFFFFF0u) fail("STL ", path, ": too many triangles");
    if (options.max_bytes &&
        text_bytes + kStlBytesPerTriangle * soup.triangles.size() > options.max_bytes)
      fail("STL ", path, ": line ", line, ": ", soup.triangles.size(), " triangles and ",
           text_bytes, " bytes of text need more than ", options.limit_name, " (",
           options.max_bytes, " bytes)");
  }
  return soup;
}

}  // namespace detail

// Reads a binary or ASCII STL file into a welded mesh. Throws tridex::Error naming the file for
// a missing or unreadable file, a truncated binary file, malformed ASCII (with its line), a
// coordinate that is not finite, and — with options.require_closed — a mesh that is not closed
// (with the edge counts of check_mesh).
inline Mesh read_stl(const std::string& path, StlOptions options = {}) {
  {
    namespace fs = std::filesystem;
    std::error_code error;
    fs::file_status status = fs::status(path, error);
    if (fs::is_directory(status)) detail::fail("STL ", path, ": is a directory");
    if (fs::exists(status) && !fs::is_regular_file(status))
      detail::fail("STL ", path, ": is not a regular file");
  }
  std::ifstream in(path, std::ios::binary);
  if (!in) detail::fail("STL ", path, ": cannot open the file");
  in.seekg(0, std::ios::end);
  const auto size = static_cast<std::uint64_t>(in.tellg());
  in.seekg(0, std::ios::beg);
  Mesh soup;
  unsigned char header[84] = {};
  in.read(reinterpret_cast<char*>(header), 84);
  std::uint64_t binary_count = in.gcount() == 84 ? detail::load_u32_le(header + 80) : 0;
  if (in.gcount() == 84 && size == 84 + 50 * binary_count) {
    if (binary_count > 0x55555550u)
      detail::fail("STL ", path, ": too many triangles (", binary_count, ")");
    if (options.max_bytes && kStlBytesPerTriangle * binary_count > options.max_bytes)
      detail::fail("STL ", path, ": the header declares ", binary_count, " triangles, about ",
                   kStlBytesPerTriangle * binary_count / (1 << 20), " MiB to read, more than ",
                   options.limit_name, " (", options.max_bytes / (1 << 20), " MiB)");
    soup = detail::read_stl_binary(in, path, static_cast<std::uint32_t>(binary_count));
  } else {
    std::string_view start(reinterpret_cast<const char*>(header),
                           static_cast<std::size_t>(in.gcount()));
    std::size_t first = start.find_first_not_of(" \t\r\n");
    if (first == std::string_view::npos || start.substr(first, 5) != "solid") {
      if (size < 84)
        detail::fail("STL ", path, ": file of ", size, " bytes is too short for a binary STL");
      detail::fail("STL ", path, ": binary header announces ", binary_count, " triangles (",
                   84 + 50 * binary_count, " bytes) but the file has ", size,
                   " bytes: truncated or not an STL file");
    }
    if (options.max_bytes && size > options.max_bytes)
      detail::fail("STL ", path, ": ", size, " bytes of text are more than ", options.limit_name,
                   " (", options.max_bytes, " bytes)");
    std::string text(static_cast<std::size_t>(size), '\0');
    in.seekg(0, std::ios::beg);
    in.read(text.data(), static_cast<std::streamsize>(size));
    if (static_cast<std::uint64_t>(in.gcount()) != size) detail::fail("STL ", path, ": read error");
    // Text never holds a NUL byte; a binary file whose header starts with "solid" does.
    if (text.find('\0') != std::string::npos)
      detail::fail("STL ", path, ": binary header announces ", binary_count, " triangles (",
                   84 + 50 * binary_count, " bytes) but the file has ", size, " bytes: truncated");
    soup = detail::read_stl_ascii(std::move(text), path, options);
  }
  Mesh mesh = weld_vertices(soup);
  if (options.require_closed) {
    MeshCheck c = check_mesh(mesh);
    if (!c.closed())
      detail::fail("STL ", path, ": mesh is not closed (", c.boundary_edges, " boundary edges, ",
                   c.non_manifold_edges, " non-manifold edges, ", c.misoriented_edges,
                   " misoriented edges)");
  }
  return mesh;
}

namespace detail {

// The 50-byte binary STL records of triangles [first, last) into `record`, facet normals from
// the vertex order.
inline void format_stl_records(const Mesh& mesh, std::size_t first, std::size_t last,
                               unsigned char* record) {
  for (std::size_t k = first; k < last; ++k, record += 50) {
    const glm::uvec3& t = mesh.triangles[k];
    const glm::vec3 &a = mesh.positions[t.x], &b = mesh.positions[t.y], &c = mesh.positions[t.z];
    Vec3 normal = glm::cross(Vec3(b) - Vec3(a), Vec3(c) - Vec3(a));
    double length = glm::length(normal);
    normal = length > 0 ? normal / length : Vec3(0);
    const glm::vec3 values[4] = {glm::vec3(normal), a, b, c};
    for (int v = 0; v < 4; ++v)
      for (int e = 0; e < 3; ++e) store_f32_le(record + 12 * v + 4 * e, values[v][e]);
    record[48] = record[49] = 0;
  }
}

}  // namespace detail

// Writes `mesh` as binary STL to a stream. Throws tridex::Error if a triangle names a missing
// vertex, the mesh has more than 2^32 − 1 triangles, or the stream fails.
//
// The records are formatted on `threads` threads (1 unless asked; 0: every hardware thread), a
// group of batches at a time, each batch into a buffer of its own; while the threads format the
// next group, a thread of its own writes the last one's buffers in order. The bytes do not
// depend on the thread count. One thread formats and writes by turns.
inline void write_stl(std::ostream& out, const Mesh& mesh, unsigned threads = 1) {
  detail::require_valid_indices(mesh, "write_stl");
  if (mesh.triangles.size() > 0xFFFFFFFFu)
    detail::fail("write_stl: ", mesh.triangles.size(), " triangles do not fit in STL");
  unsigned char header[84] = {};
  const char title[] = "binary STL written by tridex";
  std::memcpy(header, title, sizeof title - 1);
  detail::store_u32_le(header + 80, static_cast<std::uint32_t>(mesh.triangles.size()));
  out.write(reinterpret_cast<const char*>(header), 84);
  const std::size_t triangles = mesh.triangles.size(), batch = std::size_t{1} << 15;
  const std::size_t batches = (triangles + batch - 1) / batch;
  const unsigned workers = detail::chunk_workers(batches, threads);
  const std::size_t group = 2 * std::size_t{workers};
  // Two sets of buffers: one being formatted, one being written.
  std::vector<std::vector<unsigned char>> buffers(2 * group);
  detail::BackgroundTask writer;
  auto write_group = [&out, triangles, batch](const std::vector<unsigned char>* set, std::size_t g0,
                                              std::size_t count) {
    for (std::size_t k = 0; k < count && out; ++k) {
      const std::size_t n = std::min(batch, triangles - (g0 + k) * batch);
      out.write(reinterpret_cast<const char*>(set[k].data()), static_cast<std::streamsize>(50 * n));
    }
  };
  for (std::size_t g0 = 0, parity = 0; g0 < batches; g0 += group, parity ^= 1) {
    std::vector<unsigned char>* set = buffers.data() + parity * group;
    const std::size_t count = std::min(group, batches - g0);
    detail::for_each_chunk(count, workers, [&](std::size_t k) {
      const std::size_t first = (g0 + k) * batch, last = std::min(triangles, first + batch);
      set[k].resize(50 * batch);
      detail::format_stl_records(mesh, first, last, set[k].data());
    });
    // The stream is looked at only while no writer runs.
    if (workers > 1) writer.join();  // the previous group is written: its buffers are free
    if (!out) break;
    if (workers == 1)
      write_group(set, g0, count);
    else
      writer.start([&write_group, set, g0, count] { write_group(set, g0, count); });
  }
  writer.join();
  out.flush();
  if (!out) detail::fail("write_stl: the stream failed while writing");
}

// Writes `mesh` as binary STL to `path`, atomically: into a temporary file in the same directory,
// renamed over `path` once complete; on any failure the temporary is removed and tridex::Error
// names the path.
inline void write_stl(const std::string& path, const Mesh& mesh, unsigned threads = 1) {
  namespace fs = std::filesystem;
  static std::atomic<unsigned> counter{0};
  fs::path target(path);
  fs::path temporary = target;
  temporary +=
      ".tmp-" + std::to_string(TRIDEX_GETPID()) + "-" + std::to_string(counter.fetch_add(1));
  try {
    {
      std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
      if (!out) detail::fail("write_stl: cannot create ", temporary.string());
      write_stl(out, mesh, threads);
      out.close();
      if (!out) detail::fail("write_stl: cannot finish writing ", temporary.string());
    }
    std::error_code error;
    fs::rename(temporary, target, error);
    if (error)
      detail::fail("write_stl: cannot rename the temporary file to ", path, ": ", error.message());
  } catch (const Error& e) {
    std::error_code ignored;
    fs::remove(temporary, ignored);
    detail::fail("write_stl ", path, ": ", e.what());
  }
}

}  // namespace tridex

#undef TRIDEX_GETPID
