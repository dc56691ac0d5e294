#include "ros/support/ros_master.hpp"

#include "child_process.hpp"
#include "read_file.hpp"
#include "temp_dir.hpp"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <stdexcept>
#include <thread>

namespace staa::test {

namespace {

using std::chrono::milliseconds;
using Clock = std::chrono::steady_clock;

std::runtime_error systemError(const std::string& what) {
  return std::runtime_error(what + ": " + std::strerror(errno));
}

// The program's path: `name` itself when it has a slash, else the first match on PATH.
std::string findProgram(const std::string& name) {
  if (name.find('/') != std::string::npos) return name;
  const char* path = std::getenv("PATH");
  std::string_view rest = path != nullptr ? path : "/usr/bin:/bin";
  while (!rest.empty()) {
    const std::size_t colon = rest.find(':');
    const std::filesystem::path candidate = std::filesystem::path(rest.substr(0, colon)) / name;
    if (::access(candidate.c_str(), X_OK) == 0) return candidate.string();
    rest = colon == std::string_view::npos ? std::string_view{} : rest.substr(colon + 1);
  }
  throw std::runtime_error("program '" + name + "' not found on PATH");
}

std::vector<std::string> completeLines(const std::string& text) {
  std::vector<std::string> lines;
  std::size_t start = 0;
  for (std::size_t nl = text.find('\n'); nl != std::string::npos; nl = text.find('\n', start)) {
    lines.push_back(text.substr(start, nl - start));
    start = nl + 1;
  }
  return lines;
}

// ---- a minimal XML-RPC client: HTTP/1.0 POST, the response's value parsed into a tree ----

struct XmlRpcValue {
  std::string text;                 // a scalar's text (strings unescaped)
  std::vector<XmlRpcValue> items;   // an array's elements
  bool is_array = false;
};

std::string xmlEscape(std::string_view s) {
  std::string out;
  for (const char c : s) {
    if (c == '<') out += "&lt;";
    else if (c == '>') out += "&gt;";
    else if (c == '&') out += "&amp;";
    else out += c;
  }
  return out;
}

std::string xmlUnescape(std::string_view s) {
  static const std::pair<std::string_view, char> kEntities[] = {
      {"&lt;", '<'}, {"&gt;", '>'}, {"&amp;", '&'}, {"&quot;", '"'}, {"&apos;", '\''}};
  std::string out;
  for (std::size_t i = 0; i < s.size();) {
    bool replaced = false;
    for (const auto& [entity, c] : kEntities) {
      if (s.substr(i, entity.size()) == entity) {
        out += c;
        i += entity.size();
        replaced = true;
        break;
      }
    }
    if (!replaced) out += s[i++];
  }
  return out;
}

class XmlRpcParser {
 public:
  explicit XmlRpcParser(std::string_view body) : s_(body) {}

  // The first value of the response's params.
  XmlRpcValue response() {
    pos_ = s_.find("<param>");
    if (pos_ == std::string_view::npos) throw std::runtime_error("XML-RPC response without <param>");
    pos_ += 7;
    return value();
  }

 private:
  void skipSpace() {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\n' || s_[pos_] == '\r' || s_[pos_] == '\t')) ++pos_;
  }
  bool accept(std::string_view tag) {
    skipSpace();
    if (s_.substr(pos_, tag.size()) != tag) return false;
    pos_ += tag.size();
    return true;
  }
  void expect(std::string_view tag) {
    if (!accept(tag)) {
      throw std::runtime_error("XML-RPC response: expected " + std::string(tag) + " at byte " + std::to_string(pos_));
    }
  }
  std::string_view until(std::string_view end) {
    const std::size_t at = s_.find(end, pos_);
    if (at == std::string_view::npos) throw std::runtime_error("XML-RPC response: no " + std::string(end));
    const std::string_view text = s_.substr(pos_, at - pos_);
    pos_ = at + end.size();
    return text;
  }
  XmlRpcValue value() {
    expect("<value>");
    XmlRpcValue v;
    if (accept("<array>")) {
      v.is_array = true;
      expect("<data>");
      while (!accept("</data>")) v.items.push_back(value());
      expect("</array>");
      expect("</value>");
      return v;
    }
    static const std::pair<std::string_view, std::string_view> kScalars[] = {
        {"<string>", "</string>"}, {"<int>", "</int>"}, {"<i4>", "</i4>"},
        {"<boolean>", "</boolean>"}, {"<double>", "</double>"}};
    for (const auto& [open, close] : kScalars) {
      if (accept(open)) {
        v.text = xmlUnescape(until(close));
        expect("</value>");
        return v;
      }
    }
    v.text = xmlUnescape(until("</value>"));  // a bare value is a string
    return v;
  }

