// tridex command — the post lint (lint.hpp). It reads the program's text block by block, without
// the interpreter, so that it also runs on a program the interpreter rejects; the one finding
// that needs the interpreter (arc centres that fit only the other G90.1/G91.1 mode) comes from
// the interpreter's own message (gcode/src/motion.cpp).
#include "checks/lint.hpp"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdlib>
#include <map>

namespace tridex::cli {

namespace {

struct LintWord {
  char letter = 0;
  double value = 0;
  bool decimal = false;  // written with a decimal point
  std::string text;      // as written, e.g. "X102"
};

struct LintBlock {
  int line = 0;
  std::vector<LintWord> words;
  bool parametric = false;  // parameters, expressions or keywords: not plain numbers

  const LintWord* find(char letter) const {
    for (const LintWord& w : words)
      if (w.letter == letter) return &w;
    return nullptr;
  }
  // G or M code `code` times ten (G43.4 is 434), as written in this block.
  bool has_code(char letter, int code10) const {
    for (const LintWord& w : words)
      if (w.letter == letter && std::lround(w.value * 10) == code10) return true;
    return false;
  }
};

// The words of one line: comments in parentheses and after ';' dropped, letters upper-cased.
LintBlock lint_parse_line(std::string_view line, int number) {
  LintBlock block;
  block.line = number;
  std::size_t i = 0;
  while (i < line.size()) {
    const char c = line[i];
    if (c == '(') {
      const std::size_t close = line.find(')', i);
      if (close == std::string_view::npos) break;
      i = close + 1;
      continue;
    }
    if (c == ';') break;
    if (c == '#' || c == '[' || c == '=' || c == '<') block.parametric = true;
    if (!std::isalpha(static_cast<unsigned char>(c))) {
      ++i;
      continue;
    }
    LintWord word;
    word.letter = static_cast<char>(std::toupper(static_cast<unsigned char>(c)));
    ++i;
    while (i < line.size() && (line[i] == ' ' || line[i] == '\t')) ++i;
    const std::size_t start = i;
    while (i < line.size() && (std::isdigit(static_cast<unsigned char>(line[i])) ||
                               line[i] == '.' || line[i] == '+' || line[i] == '-'))
      ++i;
    const std::string number_text(line.substr(start, i - start));
    char* end = nullptr;
    word.value = std::strtod(number_text.c_str(), &end);
    if (number_text.empty() || end != number_text.c_str() + number_text.size()) {
      block.parametric = true;  // a keyword (o100 sub, IF) or an expression
      continue;
    }
    word.decimal = number_text.find('.') != std::string::npos;
    word.text = std::string(1, word.letter) + number_text;
    block.words.push_back(std::move(word));
  }
  return block;
}

std::vector<LintBlock> lint_blocks(std::string_view text) {
  std::vector<LintBlock> blocks;
  int number = 0;
  std::size_t at = 0;
  while (at <= text.size()) {
    std::size_t end = text.find('\n', at);
    if (end == std::string_view::npos) end = text.size();
    ++number;
    blocks.push_back(lint_parse_line(text.substr(at, end - at), number));
    at = end + 1;
  }
  return blocks;
}

// Median size of the XYZ coordinates a section of blocks writes, mm (0: fewer than 20).
double lint_coordinate_size(const std::vector<LintBlock>& blocks, std::size_t from, std::size_t to,
                            double unit) {
  std::vector<double> sizes;
  for (std::size_t k = from; k < to; ++k) {
    const LintBlock& b = blocks[k];
    if (b.parametric || b.has_code('G', 100) || b.has_code('G', 920) || b.has_code('G', 530) ||
        b.has_code('G', 280) || b.has_code('G', 300))
      continue;
    for (const LintWord& w : b.words)
      if ((w.letter == 'X' || w.letter == 'Y' || w.letter == 'Z') && w.value != 0)
        sizes.push_back(std::abs(w.value) * unit);
  }
  // A few coordinates say nothing about a section's unit (a test of G20 moving to X1 Y1).
  if (sizes.size() < 20) return 0;
  std::nth_element(sizes.begin(), sizes.begin() + static_cast<std::ptrdiff_t>(sizes.size() / 2),
                   sizes.end());
  return sizes[sizes.size() / 2];
}

// G20/G21 after the program chose its units: every later coordinate is read 25.4 times too large
// or too small. `strict` (diff) flags every switch; otherwise a switch whose section writes
// coordinates more than 4 times larger or smaller (in mm) than the program's first section, as
// a stray G20 in a millimetre program does (a deliberate inch section writes inch-sized numbers).
void lint_units(const std::vector<LintBlock>& blocks, const std::string& file, bool strict,
                std::vector<LintFinding>& out) {
  struct Switch {
    std::size_t block;
    int code;
  };
  std::vector<Switch> switches;
  int units = 0;  // 200 (G20) or 210 (G21)
  for (std::size_t k = 0; k < blocks.size(); ++k)
    for (int code : {200, 210})
      if (blocks[k].has_code('G', code) && units != code) {
        switches.push_back({k, code});
        units = code;
      }
  double reference = 0;
  for (std::size_t s = 0; s < switches.size(); ++s) {
    const std::size_t from = s == 0 ? 0 : switches[s].block;
    const std::size_t to = s + 1 < switches.size() ? switches[s + 1].block : blocks.size();
    const double size = lint_coordinate_size(blocks, from, to, switches[s].code == 200 ? 25.4 : 1);
    if (s > 0) {
      const bool odd = reference > 0 && size > 0 && (size > 4 * reference || size * 4 < reference);
      if (strict || odd)
        out.push_back({file, blocks[switches[s].block].line, "units_change",
                       std::string(switches[s].code == 200 ? "G20 (inch)" : "G21 (mm)") +
                           " changes the units mid-program (" +
                           (switches[s - 1].code == 200 ? "G20" : "G21") + " since line " +
                           std::to_string(blocks[switches[s - 1].block].line) +
                           "): every later coordinate is read in the other unit"});
    }
    if (reference == 0) reference = size;
  }
}

// A block that moves Z as a programmed position (not a reference return, machine coordinates,
// an offset setting or a dwell).
bool lint_moves_z(const LintBlock& b) {
  if (!b.find('Z')) return false;
  for (int code : {40, 100, 280, 300, 520, 530, 650, 680, 682, 920})
    if (b.has_code('G', code)) return false;
  return true;
}

// A code that applies a tool length: G43, Fanuc's TCP G43.4/G43.5, Haas's TCPC G234 (a program of
// another control has no G234).
bool lint_applies_length(const LintBlock& b) {
  return b.has_code('G', 430) || b.has_code('G', 434) || b.has_code('G', 435) ||
         b.has_code('G', 2340);
}

// G43 H after each tool change, before the tool moves along Z; and H matching the tool (when the
// program elsewhere numbers H as its tools: some shops keep lengths in other registers).
void lint_length_offsets(const std::vector<LintBlock>& blocks, const std::string& file, bool expect,
                         bool strict, std::vector<LintFinding>& out) {
  int selected = -1, loaded = -1, change_line = 0, matches = 0;
  bool needed = false;
  std::vector<LintFinding> mismatches;
  for (const LintBlock& b : blocks) {
    if (const LintWord* t = b.find('T'); t && !b.parametric) selected = static_cast<int>(t->value);
    if (b.has_code('M', 60) && selected >= 0) {
      loaded = selected;
      needed = expect && loaded > 0;  // T0 M6 empties the spindle
      change_line = b.line;
    }
    const bool g43 = lint_applies_length(b);
    if (g43) {
      needed = false;
      const LintWord* h = b.find('H');
      // G43 without H: LinuxCNC applies the loaded tool's length, a Fanuc no new one; only diff
      // (strict), where the reference program writes an H here, calls it missing.
      if (!h && strict && loaded > 0)
        out.push_back({file, b.line, "g43_missing",
                       "G43 without H after the tool change at line " +
                           std::to_string(change_line) + " (T" + std::to_string(loaded) + ")"});
      if (h && loaded > 0 && !b.parametric) {
        if (static_cast<int>(h->value) == loaded)
          ++matches;
        else
          mismatches.push_back({file, b.line, "g43_h_mismatch",
                                "G43 " + h->text + " with tool " + std::to_string(loaded) +
                                    " loaded (line " + std::to_string(change_line) +
                                    "): the length of another tool is applied"});
      }
    } else if (needed && lint_moves_z(b)) {
      out.push_back({file, b.line, "g43_missing",
                     "Z moves with no G43 H since the tool change at line " +
                         std::to_string(change_line) + " (T" + std::to_string(loaded) +
                         "): the tool's length is not applied"});
      needed = false;
    }
  }
  if (strict || (matches >= 2 && mismatches.size() * 3 <= static_cast<std::size_t>(matches)))
    out.insert(out.end(), mismatches.begin(), mismatches.end());
}

// Coordinates written without a decimal point in a program that otherwise writes them: on a
// control without decimal-point input (Fanuc parameter 3401 bit 0 clear) X102 is 102 least
// increments, 0.102 mm. Zero means the same either way; K is a repeat count in a canned cycle.
void lint_decimal_points(const std::vector<LintBlock>& blocks, const std::string& file,
                         const LintSettings& settings, std::vector<LintFinding>& out) {
  if (settings.decimal_point_input == true || settings.linuxcnc) return;
  constexpr std::string_view kCoordinates = "XYZIJKRABCUVW";
  std::vector<std::pair<int, std::string>> integers;
  long long decimals = 0;
  bool cycle = false;
  for (const LintBlock& b : blocks) {
    for (int code : {0, 10, 20, 30, 800}) cycle = cycle && !b.has_code('G', code);
    for (int code : {730, 740, 760, 810, 820, 830, 840, 850, 860, 870, 880, 890})
      cycle = cycle || b.has_code('G', code);
    if (b.parametric || b.has_code('G', 40) || b.has_code('G', 100) || b.has_code('G', 650) ||
        b.has_code('M', 980))
      continue;
    for (const LintWord& w : b.words) {
      if (kCoordinates.find(w.letter) == std::string_view::npos || (cycle && w.letter == 'K'))
        continue;
      if (w.decimal)
        ++decimals;
      else if (w.value != 0)
        integers.emplace_back(b.line, w.text);
    }
  }
  // "Otherwise writes decimals": at least 100 coordinates with a point for each without one (a
  // post formats every coordinate alike; a hand-written program mixes Z1 with X1.25).
  // In diff (strict) the reference's own integers are not counted against B, so a program with
  // one integer in ten coordinates is still checked.
  const double ratio = settings.strict ? 10 : 100;
  if (decimals < (settings.strict ? 20 : 100) ||
      static_cast<double>(integers.size()) * ratio > static_cast<double>(decimals))
    return;
  for (const auto& [line, text] : integers)
    out.push_back(
        {file, line, "integer_coordinate",
         text + " has no decimal point in a program that writes them: " +
             (settings.decimal_point_input == false
                  ? "this control reads it in least increments (" + text + " is " +
                        std::to_string(std::atof(text.c_str() + 1) / 1000) + " mm)"
                  : "a control without decimal-point input reads it in least increments (1/1000 "
                    "mm); the machine file's \"decimal_point_input\" says which")});
}

}  // namespace

bool program_uses_g43(std::string_view text) {
  for (const LintBlock& b : lint_blocks(text))
    if (lint_applies_length(b)) return true;
  return false;
}

std::vector<LintFinding> lint_text(std::string_view text, const std::string& file,
                                   const LintSettings& settings) {
  const std::vector<LintBlock> blocks = lint_blocks(text);
  std::vector<LintFinding> out;
  lint_units(blocks, file, settings.strict, out);
  bool uses_g43 = settings.expect_g43;
  for (const LintBlock& b : blocks) uses_g43 = uses_g43 || lint_applies_length(b);
  lint_length_offsets(blocks, file, uses_g43, settings.strict, out);
  lint_decimal_points(blocks, file, settings, out);
  std::stable_sort(out.begin(), out.end(),
                   [](const LintFinding& a, const LintFinding& b) { return a.line < b.line; });
  return out;
}

LintFinding lint_error_finding(const std::string& file, int line, const std::string& message) {
  const bool mode = message.find("is G90.1 missing") != std::string::npos ||
                    message.find("is G91.1 missing") != std::string::npos;
  return {file, line, mode ? "arc_centre_mode" : "program_error", message};
}

Json lint_json(const LintFinding& f) {
  return {{"file", f.file}, {"line", f.line}, {"code", f.code}, {"message", f.message}};
}

std::string lint_text_line(const LintFinding& f) {
  return f.file + ":" + std::to_string(f.line) + ": " + f.code + ": " + f.message;
}

}  // namespace tridex::cli
