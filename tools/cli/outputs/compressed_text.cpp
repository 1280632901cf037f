#include "outputs/compressed_text.hpp"

#include <stdexcept>

#include <zlib.h>

#include "outputs/html_report.hpp"
#include "tridex/parallel.hpp"

namespace tridex::cli {

std::string deflate_raw(std::string_view bytes) {
  z_stream stream{};
  // windowBits −15: raw DEFLATE, no zlib header or checksum (what "deflate-raw" reads).
  if (deflateInit2(&stream, 6, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
    throw std::runtime_error("zlib: deflateInit2 failed");
  std::string out(deflateBound(&stream, static_cast<uLong>(bytes.size())), '\0');
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(bytes.data()));
  stream.avail_in = static_cast<uInt>(bytes.size());
  stream.next_out = reinterpret_cast<Bytef*>(out.data());
  stream.avail_out = static_cast<uInt>(out.size());
  const int status = deflate(&stream, Z_FINISH);
  deflateEnd(&stream);
  if (status != Z_STREAM_END) throw std::runtime_error("zlib: deflate did not finish");
  out.resize(stream.total_out);
  return out;
}

std::string inflate_raw(std::string_view deflated) {
  z_stream stream{};
  if (inflateInit2(&stream, -15) != Z_OK) throw std::runtime_error("zlib: inflateInit2 failed");
  stream.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(deflated.data()));
  stream.avail_in = static_cast<uInt>(deflated.size());
  std::string out;
  char buffer[1 << 16];
  int status = Z_OK;
  while (status == Z_OK) {
    stream.next_out = reinterpret_cast<Bytef*>(buffer);
    stream.avail_out = sizeof buffer;
    status = inflate(&stream, Z_NO_FLUSH);
    out.append(buffer, sizeof buffer - stream.avail_out);
  }
  inflateEnd(&stream);
  if (status != Z_STREAM_END) throw std::runtime_error("zlib: the data does not inflate");
  return out;
}

CompressedText compress_lines(std::string_view text, std::size_t lines_per_chunk,
                              std::size_t budget_bytes, unsigned threads) {
  CompressedText result;
  result.lines_per_chunk = lines_per_chunk;
  std::vector<std::string_view> pieces;  // each chunk's text, its lines' '\n' included
  std::size_t begin = 0, in_chunk = 0;
  for (std::size_t at = 0; at < text.size(); ++at) {
    if (text[at] != '\n') continue;
    ++result.lines;
    if (++in_chunk == lines_per_chunk) {
      pieces.push_back(text.substr(begin, at + 1 - begin));
      begin = at + 1, in_chunk = 0;
    }
  }
  if (begin < text.size()) {  // a last line without '\n', or a last partial chunk
    if (text.back() != '\n') ++result.lines;
    pieces.push_back(text.substr(begin));
  }
  std::vector<std::string> encoded(pieces.size());
  detail::for_each_chunk(pieces.size(), threads, [&](std::size_t c) {
    const std::string deflated = deflate_raw(pieces[c]);
    encoded[c] = base64({reinterpret_cast<const std::uint8_t*>(deflated.data()), deflated.size()});
  });
  std::size_t used = 0;
  for (std::size_t c = 0; c < encoded.size(); ++c) {
    if (used + encoded[c].size() > budget_bytes) break;
    used += encoded[c].size();
    result.chunks.push_back(std::move(encoded[c]));
    result.lines_kept = std::min(result.lines, (c + 1) * lines_per_chunk);
  }
  return result;
}

}  // namespace tridex::cli
