// tridex command — the machining time (see machining_time.hpp).
#include "checks/machining_time.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <utility>

namespace tridex::cli {

namespace {

// The same direction as the spindle-direction groups (gcode::DirectionGrouper's default
// tolerance, 1e-3°), so that the report's directions are the groups'.
const double kSameDirection = std::cos(glm::radians(1e-3));

}  // namespace

MachiningTimer::MachiningTimer(const gcode::MachineConfig& machine)
    : rates_(machine.rates), kinematics_(machine.kinematics) {}

void MachiningTimer::charge(int tool, const Vec3& axis, double seconds) {
  time_.by_tool[tool] += seconds;
  auto same = [&](std::size_t d) {
    return glm::dot(time_.by_direction[d].first, axis) >= kSameDirection;
  };
  std::size_t found = time_.by_direction.size();
  if (last_direction_ < found && same(last_direction_)) {
    found = last_direction_;
  } else {
    for (std::size_t d = 0; d < time_.by_direction.size(); ++d)
      if (same(d)) {
        found = d;
        break;
      }
  }
  if (found == time_.by_direction.size())
    time_.by_direction.emplace_back(glm::normalize(axis), 0.0);
  time_.by_direction[found].second += seconds;
  last_direction_ = found;
}

// The slowest axis's minutes: every axis of the machine moves at most at its rapid rate.
double MachiningTimer::rapid_minutes(const gcode::Move& move) {
  Vec3 linear = move.end - move.start;
  gcode::RotaryPositions turned{};
  if (kinematics_ && move.rotary_axes) {
    // The first move starts where the machine puts its start point at the current rotaries.
    Vec3 start = have_last_ ? last_machine_
                            : gcode::machine_from_part(*kinematics_, move.start, move.rotary);
    linear = move.machine - start;
    if (have_last_)
      for (std::size_t i = 0; i < 3; ++i) turned[i] = std::abs(move.rotary[i] - last_rotary_[i]);
  }
  double minutes = 0;
  if (rates_.rapid_per_axis) {
    for (int a = 0; a < 3; ++a)
      minutes = std::max(minutes, std::abs(linear[a]) / rates_.rapid_mm_per_min[a]);
  } else {
    minutes = glm::length(linear) / rates_.rapid_mm_per_min.x;
  }
  bool untimed = false;
  for (std::size_t i = 0; i < 3; ++i) {
    if (turned[i] == 0) continue;
    if (rates_.rapid_deg_per_min[i] > 0)
      minutes = std::max(minutes, turned[i] / rates_.rapid_deg_per_min[i]);
    else
      untimed = true;
  }
  if (untimed) ++time_.untimed_turns;
  return minutes;
}

void MachiningTimer::add(const gcode::Move& move) {
  // A rapid's machine deltas are from the previous move's end, the far approaches included.
  auto remember = [&] {
    if (!kinematics_ || !move.rotary_axes) return;
    have_last_ = true;
    last_machine_ = move.machine;
    last_rotary_ = move.rotary;
  };
  if (move.from_far) {
    ++time_.untimed_approaches;
    remember();
    return;
  }
  double seconds = 0;
  if (move.feed > 0) {
    double feed = move.feed;
    if (rates_.max_feed_mm_per_min && feed > *rates_.max_feed_mm_per_min) {
      feed = *rates_.max_feed_mm_per_min;
      ++time_.capped_feeds;
    }
    seconds = 60 * glm::length(move.end - move.start) / feed;
    time_.feed_s += seconds;
  } else {
    seconds = 60 * rapid_minutes(move);
    time_.rapid_s += seconds;
  }
  remember();
  if (move.pose != gcode::PoseLaw::fixed) {
    time_.by_tool[move.tool] += seconds;
    time_.simultaneous_s += seconds;
    ++time_.simultaneous_moves;
    return;
  }
  charge(move.tool, move.axis, seconds);
}

void MachiningTimer::add(const gcode::Dwell& dwell) {
  time_.dwell_s += dwell.seconds;
  charge(dwell.tool, dwell.axis, dwell.seconds);
}

Json machining_time_json(const MachiningTimer& timer) {
  const MachiningTime& t = timer.time();
  const gcode::MachineRates& rates = timer.rates();
  Json by_tool = Json::array();
  for (const auto& [tool, s] : t.by_tool) by_tool.push_back({{"tool", tool}, {"s", s}});
  Json by_direction = Json::array();
  for (const auto& [axis, s] : t.by_direction)
    by_direction.push_back({{"direction", to_json(axis)}, {"s", s}});
  Json j = {{"total_s", t.total_s()}, {"feed_s", t.feed_s}, {"rapid_s", t.rapid_s},
            {"dwell_s", t.dwell_s},   {"by_tool", by_tool}, {"by_direction", by_direction}};
  if (t.simultaneous_moves > 0)
    j["simultaneous"] = {{"moves", t.simultaneous_moves}, {"s", t.simultaneous_s}};
  j["rapid_rate_mm_per_min"] =
      rates.rapid_per_axis ? to_json(rates.rapid_mm_per_min) : Json(rates.rapid_mm_per_min.x);
  j["rapid_rate_source"] = rates.source;
  Json turn_rates = Json::object();
  for (std::size_t i = 0; i < 3; ++i)
    if (rates.rapid_deg_per_min[i] > 0)
      turn_rates[std::string(1, static_cast<char>('A' + i))] = rates.rapid_deg_per_min[i];
  if (!turn_rates.empty()) j["rapid_rate_deg_per_min"] = turn_rates;
  if (rates.max_feed_mm_per_min) j["max_feed_mm_per_min"] = *rates.max_feed_mm_per_min;
  j["feeds_capped"] = t.capped_feeds;
  j["untimed_turns"] = t.untimed_turns;
  j["untimed_approaches"] = t.untimed_approaches;
  return j;
}

std::string duration_text(double seconds) {
  long long s = std::llround(seconds);
  char text[64];
  if (s >= 3600)
    std::snprintf(text, sizeof text, "%lld h %02lld min %02lld s", s / 3600, s / 60 % 60, s % 60);
  else if (s >= 60)
    std::snprintf(text, sizeof text, "%lld min %02lld s", s / 60, s % 60);
  else
    std::snprintf(text, sizeof text, "%.1f s", seconds);
  return text;
}

std::string machining_time_text(const MachiningTimer& timer) {
  const MachiningTime& t = timer.time();
  const gcode::MachineRates& rates = timer.rates();
  char rate[96];
  if (rates.rapid_per_axis)
    std::snprintf(rate, sizeof rate, "[%g, %g, %g]", rates.rapid_mm_per_min.x,
                  rates.rapid_mm_per_min.y, rates.rapid_mm_per_min.z);
  else
    std::snprintf(rate, sizeof rate, "%g", rates.rapid_mm_per_min.x);
  return "machining time " + duration_text(t.total_s()) + " (feed " + duration_text(t.feed_s) +
         ", rapid " + duration_text(t.rapid_s) + ", dwell " + duration_text(t.dwell_s) +
         ") with rapids at " + rate + " mm/min (" +
         (rates.source == "default" ? std::string("the default") : "from " + rates.source) + ")";
}

}  // namespace tridex::cli
