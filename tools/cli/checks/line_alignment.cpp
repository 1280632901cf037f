// tridex command — line alignment of two program texts (line_alignment.hpp).
#include "checks/line_alignment.hpp"

#include <algorithm>
#include <cctype>
#include <unordered_map>

namespace tridex::cli {

namespace {

// Edits beyond which the middle of the two texts is not aligned (Myers keeps d² entries).
constexpr int kAlignmentMaxEdits = 3000;

std::vector<std::string_view> alignment_split_lines(std::string_view text) {
  std::vector<std::string_view> lines;
  std::size_t at = 0;
  while (at <= text.size()) {
    std::size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    std::string_view line = text.substr(at, end - at);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    lines.push_back(line);
    at = end + 1;
  }
  if (!lines.empty() && lines.back().empty() && !text.empty() && text.back() == '\n')
    lines.pop_back();
  return lines;
}

// Myers' greedy forward search on x[0, n) and y[0, m); marks matched entries. False when the
// texts differ by more than kAlignmentMaxEdits.
bool myers_match(const std::vector<int>& x, const std::vector<int>& y, std::vector<int>& x_to_y) {
  const int n = static_cast<int>(x.size()), m = static_cast<int>(y.size());
  const int limit = std::min(n + m, kAlignmentMaxEdits);
  const int offset = limit + 1;
  std::vector<int> v(static_cast<std::size_t>(2 * limit + 3), 0);
  std::vector<std::vector<int>> trace;
  int found = -1;
  for (int d = 0; d <= limit && found < 0; ++d) {
    trace.emplace_back(v.begin() + offset - d, v.begin() + offset + d + 1);
    for (int k = -d; k <= d; k += 2) {
      int px = (k == -d || (k != d && v[offset + k - 1] < v[offset + k + 1]))
                   ? v[offset + k + 1]
                   : v[offset + k - 1] + 1;
      int py = px - k;
      while (px < n && py < m && x[px] == y[py]) ++px, ++py;
      v[offset + k] = px;
      if (px >= n && py >= m) {
        found = d;
        break;
      }
    }
  }
  if (found < 0) return false;
  int px = n, py = m;
  for (int d = found; d > 0; --d) {
    const std::vector<int>& before = trace[static_cast<std::size_t>(d)];  // v before step d
    auto at = [&](int k) { return before[static_cast<std::size_t>(k + d)]; };
    const int k = px - py;
    const int prev_k = (k == -d || (k != d && at(k - 1) < at(k + 1))) ? k + 1 : k - 1;
    const int prev_x = at(prev_k), prev_y = prev_x - prev_k;
    while (px > prev_x && py > prev_y) --px, --py, x_to_y[static_cast<std::size_t>(px)] = py;
    px = prev_x, py = prev_y;
  }
  while (px > 0 && py > 0) --px, --py, x_to_y[static_cast<std::size_t>(px)] = py;
  return true;
}

}  // namespace

std::vector<int> align_sequences(const std::vector<int>& x, const std::vector<int>& y,
                                 bool* exact) {
  const int n = static_cast<int>(x.size()), m = static_cast<int>(y.size());
  std::vector<int> x_to_y(x.size(), -1);
  int head = 0;
  while (head < n && head < m && x[head] == y[head]) x_to_y[head] = head, ++head;
  int tail = 0;
  while (tail < n - head && tail < m - head && x[n - 1 - tail] == y[m - 1 - tail])
    x_to_y[n - 1 - tail] = m - 1 - tail, ++tail;
  std::vector<int> mx(x.begin() + head, x.end() - tail), my(y.begin() + head, y.end() - tail);
  std::vector<int> middle(mx.size(), -1);
  const bool found = myers_match(mx, my, middle);
  if (exact) *exact = found;
  for (std::size_t i = 0; i < middle.size(); ++i)
    if (middle[i] >= 0) x_to_y[head + i] = middle[i] + head;
  return x_to_y;
}

std::string normalized_block(std::string_view line) {
  std::string out;
  bool comment = false;
  for (char c : line) {
    if (comment) {
      comment = c != ')';
      continue;
    }
    if (c == '(') {
      comment = true;
      continue;
    }
    if (c == ';') break;
    if (c == ' ' || c == '\t' || c == '\r') continue;
    out += static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
  }
  if (!out.empty() && out[0] == 'N') {
    std::size_t i = 1;
    while (i < out.size() && std::isdigit(static_cast<unsigned char>(out[i]))) ++i;
    if (i > 1) out.erase(0, i);
  }
  return out;
}

LineAlignment align_lines(std::string_view a_text, std::string_view b_text) {
  const std::vector<std::string_view> a = alignment_split_lines(a_text),
                                      b = alignment_split_lines(b_text);
  std::unordered_map<std::string, int> ids;
  std::vector<int> x, y;
  for (std::string_view line : a)
    x.push_back(ids.emplace(normalized_block(line), ids.size()).first->second);
  for (std::string_view line : b)
    y.push_back(ids.emplace(normalized_block(line), ids.size()).first->second);
  const int blank = ids.emplace("", ids.size()).first->second;
  const int n = static_cast<int>(x.size()), m = static_cast<int>(y.size());
  LineAlignment out;
  const std::vector<int> x_to_y = align_sequences(x, y, &out.exact);
  out.a_to_b.assign(a.size() + 1, 0);
  out.b_to_a.assign(b.size() + 1, 0);
  out.changed_a.assign(a.size() + 1, 0);
  out.changed_b.assign(b.size() + 1, 1);
  out.changed_b[0] = 0;
  int next_b = 0;  // the B line after the last matched one (0-based)
  for (int i = 0; i < n; ++i) {
    const int j = x_to_y[static_cast<std::size_t>(i)];
    if (j >= 0) {
      next_b = j + 1;
      out.b_to_a[static_cast<std::size_t>(j + 1)] = i + 1;
      out.changed_b[static_cast<std::size_t>(j + 1)] = 0;
    }
    out.a_to_b[static_cast<std::size_t>(i + 1)] = j >= 0 ? j + 1 : std::min(next_b + 1, m);
    out.changed_a[static_cast<std::size_t>(i + 1)] =
        j < 0 && x[static_cast<std::size_t>(i)] != blank;
  }
  int next_a = 0;
  for (int j = 0; j < m; ++j) {
    if (out.changed_b[static_cast<std::size_t>(j + 1)] == 0) {
      next_a = out.b_to_a[static_cast<std::size_t>(j + 1)];
      continue;
    }
    out.b_to_a[static_cast<std::size_t>(j + 1)] = std::min(next_a + 1, n);
    if (y[static_cast<std::size_t>(j)] == blank) out.changed_b[static_cast<std::size_t>(j + 1)] = 0;
  }
  return out;
}

int changed_at_or_before(const std::vector<char>& changed, int line) {
  for (int l = std::min(line, static_cast<int>(changed.size()) - 1); l >= 1; --l)
    if (changed[static_cast<std::size_t>(l)]) return l;
  return 0;
}

int changed_after(const std::vector<char>& changed, int line) {
  for (int l = std::max(line + 1, 1); l < static_cast<int>(changed.size()); ++l)
    if (changed[static_cast<std::size_t>(l)]) return l;
  return 0;
}

}  // namespace tridex::cli
