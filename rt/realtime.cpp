#include "rt/realtime.hpp"

#include "rt/errors.hpp"

#include <alloca.h>
#include <algorithm>
#include <cerrno>
#include <condition_variable>
#include <cstdio>
#include <cstdlib>
#include <cstdint>
#include <cstring>
#include <exception>
#include <limits.h>
#include <malloc.h>
#include <mutex>
#include <optional>
#include <pthread.h>
#include <sched.h>
#include <stdexcept>
#include <sys/mman.h>
#include <sys/resource.h>
#include <system_error>
#include <unistd.h>

#if defined(__SANITIZE_ADDRESS__)
#define STAA_RT_ASAN 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define STAA_RT_ASAN 1
#endif
#endif

namespace staa::rt {

namespace {

// Kept free below the prefaulted part of a stack: the frames of the prefault itself, a
// signal handler, and glibc's own use of the stack.
constexpr std::size_t kStackMargin = 32 * 1024;
// Added to a thread's requested stack (besides what glibc takes at its top, measured below):
// the trampoline's frames above the body's, and kStackMargin.
constexpr std::size_t kStackHeadroom = 64 * 1024;
constexpr std::size_t kThreadNameMax = 15;  // pthread_setname_np: 16 bytes with the NUL
constexpr unsigned kCapIpcLockBit = 14;   // linux/capability.h: CAP_IPC_LOCK

std::size_t pageSize() {
  const long p = ::sysconf(_SC_PAGESIZE);
  return p > 0 ? static_cast<std::size_t>(p) : 4096;
}

// Bytes of the calling thread's stack below this frame that may be touched, or nullopt when
// the stack's bounds are unknown.
std::optional<std::size_t> stackRoom() {
  pthread_attr_t attr;
  if (::pthread_getattr_np(::pthread_self(), &attr) != 0) return std::nullopt;
  void* low = nullptr;
  std::size_t size = 0;
  const int rc = ::pthread_attr_getstack(&attr, &low, &size);
  ::pthread_attr_destroy(&attr);
  if (rc != 0 || low == nullptr) return std::nullopt;
  // The real frame, not a local's address (which a sanitizer may move to a fake stack).
  const auto here = reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0));
  const auto bottom = reinterpret_cast<std::uintptr_t>(low);
  if (here <= bottom + kStackMargin) return 0;
  return here - bottom - kStackMargin;
}

// Bytes of the calling thread's stack from its top down to this frame.
[[gnu::noinline]] std::size_t stackUsedAbove() {
  pthread_attr_t attr;
  if (::pthread_getattr_np(::pthread_self(), &attr) != 0) return 0;
  void* low = nullptr;
  std::size_t size = 0;
  const int rc = ::pthread_attr_getstack(&attr, &low, &size);
  ::pthread_attr_destroy(&attr);
  if (rc != 0) return 0;
  const auto high = reinterpret_cast<std::uintptr_t>(low) + size;
  const auto here = reinterpret_cast<std::uintptr_t>(__builtin_frame_address(0));
  return here < high ? high - here : 0;
}

// What a new thread's stack loses before its start routine runs: glibc carves the thread
// descriptor and the static TLS of every loaded module out of the stack allocation, so a
// large thread_local anywhere in the program (or a sanitizer's per-thread state) shrinks every
// thread's stack. Measured once, with a probe thread; 0 when the probe cannot run.
std::size_t stackTopOverhead() {
  static const std::size_t overhead = [] {
    std::size_t measured = 0;
    pthread_t probe;
    auto measure = [](void* out) -> void* {
      *static_cast<std::size_t*>(out) = stackUsedAbove();
      return nullptr;
    };
    if (::pthread_create(&probe, nullptr, measure, &measured) != 0) return std::size_t{0};
    ::pthread_join(probe, nullptr);
    return measured;
  }();
  return overhead;
}

// Touches `bytes` of stack below the caller, one write per page, from the top down (the
// direction the stack grows). alloca instead of recursion or a fixed array: one frame of
// exactly the size asked for.
[[gnu::noinline]] void touchStack(std::size_t bytes) {
  if (bytes == 0) return;
  auto* p = static_cast<volatile char*>(alloca(bytes));
  const std::size_t page = pageSize();
  for (std::size_t off = bytes; off > 0; off = off > page ? off - page : 0) p[off - 1] = 0;
  p[0] = 0;
}

