#include "pipeline/progress.hpp"

#include <unistd.h>

#include <cstdio>

#include "errors.hpp"

namespace tridex::cli {

bool stderr_is_terminal() { return ::isatty(STDERR_FILENO) == 1; }

void Progress::stage(const std::string& text) {
  if (!enabled_) return;
  double seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start_).count();
  // On a terminal each stage overwrites the last; in a log each gets its own line. The text may
  // hold a file name: escaped (errors.hpp).
  const std::string shown = terminal_safe(text);
  if (terminal_) {
    std::fprintf(stderr, "\r\033[K[%6.2f s] %s", seconds, shown.c_str());
    open_ = true;
  } else {
    std::fprintf(stderr, "[%6.2f s] %s\n", seconds, shown.c_str());
  }
  std::fflush(stderr);
}

void Progress::finish() {
  if (!enabled_ || !open_) return;
  std::fputc('\n', stderr);
  std::fflush(stderr);
  open_ = false;
}

}  // namespace tridex::cli
