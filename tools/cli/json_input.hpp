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

// Reads and parses the file at `path`; throws InputError (a directory, a special file, a file
// that cannot be read, or any parse_json_text fault).
nlohmann::json read_json_file(const std::filesystem::path& path);

// The JSON type of `value` in words ("a string", "null"), for messages.
std::string json_type_name(const nlohmann::json& value);

}  // namespace tridex::cli
