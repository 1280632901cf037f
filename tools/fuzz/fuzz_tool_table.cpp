// libFuzzer harness over the tool table (JSON in the CAMotics schema): parse_json_text and
// ToolTable::from_json. Any input must give a table of valid cutters or throw InputError (exit
// status 2); any other exception escaping (a JSON library error, say) ends the run as a crash.
#include <cmath>
#include <cstdint>
#include <cstdlib>
#include <string>

#include "errors.hpp"
#include "inputs/tool_table.hpp"
#include "inputs/json_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    tridex::cli::ToolTable table =
        tridex::cli::ToolTable::from_json(tridex::cli::parse_json_text(text, "fuzz"), "fuzz");
    for (int number = 0; number < 8; ++number)
      if (const tridex::cli::ToolSpec* spec = table.find(number))
        if (!(spec->cutter.radius() > 0) || !std::isfinite(spec->cutter.radius())) std::abort();
  } catch (const tridex::cli::InputError&) {
  }
  return 0;
}
