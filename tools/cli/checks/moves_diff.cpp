// tridex moves A --diff B (issue 39): the two programs' moves aligned by geometry and order, so
// that a reordered block or a split arc is one change, not a thousand. Each block's moves (an
// arc's chords, a cycle's pieces) are one record keyed by its kind, tool, spindle axis and end
// point (rounded to 0.001 mm; not its start, which a reordered neighbour changes); the records are
// aligned with Myers' diff (line_alignment.hpp). A hunk only one side has, whose points lie on
// the other side's next matched block, is a split (or merged) line or arc: no change. A deleted
// run of records that another hunk inserts elsewhere is one `moved` change.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <map>

#include "checks/line_alignment.hpp"
#include "commands.hpp"
#include "errors.hpp"
#include "inputs/program_input.hpp"
#include "json_text.hpp"
#include "outputs/output.hpp"

namespace tridex::cli {

namespace {

constexpr double kMovesDiffPointTolerance = 0.01;  // mm: a split point on the other's path

struct BlockRecord {
  int file = 0, line = 0, tool = 0;
  gcode::MoveKind kind = gcode::MoveKind::rapid;
  Vec3 axis{0, 0, 1};
  std::vector<Vec3> path;  // the start, then each move's end
  std::string key;
};

std::vector<BlockRecord> block_records(const ListOptions& options, const std::string& program) {
  ListOptions own = options;
  own.program = program;
  const ProgramInput input = resolve_program(own);
  std::vector<BlockRecord> records;
  interpret(
      input, interpreter_options(own),
      [&](const gcode::Move& m, std::size_t) {
        if (records.empty() || records.back().line != m.line || records.back().file != m.file ||
            records.back().kind != m.kind || records.back().tool != m.tool) {
          BlockRecord r;
          r.file = m.file, r.line = m.line, r.tool = m.tool, r.kind = m.kind, r.axis = m.axis;
          r.path.push_back(m.start);
          records.push_back(std::move(r));
        }
        records.back().path.push_back(m.end);
      },
      {}, options.max_moves);
  for (BlockRecord& r : records) {
    const Vec3& e = r.path.back();
    char key[200];
    std::snprintf(key, sizeof key, "%s T%d %.3f %.3f %.3f %.4f %.4f %.4f", gcode::to_string(r.kind),
                  r.tool, e.x, e.y, e.z, r.axis.x, r.axis.y, r.axis.z);
    r.key = key;
  }
  return records;
}

double distance_to_path(const Vec3& p, const std::vector<Vec3>& path) {
  double best = glm::length(p - path.front());
  for (std::size_t k = 1; k < path.size(); ++k) {
    const Vec3 a = path[k - 1], d = path[k] - a;
    const double l2 = glm::dot(d, d);
    const double t = l2 > 0 ? std::clamp(glm::dot(p - a, d) / l2, 0.0, 1.0) : 0.0;
    best = std::min(best, glm::length(p - (a + t * d)));
  }
  return best;
}

// The extra records [from, to) of one side lie on `next`, the other side's matched block after
// them, and are of its kind and tool: a split (or merged) line or arc.
bool split_of(const std::vector<BlockRecord>& side, std::size_t from, std::size_t to,
              const BlockRecord* next) {
  if (!next) return false;
  for (std::size_t k = from; k < to; ++k) {
    if (side[k].kind != next->kind || side[k].tool != next->tool) return false;
    for (const Vec3& p : side[k].path)
      if (distance_to_path(p, next->path) > kMovesDiffPointTolerance) return false;
  }
  return true;
}

struct Hunk {
  std::size_t a0, a1, b0, b1;  // [a0, a1) of A, [b0, b1) of B unmatched
};

Json side_json(const std::vector<BlockRecord>& records, std::size_t from, std::size_t to,
               const std::vector<std::string>& files) {
  Json lines = Json::array();
  for (std::size_t k = from; k < to && lines.size() < 50; ++k)
    if (lines.empty() || lines.back() != records[k].line) lines.push_back(records[k].line);
  Json j = {{"lines", lines}, {"blocks", to - from}};
  if (from < to && records[from].file != 0 &&
      static_cast<std::size_t>(records[from].file) < files.size())
    j["file"] = files[static_cast<std::size_t>(records[from].file)];
  return j;
}

std::vector<Hunk> hunks_of(const std::vector<int>& a_to_b, std::size_t n, std::size_t m) {
  std::vector<Hunk> hunks;
  std::size_t i = 0, j = 0;
  while (i < n || j < m) {
    if (i < n && a_to_b[i] == static_cast<int>(j)) {
      ++i, ++j;
      continue;
    }
    Hunk h{i, i, j, j};
    while (i < n && a_to_b[i] < 0) ++i;
    h.a1 = i;
    const std::size_t b_end = i < n ? static_cast<std::size_t>(a_to_b[i]) : m;
    j = b_end;
    h.b1 = b_end;
    hunks.push_back(h);
  }
  return hunks;
}

}  // namespace

int run_moves_diff(const ListOptions& options) {
  const std::vector<BlockRecord> a = block_records(options, options.program);
  const std::vector<BlockRecord> b = block_records(options, options.diff);
  std::map<std::string, int> ids;
  std::vector<int> x, y;
  for (const BlockRecord& r : a) x.push_back(ids.emplace(r.key, ids.size()).first->second);
  for (const BlockRecord& r : b) y.push_back(ids.emplace(r.key, ids.size()).first->second);
  const std::vector<int> a_to_b = align_sequences(x, y);
  std::vector<Hunk> hunks = hunks_of(a_to_b, a.size(), b.size());
  std::vector<std::string> out;
  std::vector<bool> used(hunks.size(), false);
  long long splits = 0;
  const std::vector<std::string> no_files;
  for (std::size_t h = 0; h < hunks.size(); ++h) {
    const Hunk& k = hunks[h];
    const bool only_a = k.b0 == k.b1, only_b = k.a0 == k.a1;
    if ((only_b && split_of(b, k.b0, k.b1, k.a1 < a.size() ? &a[k.a1] : nullptr)) ||
        (only_a && split_of(a, k.a0, k.a1, k.b1 < b.size() ? &b[k.b1] : nullptr))) {
      used[h] = true, ++splits;
      continue;
    }
    if (used[h] || !only_a) continue;
    // A deleted run that some insertion repeats: moved.
    for (std::size_t g = 0; g < hunks.size(); ++g) {
      const Hunk& o = hunks[g];
      if (used[g] || o.a0 != o.a1 || o.b1 - o.b0 != k.a1 - k.a0 ||
          !std::equal(x.begin() + static_cast<std::ptrdiff_t>(k.a0),
                      x.begin() + static_cast<std::ptrdiff_t>(k.a1),
                      y.begin() + static_cast<std::ptrdiff_t>(o.b0)))
        continue;
      used[h] = used[g] = true;
      out.push_back(dump_json(Json{{"change", "moved"},
                                   {"a", side_json(a, k.a0, k.a1, no_files)},
                                   {"b", side_json(b, o.b0, o.b1, no_files)}}));
      break;
    }
  }
  for (std::size_t h = 0; h < hunks.size(); ++h) {
    if (used[h]) continue;
    const Hunk& k = hunks[h];
    Json record = {{"change", k.a0 == k.a1 ? "added" : k.b0 == k.b1 ? "removed" : "changed"}};
    if (k.a0 < k.a1) record["a"] = side_json(a, k.a0, k.a1, no_files);
    if (k.b0 < k.b1) record["b"] = side_json(b, k.b0, k.b1, no_files);
    out.push_back(dump_json(record));
  }
  const std::size_t changes = out.size();
  out.push_back(dump_json(Json{{"summary",
                                {{"blocks_a", a.size()},
                                 {"blocks_b", b.size()},
                                 {"changes", changes},
                                 {"splits", splits}}}}));
  std::string text;
  for (const std::string& line : out) text += line + "\n";
  if (options.output == "-")
    std::fwrite(text.data(), 1, text.size(), stdout);
  else
    write_file_atomically(options.output, text);
  return changes == 0 ? kSuccess : kFindings;
}

}  // namespace tridex::cli