// Prefaults up to `bytes` of the calling thread's stack; returns a warning line, or "".
std::string prefaultStack(std::size_t bytes, const std::string& who) {
  if (bytes == 0) return "";
  const std::optional<std::size_t> room = stackRoom();
  if (!room) {
    touchStack(std::min<std::size_t>(bytes, 64 * 1024));  // bounds unknown: only what is surely there
    return who + ": stack bounds unknown (pthread_getattr_np failed); prefaulted 64 KiB, not " +
           std::to_string(bytes) + " bytes";
  }
  if (bytes > *room) {
    touchStack(*room);
    return who + ": stack prefault of " + std::to_string(bytes) + " bytes exceeds the stack left (" +
           std::to_string(*room) + " bytes); prefaulted that";
  }
  touchStack(bytes);
  return "";
}

// When memory is already being locked (VmLck > 0: an earlier mlockall with MCL_FUTURE), the
// bytes that may still be locked under RLIMIT_MEMLOCK; nullopt when nothing is locked yet or
// no limit applies (unlimited, or CAP_IPC_LOCK).
std::optional<std::size_t> futureLockBudget() {
  rlimit limit{};
  if (::getrlimit(RLIMIT_MEMLOCK, &limit) != 0 || limit.rlim_cur == RLIM_INFINITY) return std::nullopt;
  std::FILE* status = std::fopen("/proc/self/status", "re");
  if (status == nullptr) return std::nullopt;
  std::optional<std::size_t> locked_kib;
  bool ipc_lock = false;
  char line[256];
  while (std::fgets(line, sizeof line, status) != nullptr) {
    unsigned long long value = 0;
    if (std::sscanf(line, "VmLck: %llu kB", &value) == 1) locked_kib = static_cast<std::size_t>(value);
    if (std::sscanf(line, "CapEff: %llx", &value) == 1) ipc_lock = (value >> kCapIpcLockBit) & 1U;
  }
  std::fclose(status);
  if (!locked_kib || *locked_kib == 0 || ipc_lock) return std::nullopt;
  const std::size_t locked = *locked_kib * 1024;
  return limit.rlim_cur > locked ? static_cast<std::size_t>(limit.rlim_cur) - locked : 0;
}

std::string threadLabel(const std::string& name) { return "thread " + name; }

// Owns a pthread_attr_t so that every exit path destroys it.
class Attr {
 public:
  explicit Attr(const std::string& who) {
    if (const int rc = ::pthread_attr_init(&attr_); rc != 0) {
      throw std::system_error(rc, std::generic_category(), who + ": pthread_attr_init");
    }
  }
  Attr(const Attr&) = delete;
  Attr& operator=(const Attr&) = delete;
  ~Attr() { ::pthread_attr_destroy(&attr_); }
  pthread_attr_t* get() { return &attr_; }

 private:
  pthread_attr_t attr_;
};

// Handed from start() to the new thread: the thread reports what it achieved, then start()
// returns. Lives on start()'s stack; the thread stops touching it once `done` is set.
struct Startup {
  RtThread* self = nullptr;
  std::string name;
  int cpu = -1;
  std::mutex mutex;
  std::condition_variable cv;
  bool done = false;
  bool realtime = false;
  bool pinned = false;
  std::string warning;
};

void appendWarning(std::string& to, const std::string& line) {
  if (line.empty()) return;
  if (!to.empty()) to += "; ";
  to += line;
}

}  // namespace

