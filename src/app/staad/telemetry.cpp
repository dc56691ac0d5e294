#include "app/staad/telemetry.hpp"

#include <cerrno>
#include <cstring>
#include <stdexcept>

namespace staa::staad {

namespace {
std::size_t roundUpPowerOfTwo(std::size_t n) {
  std::size_t p = 2;
  while (p < n) p <<= 1;
  return p;
}
}  // namespace

TelemetryRing::TelemetryRing(std::size_t min_capacity)
    : slots_(std::make_unique<TelemetryRecord[]>(roundUpPowerOfTwo(min_capacity))),
      mask_(roundUpPowerOfTwo(min_capacity) - 1) {}

bool TelemetryRing::push(const TelemetryRecord& record) {
  const std::size_t head = head_.load(std::memory_order_relaxed);
  if (head - tail_.load(std::memory_order_acquire) > mask_) {
    dropped_.fetch_add(1, std::memory_order_relaxed);
    return false;
  }
  slots_[head & mask_] = record;
  head_.store(head + 1, std::memory_order_release);
  return true;
}

bool TelemetryRing::pop(TelemetryRecord& out) {
  const std::size_t tail = tail_.load(std::memory_order_relaxed);
  if (tail == head_.load(std::memory_order_acquire)) return false;
  out = slots_[tail & mask_];
  tail_.store(tail + 1, std::memory_order_release);
  return true;
}

const char* telemetryHeader() { return "t_s,x,y,theta,v,w,v_cmd,w_cmd,expansions,depth,budget_used_ms,overrun"; }

std::string formatTelemetryRow(const TelemetryRecord& r) {
  char line[256];
  const int n = std::snprintf(line, sizeof line, "%.6f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%.4f,%u,%d,%.3f,%d", r.t_s, r.x, r.y,
                              r.theta, r.v, r.w, r.v_cmd, r.w_cmd, static_cast<unsigned>(r.expansions),
                              static_cast<int>(r.depth), r.budget_used_ms, r.overrun ? 1 : 0);
  return std::string(line, n > 0 ? static_cast<std::size_t>(n) : 0u);
}

TelemetryWriter::~TelemetryWriter() { close(); }

void TelemetryWriter::open(const std::filesystem::path& path) {
  close();
  file_ = std::fopen(path.c_str(), "w");
  if (file_ == nullptr) {
    std::string message = "telemetry file ";
    message.append(path.string()).append(": ").append(std::strerror(errno));
    throw std::runtime_error(message);
  }
  path_ = path;
  rows_ = 0;
  std::fputs(telemetryHeader(), file_);
  std::fputc('\n', file_);
}

void TelemetryWriter::write(const TelemetryRecord& record) {
  if (file_ == nullptr) return;
  const std::string row = formatTelemetryRow(record);
  std::fwrite(row.data(), 1, row.size(), file_);
  std::fputc('\n', file_);
  ++rows_;
}

void TelemetryWriter::flush() {
  if (file_ != nullptr) std::fflush(file_);
}

void TelemetryWriter::close() {
  if (file_ == nullptr) return;
  std::fclose(file_);
  file_ = nullptr;
}

}  // namespace staa::staad