  std::string_view s_;
  std::size_t pos_ = 0;
};

std::optional<std::string> httpPost(int port, const std::string& body, milliseconds timeout) {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) return std::nullopt;
  timeval tv{};
  tv.tv_sec = static_cast<time_t>(timeout.count() / 1000);
  tv.tv_usec = static_cast<suseconds_t>((timeout.count() % 1000) * 1000);
  ::setsockopt(fd, SOL_SOCKET, SO_RCVTIMEO, &tv, sizeof tv);
  ::setsockopt(fd, SOL_SOCKET, SO_SNDTIMEO, &tv, sizeof tv);
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_port = htons(static_cast<std::uint16_t>(port));
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  std::optional<std::string> response;
  if (::connect(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) == 0) {
    const std::string request = "POST /RPC2 HTTP/1.0\r\nHost: 127.0.0.1\r\nContent-Type: text/xml\r\nContent-Length: " +
                                std::to_string(body.size()) + "\r\n\r\n" + body;
    bool sent = true;
    for (std::size_t off = 0; sent && off < request.size();) {
      const ssize_t n = ::send(fd, request.data() + off, request.size() - off, MSG_NOSIGNAL);
      sent = n > 0;
      if (sent) off += static_cast<std::size_t>(n);
    }
    std::string in;
    char buf[4096];
    ssize_t n = 0;
    while (sent && (n = ::recv(fd, buf, sizeof buf, 0)) > 0) in.append(buf, static_cast<std::size_t>(n));
    // HTTP/1.0: the server closes after the response; a timeout (n < 0) leaves it incomplete.
    const std::size_t header_end = in.find("\r\n\r\n");
    if (sent && n == 0 && in.rfind("HTTP/1.", 0) == 0 && in.find(" 200 ") != std::string::npos &&
        header_end != std::string::npos) {
      response = in.substr(header_end + 4);
    }
  }
  ::close(fd);
  return response;
}

// getSystemState's publishers (index 0) or subscribers (1) of `topic`.
std::vector<std::string> nodesOf(const RosMaster& master, const std::string& topic, std::size_t which) {
  const std::optional<std::string> body = master.call("getSystemState", {"/staa_test"});
  if (!body) return {};
  const XmlRpcValue r = XmlRpcParser(*body).response();  // [code, status, [pubs, subs, services]]
  if (!r.is_array || r.items.size() < 3 || r.items[0].text != "1" || r.items[2].items.size() < 2) return {};
  for (const XmlRpcValue& entry : r.items[2].items[which].items) {
    if (entry.items.size() == 2 && entry.items[0].text == topic) {
      std::vector<std::string> nodes;
      for (const XmlRpcValue& node : entry.items[1].items) nodes.push_back(node.text);
      return nodes;
    }
  }
  return {};
}

template <class Predicate>
bool pollUntil(milliseconds timeout, Predicate done) {
  const auto deadline = Clock::now() + timeout;
  while (!done()) {
    if (Clock::now() >= deadline) return false;
    std::this_thread::sleep_for(milliseconds(10));
  }
  return true;
}

std::atomic<int> g_master_count{0};

}  // namespace

// ---------------------------------------------------------------------------------------------

