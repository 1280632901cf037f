// libFuzzer harness over the CAMotics project (.camotics, JSON): parse_json_text and
// project_from_json. Any input must give a project or throw InputError (exit status 2); any other
// exception escaping ends the run as a crash.
#include <cstdint>
#include <string>

#include "errors.hpp"
#include "inputs/project.hpp"
#include "inputs/json_input.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  std::string text(reinterpret_cast<const char*>(data), size);
  try {
    // Program files are looked up relative to the project's folder; /tmp holds none of the
    // seeds' names, so most inputs stop there, after the JSON has been read.
    tridex::cli::project_from_json(tridex::cli::parse_json_text(text, "fuzz.camotics"),
                                   "/tmp/fuzz.camotics");
  } catch (const tridex::cli::InputError&) {
  }
  return 0;
}
