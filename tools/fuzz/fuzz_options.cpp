// libFuzzer harness over the option parsers that take structured text: --stock, --envelope and
// --max-memory. Any input must parse or throw InputError (exit status 2); a parsed box must be
// finite with min below max on every axis.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "errors.hpp"
#include "inputs/stock.hpp"
#include "pipeline/memory.hpp"

namespace {

void require_box(const tridex::Aabb& box) {
  for (int a = 0; a < 3; ++a)
    if (!std::isfinite(box.min[a]) || !std::isfinite(box.max[a]) || !(box.min[a] < box.max[a]))
      std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    tridex::cli::StockSpec spec = tridex::cli::parse_stock(text);
    if (spec.kind == tridex::cli::StockSpec::Kind::box) require_box(spec.box);
    if (spec.margin_mm && !(*spec.margin_mm >= 0 && std::isfinite(*spec.margin_mm))) std::abort();
  } catch (const tridex::cli::InputError&) {
  }
  try {
    require_box(tridex::cli::parse_envelope(text));
  } catch (const tridex::cli::InputError&) {
  }
  try {
    tridex::cli::parse_memory(text);
  } catch (const tridex::cli::InputError&) {
  }
  return 0;
}
