// tridex::gcode — the lexer and expression evaluator: RS274/NGC word syntax (NIST IR 6556 §3.3)
// with its parameters and expressions (§3.5–3.6) as LinuxCNC reads them (o-words: LinuxCNC's
// "O Codes" chapter), Fanuc Macro B's statements (IF/GOTO/WHILE/DO/END, Fanuc 0i-MF operator's
// manual, "Custom Macro"), Fanuc's block delete, '%' delimiters and ISO ':' program numbers.
#include "tridex/gcode/lexer.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <numbers>

#include <fast_float/fast_float.h>

#include "tridex/error.hpp"

namespace tridex::gcode {
namespace {

constexpr double kDegree = std::numbers::pi / 180.0;
// LinuxCNC compares for equality within this (rs274ngc's TOLERANCE_EQUAL), so that a loop
// counter built from decimal steps still meets its bound.
constexpr double kEqualTolerance = 1e-4;
constexpr int kMaxParameter = 999999;  // Fanuc: six digits (#901001 in pallet programs)
constexpr int kMaxDepth = 64;          // nested brackets and parameter references

bool is_space(char c) { return c == ' ' || c == '\t' || c == '\r' || c == '\f' || c == '\v'; }
bool is_digit(char c) { return c >= '0' && c <= '9'; }
bool is_alpha(char c) { return (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z'); }
char upper(char c) { return c >= 'a' && c <= 'z' ? static_cast<char>(c - 'a' + 'A') : c; }

std::string describe(char c) {
  unsigned char u = static_cast<unsigned char>(c);
  char text[32];
  if (u >= 0x21 && u < 0x7f)
    std::snprintf(text, sizeof text, "'%c'", c);
  else
    std::snprintf(text, sizeof text, "byte 0x%02X", u);
  return text;
}

std::string format(double v) {
  char text[48];
  std::snprintf(text, sizeof text, "%.10g", v);
  return text;
}

// Thrown inside the parser, caught by the entry points: where and why.
struct Failure {
  std::size_t at;
  std::string message;
};

enum class Op {
  none,
  power,
  times,
  divide,
  mod,
  plus,
  minus,
  eq,
  ne,
  gt,
  ge,
  lt,
  le,
  and_,
  or_,
  xor_
};

int precedence(Op op) {
  switch (op) {
    case Op::power:
      return 5;
    case Op::times:
    case Op::divide:
    case Op::mod:
      return 4;
    case Op::plus:
    case Op::minus:
      return 3;
    case Op::eq:
    case Op::ne:
    case Op::gt:
    case Op::ge:
    case Op::lt:
    case Op::le:
      return 2;
    case Op::and_:
    case Op::or_:
    case Op::xor_:
      return 1;
    case Op::none:
      return 0;
  }
  return 0;
}

constexpr const char* kFunctions[] = {"ABS", "ACOS", "ASIN", "ATAN",  "COS", "EXISTS", "EXP",
                                      "FIX", "FUP",  "LN",   "ROUND", "SIN", "SQRT",   "TAN"};

class Parser {
 public:
  Parser(std::string_view text, ParameterReader* parameters)
      : text_(text), n_(text.size()), parameters_(parameters) {}

  [[noreturn]] void fail(std::size_t at, std::string message) const {
    throw Failure{std::min(at, n_), std::move(message)};
  }

  void spaces() {
    while (i_ < n_ && is_space(text_[i_])) ++i_;
  }

  // Case-insensitive keyword at the cursor (after spaces); consumed when it matches.
  bool keyword(std::string_view word) {
    spaces();
    if (n_ - i_ < word.size()) return false;
    for (std::size_t k = 0; k < word.size(); ++k)
      if (upper(text_[i_ + k]) != word[k]) return false;
    i_ += word.size();
    return true;
  }

  // An unsigned decimal number at the cursor: digits with at most one point.
  double number() {
    // The common case (a coordinate or code of at most 15 digits) read in one pass: the digits
    // form an integer below 10^15 < 2^53 and the scale a power of ten up to 10^15, both exact in
    // a double, so one division is correctly rounded (Clinger's fast path, which fast_float takes
    // for these too): the same double as fast_float's, bit for bit. Anything else (more digits,
    // two points, no digit, out of range) is read again below with its messages.
    static constexpr double kScale[] = {1e0, 1e1, 1e2,  1e3,  1e4,  1e5,  1e6,  1e7,
                                        1e8, 1e9, 1e10, 1e11, 1e12, 1e13, 1e14, 1e15};
    const std::size_t first = i_;
    std::uint64_t mantissa = 0;
    std::size_t count = 0, fraction = 0, dots = 0;
    for (; i_ < n_; ++i_) {
      const char c = text_[i_];
      if (is_digit(c)) {
        mantissa = mantissa * 10 + static_cast<std::uint64_t>(c - '0');
        ++count;
        fraction += dots;
      } else if (c == '.') {
        ++dots;
      } else {
        break;
      }
    }
    if (count > 0 && count <= 15 && dots <= 1) {
      const double value = static_cast<double>(mantissa) / kScale[fraction];
      if (value <= kMaxWordValue) return value;
    }
    i_ = first;
    return checked_number();
  }

  // number() for what its fast path leaves: fast_float, and the messages of malformed numbers.
  double checked_number() {
    std::size_t start = i_, digits = 0, points = 0;
    while (i_ < n_ && (is_digit(text_[i_]) || text_[i_] == '.')) {
      (text_[i_] == '.' ? points : digits)++;
      ++i_;
    }
    if (digits == 0) fail(start, "expected a number");
    if (points > 1) fail(start, "malformed number");
    double value = 0;
    auto result = fast_float::from_chars(text_.data() + start, text_.data() + i_, value,
                                         fast_float::chars_format::fixed);
    if (result.ptr != text_.data() + i_) fail(start, "malformed number");
    if (result.ec != std::errc() || !std::isfinite(value) || value > kMaxWordValue)
      fail(start, "number out of range (limit 1e9) '" +
                      std::string(text_.substr(start, std::min<std::size_t>(i_ - start, 24))) +
                      "'");
    return value;
  }

  ParameterReader& reader(std::size_t at) {
    if (!parameters_)
      fail(at, describe(text_[at]) + ": parameters and expressions are not supported");
    return *parameters_;
  }

  // After '#': `<name>` or a parameter number (a number, a parameter, a bracketed expression).
  struct Reference {
    int number = -1;
    std::string name;
  };
  Reference reference(std::size_t hash) {
    spaces();
    Reference ref;
    if (i_ < n_ && text_[i_] == '<') {
      std::size_t open = i_++;
      std::string as_written;
      while (i_ < n_ && text_[i_] != '>') {
        if (!is_space(text_[i_])) {
          as_written.push_back(text_[i_]);
          ref.name.push_back(
              static_cast<char>(std::tolower(static_cast<unsigned char>(text_[i_]))));
        }
        ++i_;
      }
      if (i_ == n_) fail(open, "named parameter '<' is not closed by '>'");
      ++i_;
      if (ref.name.empty()) fail(open, "empty parameter name");
      // LinuxCNC reads #<_hal[pin]> from the running HAL (with the INI's [RS274NGC]FEATURES bit
      // HAL_PIN_VARS); rs274 run standalone has none and refuses it, "not defined". The machine
      // file's "variables" may give the value its configuration sets (HALCMD setp / sets).
      if (ref.name.starts_with("_hal[") && !reader(hash).named(ref.name)) {
        const std::size_t close = as_written.find(']');
        const std::string pin =
            as_written.substr(5, close == std::string::npos ? std::string::npos : close - 5);
        fail(hash, "parameter #<" + as_written + "> reads HAL pin " + pin +
                       ", whose value is known only on the running machine (LinuxCNC's rs274 "
                       "run standalone refuses it too): give it in the machine file's "
                       "\"variables\" ({\"#<_hal[" +
                       pin +
                       "]>\": value}, the value the configuration's HALCMD setp or sets gives "
                       "it), or set the value in the program instead");
      }
      return ref;
    }
    Value index = primary(hash);
    double v = index.number;
    if (std::abs(v - std::round(v)) > 1e-6 || v < 0 || v > kMaxParameter)
      fail(hash, "parameter number " + format(v) + " must be an integer in [0, 999999]");
    ref.number = static_cast<int>(std::lround(v));
    return ref;
  }

  Value read(const Reference& ref, std::size_t at) {
    ParameterReader& r = reader(at);
    if (ref.number >= 0) {
      try {
        return r.numbered(ref.number);
      } catch (const tridex::Error& e) {
        fail(at, e.what());
      }
    }
    std::optional<Value> value = r.named(ref.name);
    if (!value) fail(at, "parameter #<" + ref.name + "> is not defined");
    return *value;
  }

  // A sign, then a number, a parameter, a bracketed expression or a function call.
  Value primary(std::size_t context) {
    if (++depth_ > kMaxDepth) fail(i_, "expression nested too deeply");
    spaces();
    if (i_ == n_) fail(context, "expression ends too early");
    Value result;
    char c = text_[i_];
    if (c == '-' || c == '+') {
      ++i_;
      Value v = primary(context);
      result = Value{c == '-' ? -v.number : v.number, false};
    } else if (is_digit(c) || c == '.') {
      result = Value{number(), false};
    } else if (c == '#') {
      std::size_t at = i_++;
      reader(at);
      Reference ref = reference(at);
      result = read(ref, at);
    } else if (c == '[') {
      reader(i_);
      result = bracketed();
    } else if (is_alpha(c)) {
      result = function();
    } else {
      fail(i_, "unexpected " + describe(c) + " in a value");
    }
    --depth_;
    return result;
  }

  Value bracketed() {
    std::size_t open = i_++;
    Value v = expression(open);
    spaces();
    if (i_ == n_ || text_[i_] != ']') fail(open, "'[' is not closed by ']'");
    ++i_;
    return v;
  }

  Value function() {
    std::size_t at = i_;
    std::string name;
    while (i_ < n_ && is_alpha(text_[i_])) name.push_back(upper(text_[i_++]));
    bool known =
        std::find(std::begin(kFunctions), std::end(kFunctions), name) != std::end(kFunctions);
    if (!known) fail(at, "unknown function or word '" + name + "'");
    reader(at);
    spaces();
    if (i_ == n_ || text_[i_] != '[') fail(i_, name + " needs its argument in [ ]");
    if (name == "EXISTS") {
      std::size_t open = i_++;
      spaces();
      if (i_ == n_ || text_[i_] != '#') fail(i_, "EXISTS needs a named parameter #<name>");
      std::size_t hash = i_++;
      Reference ref = reference(hash);
      spaces();
      if (i_ == n_ || text_[i_] != ']') fail(open, "'[' is not closed by ']'");
      ++i_;
      if (ref.number >= 0) fail(hash, "EXISTS needs a named parameter #<name>");
      return Value{parameters_->named(ref.name) ? 1.0 : 0.0, false};
    }
    double x = bracketed().number;
    double y = 0;
    if (name == "ATAN") {  // ATAN[y]/[x] (both dialects) or ATAN[y,x] is not RS274; keep to /[x]
      spaces();
      if (i_ < n_ && text_[i_] == '/') {
        ++i_;
        spaces();
        if (i_ == n_ || text_[i_] != '[') fail(i_, "ATAN[y]/[x] needs [x]");
        double xx = bracketed().number;
        return Value{std::atan2(x, xx) / kDegree, false};
      }
      return Value{std::atan(x) / kDegree, false};
    }
    double r = 0;
    if (name == "ABS")
      r = std::abs(x);
    else if (name == "ACOS" || name == "ASIN") {
      if (x < -1 || x > 1) fail(at, name + " of " + format(x) + " (outside [-1, 1])");
      r = (name == "ACOS" ? std::acos(x) : std::asin(x)) / kDegree;
    } else if (name == "COS")
      r = std::cos(x * kDegree);
    else if (name == "SIN")
      r = std::sin(x * kDegree);
    else if (name == "TAN")
      r = std::tan(x * kDegree);
    else if (name == "EXP")
      r = std::exp(x);
    else if (name == "LN") {
      if (!(x > 0)) fail(at, "LN of " + format(x) + " (must be positive)");
      r = std::log(x);
    } else if (name == "SQRT") {
      if (x < 0) fail(at, "SQRT of " + format(x) + " (negative)");
      r = std::sqrt(x);
    } else if (name == "ROUND")
      r = std::round(x);
    // Fanuc rounds FIX toward zero and FUP away from it; LinuxCNC floors and ceils.
    else if (name == "FIX")
      r = parameters_->vacant_words_omitted() ? std::trunc(x) : std::floor(x);
    else if (name == "FUP")
      r = parameters_->vacant_words_omitted() ? (x < 0 ? std::floor(x) : std::ceil(x))
                                              : std::ceil(x);
    (void)y;
    if (!std::isfinite(r)) fail(at, name + " of " + format(x) + " is out of range");
    return Value{r, false};
  }

  Op binary_operator() {
    spaces();
    if (i_ == n_) return Op::none;
    char c = text_[i_];
    auto take = [&](std::size_t length, Op op) {
      i_ += length;
      return op;
    };
    if (c == '*')
      return i_ + 1 < n_ && text_[i_ + 1] == '*' ? take(2, Op::power) : take(1, Op::times);
    if (c == '/') return take(1, Op::divide);
    if (c == '+') return take(1, Op::plus);
    if (c == '-') return take(1, Op::minus);
    static constexpr std::pair<std::string_view, Op> kWords[] = {
        {"MOD", Op::mod}, {"EQ", Op::eq}, {"NE", Op::ne},    {"GT", Op::gt},    {"GE", Op::ge},
        {"LT", Op::lt},   {"LE", Op::le}, {"AND", Op::and_}, {"XOR", Op::xor_}, {"OR", Op::or_}};
    for (const auto& [word, op] : kWords)
      if (keyword(word)) return op;
    return Op::none;
  }

  Value apply(Op op, Value a, Value b, std::size_t at) {
    double x = a.number, y = b.number;
    switch (op) {
      case Op::power:
        if (x < 0 && y != std::floor(y))
          fail(at, "negative " + format(x) + " raised to a fraction");
        return finite(std::pow(x, y), at);
      case Op::times:
        return finite(x * y, at);
      case Op::divide:
        if (y == 0) fail(at, "division by zero");
        return finite(x / y, at);
      case Op::mod: {
        if (y == 0) fail(at, "MOD by zero");
        double r = std::fmod(x, y);
        if (r < 0) r += std::abs(y);  // rs274ngc's rule: the result is not negative
        return Value{r, false};
      }
      case Op::plus:
        return finite(x + y, at);
      case Op::minus:
        return finite(x - y, at);
      case Op::eq:
      case Op::ne: {
        // Fanuc: vacant equals only vacant (#1 EQ 0 is false for an unset #1). LinuxCNC has no
        // vacant value: an unset numbered parameter is 0 and compares as 0.
        const bool by_vacancy = (a.vacant || b.vacant) && parameters_->vacant_words_omitted();
        bool equal = by_vacancy ? a.vacant == b.vacant : std::abs(x - y) < kEqualTolerance;
        return Value{(op == Op::eq) == equal ? 1.0 : 0.0, false};
      }
      case Op::gt:
        return Value{x > y ? 1.0 : 0.0, false};
      case Op::ge:
        return Value{x >= y ? 1.0 : 0.0, false};
      case Op::lt:
        return Value{x < y ? 1.0 : 0.0, false};
      case Op::le:
        return Value{x <= y ? 1.0 : 0.0, false};
      case Op::and_:
        return Value{(x != 0 && y != 0) ? 1.0 : 0.0, false};
      case Op::or_:
        return Value{(x != 0 || y != 0) ? 1.0 : 0.0, false};
      case Op::xor_:
        return Value{((x != 0) != (y != 0)) ? 1.0 : 0.0, false};
      case Op::none:
        break;
    }
    return a;
  }

  Value finite(double v, std::size_t at) const {
    if (!std::isfinite(v) || std::abs(v) > 1e300) fail(at, "arithmetic overflow");
    return Value{v, false};
  }

  // Operator-precedence parsing of `primary (op primary)*`, on fixed stacks (no allocation per
  // expression: left-associative operators reduce at once, so only a chain of ** or of rising
  // precedence deepens them).
  Value expression(std::size_t context) {
    constexpr std::size_t kStack = 32;
    std::array<Value, kStack + 1> values;
    std::array<std::pair<Op, std::size_t>, kStack> ops;
    std::size_t nv = 0, no = 0;
    values[nv++] = primary(context);
    auto reduce = [&] {
      auto [op, at] = ops[--no];
      Value b = values[--nv];
      values[nv - 1] = apply(op, values[nv - 1], b, at);
    };
    for (;;) {
      std::size_t save = i_;
      spaces();
      std::size_t at = i_;
      Op op = binary_operator();
      if (op == Op::none) {
        i_ = save;
        break;
      }
      // ** is right-associative; the others associate to the left.
      while (no > 0 && (precedence(ops[no - 1].first) > precedence(op) ||
                        (precedence(ops[no - 1].first) == precedence(op) && op != Op::power)))
        reduce();
      if (no == kStack) fail(at, "expression too deeply chained");
      ops[no++] = {op, at};
      values[nv++] = primary(at);
    }
    while (no > 0) reduce();
    return values[0];
  }

  std::string_view text_;
  std::size_t n_;
  std::size_t i_ = 0;
  int depth_ = 0;
  ParameterReader* parameters_;
};

class LineLexer : public Parser {
 public:
  LineLexer(std::string_view text, Block& block, ParameterReader* parameters)
      : Parser(text, parameters), block_(block) {}

  void run() {
    bool first = true;  // nothing but spaces, a block delete and an N number seen yet
    while (i_ < n_) {
      char c = text_[i_];
      if (is_space(c)) {
        ++i_;
        continue;
      }
      if (c == '(') {
        std::size_t open = i_;
        while (i_ < n_ && text_[i_] != ')') ++i_;
        if (i_ == n_) fail(open, "comment '(' is not closed on this line");
        ++i_;
        continue;
      }
      if (c == ';') break;
      if (c == '/') {
        if (!first || block_.block_delete || !block_.words.empty())
          fail(i_, "'/' (block delete) is only allowed at the start of a block");
        block_.block_delete = true;
        ++i_;
        continue;
      }
      if (c == '%') {
        if (!first || !block_.words.empty()) fail(i_, "'%' must be alone on its line");
        std::size_t j = i_ + 1;
        while (j < n_ && is_space(text_[j])) ++j;
        if (j < n_ && text_[j] != '(' && text_[j] != ';') fail(j, "'%' must be alone on its line");
        block_.percent = true;
        return;  // anything after it is a comment
      }
      if (c == ':' && first && block_.words.empty()) {  // Fanuc ISO program number
        std::size_t at = i_++;
        spaces();
        block_.words.push_back(Word{'O', number(), static_cast<int>(at) + 1});
        first = false;
        continue;
      }
      if (c == '#') {
        assignment();
        first = false;
        continue;
      }
      if (c == '@' || c == '^') {  // LinuxCNC's polar radius and angle (the interpreter checks)
        std::size_t start = i_++;
        word(c, start);
        first = false;
        continue;
      }
      if (c == '<' && first && block_.words.empty() && program_name()) continue;
      if (!is_alpha(c)) {
        if (c == '[' || c == ']' || c == '=')
          fail(i_, describe(c) + (parameters_ ? " where a word was expected"
                                              : ": parameters and expressions are not supported"));
        fail(i_, "unexpected " + describe(c));
      }
      std::size_t start = i_;
      char letter = upper(c);
      bool sequence_only = block_.words.size() == 1 && block_.words[0].letter == 'N';
      if (letter == 'O' && first && block_.words.empty() && program_name()) continue;
      if (i_ + 1 < n_ && is_alpha(text_[i_ + 1])) {  // a keyword: no word has a letter after it
        if ((first || sequence_only) && statement()) return;
        fail(start, "unexpected " + describe(c) + describe(text_[i_ + 1]) +
                        " (a word is a letter and a number)");
      }
      if (letter == 'O' && (first || sequence_only) && o_word()) return;
      ++i_;
      word(letter, start);
      first = false;
    }
  }

 private:
  void word(char letter, std::size_t start) {
    spaces();
    bool expression = i_ < n_ && (text_[i_] == '#' || text_[i_] == '[' || is_alpha(text_[i_]));
    bool sign_then_expression = false;
    if (!expression && i_ < n_ && (text_[i_] == '-' || text_[i_] == '+')) {
      std::size_t j = i_ + 1;
      while (j < n_ && is_space(text_[j])) ++j;
      sign_then_expression = j < n_ && (text_[j] == '#' || text_[j] == '[' || is_alpha(text_[j]));
    }
    Value v;
    if (expression || sign_then_expression) {
      if (!parameters_)
        fail(i_, std::string("word ") + letter + ": parameters and expressions are not supported");
      v = primary(start);
      if (v.vacant) {
        if (parameters_->vacant_words_omitted()) {  // Fanuc: as if not written
          std::string written(1, letter);
          for (std::size_t k = start + 1; k < i_; ++k)
            if (!is_space(text_[k])) written.push_back(text_[k]);
          block_.vacant_words.push_back(std::move(written));
          return;
        }
        v = Value{0, false};
      }
    } else {
      bool negative = false;
      if (i_ < n_ && (text_[i_] == '+' || text_[i_] == '-')) {
        negative = text_[i_] == '-';
        ++i_;
        spaces();
      }
      if (i_ == n_ || !(is_digit(text_[i_]) || text_[i_] == '.'))
        fail(start, std::string("word ") + letter + " has no number");
      std::size_t at = i_;
      try {
        v.number = number();
      } catch (Failure& f) {
        f.message = std::string("word ") + letter + ": " + f.message;
        f.at = at;
        throw;
      }
      if (negative) v.number = -v.number;
    }
    if (!std::isfinite(v.number) || std::abs(v.number) > kMaxWordValue)
      fail(start, std::string("word ") + letter + ": value " + format(v.number) +
                      " out of range (limit 1e9)");
    block_.words.push_back(Word{letter, v.number, static_cast<int>(start) + 1});
  }

  void assignment() {
    std::size_t hash = i_++;
    reader(hash);
    Reference ref = reference(hash);
    spaces();
    if (i_ == n_ || text_[i_] != '=') fail(i_, "expected '=' after the parameter");
    ++i_;
    Value v = expression(hash);
    block_.assignments.push_back(
        Assignment{ref.number, std::move(ref.name), v, static_cast<int>(hash) + 1});
  }

  long long integer_value(std::size_t at, const char* what) {
    double v = primary(at).number;
    if (std::abs(v - std::round(v)) > 1e-6 || v < 0 || v > kMaxWordValue)
      fail(at, std::string(what) + " " + format(v) + " must be a non-negative integer");
    return std::llround(v);
  }

  // Fanuc Macro B statements; false when the letters are none of them.
  bool statement() {
    std::size_t at = i_;
    Control& control = block_.control;
    control.column = static_cast<int>(at) + 1;
    if (keyword("IF")) {
      reader(at);
      spaces();
      if (i_ == n_ || text_[i_] != '[') fail(i_, "IF needs a condition in [ ]");
      bool condition = bracketed().number != 0;
      std::size_t then_at = (spaces(), i_);
      if (keyword("GOTO")) {
        if (condition) {
          control.kind = ControlKind::jump;
          control.number = integer_value(then_at, "GOTO target");
        }
        i_ = n_;  // a false condition leaves the target unevaluated
        return true;
      }
      if (keyword("THEN")) {
        if (!condition) i_ = n_;
        run();
        return true;
      }
      fail(then_at, "IF [...] needs GOTO n or THEN");
    }
    if (keyword("GOTO")) {
      reader(at);
      control.kind = ControlKind::jump;
      control.number = integer_value(at, "GOTO target");
      finish();
      return true;
    }
    if (keyword("WHILE")) {
      reader(at);
      spaces();
      if (i_ == n_ || text_[i_] != '[') fail(i_, "WHILE needs a condition in [ ]");
      control.condition = bracketed().number != 0;
      std::size_t do_at = (spaces(), i_);
      if (!keyword("DO")) fail(do_at, "WHILE [...] needs DO m");
      control.kind = ControlKind::while_loop;
      control.number = integer_value(do_at, "DO number");
      finish();
      return true;
    }
    if (keyword("DO")) {
      control.kind = ControlKind::while_loop;
      control.condition = true;
      control.number = integer_value(at, "DO number");
      finish();
      return true;
    }
    if (keyword("END")) {
      control.kind = ControlKind::end_loop;
      control.number = integer_value(at, "END number");
      finish();
      return true;
    }
    // External output (Fanuc 0i-MF operator's manual, "External output commands"; Haas the same
    // on its serial port or a file): POPEN, DPRNT[...] or BPRNT[...], PCLOS. It sends text and
    // values to a device and moves nothing, so it is read and does nothing. DPRNT's text (letters,
    // digits, '*' for a space, #n[ab] for a value of a integer and b decimal digits) is not an
    // expression: only its brackets are checked.
    if (keyword("POPEN") || keyword("PCLOS")) {
      finish();
      return true;
    }
    if (keyword("DPRNT") || keyword("BPRNT")) {
      spaces();
      if (i_ == n_ || text_[i_] != '[') fail(i_, "DPRNT and BPRNT need their text in [ ]");
      const std::size_t open = i_;
      int depth = 0;
      do {
        depth += text_[i_] == '[' ? 1 : text_[i_] == ']' ? -1 : 0;
        ++i_;
      } while (i_ < n_ && depth > 0);
      if (depth > 0) fail(open, "'[' of the output text is not closed on this line");
      finish();
      return true;
    }
    return false;
  }

  // Only comments may follow a statement.
  void finish() {
    spaces();
    while (i_ < n_) {
      if (text_[i_] == '(') {
        while (i_ < n_ && text_[i_] != ')') ++i_;
        if (i_ == n_) fail(i_, "comment '(' is not closed on this line");
        ++i_;
      } else if (text_[i_] == ';') {
        return;
      } else if (!is_space(text_[i_])) {
        fail(i_, "unexpected " + describe(text_[i_]) + " after the statement");
      } else {
        ++i_;
      }
    }
  }

  // LinuxCNC's o-word keywords.
  static constexpr std::pair<std::string_view, OKeyword> kOKeywords[] = {
      {"ENDSUB", OKeyword::endsub},
      {"SUB", OKeyword::sub},
      {"CALL", OKeyword::call},
      {"ELSEIF", OKeyword::elseif},
      {"ELSE", OKeyword::else_},
      {"ENDIF", OKeyword::endif},
      {"IF", OKeyword::if_},
      {"ENDWHILE", OKeyword::endwhile},
      {"WHILE", OKeyword::while_},
      {"DO", OKeyword::do_},
      {"ENDREPEAT", OKeyword::endrepeat},
      {"REPEAT", OKeyword::repeat},
      {"BREAK", OKeyword::break_},
      {"CONTINUE", OKeyword::continue_},
      {"RETURN", OKeyword::return_}};

  // A program name that is not a number, alone on its line but for comments: `O7997A`,
  // `OCIRCLE` (letters and digits after O, at least one letter: no o-word or O number reads so)
  // or Fanuc's `<NAME>` (FANUC Series 30i/0i-F program names, which stand where the O number
  // did). False, reading nothing, for anything else.
  bool program_name() {
    const bool bracket = text_[i_] == '<';
    std::size_t j = i_ + 1;
    bool letter = bracket;
    if (bracket) {
      while (j < n_ && text_[j] != '>' && text_[j] != '(' && text_[j] != ';') ++j;
      if (j == n_ || text_[j] != '>' || j == i_ + 1) return false;
      ++j;
    } else {
      while (j < n_ && (is_alpha(text_[j]) || is_digit(text_[j]) || text_[j] == '_')) {
        letter |= !is_digit(text_[j]);
        ++j;
      }
    }
    std::size_t end = j;
    while (j < n_ && is_space(text_[j])) ++j;
    if (!letter || (j < n_ && text_[j] != '(' && text_[j] != ';')) return false;
    if (!bracket) {  // `o100sub`: LinuxCNC's o-word written without its space
      std::size_t k = i_ + 1;
      while (k < end && is_digit(text_[k])) ++k;
      std::string letters;
      for (std::size_t m = k; m < end; ++m) letters.push_back(upper(text_[m]));
      for (const auto& keyword : kOKeywords)
        if (k > i_ + 1 && letters == keyword.first) return false;
    }
    block_.program_name.assign(text_.substr(i_, end - i_));
    if (!bracket) block_.program_name[0] = 'O';
    block_.program_name_column = static_cast<int>(i_) + 1;
    i_ = j;
    return true;
  }

  // LinuxCNC `o<label> keyword …`; false for a Fanuc `O1234` program number.
  bool o_word() {
    std::size_t at = i_;
    std::size_t j = i_ + 1;
    while (j < n_ && is_space(text_[j])) ++j;
    std::string label;
    if (j < n_ && text_[j] == '<') {
      std::size_t open = j++;
      while (j < n_ && text_[j] != '>') {
        if (!is_space(text_[j]))
          label.push_back(static_cast<char>(std::tolower(static_cast<unsigned char>(text_[j]))));
        ++j;
      }
      if (j == n_) fail(open, "o-word name '<' is not closed by '>'");
      ++j;
    } else {
      std::size_t digits = j;
      while (j < n_ && is_digit(text_[j])) ++j;
      if (j == digits) return false;
      std::size_t first_digit = digits;
      while (first_digit + 1 < j && text_[first_digit] == '0') ++first_digit;
      label.assign(text_.substr(first_digit, j - first_digit));
    }
    while (j < n_ && is_space(text_[j])) ++j;
    if (j == n_ || !is_alpha(text_[j])) {
      if (text_[at + 1] == '<' || (j < n_ && text_[j] == '<'))
        fail(at, "o-word o<" + label + "> needs a keyword (sub, call, if, while, …)");
      return false;
    }
    // The keyword is the whole run of letters: `callsub` is not `call` followed by junk.
    std::size_t end = j;
    while (end < n_ && is_alpha(text_[end])) ++end;
    std::string_view name = text_.substr(j, end - j);
    i_ = j;
    for (const auto& [word, kw] : kOKeywords) {
      if (name.size() == word.size() && keyword(word)) {
        if (!parameters_) fail(at, "o-words are not supported here");
        Control& control = block_.control;
        control.kind = ControlKind::o_word;
        control.column = static_cast<int>(at) + 1;
        control.label = std::move(label);
        control.keyword = kw;
        control.arguments = text_.substr(i_);
        control.arguments_column = static_cast<int>(i_) + 1;
        i_ = n_;
        return true;
      }
    }
    fail(j, "unknown o-word keyword '" + std::string(name) +
                "' (LinuxCNC's are sub, endsub, call, return, if, elseif, else, endif, while, "
                "endwhile, "
                "do, repeat, endrepeat, break, continue)");
  }

  Block& block_;
};

}  // namespace

const char* to_string(OKeyword keyword) {
  switch (keyword) {
    case OKeyword::sub:
      return "sub";
    case OKeyword::endsub:
      return "endsub";
    case OKeyword::call:
      return "call";
    case OKeyword::if_:
      return "if";
    case OKeyword::elseif:
      return "elseif";
    case OKeyword::else_:
      return "else";
    case OKeyword::endif:
      return "endif";
    case OKeyword::while_:
      return "while";
    case OKeyword::endwhile:
      return "endwhile";
    case OKeyword::do_:
      return "do";
    case OKeyword::repeat:
      return "repeat";
    case OKeyword::endrepeat:
      return "endrepeat";
    case OKeyword::break_:
      return "break";
    case OKeyword::continue_:
      return "continue";
    case OKeyword::return_:
      return "return";
  }
  return "?";
}

bool lex_line(std::string_view line, Block& block, LexError& error, ParameterReader* parameters) {
  block.clear();
  try {
    LineLexer(line, block, parameters).run();
    return true;
  } catch (const Failure& f) {
    error.column = static_cast<int>(f.at) + 1;
    error.message = f.message;
    return false;
  }
}

bool evaluate_arguments(std::string_view text, int column, ParameterReader& parameters,
                        std::vector<Value>& values, LexError& error) {
  values.clear();
  Parser parser(text, &parameters);
  try {
    for (;;) {
      parser.spaces();
      if (parser.i_ == parser.n_ || text[parser.i_] == ';') break;
      char c = text[parser.i_];
      if (c == '(') {
        while (parser.i_ < parser.n_ && text[parser.i_] != ')') ++parser.i_;
        if (parser.i_ == parser.n_)
          parser.fail(parser.i_, "comment '(' is not closed on this line");
        ++parser.i_;
        continue;
      }
      if (c != '[') parser.fail(parser.i_, "expected an argument in [ ], found " + describe(c));
      values.push_back(parser.bracketed());
    }
    return true;
  } catch (const Failure& f) {
    error.column = column + static_cast<int>(f.at);
    error.message = f.message;
    return false;
  }
}

void skim_line(std::string_view line, Skim& skim) {
  skim = Skim{};
  std::size_t i = 0, n = line.size();
  auto spaces = [&] {
    while (i < n && is_space(line[i])) ++i;
  };
  auto match = [&](std::string_view word) {
    spaces();
    if (n - i < word.size()) return false;
    for (std::size_t k = 0; k < word.size(); ++k)
      if (upper(line[i + k]) != word[k]) return false;
    i += word.size();
    return true;
  };
  auto integer = [&]() -> long long {
    spaces();
    long long v = 0;
    std::size_t digits = 0;
    while (i < n && is_digit(line[i]) && digits < 12) {
      v = v * 10 + (line[i++] - '0');
      ++digits;
    }
    return digits ? v : -1;
  };
  spaces();
  if (i < n && line[i] == '/') ++i;
  spaces();
  if (i < n && upper(line[i]) == 'N' && !(i + 1 < n && is_alpha(line[i + 1]))) {
    ++i;
    skim.sequence = integer();
  }
  if (match("WHILE")) {
    // WHILE [..] DO m: the loop number is after DO, outside the brackets.
    int depth = 0;
    while (i < n) {
      if (line[i] == '[') ++depth;
      if (line[i] == ']') --depth;
      ++i;
      if (depth == 0) break;
    }
    if (match("DO")) {
      skim.kind = ControlKind::while_loop;
      skim.number = integer();
    }
    return;
  }
  if (match("DO")) {
    skim.kind = ControlKind::while_loop;
    skim.number = integer();
    return;
  }
  if (match("END")) {
    skim.kind = ControlKind::end_loop;
    skim.number = integer();
    return;
  }
  if (i < n && upper(line[i]) == 'O') {
    Block block;
    LexError error;
    // The o-word part of the lexer reads the label and keyword without evaluating anything.
    struct NoParameters : ParameterReader {
      Value numbered(int) override { return Value{}; }
      std::optional<Value> named(std::string_view) override { return std::nullopt; }
      bool vacant_words_omitted() const override { return true; }
    } none;
    std::size_t end = line.find_first_of("([;", i);
    std::string_view head = line.substr(i, end == std::string_view::npos ? n - i : end - i);
    if (lex_line(head, block, error, &none) && block.control.kind == ControlKind::o_word) {
      skim.kind = ControlKind::o_word;
      skim.label = std::move(block.control.label);
      skim.keyword = block.control.keyword;
    }
  }
}

}  // namespace tridex::gcode
