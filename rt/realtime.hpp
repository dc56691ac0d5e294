#pragma once
// Real-time set-up of the process and its threads (docs/ARCHITECTURE.md section 3), in the order
// the daemon calls it: (1) config loaded and every workspace created, (2) lockMemory(),
// (3) threads started (RtThread, or a PeriodicActivity that owns one), (4) READY=1. Every
// pthread_* return code is checked as a return value (they do not set errno).

#include <cstddef>
#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace staa::rt {

struct MemoryReport {
  bool locked = false;       // mlockall(MCL_CURRENT | MCL_FUTURE) succeeded
  bool malloc_tuned = false; // M_TRIM_THRESHOLD / M_MMAP_MAX set (no trimming, no mmap)
  std::size_t heap_prefaulted = 0;
  std::vector<std::string> warnings;  // one line each, for the log (e.g. mlockall: EPERM ...)
};

// Tunes malloc (mallopt: never trim the heap, never serve a request by mmap), locks all
// current and future pages, and prefaults `heap_bytes` of heap (allocated, touched, freed:
// it stays in the process, locked) and `stack_bytes` of the calling thread's stack.
MemoryReport lockMemory(std::size_t heap_bytes, std::size_t stack_bytes);

// Sets the calling thread's nice value (-20..19; normal scheduling's share of the CPU).
// Returns an empty string, or why it was refused (a lower value needs CAP_SYS_NICE or
// RLIMIT_NICE, systemd's LimitNICE=).
std::string setThisThreadNice(int nice);

struct ThreadSpec {
  std::string name;                      // <= 15 characters (pthread_setname_np)
  int priority = 0;                      // SCHED_FIFO priority 1..99; 0: normal scheduling
  int cpu = -1;                          // CPU to pin to; -1: any
  std::size_t stack_bytes = 512 * 1024;  // prefaulted by the thread before its body runs
};

// A thread started with explicit attributes (PTHREAD_EXPLICIT_SCHED, SCHED_FIFO at the
// priority, affinity). When real-time scheduling is not permitted (EPERM), it starts with
// normal scheduling instead and warning() says so in one line; other failures throw
// std::system_error naming the thread and the call.
class RtThread {
 public:
  RtThread();
  RtThread(const RtThread&) = delete;
  RtThread& operator=(const RtThread&) = delete;
  ~RtThread();  // joins

  void start(const ThreadSpec& spec, std::function<void()> body);
  void join();
  bool running() const { return started_; }
  bool realtime() const { return realtime_; }   // runs under SCHED_FIFO
  bool pinned() const { return pinned_; }
  const std::string& warning() const { return warning_; }

 private:
  struct Native;  // the pthread_t, kept out of this header
  static void* trampoline(void* self);
  std::unique_ptr<Native> native_;
  bool started_ = false;
  bool realtime_ = false;
  bool pinned_ = false;
  std::size_t stack_bytes_ = 0;
  std::string warning_;
  std::function<void()> body_;
};

}  // namespace staa::rt
