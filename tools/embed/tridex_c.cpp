// tridex embedded — the C API (include/tridex.h) over the session (session.hpp). Every entry point
// catches what the session throws and turns it into a status and tridex_last_error()'s text, as
// the command maps them to exit statuses (cli/main.cpp): G-code and input errors are bad input,
// anything else a failure.
#include "tridex.h"

#include <algorithm>
#include <exception>
#include <memory>
#include <new>
#include <string>
#include <utility>
#include <vector>

#include "errors.hpp"
#include "session.hpp"
#include "tridex/gcode/diagnostic.hpp"

#ifndef TRIDEX_VERSION
#define TRIDEX_VERSION "unknown"
#endif

struct tridex_session {
  std::unique_ptr<tridex::embed::Session> session;
};

namespace {

thread_local std::string last_error;

template <class Body>
tridex_status guarded(Body&& body) {
  last_error.clear();
  try {
    body();
    return TRIDEX_OK;
  } catch (const tridex::gcode::GcodeError& e) {
    last_error = e.what();
    return TRIDEX_BAD_INPUT;
  } catch (const tridex::cli::InputError& e) {
    last_error = e.what();
    return TRIDEX_BAD_INPUT;
  } catch (const std::bad_alloc&) {
    last_error = "out of memory (use a larger cell)";
    return TRIDEX_ERROR;
  } catch (const std::exception& e) {
    last_error = e.what();
    return TRIDEX_ERROR;
  } catch (...) {
    last_error = "unknown failure";
    return TRIDEX_ERROR;
  }
}

tridex::Vec3 vec3(const double p[3]) { return tridex::Vec3(p[0], p[1], p[2]); }

tridex_status bad_call(const char* what) {
  last_error = std::string(what) + " is null";
  return TRIDEX_BAD_CALL;
}

}  // namespace

extern "C" {

const char* tridex_last_error(void) { return last_error.c_str(); }
const char* tridex_version(void) { return TRIDEX_VERSION; }

tridex_status tridex_session_new(const tridex_session_options* options, tridex_session** out) {
  if (!options) return bad_call("options");
  if (!out) return bad_call("out");
  *out = nullptr;
  return guarded([&] {
    tridex::embed::SessionOptions o;
    o.stock = tridex::Aabb{tridex::Vec3(options->stock[0], options->stock[1], options->stock[2]),
                           tridex::Vec3(options->stock[3], options->stock[4], options->stock[5])};
    o.tools = options->tools ? options->tools : "";
    o.machine = options->machine ? options->machine : "";
    o.cell = options->cell;
    o.threads = options->threads;
    o.stock_file = options->stock_file ? options->stock_file : "";
    auto handle = std::make_unique<tridex_session>();
    handle->session = std::make_unique<tridex::embed::Session>(o);
    *out = handle.release();
  });
}

void tridex_session_free(tridex_session* session) { delete session; }

tridex_status tridex_session_feed(tridex_session* session, const char* text) {
  if (!session) return bad_call("session");
  if (!text) return bad_call("text");
  return guarded([&] { session->session->feed(text); });
}

tridex_status tridex_session_feed_measured(tridex_session* session, const char* text,
                                           double* removed) {
  if (!session) return bad_call("session");
  if (!text) return bad_call("text");
  if (!removed) return bad_call("removed");
  return guarded([&] { *removed = session->session->feed_measured(text); });
}

tridex_status tridex_session_add_move(tridex_session* session, const double start[3],
                                      const double end[3], int tool, const double axis[3],
                                      int rapid) {
  if (!session) return bad_call("session");
  if (!start) return bad_call("start");
  if (!end) return bad_call("end");
  if (!axis) return bad_call("axis");
  return guarded(
      [&] { session->session->add_move(vec3(start), vec3(end), tool, vec3(axis), rapid != 0); });
}

tridex_status tridex_session_extent(tridex_session* session, const double point[3],
                                    const double direction[3], double* spans, int capacity,
                                    int* count) {
  if (!session) return bad_call("session");
  if (!point) return bad_call("point");
  if (!direction) return bad_call("direction");
  if (!count) return bad_call("count");
  if (capacity > 0 && !spans) return bad_call("spans");
  return guarded([&] {
    const std::vector<std::pair<double, double>> found =
        session->session->extent(vec3(point), vec3(direction));
    for (std::size_t k = 0; k < found.size() && k < static_cast<std::size_t>(std::max(0, capacity));
         ++k)
      spans[2 * k] = found[k].first, spans[2 * k + 1] = found[k].second;
    *count = static_cast<int>(found.size());
  });
}

tridex_status tridex_session_removed_volume(tridex_session* session, double* out) {
  if (!session) return bad_call("session");
  if (!out) return bad_call("out");
  return guarded([&] { *out = session->session->removed_volume(); });
}

tridex_status tridex_session_would_cut(tridex_session* session, const char* block, double* out) {
  if (!session) return bad_call("session");
  if (!block) return bad_call("block");
  if (!out) return bad_call("out");
  return guarded([&] { *out = session->session->would_cut(block); });
}

tridex_status tridex_session_inside(tridex_session* session, const double point[3], int* out) {
  if (!session) return bad_call("session");
  if (!point) return bad_call("point");
  if (!out) return bad_call("out");
  return guarded(
      [&] { *out = session->session->inside(tridex::Vec3(point[0], point[1], point[2])) ? 1 : 0; });
}

tridex_status tridex_session_write_stl(tridex_session* session, const char* path) {
  if (!session) return bad_call("session");
  if (!path) return bad_call("path");
  return guarded([&] { session->session->write_stl(path); });
}

tridex_status tridex_session_moves(tridex_session* session, long long* out) {
  if (!session) return bad_call("session");
  if (!out) return bad_call("out");
  *out = session->session->moves();
  return TRIDEX_OK;
}

tridex_status tridex_session_warning_count(tridex_session* session, int* out) {
  if (!session) return bad_call("session");
  if (!out) return bad_call("out");
  *out = static_cast<int>(session->session->warnings().size());
  return TRIDEX_OK;
}

const char* tridex_session_warning(tridex_session* session, int index) {
  if (!session || index < 0 ||
      static_cast<std::size_t>(index) >= session->session->warnings().size())
    return nullptr;
  return session->session->warnings()[static_cast<std::size_t>(index)].c_str();
}

}  // extern "C"
