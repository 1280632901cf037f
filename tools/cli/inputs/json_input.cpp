#include "inputs/json_input.hpp"

#include <cstdio>
#include <fstream>
#include <iterator>
#include <set>
#include <vector>

#include "errors.hpp"

namespace tridex::cli {

namespace fs = std::filesystem;

namespace {

using InputJson = nlohmann::json;

constexpr int kMaxJsonDepth = 64;

// nlohmann's SAX interface, passed through to its DOM builder, with two additions: a key that an
// object already holds stops the parse (the library would keep the last silently), and a parse
// error is recorded with its byte position instead of thrown as library text.
class CheckedSax {
 public:
  explicit CheckedSax(InputJson& result) : dom_(result, false) {}

  bool null() { return dom_.null(); }
  bool boolean(bool value) { return dom_.boolean(value); }
  bool number_integer(InputJson::number_integer_t value) { return dom_.number_integer(value); }
  bool number_unsigned(InputJson::number_unsigned_t value) { return dom_.number_unsigned(value); }
  bool number_float(InputJson::number_float_t value, const InputJson::string_t& text) {
    return dom_.number_float(value, text);
  }
  bool string(InputJson::string_t& value) { return dom_.string(value); }
  bool binary(InputJson::binary_t& value) { return dom_.binary(value); }
  bool start_object(std::size_t size) {
    if (!deeper()) return false;
    keys_.emplace_back();
    return dom_.start_object(size);
  }
  bool key(InputJson::string_t& key) {
    if (!keys_.back().insert(key).second) {
      duplicate = key;
      return false;
    }
    last_key = key;
    return dom_.key(key);
  }
  bool end_object() {
    keys_.pop_back();
    --depth_;
    return dom_.end_object();
  }
  bool start_array(std::size_t size) { return deeper() && dom_.start_array(size); }
  bool end_array() {
    --depth_;
    return dom_.end_array();
  }
  bool parse_error(std::size_t position, const std::string& token,
                   const nlohmann::detail::exception& error) {
    error_position = position;
    error_token = token;
    error_id = error.id;
    failed = true;
    return false;
  }

  bool failed = false;
  std::size_t error_position = 0;
  std::string error_token;
  int error_id = 0;
  std::string duplicate;
  std::string last_key;  // the key most recently read, where a fault most likely is
  bool too_deep = false;

 private:
  // No file tridex reads nests deeper than a few levels; a bound keeps every reader of the
  // document (recursive ones included, such as a machine's "profile") from deep recursion.
  bool deeper() {
    if (++depth_ <= kMaxJsonDepth) return true;
    too_deep = true;
    return false;
  }
  int depth_ = 0;

  nlohmann::detail::json_sax_dom_parser<InputJson> dom_;
  std::vector<std::set<std::string>> keys_;
};

// Printable, short: a token may hold control bytes or run long.
std::string shown(const std::string& text) {
  std::string out;
  for (char c : text) {
    if (out.size() >= 40) return out + "...";
    auto u = static_cast<unsigned char>(c);
    if (u >= 0x20 && u < 0x7f) {
      out += c;
    } else {
      char hex[8];
      std::snprintf(hex, sizeof hex, "\\x%02x", u);
      out += hex;
    }
  }
  return out;
}

}  // namespace

InputJson parse_json_text(const std::string& text, const std::string& source) {
  InputJson result;
  CheckedSax sax(result);
  bool ok = InputJson::sax_parse(text, &sax);
  if (!sax.duplicate.empty())
    input_error(source, ": key \"", shown(sax.duplicate), "\" appears twice in one object");
  if (sax.too_deep)
    input_error(source, ": objects and arrays nested more than ", kMaxJsonDepth,
                " deep (no tridex input needs that)",
                sax.last_key.empty() ? std::string() : " (at key \"" + shown(sax.last_key) + "\")");
  if (!ok || sax.failed) {
    // The position counts the bytes read, the offending one included.
    std::size_t end = std::min(sax.error_position, text.size());
    std::size_t line = 1, column = 1;
    for (std::size_t k = 0; k + 1 < end; ++k) {
      if (text[k] == '\n')
        ++line, column = 1;
      else
        ++column;
    }
    if (sax.error_id == 406)  // number overflow
      input_error(
          source, ":", line, ":", column, ": the number ", shown(sax.error_token),
          " is out of range",
          sax.last_key.empty() ? std::string() : " (after key \"" + shown(sax.last_key) + "\")");
    input_error(source, ":", line, ":", column, ": not valid JSON",
                sax.error_token.empty() ? std::string() : " at '" + shown(sax.error_token) + "'");
  }
  return result;
}

std::string read_text_file(const fs::path& path, const std::string& kind) {
  std::error_code error;
  fs::file_status status = fs::status(path, error);
  if (!fs::exists(status)) input_error(path.string(), ": no such file");
  if (fs::is_directory(status)) input_error(path.string(), ": is a directory, not ", kind);
  if (!fs::is_regular_file(status)) input_error(path.string(), ": is not a regular file");
  std::string text;
  try {
    std::ifstream in(path, std::ios::binary);
    if (!in) input_error(path.string(), ": cannot open the file");
    text.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
    if (in.bad()) input_error(path.string(), ": cannot read the file");
  } catch (const InputError&) {
    throw;
  } catch (const std::exception&) {  // libstdc++'s filebuf throws on a read error
    input_error(path.string(), ": cannot read the file");
  }
  return text;
}

InputJson read_json_file(const fs::path& path) {
  return parse_json_text(read_text_file(path, "a JSON file"), path.string());
}

std::string json_type_name(const InputJson& value) {
  switch (value.type()) {
    case InputJson::value_t::null:
      return "null";
    case InputJson::value_t::object:
      return "an object";
    case InputJson::value_t::array:
      return "an array";
    case InputJson::value_t::string:
      return "a string";
    case InputJson::value_t::boolean:
      return "a boolean";
    case InputJson::value_t::binary:
      return "binary data";
    case InputJson::value_t::discarded:
      return "nothing";
    default:
      return "a number";
  }
}

}  // namespace tridex::cli
