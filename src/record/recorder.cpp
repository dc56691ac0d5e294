#include "record/recorder.hpp"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <system_error>

namespace staa::record {

namespace {
// 2026-12-03T11:15:00Z -> 20261203T111500Z (for file names).
std::string compactUtcNow() {
  std::string stamp = utcNow();
  stamp.erase(std::remove_if(stamp.begin(), stamp.end(), [](char c) { return c == '-' || c == ':'; }), stamp.end());
  return stamp;
}
}  // namespace

// ---- the recording thread's half ----

CycleRecorder::CycleRecorder(const RecordLimits& limits, CycleSink& sink, std::uint16_t agent)
    : limits_(limits), sink_(sink), agent_(agent), buffer_(maxCycleBytes(limits)) {}

PlannerBudget CycleRecorder::before(const ControlCycle& cycle, const BudgetSpec& spec, ClockFn clock) {
  memory_ = cycle.memory();
  fresh_ = cycle.searchesFresh();
  if (cycle.goalChanges() != goal_changes_) flags_ |= kGoalSet;
  goal_changes_ = cycle.goalChanges();
  if (spec.isExpansions()) {
    budget_ = spec.make();
  } else {
    BudgetTap::install(clock);
    BudgetTap::arm(spec.limitNs());
    budget_ = spec.make(&BudgetTap::now);
  }
  return budget_;
}

void CycleRecorder::after(const ControlCycle& cycle, std::int64_t time_ns, const UnicycleState& robot, StepKind step,
                          std::uint8_t fault, const CycleOutput* out, const CommandRecord& command,
                          std::uint32_t map_sequence) {
  CycleView v;
  v.agent = agent_;
  v.cycle = cycle_;
  v.time_ns = time_ns;
  v.map_sequence = map_sequence;
  v.step = step;
  v.fault = fault;
  v.flags = flags_;
  v.memory = memory_;
  v.fresh = fresh_;
  v.robot = robot;
  const bool wall = budget_.kind() == PlannerBudget::Kind::kWallClock;
  v.budget = budgetRecord(budget_, wall && out != nullptr ? BudgetTap::result() : BudgetCut{});
  v.obstacles = obstacles_;
  v.out = out;
  // The path and G~ are this step's only when it followed a path.
  if (out != nullptr && out->state == CycleState::kDriving &&
      (out->path_status == PathStatus::kFound || out->path_held)) {
    v.route = cycle.lastPath();
    v.subgoal = cycle.localMap().intermediateGoal().pose;
    v.subgoal_final = cycle.localMap().intermediateGoal().is_final;
  }
  v.command = command;
  last_size_ = encodeCycle(v, limits_, buffer_);
  if (last_size_ > 0) {
    sink_.take(std::span<const std::byte>(buffer_.data(), last_size_));
  } else {
    ++failed_;
  }
  ++cycle_;
  flags_ = 0;
  obstacles_ = ObstacleInputs{};
}

// ---- the service thread's half ----

RecordingService::RecordingService(Session session, RecorderOptions options,
                                   std::function<void(const std::string&)> warn)
    : session_(std::move(session)), options_(std::move(options)), warn_(std::move(warn)) {}

RecordingService::~RecordingService() { close(); }

void RecordingService::failed(const std::string& what) {
  ++stats_.write_failures;
  stats_.last_error = what;
  if (!failing_ && warn_) warn_("recorder: " + what + " (recording goes on in memory; the robot is not affected)");
  failing_ = true;
}

std::filesystem::path RecordingService::nextContinuousPath() {
  const std::filesystem::path& base = options_.path;
  const std::string stamp = compactUtcNow();
  char index[16];
  std::snprintf(index, sizeof index, "%04llu", static_cast<unsigned long long>(++file_index_));
  const std::string ext = base.has_extension() ? base.extension().string() : std::string(".mcap");
  return base.parent_path() / (base.stem().string() + "-" + stamp + "-" + index + ext);
}

void RecordingService::continuous(std::span<const std::byte> record, std::int64_t time_ns) {
  if (options_.path.empty()) return;
  if (!file_) {
    if (time_ns < retry_after_ns_) return;
    file_ = std::make_unique<RecordingFile>(nextContinuousPath(), session_);
    if (!file_->ok()) {
      failed(file_->error());
      file_.reset();
      retry_after_ns_ = time_ns + 10'000'000'000;  // try again in 10 s
      return;
    }
    ++stats_.files;
    stats_.current_file = file_->path().string();
  }
  const std::uint64_t before = file_->bytes();
  file_->add(record);
  stats_.bytes_written += file_->bytes() - before;
  if (!file_->ok()) {
    failed(file_->error());
    file_.reset();
    retry_after_ns_ = time_ns + 10'000'000'000;
    return;
  }
  failing_ = false;
  if (file_->bytes() >= options_.max_file_bytes) {
    file_->close();
    written_.push_back(file_->path());
    file_.reset();
    stats_.current_file.clear();
    while (written_.size() > std::max<std::size_t>(1, options_.max_files) - 1) {
      std::error_code ec;
      std::filesystem::remove(written_.front(), ec);
      written_.pop_front();
    }
  }
}

void RecordingService::collectWrite() {
  if (!write_) return;
  const std::string error = write_->error.get();
  if (error.empty()) {
    if (write_->fault) {
      ++stats_.fault_files;
      stats_.last_fault_file = write_->file.string();
    }
  } else {
    failed(error);
  }
  write_.reset();
}

void RecordingService::finishWrites() { collectWrite(); }

void RecordingService::writeHistory(const std::filesystem::path& file, std::int64_t from_ns, bool fault) {
  collectWrite();  // one at a time
  std::vector<std::vector<std::byte>> records;
  for (const Entry& e : history_) {
    if (e.time_ns >= from_ns) records.push_back(e.bytes);
  }
  write_.emplace();
  write_->file = file;
  write_->fault = fault;
  write_->error = std::async(std::launch::async, [file, session = session_, records = std::move(records)]() -> std::string {
    std::error_code ec;
    if (file.has_parent_path()) std::filesystem::create_directories(file.parent_path(), ec);
    std::filesystem::path part = file;
    part += ".part";
    RecordingFile out(part, session);
    for (const std::vector<std::byte>& r : records) out.add(r);
    out.close();
    if (!out.ok()) {
      std::filesystem::remove(part, ec);
      return out.error();
    }
    std::filesystem::rename(part, file, ec);
    if (ec) return file.string() + ": cannot be written (" + ec.message() + ")";
    return {};
  });
}

void RecordingService::take(std::span<const std::byte> record) {
  ++stats_.cycles;
  if (write_ && write_->error.wait_for(std::chrono::seconds(0)) == std::future_status::ready) collectWrite();
  CycleRecord c;
  try {
    c = decodeCycle(record, "recorder ring");
  } catch (const RecordError& e) {
    failed(e.what());
    return;
  }
  history_.push_back(Entry{c.time_ns, std::vector<std::byte>(record.begin(), record.end())});
  const auto keep = static_cast<std::int64_t>((options_.seconds + options_.fault_after_s + 1.0) * 1e9);
  while (!history_.empty() && history_.front().time_ns < c.time_ns - keep) history_.pop_front();

  continuous(record, c.time_ns);

  // A fault starts a fault file, written once fault_after_s more have been recorded.
  const std::uint8_t fault = c.step == StepKind::kFault ? c.fault : 0;
  if (fault != 0 && last_fault_ == 0 && !options_.fault_dir.empty() && !fault_at_) {
    fault_at_ = c.time_ns;
    static const char* const names[] = {"none", "stale-odometry", "stale-obstacles", "base"};
    fault_kind_ = fault < 4 ? names[fault] : "unknown";
  }
  last_fault_ = fault;
  if (fault_at_ && c.time_ns >= *fault_at_ + static_cast<std::int64_t>(options_.fault_after_s * 1e9)) writeFaultFile();
}

void RecordingService::writeFaultFile() {
  const std::filesystem::path file = options_.fault_dir / ("staad-fault-" + compactUtcNow() + "-" + fault_kind_ + ".mcap");
  writeHistory(file, *fault_at_ - static_cast<std::int64_t>(options_.seconds * 1e9), true);
  fault_at_.reset();
}

std::string RecordingService::save(const std::filesystem::path& file) {
  if (history_.empty()) return "no cycle recorded yet";
  writeHistory(file, history_.back().time_ns - static_cast<std::int64_t>(options_.seconds * 1e9), false);
  return {};
}

void RecordingService::close() {
  if (fault_at_) writeFaultFile();
  collectWrite();
  if (file_) {
    file_->close();
    if (!file_->ok()) failed(file_->error());
    written_.push_back(file_->path());
    file_.reset();
  }
}

}  // namespace staa::record

namespace staa::record {

SimRecording::SimRecording(const std::filesystem::path& path, const Session& session, const RecordLimits& limits)
    : file_(path, session), sink_(file_) {
  if (!file_.ok()) throw RecordError(file_.error());
  for (const AgentInfo& a : session.agents) recorders_.push_back(std::make_unique<CycleRecorder>(limits, sink_, a.agent));
}

void SimRecording::close() {
  file_.close();
  if (!file_.ok()) throw RecordError(file_.error());
}

}  // namespace staa::record
