// tridex::gcode — parameters: Fanuc Macro B variables (locals #1–#33 per macro call, commons
// #100–#199 and #500–#999, #0 vacant) and LinuxCNC's (#1–#30 per o-word call, #31–#5000
// global, #<name> local to a call, #<_name> global), with the system variables that posts and
// probing macros read: modal state (Fanuc #4001–#4120), positions (Fanuc #5001–#5043, LinuxCNC
// #5420–#5428, #<_x> …) and work offsets (#5221 + 20·(n−1) for G54…G59 in both dialects,
// Fanuc #7001 + 20·(p−1) for G54.1 Pp up to P48, #14001 + 20·(p−1) up to P300) and tool offsets
// (below). Sources: Fanuc 0i-MF operator's manual, "Custom macro: system variables"; Haas's mill
// operator's manual, "Macros: system variables"; LinuxCNC's "Numbered parameters" and "Predefined
// named parameters".
#include <cmath>
#include <optional>
#include <string>
#include <utility>

#include "state.hpp"

namespace tridex::gcode {
namespace {

// Work-offset key (MachineConfig numbering) and axis of a work-offset system variable, or -1.
int offset_variable(int n, int& axis) {
  if (n >= 5221 && n < 5221 + 6 * 20) {
    int k = (n - 5221) / 20, a = (n - 5221) % 20;
    if (a < 3) {
      axis = a;
      return k + 1;
    }
  }
  // G54.1 P1–P48 at #7001 (up to #7960), and P1–P300 at #14001: #10001–#13999 are tool offsets.
  for (auto [first, count] : {std::pair{7001, 48}, std::pair{14001, 300}}) {
    if (n < first || n >= first + count * 20) continue;
    int k = (n - first) / 20, a = (n - first) % 20;
    if (a < 3) {
      axis = a;
      return MachineConfig::g54_1_key(k + 1);
    }
  }
  return -1;
}

Value number(double v) { return Value{v, false}; }

// A tool offset register named by a system variable: Fanuc's tool compensation memory C (#10001…
// H wear, #11001… H geometry, #12001… D wear, #13001… D geometry, 999 each, and for offsets 1–200
// #2001… H wear, #2201… H geometry) or Haas's (#2001… H geometry, #2201… H wear, #2401… D
// geometry, #2601… D wear, 200 each; Haas's #10000s are general-purpose variables). The two
// controls swap #2001 and #2201: the machine's dialect says which.
struct OffsetRegister {
  int number;   // the H or D offset
  bool length;  // H (else D)
  bool wear;    // wear (else geometry)
};

std::optional<OffsetRegister> offset_register(int n, Dialect dialect) {
  if (dialect == Dialect::linuxcnc) return std::nullopt;
  if (dialect == Dialect::haas) {
    if (n < 2001 || n > 2800) return std::nullopt;
    const int bank = (n - 2001) / 200;  // H geometry, H wear, D geometry, D wear
    return OffsetRegister{(n - 2001) % 200 + 1, bank < 2, bank % 2 == 1};
  }
  if (n >= 2001 && n <= 2400) return OffsetRegister{(n - 2001) % 200 + 1, true, n <= 2200};
  if (n >= 10001 && n <= 13999 && n % 1000 != 0) {
    const int bank = n / 1000 - 10;  // H wear, H geometry, D wear, D geometry
    return OffsetRegister{n % 1000, bank < 2, bank % 2 == 0};
  }
  return std::nullopt;
}

}  // namespace

Value Interpreter::State::numbered(int n) {
  if (n == 0) return Value{0, true};
  if (n <= 33) return parameters.scopes.back().locals[static_cast<std::size_t>(n)];
  Vec3 program = to_program(tool.pos);  // the end of the last block: the tip is there
  switch (n) {
    // Fanuc modal information of the block before (#4001 + group − 1).
    case 4001:  // group 01: under a cycle (group 09 there), the mode G80 returns to
      if (machine.dialect != Dialect::linuxcnc && is_cycle(modal.motion))
        return number(modal.group01 < 0 ? 0 : modal.group01 / 10.0);
      return number(modal.motion < 0 ? 0 : modal.motion / 10.0);
    case 4002:
      return number(modal.plane / 10.0);
    case 4003:
      return number(modal.incremental ? 91 : 90);
    case 4005:
      return number(modal.feed_mode == FeedMode::inverse_time ? 93
                    : modal.feed_mode == FeedMode::per_minute ? 94
                                                              : 95);
    case 4006:
      return number(modal.unit == 1.0 ? 21 : 20);
    case 4007:
      return number(comp.side == 0 ? 40 : comp.side > 0 ? 41 : 42);
    case 4008:
      return number(49);
    case 4009:
      return number(is_cycle(modal.motion) ? modal.motion / 10.0 : 80);
    case 4010:
      return number(modal.retract_to_r ? 99 : 98);
    case 4014:
      return number(frame.work_key >= 100 ? 54.1 : 53 + frame.work_key);
    case 4109:
      return number(programmed_feed());
    case 4119:
      return number(modal.speed);
    case 4120:
      return number(tool.number);
    case 5001:
    case 5002:
    case 5003:
      return number(program[n - 5001] / modal.unit);
    case 5041:
    case 5042:
    case 5043:
      return number(program[n - 5041] / modal.unit);
    case 5021:
    case 5022:
    case 5023:
      return number(tool.pos[n - 5021] / modal.unit);
    // LinuxCNC: the active coordinate system (1 = G54), the tool, the current position.
    case 5220:
      return number(frame.work_key >= 100 ? 0 : frame.work_key);
    case 5400:
      return number(tool.number);
    // The loaded tool's diameter as LinuxCNC's tool table holds it (rs274ngc_pre.cc,
    // set_tool_parameters: parameters[5410] = tool_table[0].diameter): in the table's units, the
    // machine's (inches for rs274 run standalone), not the program's; 0 with no tool or one the
    // table lacks. ngcgui's subroutines size their entry moves from it (#<tooldiam> = #5410).
    case 5410:
      if (machine.dialect != Dialect::linuxcnc) break;
      if (auto d = machine.tool_diameters.find(tool.number); d != machine.tool_diameters.end())
        return number(d->second / (machine.tool_table_in_inches ? 25.4 : 1.0));
      return number(0);
    case 5420:
    case 5421:
    case 5422:
      return number(program[n - 5420] / modal.unit);
    case 5423:
    case 5424:
    case 5425:
      return number(0);
    case 5426:
    case 5427:
    case 5428:
      return number(tool.uvw_position[n - 5426] / modal.unit);
    default:
      break;
  }
  int component = 0;
  if (int key = offset_variable(n, component); key >= 0) {
    auto it = frame.offsets.find(key);
    return number(it == frame.offsets.end() ? 0.0 : it->second[component] / modal.unit);
  }
  if (auto r = offset_register(n, machine.dialect)) {
    // H: what G43 reads (a geometry never set is the machine's length of that tool). D: what the
    // program wrote, else the tool table's radius or diameter, as the machine's D registers hold.
    if (r->length)
      return number((r->wear ? wear_of(r->number) : length_geometry(r->number).value_or(0.0)) /
                    modal.unit);
    const std::map<int, double>& written = r->wear ? comp.d_wear : comp.d_geometry;
    if (auto it = written.find(r->number); it != written.end())
      return number(it->second / modal.unit);
    if (r->wear) return number(0);
    const std::optional<double> scale = d_register_scale();
    if (!scale)
      detail::fail("#", n, " (D", r->number,
                   "'s geometry) holds a diameter or a radius after Haas's setting 40: ",
                   "say which with \"d_offsets\" in the machine file, or set it in the program "
                   "before reading it");
    auto diameter = machine.tool_diameters.find(r->number);
    return number(diameter == machine.tool_diameters.end()
                      ? 0.0
                      : diameter->second / 2 / *scale / modal.unit);
  }
  auto it = parameters.globals.find(n);
  if (it != parameters.globals.end()) return it->second;
  // Unset: Fanuc's vacant; LinuxCNC's parameters start at 0 (the word rule tells them apart).
  return Value{0, true};
}

std::optional<Value> Interpreter::State::named(std::string_view name) {
  std::string key(name);
  if (!key.empty() && key[0] == '_') {
    Vec3 program = to_program(tool.pos);
    if (key == "_x" || key == "_y" || key == "_z")
      return number(program[key[1] - 'x'] / modal.unit);
    if (key == "_u" || key == "_v" || key == "_w")
      return number(tool.uvw_position[key[1] - 'u'] / modal.unit);
    if (key == "_current_tool") return number(tool.number);
    if (key == "_selected_tool") return number(tool.selected);
    if (key == "_metric") return number(modal.unit == 1.0 ? 1 : 0);
    if (key == "_imperial") return number(modal.unit == 1.0 ? 0 : 1);
    if (key == "_absolute") return number(modal.incremental ? 0 : 1);
    if (key == "_incremental") return number(modal.incremental ? 1 : 0);
    if (key == "_feed") return number(programmed_feed());
    if (key == "_inverse_time") return number(modal.feed_mode == FeedMode::inverse_time ? 1 : 0);
    if (key == "_units_per_minute") return number(modal.feed_mode == FeedMode::per_minute ? 1 : 0);
    if (key == "_units_per_rev") return number(modal.feed_mode == FeedMode::per_revolution ? 1 : 0);
    if (key == "_rpm") return number(modal.speed);
    if (key == "_motion_mode") return number(modal.motion < 0 ? 0 : modal.motion);
    if (key == "_plane") return number(modal.plane);
    if (key == "_coord_system")
      return number(frame.work_key >= 100 ? 0 : kG53 + 10 * frame.work_key);
    if (key == "_call_level") return number(static_cast<double>(parameters.scopes.size() - 1));
    if (key == "_line") return number(context.line);
    if (key == "_ccomp") return number(comp.side == 0 ? kG40 : comp.side > 0 ? kG41 : kG42);
    if (key == "_spindle_on") return number(modal.spindle_direction != 0 ? 1 : 0);
    if (key == "_spindle_cw") return number(modal.spindle_direction > 0 ? 1 : 0);
    if (key == "_ijk_absolute_mode") return number(modal.arc_absolute ? 1 : 0);
    // As LinuxCNC 2.9's interpreter run outside its task (a preview, rs274 standalone) reads
    // them: no remap under way, overrides at 100 %, a mill.
    if (key == "_task" || key == "_remap_level" || key == "_lathe_diameter_mode") return number(0);
    if (key == "_speed_override" || key == "_feed_override") return number(1);
    if (key == "_vmajor") return number(2.9);
    if (key == "_vminor") return number(0);
    auto it = parameters.named_globals.find(key);
    if (it == parameters.named_globals.end()) return std::nullopt;
    return it->second;
  }
  auto& locals = parameters.scopes.back().named;
  auto it = locals.find(key);
  if (it == locals.end()) return std::nullopt;
  return it->second;
}

void Interpreter::State::assign(const Assignment& a) {
  if (a.number < 0) {
    if (!a.name.empty() && a.name[0] == '_')
      parameters.named_globals[a.name] = a.value;
    else
      parameters.scopes.back().named[a.name] = a.value;
    return;
  }
  int n = a.number;
  if (n == 0) error(a.column, "#0 is the vacant value and cannot be set");
  if (n <= 33) {
    parameters.scopes.back().locals[static_cast<std::size_t>(n)] = a.value;
    return;
  }
  if (n == 3000)  // Fanuc's alarm: the program stops with this number
    error(a.column, "the program raises alarm #3000 = " + format_number(a.value.number));
  if (n == 3006) {  // a stop with a message for the operator
    warn(a.column,
         "#3006 = " + format_number(a.value.number) + ": the program stops for the operator here");
    return;
  }
  // An offset moves the tool as a word does, and is held to a word's range.
  auto offset_value = [&] {
    const double value = a.value.vacant ? 0.0 : a.value.number;
    if (!std::isfinite(value) || std::abs(value) > kMaxWordValue)
      error(a.column,
            "#" + std::to_string(n) + " = " + format_number(value) + ": out of range (limit 1e9)");
    return value;
  };
  int component = 0;
  if (int key = offset_variable(n, component);
      key >= 0) {  // probing macros set work offsets this way
    if (frame.tilted && key == frame.work_key)
      error(a.column, "the active work offset changes under a tilted plane");
    Vec3 value = frame.offsets.count(key) ? frame.offsets[key] : Vec3(0.0);
    value[component] = offset_value() * modal.unit;
    frame.offsets[key] = value;
    if (key == frame.work_key) {
      frame.work_offset = value;
      update_frame();
    }
    return;
  }
  if (auto r = offset_register(n, machine.dialect)) {  // tool setting and probing macros
    const double value = offset_value();
    if (r->length) {
      (r->wear ? tool_table.wear : tool_table.lengths)[r->number] = value * modal.unit;
    } else {  // read back as written, and by a G41/G42 using it (comp.cpp)
      (r->wear ? comp.d_wear : comp.d_geometry)[r->number] = value * modal.unit;
      std::string by(1, '#');
      by += std::to_string(n);
      by += context.line > 0 ? " at line " + std::to_string(context.line)
                             : " in the machine file's \"variables\"";
      comp.d_set_at[r->number] = std::move(by);
    }
    return;
  }
  if ((n >= 4001 && n <= 4400) || (n >= 5001 && n <= 5043) || (n >= 5420 && n <= 5428))
    error(a.column, "#" + std::to_string(n) + " is a read-only system variable");
  parameters.globals[n] = a.value;
}

// Offsets the control holds at the start are its registers, set as a program would set them
// (read back through them, and G43 H reads them); other variables are kept as they are.
void Interpreter::State::preset(int n, double value) {
  int component = 0;
  if (offset_variable(n, component) >= 0 || offset_register(n, machine.dialect))
    assign(Assignment{n, {}, Value{value, false}, 0});
  else
    parameters.globals[n] = Value{value, false};
}

}  // namespace tridex::gcode
