// tridex command — reading the JSON files it takes (tool tables, CAMotics projects) so that every
// fault is an InputError naming the file and the place: a directory or unreadable file, a syntax
// error or a number out of range (at line:column), a key given twice in one object. No text of
// the JSON library reaches the user.
#pragma once

#include <filesystem>
#include <string>

#include <nlohmann/json.hpp>

namespace tridex::cli {

// Parses `text`; `source` names it in messages ("tools.json"). Throws InputError.
nlohmann::json parse_json_text(const std::string& text, const std::string& source);

// The whole text of the regular file at `path`; `kind` names what it should be in messages ("a
// JSON file"). Throws InputError for a missing file, a directory, a special file, or a file that
// cannot be read.
std::string read_text_file(const std::filesystem::path& path, const std::string& kind);

// Reads and parses the file at `path`; throws InputError (read_text_file's faults, or any
// parse_json_text fault).
nlohmann::json read_json_file(const std::filesystem::path& path);

// The JSON type of `value` in words ("a string", "null"), for messages.
std::string json_type_name(const nlohmann::json& value);

}  // namespace tridex::cli
