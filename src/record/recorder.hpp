#pragma once
// The flight recorder's two halves.
//
// CycleRecorder runs in the control thread (staad) or a simulation's loop: around each
// ControlCycle::step it notes what the cycle saw and carried, gives the step a budget whose
// clock is the BudgetTap (record/budget_tap.hpp), and encodes the cycle into a buffer sized
// at construction, handed to a sink: staad's byte ring to the service thread (no allocation,
// no lock), or a simulation's RecordingFile.
//
// RecordingService runs in staad's service thread: it takes the encoded cycles from the
// ring, keeps the last `seconds` of them, writes them to rotating files (`recorder.path`,
// at most `max_file_mb` each, the oldest deleted beyond `max_files`), saves the history on
// demand (`staactl record save FILE`) and on a fault (the seconds before it and
// `fault_after_s` after, into `fault_dir`). Saves and fault files are written by a worker
// thread from a copy of the history (FILE.part, renamed when complete), so that the service
// thread keeps answering the socket. A file it cannot write (full disk, unwritable folder)
// is a warning in the log; the control thread never waits for any of it.

#include "control/control_cycle.hpp"
#include "record/budget_tap.hpp"
#include "record/cycle_record.hpp"
#include "record/recording.hpp"

#include <cmath>
#include <cstdint>
#include <deque>
#include <filesystem>
#include <functional>
#include <future>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <vector>

namespace staa::record {

// Where encoded cycles go.
class CycleSink {
 public:
  virtual ~CycleSink() = default;
  // Called in the recording thread: must not allocate in staad (a ring push).
  virtual void take(std::span<const std::byte> record) = 0;
};

class CycleRecorder {
 public:
  CycleRecorder(const RecordLimits& limits, CycleSink& sink, std::uint16_t agent = 0);

  // A new ControlCycle from the next step on (staad: a map swapped in).
  void newCycle() { flags_ |= kNewCycle; }
  // A pose correction handed to the base before the next step.
  void poseCorrected() { flags_ |= kPoseCorrected; }

  // Before the step: notes the cycle's memory (and a goal set since the last record) and
  // returns `budget` with its clock tapped
  // (a wall-clock budget's clock must be `clock`, the real one: the tap reads it).
  PlannerBudget before(const ControlCycle& cycle, const BudgetSpec& spec, ClockFn clock);
  // The moving obstacles the step will see, as handed to DynamicObstacleSet::set; the spans
  // must stay valid until after().
  void obstacles(const ObstacleInputs& inputs) { obstacles_ = inputs; }

  // After the step (out: null when staad did not step: a fault or a stop).
  void after(const ControlCycle& cycle, std::int64_t time_ns, const UnicycleState& robot, StepKind step,
             std::uint8_t fault, const CycleOutput* out, const CommandRecord& command, std::uint32_t map_sequence = 0);

  std::uint64_t cycles() const { return cycle_; }
  std::uint64_t failed() const { return failed_; }  // records that did not fit their buffer (never expected)
  std::span<const std::byte> lastRecord() const { return {buffer_.data(), last_size_}; }

 private:
  RecordLimits limits_;
  CycleSink& sink_;
  std::uint16_t agent_;
  std::vector<std::byte> buffer_;
  std::size_t last_size_ = 0;
  std::uint64_t cycle_ = 0;
  std::uint64_t failed_ = 0;
  std::uint8_t flags_ = 0;
  std::uint64_t goal_changes_ = 0;  // ControlCycle::goalChanges() at the last record
  ControlCycle::Memory memory_;
  bool fresh_ = false;
  PlannerBudget budget_;
  ObstacleInputs obstacles_;
};

// Writes each cycle straight to a file (staa-sim --record: several agents, one file).
class FileSink final : public CycleSink {
 public:
  explicit FileSink(RecordingFile& file) : file_(file) {}
  void take(std::span<const std::byte> record) override { file_.add(record); }

