// tridex command — strict parsing of numbers in option values.
#pragma once

#include <string>
#include <vector>

namespace tridex::cli {

// The whole of `text` as one finite number; throws InputError naming `what` otherwise.
double parse_number(const std::string& text, const std::string& what);
// Comma-separated finite numbers.
std::vector<double> parse_number_list(const std::string& text, const std::string& what);

}  // namespace tridex::cli
