#include "inputs/numbers.hpp"

#include <cmath>

#include <fast_float/fast_float.h>

#include "errors.hpp"

namespace tridex::cli {

double parse_number(const std::string& text, const std::string& what) {
  double value = 0;
  const char* first = text.data();
  const char* last = first + text.size();
  auto result = fast_float::from_chars(first, last, value);
  if (text.empty() || result.ec != std::errc() || result.ptr != last || !std::isfinite(value))
    input_error(what, ": \"", text, "\" is not a number");
  return value;
}

std::vector<double> parse_number_list(const std::string& text, const std::string& what) {
  std::vector<double> values;
  std::size_t start = 0;
  while (true) {
    std::size_t comma = text.find(',', start);
    std::string part =
        text.substr(start, comma == std::string::npos ? std::string::npos : comma - start);
    values.push_back(parse_number(part, what));
    if (comma == std::string::npos) break;
    start = comma + 1;
  }
  return values;
}

}  // namespace tridex::cli