 private:
  RecordingFile& file_;
};

struct RecorderOptions {
  std::filesystem::path path;            // continuous recording (rotating files); empty: off
  std::uint64_t max_file_bytes = 64ull << 20;
  std::size_t max_files = 8;             // continuous files kept (the oldest deleted)
  double seconds = 30.0;                 // history kept for saves and fault files
  std::filesystem::path fault_dir;       // fault files; empty: off
  double fault_after_s = 2.0;            // cycles after the fault in its file
  std::size_t ring_bytes = 4u << 20;     // control -> service
};

// What the service thread reports of the recorder (staactl status).
struct RecorderStats {
  std::uint64_t cycles = 0;          // records taken from the ring
  std::uint64_t bytes_written = 0;   // to continuous files
  std::uint64_t files = 0;           // continuous files started
  std::uint64_t fault_files = 0;
  std::uint64_t write_failures = 0;
  std::string current_file;
  std::string last_fault_file;
  std::string last_error;
};

class RecordingService {
 public:
  // `warn` logs a warning line (the daemon's log); called on each new write failure.
  RecordingService(Session session, RecorderOptions options, std::function<void(const std::string&)> warn);
  ~RecordingService();

  // One encoded cycle from the ring.
  void take(std::span<const std::byte> record);
  // The history (the last `seconds`) into `file`, written in the background (a save still
  // being written is finished first); the error (nothing recorded yet), or empty.
  std::string save(const std::filesystem::path& file);
  // Waits for a file being written in the background.
  void finishWrites();
  // Finishes the files (a pending fault file with what it has).
  void close();

  const RecorderStats& stats() const { return stats_; }
  const Session& session() const { return session_; }
  const RecorderOptions& options() const { return options_; }

 private:
  struct Entry {
    std::int64_t time_ns;
    std::vector<std::byte> bytes;
  };
  void continuous(std::span<const std::byte> record, std::int64_t time_ns);
  // Starts writing the history from `from_ns` into `file` on the worker thread.
  void writeHistory(const std::filesystem::path& file, std::int64_t from_ns, bool fault);
  void collectWrite();  // the worker's result, once it is done
  void failed(const std::string& what);
  void writeFaultFile();
  std::filesystem::path nextContinuousPath();

  Session session_;
  RecorderOptions options_;
  std::function<void(const std::string&)> warn_;
  std::deque<Entry> history_;
  std::unique_ptr<RecordingFile> file_;
  std::deque<std::filesystem::path> written_;  // continuous files, oldest first
  std::int64_t retry_after_ns_ = 0;            // a failed continuous file is retried after this
  std::uint8_t last_fault_ = 0;
  std::optional<std::int64_t> fault_at_;       // a fault file waits for fault_after_s more
  std::string fault_kind_;
  std::uint64_t file_index_ = 0;
  RecorderStats stats_;
  bool failing_ = false;
  struct Write {
    std::filesystem::path file;
    bool fault = false;
    std::future<std::string> error;  // empty: written
  };
  std::optional<Write> write_;
};

}  // namespace staa::record

namespace staa::record {

// A simulated run recorded straight to one file (staa-sim --record): one CycleRecorder per
// agent, events (contacts) beside them.
class SimRecording {
 public:
  // `session` complete (control, robot, map, agents); throws RecordError when the file
  // cannot be opened.
  SimRecording(const std::filesystem::path& path, const Session& session, const RecordLimits& limits);
  CycleRecorder& agent(std::size_t index) { return *recorders_.at(index); }
  void event(const std::string& topic, std::int64_t time_ns, const std::string& json) { file_.event(topic, time_ns, json); }
  // Finishes the file; throws RecordError when writing failed.
  void close();

 private:
  RecordingFile file_;
  FileSink sink_;
  std::vector<std::unique_ptr<CycleRecorder>> recorders_;
};

// Simulated seconds as the recording's nanoseconds.
inline std::int64_t simNanos(double seconds) { return static_cast<std::int64_t>(std::llround(seconds * 1e9)); }

}  // namespace staa::record
