#include "record/replay.hpp"

#include "control/dwa_controller.hpp"
#include "control/pd_controller.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>

namespace staa::record {

Recording loadRecording(const std::filesystem::path& path, bool salvage) {
  McapFile file = readMcap(path, salvage);
  const std::string source = path.string();
  const McapMetadata* meta = file.findMetadata(kSessionMetadata);
  if (meta == nullptr) {
    throw RecordError(source + ": no '" + kSessionMetadata + "' metadata: not a staa recording (written by another tool?)");
  }
  Recording r;
  r.path = path;
  r.session = sessionFromMetadata(*meta, source);
  r.truncated = file.truncated;
  r.bytes = file.bytes.size();
  bool first = true;
  for (const McapMessage& m : file.messages) {
    const McapChannel& ch = file.channels.at(m.channel_id);
    (ch.message_encoding == kCycleEncoding ? r.cycle_bytes : r.json_bytes) += m.data.size();
    if (ch.message_encoding == kCycleEncoding) {
      CycleRecord c = decodeCycle(m.data, source + ": " + ch.topic + " message " + std::to_string(m.sequence));
      if (first || c.time_ns < r.first_time_ns) r.first_time_ns = c.time_ns;
      first = false;
      std::vector<CycleRecord>& cycles = r.agents[c.agent];
      if (!cycles.empty() && c.cycle <= cycles.back().cycle) {
        throw RecordError(source + ": " + ch.topic + ": cycle " + std::to_string(c.cycle) + " after cycle " +
                          std::to_string(cycles.back().cycle) + " (out of order)");
      }
      cycles.push_back(std::move(c));
    } else if (ch.message_encoding == "json" && ch.metadata.empty()) {
      r.events.push_back({ch.topic, static_cast<std::int64_t>(m.log_time),
                          std::string(reinterpret_cast<const char*>(m.data.data()), m.data.size())});
    }
  }
  for (const auto& [agent, cycles] : r.agents) {
    const bool known = std::any_of(r.session.agents.begin(), r.session.agents.end(),
                                   [&](const AgentInfo& a) { return a.agent == agent; });
    if (!known) throw RecordError(source + ": cycles of agent " + std::to_string(agent) + ", whom the session does not list");
  }
  return r;
}

double planDistance(std::span<const UnicycleState> a, std::span<const UnicycleState> b) {
  auto toPolyline = [](const Vec2& p, std::span<const UnicycleState> line) {
    if (line.empty()) return 0.0;
    double best = (p - line[0].position()).norm();
    for (std::size_t i = 1; i < line.size(); ++i) {
      const Vec2 s = line[i - 1].position(), e = line[i].position();
      const Vec2 d = e - s;
      const double len2 = d.squaredNorm();
      const double t = len2 > 0.0 ? std::clamp((p - s).dot(d) / len2, 0.0, 1.0) : 0.0;
      best = std::min(best, (p - (s + t * d)).norm());
    }
    return best;
  };
  if (a.empty() || b.empty()) return 0.0;
  double d = 0.0;
  for (const UnicycleState& s : a) d = std::max(d, toPolyline(s.position(), b));
  for (const UnicycleState& s : b) d = std::max(d, toPolyline(s.position(), a));
  return d;
}

namespace {

std::unique_ptr<LocalController> controllerFor(const AgentInfo& info, const RobotProfile& robot,
                                               const ControlConfig& config) {
  if (info.controller == "dwa") return std::make_unique<DwaController>(robot, config.local);
  if (info.controller == "pd") return std::make_unique<PdController>(robot);
  if (info.controller != "staa") throw RecordError("agent " + std::to_string(info.agent) + ": unknown controller '" + info.controller + "'");
  return nullptr;
}

std::string memoryDifference(const ControlCycle::Memory& replayed, const CycleRecord& r) {
  auto same = [](double a, double b) { return std::memcmp(&a, &b, sizeof a) == 0; };
  if (replayed.goal.has_value() != r.has_goal) return "memory: goal set in one, not in the other";
  if (r.has_goal && (!same(replayed.goal->x, r.goal.x) || !same(replayed.goal->y, r.goal.y) ||
                     !same(replayed.goal->theta, r.goal.theta))) {
    return "memory: another goal";
  }
  if (replayed.state != r.state) return std::string("memory: state ") + toString(r.state) + " vs " + toString(replayed.state);
  if (replayed.held_valid != r.held_valid) return "memory: a held path in one, not in the other";
  if (replayed.path_misses != r.path_misses) {
    return "memory: path misses " + std::to_string(r.path_misses) + " vs " + std::to_string(replayed.path_misses);
  }
  const ControlCycle::Memory recorded = r.memory();
  if (replayed.held_passage != recorded.held_passage || replayed.route_chosen != recorded.route_chosen ||
      replayed.route_in_passage != recorded.route_in_passage) {
    return "memory: another route choice between M' and M'' (or a held path in another map)";
  }
  return {};
}

std::string routeDifference(std::span<const Vec2> recorded, std::span<const Vec2> replayed) {
  if (recorded.empty()) return {};  // not recorded (the step followed no path)
  if (recorded.size() != replayed.size()) {
    return "global path of " + std::to_string(recorded.size()) + " vs " + std::to_string(replayed.size()) + " points";
  }
  for (std::size_t i = 0; i < recorded.size(); ++i) {
    if (std::memcmp(recorded[i].data(), replayed[i].data(), 2 * sizeof(double)) != 0) {
      return "global path point " + std::to_string(i) + " differs";
    }
  }
  return {};
}

std::uint32_t medianPops(const std::vector<CycleRecord>& cycles) {
  std::vector<std::uint32_t> pops;
  for (const CycleRecord& c : cycles) {
    if (c.stepped() && c.out.planned) pops.push_back(c.out.pops);
  }
  if (pops.empty()) return 1000;
  std::nth_element(pops.begin(), pops.begin() + static_cast<std::ptrdiff_t>(pops.size() / 2), pops.end());
  return std::max<std::uint32_t>(1, pops[pops.size() / 2]);
}

}  // namespace

ReplayResult replay(const Recording& recording, const ReplayOptions& options,
                    const std::function<void(const ReplayedCycle&)>& each) {
  const Session& session = recording.session;
  const bool changed = options.control.has_value() || options.budget.has_value();
  const ControlConfig config = options.control.value_or(session.control);
  ReplayResult result;
  const auto wall0 = std::chrono::steady_clock::now();

  for (const auto& [agent, cycles] : recording.agents) {
    if (options.agent && *options.agent != agent) continue;
    const auto info_it = std::find_if(session.agents.begin(), session.agents.end(),
                                      [&](const AgentInfo& a) { return a.agent == agent; });
    ControlConfig own = config;
    if (info_it->ghost) own.blind_corners.enabled = false;  // as the simulator built the ghost's cycle
    const std::unique_ptr<LocalController> controller = controllerFor(*info_it, session.robot, own);
    auto cycle = std::make_unique<ControlCycle>(session.map, session.robot, own);
    cycle->setLocalController(controller.get());
    DynamicObstacleSet obstacles(cycle->obstacleCapacity());
    std::vector<PolygonView> views;
    std::vector<Vec2> velocities;
    std::vector<double> turn_rates;
    const std::uint32_t fallback_pops = medianPops(cycles);

    AgentReplay ar;
    ar.agent = agent;
    double distance_sum = 0.0;
    bool exact = false;
    auto tally = [&ar](const CycleRecord& r, double t, bool is_exact, const std::string& difference) {
      if (difference.empty()) {
        is_exact ? ++ar.identical : ++ar.best_effort_identical;
        return;
      }
      ++ar.differing;
      if (!ar.first_difference_cycle) {
        ar.first_difference_cycle = r.cycle;
        ar.first_difference_t = t;
        ar.first_difference = difference;
      }
    };
    for (const CycleRecord& r : cycles) {
      const double t = static_cast<double>(r.time_ns - recording.first_time_ns) * 1e-9;
      if (options.from_s && t < *options.from_s - 1e-9) continue;
      if (options.to_s && t > *options.to_s + 1e-9) break;
      if (options.until_cycle && r.cycle > *options.until_cycle) break;

      if (r.map_sequence != 0) {
        // A map from ROS swapped in: the file holds the session's map only.
        ++ar.other_map;
        exact = false;
        continue;
      }
      if (r.flags & kNewCycle) {
        cycle = std::make_unique<ControlCycle>(session.map, session.robot, own);
        cycle->setLocalController(controller.get());
      }
      if (r.flags & kGoalSet) r.has_goal ? cycle->setGoal(r.goal) : cycle->clearGoal();
      if ((r.flags & kFresh) && !changed) {
        if (!exact && !ar.exact_from) ar.exact_from = r.cycle;
        exact = true;
      }
      if (r.flags & kInputsCut) exact = false;
      std::string difference = exact ? memoryDifference(cycle->memory(), r) : std::string();
      cycle->restoreMemory(r.memory());
      ++ar.cycles;
      if (exact) ++ar.exact;

      if (!r.stepped()) {
        ++ar.held;
        tally(r, t, exact, difference);
        if (each) each(ReplayedCycle{r, nullptr, *cycle, *cycle, obstacles, exact, difference});
        continue;
      }

      views.clear();
      velocities.clear();
      turn_rates.clear();
      for (const RecordedObstacle& o : r.obstacles) {
        views.emplace_back(o.polygon);
        velocities.push_back(o.velocity);
        turn_rates.push_back(o.turn_rate);
      }
      obstacles.set(views, velocities, turn_rates);

      PlannerBudget budget;
      if (options.budget) {
        budget = options.budget->make();
      } else if (changed) {
        budget = PlannerBudget::expansions(r.out.planned ? r.out.pops : fallback_pops);
      } else if (!r.budget.wall_clock) {
        budget = PlannerBudget::expansions(r.budget.max_pops);
      } else if (exact) {
        ReplayClock::arm(r.budget.cut.cut_read);
        budget = PlannerBudget::wallClock(r.budget.limit_ns, &ReplayClock::now);
      } else if (r.out.path_status == PathStatus::kAborted) {
        ReplayClock::arm(1);  // the path query ran out of time: cut it at its first look
        budget = PlannerBudget::wallClock(r.budget.limit_ns, &ReplayClock::now);
      } else {
        budget = PlannerBudget::expansions(r.out.planned ? r.out.pops : fallback_pops);
      }

      CycleInputs in;
      in.robot = r.robot;
      in.obstacles = &obstacles;
      const CycleOutput out = cycle->step(in, budget);
      const StepOutputs replayed = stepOutputs(out);
      if (difference.empty()) difference = firstDifference(r.out, replayed);
      const bool followed = out.state == CycleState::kDriving && (out.path_status == PathStatus::kFound || out.path_held);
      if (difference.empty() && followed) difference = routeDifference(r.route, cycle->lastPath());

      tally(r, t, exact, difference);
      if (!difference.empty()) {
        ar.max_command_change =
            std::max(ar.max_command_change, std::abs(r.out.v_cmd - out.v_cmd) + std::abs(r.out.w_cmd - out.w_cmd));
        const double d = planDistance(r.trajectory, out.planned ? out.plan.trajectory : std::span<const UnicycleState>{});
        ar.max_path_distance_m = std::max(ar.max_path_distance_m, d);
        distance_sum += d;
      }
      if (each) each(ReplayedCycle{r, &out, *cycle, *cycle, obstacles, exact, difference});
    }
    ar.mean_path_distance_m = ar.differing > 0 ? distance_sum / static_cast<double>(ar.differing) : 0.0;
    result.cycles += ar.cycles;
    result.identical += ar.identical + ar.best_effort_identical;
    result.agents.push_back(ar);
  }
  result.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall0).count();
  return result;
}

}  // namespace staa::record
