#include "record/config_keys.hpp"

#include <nlohmann/json.hpp>

#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <limits>
#include <type_traits>

namespace staa::record {

namespace {

// Every field, by its key. Keep in step with the structs (RecordConfigKeys.CoverEveryField).
template <typename C, typename V>
void visitControlConfig(C& c, V&& v) {
  v("rate_hz", c.rate_hz);
  v("goal_tolerance_m", c.goal_tolerance_m);
  v("goal_heading_tolerance", c.goal_heading_tolerance);
  v("goal_speed_tolerance", c.goal_speed_tolerance);
  v("inflation_m", c.inflation_m);
  v("dynamic_inflation_m", c.dynamic_inflation_m);
  v("local_inflation_m", c.local_inflation_m);
  v("max_moving_obstacles", c.max_moving_obstacles);
  v("path_hold_s", c.path_hold_s);
  v("passages", c.passages);
  v("passage_margin_m", c.passage_margin_m);
  v("blind_corners.enabled", c.blind_corners.enabled);
  v("blind_corners.reaction_s", c.blind_corners.reaction_s);
  v("blind_corners.decel", c.blind_corners.decel);
  v("blind_corners.clearance_m", c.blind_corners.clearance_m);
  v("blind_corners.min_speed", c.blind_corners.min_speed);
  v("blind_corners.range_m", c.blind_corners.range_m);
  v("blind_corners.lateral_m", c.blind_corners.lateral_m);
  auto& s = c.staa;
  v("staa.notches", s.notches);
  v("staa.dt", s.dt);
  v("staa.adapt_dt", s.adapt_dt);
  v("staa.closed_xy_m", s.closed_xy_m);
  v("staa.closed_theta_rad", s.closed_theta_rad);
  v("staa.prediction_depth", s.prediction_depth);
  v("staa.w_static", s.w_static);
  v("staa.w_dynamic", s.w_dynamic);
  v("staa.proximity_range_m", s.proximity_range_m);
  v("staa.finish_h", s.finish_h);
  v("staa.check_swept", s.check_swept);
  v("staa.max_nodes", s.max_nodes);
  v("staa.lazy_heuristic", s.lazy_heuristic);
  v("staa.brake_safety", s.brake_safety);
  v("staa.passive_safety", s.passive_safety);
  v("staa.passive_heading_spread", s.passive_heading_spread);
  v("staa.predict_turning", s.predict_turning);
  v("staa.obstacle_reaction_s", s.obstacle_reaction_s);
  v("staa.obstacle_brake_decel", s.obstacle_brake_decel);
  v("staa.brake_step_s", s.brake_step_s);
  v("staa.separate_contacts", s.separate_contacts);
  auto& h = s.heuristic;
  v("staa.heuristic.kind", h.kind);
  v("staa.heuristic.dynamic_depth", h.dynamic_depth);
  v("staa.heuristic.dynamic_inflation_m", h.dynamic_inflation_m);
  v("staa.heuristic.static_inflation_m", h.static_inflation_m);
  v("staa.heuristic.local_reach_m", h.local_reach_m);
  v("staa.heuristic.arc_steps", h.arc_steps);
  v("staa.heuristic.unreachable_penalty_s", h.unreachable_penalty_s);
  v("staa.heuristic.stop_at_goal", h.stop_at_goal);
  auto& l = c.local;
  v("local.ahead_m", l.ahead_m);
  v("local.behind_m", l.behind_m);
  v("local.side_m", l.side_m);
  v("local.cell_m", l.cell_m);
  v("local.dilate_m", l.dilate_m);
  v("local.blur_sigma_m", l.blur_sigma_m);
  auto& p = c.path;
  v("path.inflation_radius_m", p.inflation_radius_m);
  v("path.arc_tolerance_m", p.arc_tolerance_m);
  v("path.nudge_start", p.nudge_start);
  v("path.passage_inflation_m", p.passage_inflation_m);
  v("path.passage_arc_tolerance_m", p.passage_arc_tolerance_m);
  v("path.band_cost", p.band_cost);
  v("path.route_hysteresis_m", p.route_hysteresis_m);
  v("path.search.grid_cell_m", p.search.grid_cell_m);
  v("path.search.max_dynamic_polygons", p.search.max_dynamic_polygons);
  v("path.search.max_dynamic_vertices", p.search.max_dynamic_vertices);
}

std::string textOf(double v) { return nlohmann::json(v).dump(); }
std::string textOf(bool v) { return v ? "true" : "false"; }
std::string textOf(HeuristicKind v) { return toString(v); }
template <typename I>
  requires std::is_integral_v<I>
std::string textOf(I v) {
  return std::to_string(v);
}

void parseInto(const std::string& key, const std::string& text, double& out) {
  errno = 0;
  char* end = nullptr;
  const double v = std::strtod(text.c_str(), &end);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || !std::isfinite(v)) {
    throw KeyError(key + ": expected a finite number, got '" + text + "'");
  }
  out = v;
}
void parseInto(const std::string& key, const std::string& text, bool& out) {
  if (text == "true" || text == "on" || text == "1") {
    out = true;
  } else if (text == "false" || text == "off" || text == "0") {
    out = false;
  } else {
    throw KeyError(key + ": expected true or false, got '" + text + "'");
  }
}
void parseInto(const std::string& key, const std::string& text, HeuristicKind& out) {
  if (!parseHeuristicKind(text.c_str(), out)) {
    throw KeyError(key + ": expected path-rtr, path-euclid or dijkstra-rtr, got '" + text + "'");
  }
}
template <typename I>
  requires std::is_integral_v<I>
void parseInto(const std::string& key, const std::string& text, I& out) {
  errno = 0;
  char* end = nullptr;
  const long long v = std::strtoll(text.c_str(), &end, 10);
  if (text.empty() || end != text.c_str() + text.size() || errno == ERANGE || (std::is_unsigned_v<I> && v < 0) ||
      v < static_cast<long long>(std::numeric_limits<I>::min()) ||
      static_cast<unsigned long long>(v) > static_cast<unsigned long long>(std::numeric_limits<I>::max())) {
    throw KeyError(key + ": expected an integer" + (std::is_unsigned_v<I> ? std::string(" >= 0") : std::string()) +
                   ", got '" + text + "'");
  }
  out = static_cast<I>(v);
}

}  // namespace

