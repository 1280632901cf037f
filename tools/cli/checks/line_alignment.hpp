// tridex command — two versions of a program's text aligned line by line (diff, issue 39): which
// lines of each are unmatched (changed), and where each line of A falls in B. Myers' O(ND)
// difference algorithm (E. W. Myers, "An O(ND) Difference Algorithm and Its Variations",
// Algorithmica 1, 1986) on the lines with comments, spaces and N sequence numbers dropped.
#pragma once

#include <string>
#include <string_view>
#include <vector>

namespace tridex::cli {

struct LineAlignment {
  // Indexed by 1-based line number (entry 0 unused).
  std::vector<int> a_to_b;  // the B line an A line matches, or where it would be (unmatched)
  std::vector<int> b_to_a;  // the same from B to A
  std::vector<char> changed_a, changed_b;  // unmatched lines (blank or comment-only never)
  bool exact = true;  // false: more than the edit budget differed; the middle counts as changed
};

// A line as compared: comments, spaces and a leading N number dropped, letters upper-cased.
std::string normalized_block(std::string_view line);

// Myers on two sequences of ids: for each entry of x the index of its match in y, or -1.
// `exact` (optional): false when they differ by more than the edit budget (the middle unmatched).
std::vector<int> align_sequences(const std::vector<int>& x, const std::vector<int>& y,
                                 bool* exact = nullptr);

LineAlignment align_lines(std::string_view a, std::string_view b);

// The changed B line nearest before-or-at `line`, and the first after it (0: none).
int changed_at_or_before(const std::vector<char>& changed, int line);
int changed_after(const std::vector<char>& changed, int line);

}  // namespace tridex::cli