MemoryReport lockMemory(std::size_t heap_bytes, std::size_t stack_bytes) {
  MemoryReport report;

  // Never give freed heap back to the kernel and never serve a request by mmap: memory the
  // cycle frees and allocates again stays mapped (and locked), so it never faults again.
  const bool no_trim = ::mallopt(M_TRIM_THRESHOLD, -1) == 1;
  const bool no_mmap = ::mallopt(M_MMAP_MAX, 0) == 1;
  report.malloc_tuned = no_trim && no_mmap;
  if (!report.malloc_tuned) {
    report.warnings.push_back(
        "mallopt(M_TRIM_THRESHOLD, M_MMAP_MAX) refused (not glibc's malloc, or a sanitizer's): freed heap may "
        "return to the kernel and fault again");
  }

  // Pages already being locked (an earlier mlockall with MCL_FUTURE): every page faulted in
  // now is locked on the spot, and past RLIMIT_MEMLOCK the kernel refuses it, which on the
  // stack is a SIGSEGV. Stay within what may still be locked.
  if (const std::optional<std::size_t> budget = futureLockBudget()) {
    if (heap_bytes + stack_bytes > *budget) {
      report.warnings.push_back("prefault of " + std::to_string(heap_bytes) + " heap + " +
                                std::to_string(stack_bytes) + " stack bytes exceeds what RLIMIT_MEMLOCK still allows (" +
                                std::to_string(*budget) + " bytes; memory is already locked); prefaulting that");
      heap_bytes = std::min(heap_bytes, *budget);
      stack_bytes = std::min(stack_bytes, *budget - heap_bytes);
    }
  }

  // Prefault first, lock after: mlockall(MCL_CURRENT) then locks the touched heap and stack
  // too, or, when they exceed RLIMIT_MEMLOCK, fails cleanly with ENOMEM. Locking first would
  // make the later growth fail instead (a failed malloc, or a SIGSEGV on the stack).
  if (heap_bytes > 0) {
    // Allocated, touched and freed: with trimming off the pages stay in the process as free
    // heap, already faulted in.
    void* p = std::malloc(heap_bytes);
    if (p == nullptr) {
      report.warnings.push_back("heap prefault: malloc(" + std::to_string(heap_bytes) + ") failed");
    } else {
      auto* bytes = static_cast<volatile char*>(p);
      const std::size_t page = pageSize();
      for (std::size_t off = 0; off < heap_bytes; off += page) bytes[off] = 0;
      bytes[heap_bytes - 1] = 0;
      std::free(p);
      report.heap_prefaulted = heap_bytes;
    }
  }
  const std::string stack_warning = prefaultStack(stack_bytes, "main stack");
  if (!stack_warning.empty()) report.warnings.push_back(stack_warning);

#if defined(STAA_RT_ASAN)
  // AddressSanitizer reserves terabytes of shadow memory: locking it fails or takes forever.
  report.warnings.push_back("mlockall skipped: built with AddressSanitizer (its shadow memory cannot be locked)");
#else
  if (::mlockall(MCL_CURRENT | MCL_FUTURE) == 0) {
    report.locked = true;
  } else {
    const int err = errno;
    report.warnings.push_back("mlockall(MCL_CURRENT | MCL_FUTURE): " + describeErrno(err) +
                              "; memory not locked, page faults may stall real-time threads (raise "
                              "RLIMIT_MEMLOCK, e.g. LimitMEMLOCK=infinity, or grant CAP_IPC_LOCK)");
  }
#endif
  return report;
}

struct RtThread::Native {
  pthread_t thread{};
};

RtThread::RtThread() : native_(std::make_unique<Native>()) {}

RtThread::~RtThread() {
  try {
    join();
  } catch (const std::exception& e) {
    // A destructor must not throw; the failure is still worth a line.
    std::fprintf(stderr, "RtThread: %s\n", e.what());
  }
}

void RtThread::start(const ThreadSpec& spec, std::function<void()> body) {
  const std::string who = threadLabel(spec.name);
  if (started_) throw std::logic_error(who + ": start() while already running");
  if (!body) throw std::invalid_argument(who + ": empty body");

  warning_.clear();
  realtime_ = false;
  pinned_ = false;
  stack_bytes_ = spec.stack_bytes;
  body_ = std::move(body);

  if (spec.stack_bytes > (std::size_t{1} << 40)) {  // a typo or a negative number converted
    throw std::invalid_argument(who + ": stack_bytes " + std::to_string(spec.stack_bytes) + " is not a stack size");
  }
  std::string warning;
  const std::size_t page = pageSize();
  std::size_t stack_size =
      std::max<std::size_t>(spec.stack_bytes + stackTopOverhead() + kStackHeadroom, PTHREAD_STACK_MIN);
  stack_size = (stack_size + page - 1) / page * page;

  // Builds the attributes; with `fifo`, explicit SCHED_FIFO at the priority. Returns the
  // error of a refused scheduling attribute (EINVAL: priority out of range), else 0.
  auto configure = [&](Attr& attr, bool fifo) -> int {
    if (const int rc = ::pthread_attr_setstacksize(attr.get(), stack_size); rc != 0) {
      throw std::system_error(rc, std::generic_category(),
                              who + ": pthread_attr_setstacksize(" + std::to_string(stack_size) + ")");
    }
    if (!fifo) return 0;
    if (const int rc = ::pthread_attr_setinheritsched(attr.get(), PTHREAD_EXPLICIT_SCHED); rc != 0) return rc;
    if (const int rc = ::pthread_attr_setschedpolicy(attr.get(), SCHED_FIFO); rc != 0) return rc;
    sched_param param{};
    param.sched_priority = spec.priority;
    return ::pthread_attr_setschedparam(attr.get(), &param);
  };

  Startup startup;
  startup.self = this;
  startup.name = spec.name.substr(0, kThreadNameMax);
  startup.cpu = spec.cpu;

  if (spec.priority < 0) {
    appendWarning(warning, who + ": priority " + std::to_string(spec.priority) +
                               " is not a SCHED_FIFO priority (1..99, or 0 for normal); running with normal "
                               "scheduling");
  }
  const bool want_fifo = spec.priority > 0;
  int rc = 0;
  int refused = 0;  // why SCHED_FIFO was refused, 0 when it was not
  {
    Attr attr(who);
    refused = configure(attr, want_fifo);
    if (refused == 0) {
      rc = ::pthread_create(&native_->thread, attr.get(), &RtThread::trampoline, &startup);
      if (want_fifo && (rc == EPERM || rc == EINVAL)) {
        refused = rc;  // no CAP_SYS_NICE / RLIMIT_RTPRIO, or no real-time runtime in this cgroup
      }
    }
  }
  if (refused != 0) {
    appendWarning(warning, who + ": SCHED_FIFO priority " + std::to_string(spec.priority) + " not permitted (" +
                               describeErrno(refused) + "); running with normal scheduling");
    Attr attr(who);
    configure(attr, false);
    rc = ::pthread_create(&native_->thread, attr.get(), &RtThread::trampoline, &startup);
  }
  if (rc != 0) {
    body_ = nullptr;
    throw std::system_error(rc, std::generic_category(), who + ": pthread_create");
  }
  started_ = true;

  // Wait until the thread has named, pinned and prefaulted itself: realtime() and pinned()
  // then report what is really in effect.
  std::unique_lock lock(startup.mutex);
  startup.cv.wait(lock, [&] { return startup.done; });
  realtime_ = startup.realtime;
  pinned_ = startup.pinned;
  appendWarning(warning, startup.warning);
  warning_ = std::move(warning);
}

