// tridex command — the two kinds of failure and their exit statuses.
//
// The issue fixes the contract scripts rely on: 0 on success, 2 for bad input (program, tool
// table, stock, options), 1 for anything else. Bad input is an InputError (or a G-code error,
// which the command maps to 2 as well); everything else that escapes is a failure of the run.
#pragma once

#include <sstream>
#include <string>

#include "tridex/error.hpp"

namespace tridex::cli {

// `check` adds 3: the program gouges, leaves excess, crashes a rapid or leaves the envelope.
enum ExitStatus : int { kSuccess = 0, kFailure = 1, kBadInput = 2, kFindings = 3 };

class InputError : public tridex::Error {
 public:
  using tridex::Error::Error;
};

template <class... Parts>
[[noreturn]] inline void input_error(const Parts&... parts) {
  std::ostringstream message;
  (message << ... << parts);
  throw InputError(message.str());
}

}  // namespace tridex::cli
