// tridex command — a progress line on stderr for long work.
//
// Shown when stderr is a terminal or with --progress, never with --quiet. On a terminal each
// stage rewrites one line; in a log captured with --progress each stage is a line of its own.
#pragma once

#include <chrono>
#include <string>

namespace tridex::cli {

// Seconds since `start` on the steady clock: each stage's time in the report.
inline double seconds_since(std::chrono::steady_clock::time_point start) {
  return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

bool stderr_is_terminal();

class Progress {
 public:
  explicit Progress(bool enabled) : enabled_(enabled) {}
  ~Progress() { finish(); }
  bool enabled() const { return enabled_; }
  void stage(const std::string& text);  // starts a stage and shows it
  void finish();                        // ends the line
 private:
  bool enabled_;
  bool terminal_ = stderr_is_terminal();
  bool open_ = false;
  std::chrono::steady_clock::time_point start_ = std::chrono::steady_clock::now();
};

}  // namespace tridex::cli