void RtThread::join() {
  if (!started_) return;
  if (::pthread_equal(native_->thread, ::pthread_self()) != 0) {
    throw std::system_error(EDEADLK, std::generic_category(), "RtThread: join() from the thread itself");
  }
  if (const int rc = ::pthread_join(native_->thread, nullptr); rc != 0) {
    throw std::system_error(rc, std::generic_category(), "RtThread: pthread_join");
  }
  started_ = false;
  body_ = nullptr;  // releases what the body captured
}

void* RtThread::trampoline(void* arg) {
  auto* startup = static_cast<Startup*>(arg);
  RtThread* self = startup->self;
  const std::string who = threadLabel(startup->name);
  std::string warning;

  if (const int rc = ::pthread_setname_np(::pthread_self(), startup->name.c_str()); rc != 0) {
    appendWarning(warning, who + ": pthread_setname_np: " + describeErrno(rc));
  }

  bool pinned = false;
  if (startup->cpu >= 0) {
    const long cpus = ::sysconf(_SC_NPROCESSORS_CONF);
    if (startup->cpu >= CPU_SETSIZE || (cpus > 0 && startup->cpu >= cpus)) {
      appendWarning(warning, who + ": CPU " + std::to_string(startup->cpu) + " does not exist (this machine has " +
                                 std::to_string(cpus) + "); not pinned");
    } else {
      cpu_set_t set;
      CPU_ZERO(&set);
      CPU_SET(startup->cpu, &set);
      if (const int rc = ::pthread_setaffinity_np(::pthread_self(), sizeof set, &set); rc != 0) {
        appendWarning(warning, who + ": pinning to CPU " + std::to_string(startup->cpu) +
                                   " refused (pthread_setaffinity_np: " + describeErrno(rc) + "); not pinned");
      } else {
        pinned = true;
      }
    }
  }

  // What is really in effect, not what was asked for.
  int policy = SCHED_OTHER;
  sched_param param{};
  bool realtime = false;
  if (const int rc = ::pthread_getschedparam(::pthread_self(), &policy, &param); rc != 0) {
    appendWarning(warning, who + ": pthread_getschedparam: " + describeErrno(rc));
  } else {
    realtime = policy == SCHED_FIFO;
  }

  appendWarning(warning, prefaultStack(self->stack_bytes_, who));

  {
    std::lock_guard lock(startup->mutex);
    startup->realtime = realtime;
    startup->pinned = pinned;
    startup->warning = std::move(warning);
    startup->done = true;
    // Notified under the lock: start() may destroy `startup` as soon as it sees `done`.
    startup->cv.notify_one();
  }

  try {
    self->body_();
  } catch (const std::exception& e) {
    // Still fatal (std::terminate), but the log says which thread.
    std::fprintf(stderr, "%s: uncaught exception: %s\n", who.c_str(), e.what());
    throw;
  }
  return nullptr;
}

std::string setThisThreadNice(int nice) {
  // On Linux the nice value is per thread: PRIO_PROCESS with the thread's id.
  const auto tid = static_cast<id_t>(::gettid());
  if (::setpriority(PRIO_PROCESS, tid, nice) != 0) {
    const int e = errno;
    return "nice " + std::to_string(nice) + " refused: " + std::strerror(e);
  }
  return {};
}

}  // namespace staa::rt