RosProcess::RosProcess(const std::vector<std::string>& argv, const std::vector<std::string>& env,
                       const std::filesystem::path& out, const std::filesystem::path& err)
    : out_(out), err_(err) {
  if (argv.empty()) throw std::runtime_error("RosProcess: empty argv");
  // Everything the child needs is prepared before fork: after it, only async-signal-safe calls.
  const std::string program = findProgram(argv[0]);
  std::vector<char*> args;
  for (const std::string& a : argv) args.push_back(const_cast<char*>(a.c_str()));
  args.push_back(nullptr);
  std::vector<char*> envp;
  for (const std::string& e : env) envp.push_back(const_cast<char*>(e.c_str()));
  envp.push_back(nullptr);
  const int out_fd = ::open(out.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const int err_fd = ::open(err.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
  const int null_fd = ::open("/dev/null", O_RDONLY | O_CLOEXEC);
  int status_pipe[2] = {-1, -1};  // the child's errno when exec fails; closed by a good exec
  if (out_fd < 0 || err_fd < 0 || null_fd < 0 || ::pipe2(status_pipe, O_CLOEXEC) != 0) {
    const auto e = systemError("RosProcess: cannot open " + out.string() + " / " + err.string());
    for (const int fd : {out_fd, err_fd, null_fd, status_pipe[0], status_pipe[1]}) {
      if (fd >= 0) ::close(fd);
    }
    throw e;
  }
  const pid_t parent = ::getpid();
  const pid_t pid = ::fork();
  if (pid == 0) {
    // Its own group (killed as one); killed with the test when the test process dies, so a
    // test killed by ctest's timeout leaves no master behind.
    ::setpgid(0, 0);
    ::prctl(PR_SET_PDEATHSIG, SIGKILL);
    if (::getppid() != parent) ::_exit(127);
    sigset_t none;
    sigemptyset(&none);
    ::sigprocmask(SIG_SETMASK, &none, nullptr);
    for (const int sig : {SIGINT, SIGTERM, SIGUSR1, SIGUSR2, SIGHUP, SIGPIPE}) ::signal(sig, SIG_DFL);
    ::dup2(null_fd, 0);
    ::dup2(out_fd, 1);
    ::dup2(err_fd, 2);
    ::execve(program.c_str(), args.data(), envp.data());
    const int e = errno;
    [[maybe_unused]] const ssize_t n = ::write(status_pipe[1], &e, sizeof e);
    ::_exit(127);
  }
  const int fork_errno = errno;
  for (const int fd : {out_fd, err_fd, null_fd, status_pipe[1]}) ::close(fd);
  if (pid < 0) {
    ::close(status_pipe[0]);
    errno = fork_errno;
    throw systemError("RosProcess: fork for " + program);
  }
  // Set in the parent too, so the group exists before anyone signals it.
  ::setpgid(pid, pid);
  pid_ = pid;
  int exec_errno = 0;
  ssize_t n;
  do {
    n = ::read(status_pipe[0], &exec_errno, sizeof exec_errno);
  } while (n < 0 && errno == EINTR);
  ::close(status_pipe[0]);
  if (n > 0) {
    ::waitpid(pid_, &status_, 0);
    reaped_ = true;
    errno = exec_errno;
    throw systemError("RosProcess: cannot execute " + program);
  }
}

RosProcess::RosProcess(RosProcess&& o) noexcept
    : pid_(o.pid_), status_(o.status_), reaped_(o.reaped_), out_(std::move(o.out_)), err_(std::move(o.err_)) {
  o.pid_ = -1;
}

RosProcess& RosProcess::operator=(RosProcess&& o) noexcept {
  if (this != &o) {
    killGroupAndReap();
    pid_ = o.pid_;
    status_ = o.status_;
    reaped_ = o.reaped_;
    out_ = std::move(o.out_);
    err_ = std::move(o.err_);
    o.pid_ = -1;
  }
  return *this;
}

RosProcess::~RosProcess() { killGroupAndReap(); }

bool RosProcess::poll() {
  if (reaped_ || pid_ <= 0) return true;
  if (::waitpid(pid_, &status_, WNOHANG) == pid_) reaped_ = true;
  return reaped_;
}

bool RosProcess::alive() { return pid_ > 0 && !poll(); }

void RosProcess::kill(int sig) {
  if (pid_ > 0 && !reaped_) ::kill(-pid_, sig);
}

std::optional<int> RosProcess::wait(milliseconds timeout) {
  if (pid_ <= 0) return std::nullopt;
  pollUntil(timeout, [&] { return poll(); });
  if (reaped_ && WIFEXITED(status_)) return WEXITSTATUS(status_);
  return std::nullopt;
}

std::optional<int> RosProcess::stop(milliseconds grace) {
  kill(SIGTERM);
  const std::optional<int> code = wait(grace);
  killGroupAndReap();
  return code;
}

void RosProcess::killGroupAndReap() {
  if (pid_ <= 0) return;
  // The group may outlive its leader (a child it started): killed either way while the
  // leader is unreaped, which keeps the group's id from being reused.
  if (!reaped_) {
    ::kill(-pid_, SIGKILL);
    ::waitpid(pid_, &status_, 0);
    reaped_ = true;
  }
}

std::string RosProcess::out() const { return readFile(out_); }
std::string RosProcess::err() const { return readFile(err_); }

std::vector<std::string> RosProcess::waitForLines(std::size_t lines, milliseconds timeout) {
  std::vector<std::string> got;
  pollUntil(timeout, [&] {
    const bool exited = !alive();
    got = completeLines(out());
    return got.size() >= lines || exited;
  });
  return got;
}

std::vector<std::string> RosRun::lines() const { return completeLines(out); }

// ---------------------------------------------------------------------------------------------

int freeLocalPort() {
  const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
  if (fd < 0) throw systemError("freeLocalPort: socket");
  sockaddr_in addr{};
  addr.sin_family = AF_INET;
  addr.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t len = sizeof addr;
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 ||
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&addr), &len) != 0) {
    const auto e = systemError("freeLocalPort: bind 127.0.0.1:0");
    ::close(fd);
    throw e;
  }
  ::close(fd);
  return ntohs(addr.sin_port);
}

