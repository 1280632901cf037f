// tridex command — the two kinds of failure and their exit statuses.
//
// The issue fixes the contract scripts rely on: 0 on success, 2 for bad input (program, tool
// table, stock, options), 1 for anything else. Bad input is an InputError (or a G-code error,
// which the command maps to 2 as well); everything else that escapes is a failure of the run.
#pragma once

#include <sstream>
#include <string>
#include <string_view>

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

namespace tridex::cli {

// `text` made safe for a terminal: control characters (C0 but newline and tab, DEL, and the C1
// controls U+0080-U+009F that some terminals obey), and bytes that are not UTF-8, are written as
// \xNN, so a program's comment, a tool's description or a file name cannot retitle, clear or
// reprogram the terminal the message is printed on. Valid UTF-8 text passes unchanged.
inline std::string terminal_safe(std::string_view text) {
  std::string out;
  out.reserve(text.size());
  auto escape = [&out](unsigned char byte) {
    static const char* hex = "0123456789abcdef";
    out += "\\x";
    out += hex[byte >> 4];
    out += hex[byte & 15];
  };
  for (std::size_t i = 0; i < text.size();) {
    const auto c = static_cast<unsigned char>(text[i]);
    if (c < 0x80) {
      if ((c < 0x20 && c != '\n' && c != '\t') || c == 0x7f)
        escape(c);
      else
        out += static_cast<char>(c);
      ++i;
      continue;
    }
    const std::size_t length = c >= 0xf0 ? 4 : c >= 0xe0 ? 3 : c >= 0xc2 ? 2 : 0;
    bool valid = length > 0 && c <= 0xf4 && i + length <= text.size();
    for (std::size_t k = 1; valid && k < length; ++k)
      valid = (static_cast<unsigned char>(text[i + k]) & 0xc0) == 0x80;
    if (valid && length == 3) {  // no overlong forms, no surrogates
      const auto d = static_cast<unsigned char>(text[i + 1]);
      valid = !(c == 0xe0 && d < 0xa0) && !(c == 0xed && d >= 0xa0);
    }
    if (valid && length == 4) {
      const auto d = static_cast<unsigned char>(text[i + 1]);
      valid = !(c == 0xf0 && d < 0x90) && !(c == 0xf4 && d >= 0x90);
    }
    const bool c1 = valid && c == 0xc2 && static_cast<unsigned char>(text[i + 1]) < 0xa0;
    if (!valid || c1) {
      escape(c);
      ++i;
      continue;
    }
    out.append(text.substr(i, length));
    i += length;
  }
  return out;
}

}  // namespace tridex::cli