std::string controlConfigJson(const ControlConfig& config) {
  nlohmann::ordered_json j = nlohmann::ordered_json::object();
  visitControlConfig(config, [&](const char* key, const auto& value) {
    using T = std::decay_t<decltype(value)>;
    if constexpr (std::is_same_v<T, HeuristicKind>) {
      j[key] = toString(value);
    } else {
      j[key] = value;
    }
  });
  return j.dump();
}

ControlConfig controlConfigFromJson(const std::string& text, const ControlConfig& base) {
  nlohmann::json j;
  try {
    j = nlohmann::json::parse(text);
  } catch (const nlohmann::json::exception& e) {
    throw KeyError(std::string("the control configuration is not JSON: ") + e.what());
  }
  if (!j.is_object()) throw KeyError("the control configuration is not a JSON object");
  ControlConfig c = base;
  std::size_t known = 0;
  visitControlConfig(c, [&](const char* key, auto& value) {
    using T = std::decay_t<decltype(value)>;
    const auto it = j.find(key);
    if (it == j.end()) return;
    ++known;
    try {
      if constexpr (std::is_same_v<T, HeuristicKind>) {
        parseInto(key, it->template get<std::string>(), value);
      } else {
        value = it->template get<T>();
      }
    } catch (const nlohmann::json::exception&) {
      throw KeyError(std::string(key) + ": the recorded value " + it->dump() + " does not fit the field");
    }
  });
  if (known != j.size()) {
    for (const auto& [key, value] : j.items()) {
      bool found = false;
      visitControlConfig(c, [&](const char* k, auto&) { found = found || key == k; });
      if (!found) throw KeyError("the control configuration has the unknown key '" + key + "' (a newer recorder?)");
    }
  }
  return c;
}

void setControlKey(ControlConfig& config, const std::string& key, const std::string& value) {
  bool found = false;
  visitControlConfig(config, [&](const char* k, auto& field) {
    if (key != k) return;
    found = true;
    parseInto(key, value, field);
  });
  if (!found) {
    std::string keys;
    visitControlConfig(config, [&](const char* k, auto&) { keys += keys.empty() ? k : std::string(", ") + k; });
    throw KeyError("unknown key '" + key + "' (the keys: " + keys + ")");
  }
}

std::vector<std::pair<std::string, std::string>> controlConfigKeys(const ControlConfig& config) {
  std::vector<std::pair<std::string, std::string>> out;
  visitControlConfig(config, [&](const char* k, const auto& v) { out.emplace_back(k, textOf(v)); });
  return out;
}

std::string robotProfileJson(const RobotProfile& robot) {
  nlohmann::ordered_json j;
  j["name"] = robot.name;
  nlohmann::ordered_json fp = nlohmann::ordered_json::array();
  for (const Vec2& p : robot.footprint) fp.push_back({p.x(), p.y()});
  j["footprint"] = fp;
  const MotionLimits& l = robot.limits;
  j["limits"] = {{"v_max", l.v_max}, {"v_min", l.v_min}, {"w_max", l.w_max}, {"a_max", l.a_max}, {"b_max", l.b_max}};
  return j.dump();
}

RobotProfile robotProfileFromJson(const std::string& text) {
  try {
    const nlohmann::json j = nlohmann::json::parse(text);
    RobotProfile r;
    r.name = j.at("name").get<std::string>();
    for (const auto& p : j.at("footprint")) r.footprint.emplace_back(p.at(0).get<double>(), p.at(1).get<double>());
    const auto& l = j.at("limits");
    r.limits.v_max = l.at("v_max").get<double>();
    r.limits.v_min = l.at("v_min").get<double>();
    r.limits.w_max = l.at("w_max").get<double>();
    r.limits.a_max = l.at("a_max").get<double>();
    r.limits.b_max = l.at("b_max").get<double>();
    if (r.footprint.size() < 3) throw KeyError("the robot profile's footprint has fewer than 3 vertices");
    return r;
  } catch (const nlohmann::json::exception& e) {
    throw KeyError(std::string("the robot profile is not as written: ") + e.what());
  }
}

}  // namespace staa::record
