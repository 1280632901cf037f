// tridex — errors raised by the kernel.
//
// The kernel rejects invalid parameters (NaN coordinates, non-positive radii, empty or
// oversized grids, malformed meshes) by throwing tridex::Error with a message that names the
// offending parameter and value. Geometric work on valid input never throws.
#pragma once

#include <cmath>
#include <sstream>
#include <stdexcept>
#include <string>

namespace tridex {

class Error : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

namespace detail {

template <class... Parts>
[[noreturn]] inline void fail(const Parts&... parts) {
  std::ostringstream message;
  (message << ... << parts);
  throw Error(message.str());
}

inline void require_finite(double value, const char* what) {
  if (!std::isfinite(value)) fail(what, " must be finite, got ", value);
}

inline void require_positive(double value, const char* what) {
  require_finite(value, what);
  if (!(value > 0)) fail(what, " must be positive, got ", value);
}

}  // namespace detail
}  // namespace tridex