RosMaster::RosMaster(const std::string& name, milliseconds timeout) {
  const char* keep = std::getenv("STAA_KEEP_ROS_TEST_DIRS");
  keep_dir_ = keep != nullptr && std::string(keep) == "1";
  dir_ = freshDir("staa-ros", name + "-" + std::to_string(g_master_count.fetch_add(1)));
  std::filesystem::create_directories(dir_ / "log");
  const auto start = Clock::now();
  const auto deadline = start + timeout;
  std::string why;
  // A port found free may be taken before rosmaster binds it: a few tries with new ports.
  for (int attempt = 1; attempt <= 5; ++attempt) {
    if (tryStart(deadline, why)) {
      startup_ = std::chrono::duration_cast<milliseconds>(Clock::now() - start);
      return;
    }
    if (Clock::now() >= deadline) break;
  }
  const std::string log = master_.err();
  master_ = RosProcess();
  if (!keep_dir_) std::filesystem::remove_all(dir_);
  throw std::runtime_error("RosMaster '" + name + "': rosmaster did not start: " + why + "\n" + log);
}

bool RosMaster::tryStart(Clock::time_point deadline, std::string& why) {
  port_ = freeLocalPort();
  master_ = RosProcess({"rosmaster", "--core", "-p", std::to_string(port_)}, childEnvironment(),
                       dir_ / "rosmaster.out", dir_ / "rosmaster.err");
  while (Clock::now() < deadline) {
    if (!master_.alive()) {
      why = "rosmaster exited (status " + std::to_string(master_.rawStatus()) + ") on port " + std::to_string(port_);
      return false;
    }
    // rosmaster does not exit when its port is taken: it logs this and hangs.
    if (master_.err().find("already in use") != std::string::npos) {
      why = "port " + std::to_string(port_) + " was taken";
      master_ = RosProcess();
      return false;
    }
    if (const std::optional<long> pid = masterPid()) {
      if (*pid == master_.pid()) return true;
      why = "another master (pid " + std::to_string(*pid) + ") answers on port " + std::to_string(port_);
      master_ = RosProcess();
      return false;
    }
    std::this_thread::sleep_for(milliseconds(10));
  }
  why = "no answer on port " + std::to_string(port_) + " before the deadline";
  return false;
}

