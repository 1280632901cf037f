// A large program's text for the offline page, compressed: the page must show the text of any
// line at the slider (issue 32), and a paper-scale program is 144 MB of G-code, which inlined
// as it is made a 154 MB page that took Chromium 6.5 s to parse before anything was drawn.
// G-code deflates about 5.6:1 (many near-identical lines), and the page inflates only the chunk
// of lines the slider is in (the browser's DecompressionStream("deflate-raw"), no library), so
// the text costs little to load. RFC 1951 (DEFLATE) through zlib.
#pragma once

#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

namespace tridex::cli {

struct CompressedText {
  std::size_t lines_per_chunk = 0;
  std::vector<std::string> chunks;  // base64 of raw DEFLATE, chunk k = lines [k·n + 1, (k+1)·n]
  std::size_t lines = 0;            // lines in the text
  std::size_t lines_kept = 0;       // lines the chunks hold (fewer when the budget ran out)
};

// `text` (UTF-8, '\n'-separated lines) cut into chunks of `lines_per_chunk` lines, each deflated
// on its own (chunks in parallel on `threads`, 0: all; the result does not depend on it). Chunks
// are kept in order while their base64 size stays within `budget_bytes`.
CompressedText compress_lines(std::string_view text, std::size_t lines_per_chunk,
                              std::size_t budget_bytes, unsigned threads = 0);

// Raw DEFLATE of `bytes` (zlib, level 6, no header): for compress_lines and its tests.
std::string deflate_raw(std::string_view bytes);
// The inverse, for the tests (the page inflates in the browser).
std::string inflate_raw(std::string_view deflated);

}  // namespace tridex::cli