RosMaster::~RosMaster() {
  // SIGINT is rosmaster's clean shutdown; the group is killed after 2 s anyway.
  master_.kill(SIGINT);
  master_.wait(milliseconds(2000));
  master_ = RosProcess();
  if (!keep_dir_) {
    std::error_code ignored;
    std::filesystem::remove_all(dir_, ignored);
  }
}

std::string RosMaster::uri() const { return "http://127.0.0.1:" + std::to_string(port_); }

std::vector<std::string> RosMaster::env() const {
  return {"ROS_MASTER_URI=" + uri(), "ROS_HOME=" + dir_.string(), "ROS_LOG_DIR=" + (dir_ / "log").string(),
          "ROS_IP=127.0.0.1"};
}

std::vector<std::string> RosMaster::childEnvironment(const std::vector<std::string>& extra) const {
  const auto nameOf = [](const std::string& entry) { return entry.substr(0, entry.find('=') + 1); };
  std::vector<std::string> drop{"NOTIFY_SOCKET=", "WATCHDOG_", "ROS_MASTER_URI=", "ROS_HOSTNAME=", "ROS_IP=",
                                "ROS_HOME=", "ROS_LOG_DIR=", "ROS_NAMESPACE="};
  for (const std::string& x : extra) drop.push_back(nameOf(x));
  std::vector<std::string> result = environmentWithout(drop);
  for (const std::string& e : env()) {
    const bool overridden = std::any_of(extra.begin(), extra.end(), [&](const std::string& x) { return nameOf(x) == nameOf(e); });
    if (!overridden) result.push_back(e);
  }
  result.insert(result.end(), extra.begin(), extra.end());
  return result;
}

RosProcess RosMaster::spawn(const std::string& name, const std::vector<std::string>& argv,
                            const std::vector<std::string>& extra_env) const {
  return RosProcess(argv, childEnvironment(extra_env), dir_ / (name + ".out"), dir_ / (name + ".err"));
}

RosRun RosMaster::run(const std::string& name, const std::vector<std::string>& argv, milliseconds timeout,
                      const std::vector<std::string>& extra_env) const {
  RosProcess p = spawn(name, argv, extra_env);
  RosRun r;
  r.exit_code = p.wait(timeout);
  p = RosProcess();  // killed if it timed out
  r.out = readFile(dir_ / (name + ".out"));
  r.err = readFile(dir_ / (name + ".err"));
  return r;
}

std::optional<std::string> RosMaster::call(std::string_view method, const std::vector<std::string>& params,
                                           milliseconds timeout) const {
  std::string body = "<?xml version=\"1.0\"?><methodCall><methodName>" + std::string(method) + "</methodName><params>";
  for (const std::string& p : params) body += "<param><value><string>" + xmlEscape(p) + "</string></value></param>";
  body += "</params></methodCall>";
  return httpPost(port_, body, timeout);
}

std::optional<long> RosMaster::masterPid() const {
  const std::optional<std::string> body = call("getPid", {"/staa_test"}, milliseconds(500));
  if (!body) return std::nullopt;
  try {
    const XmlRpcValue r = XmlRpcParser(*body).response();  // [code, status, pid]
    if (r.is_array && r.items.size() == 3 && r.items[0].text == "1") return std::stol(r.items[2].text);
  } catch (const std::exception&) {
  }
  return std::nullopt;
}

std::vector<std::string> RosMaster::publishers(const std::string& topic) const { return nodesOf(*this, topic, 0); }
std::vector<std::string> RosMaster::subscribers(const std::string& topic) const { return nodesOf(*this, topic, 1); }

bool RosMaster::waitForPublisher(const std::string& topic, milliseconds timeout) const {
  return pollUntil(timeout, [&] { return !publishers(topic).empty(); });
}

bool RosMaster::waitForSubscriber(const std::string& topic, milliseconds timeout) const {
  return pollUntil(timeout, [&] { return !subscribers(topic).empty(); });
}

}  // namespace staa::test
