// basesim: the simulated HSR base firmware for the hardware-in-the-loop tests. It listens on a
// Unix SOCK_SEQPACKET socket (what staad's `socketcan.interface: unix:PATH` connects to, one
// struct can_frame per record) and speaks the CAN profile through hal/socketcan's codec, the
// same functions the driver uses, so the two can only disagree with the profile file:
//
//   - integrates the commanded v, w with acceleration limits (a brake is the same full
//     deceleration), exactly as a base would, and keeps its true pose;
//   - sends odometry (v, w, dt_us) at odometry.rate_hz, status at status.rate_hz and its
//     heartbeat at heartbeat.rate_hz;
//   - stops by itself (decelerates to 0) when no valid command came for --command-timeout
//     (0.5 s, as the HSR does), whatever happened to the host.
//
// Faults on cue through a control socket (--control PATH, a Unix stream socket, one command
// per line, one JSON reply per line):
//
//   silence_odometry on|off    no odometry frames
//   silence_heartbeat on|off   no status and no heartbeat frames
//   busoff                     a CAN_ERR_FLAG|CAN_ERR_BUSOFF error frame, then the host's
//                              controller is off the bus: nothing sent, nothing received
//   restart                    a CAN_ERR_RESTARTED error frame, then back on the bus
//   corrupt N                  next N odometry frames come with a bad one beside each, in
//                              turn: bad checksum, wrong DLC, counter going back, huge v,
//                              and a reordered pair (the valid stream stays fresh)
//   estop on|off               the emergency stop: status bit, the base decelerates to 0
//   state                      {"ok":true,"state":{...}}: true v, w, pose, time since the
//                              last valid command, counters
//   quit                       exits 0
//
// stdout: one JSON line per event ({"event":"connected"}, ...), nothing else; stderr: errors.
// Usage:
//   basesim --socket PATH --control PATH --profile config/can/hsr_base.yaml
//           [--accel 0.5] [--alpha 1.5] [--command-timeout 0.5] [--start X,Y,TH]
#include "hal/socketcan/can_codec.hpp"
#include "hal/socketcan/can_profile.hpp"
#include "hal/socketcan/can_transport.hpp"

#include <CLI/CLI.hpp>
#include <nlohmann/json.hpp>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <csignal>
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <iostream>
#include <optional>
#include <sstream>
#include <string>
#include <system_error>
#include <vector>

#include <linux/can/error.h>
#include <poll.h>
#include <sys/socket.h>
#include <sys/un.h>
#include <unistd.h>

namespace {

using staa::hal::CanProfile;
using Json = nlohmann::json;

volatile std::sig_atomic_t g_stop = 0;
void onSignal(int) { g_stop = 1; }

double monotonicS() {
  return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch()).count();
}

[[noreturn]] void die(const std::string& what) {
  std::cerr << "basesim: " << what << std::endl;
  std::exit(2);
}

void event(const Json& j) { std::cout << j.dump() << std::endl; }

// A listening Unix socket of `type` at `path` (a stale file there is removed).
int listenAt(const std::string& path, int type) {
  sockaddr_un addr{};
  addr.sun_family = AF_UNIX;
  if (path.empty() || path.size() >= sizeof addr.sun_path) die("socket path '" + path + "': must be 1..107 bytes");
  std::memcpy(addr.sun_path, path.data(), path.size());
  ::unlink(path.c_str());
  const int fd = ::socket(AF_UNIX, type | SOCK_NONBLOCK | SOCK_CLOEXEC, 0);
  if (fd < 0) die("socket: " + std::system_category().message(errno));
  if (::bind(fd, reinterpret_cast<const sockaddr*>(&addr), sizeof addr) != 0 || ::listen(fd, 4) != 0) {
    die("bind/listen '" + path + "': " + std::system_category().message(errno));
  }
  return fd;
}

// v moves toward target by at most rate * dt.
double approach(double v, double target, double rate, double dt) {
  const double step = rate * dt;
  if (target > v) return std::min(target, v + step);
  return std::max(target, v - step);
}

struct Options {
  std::string socket_path;
  std::string control_path;
  std::string profile_path;
  double accel = 0.5;            // m/s^2, also the brake's deceleration
  double alpha = 1.5;            // rad/s^2
  double command_timeout = 0.5;  // s without a valid command: the base stops by itself
  double x = 0.0, y = 0.0, theta = 0.0;
};

struct ControlClient {
  int fd = -1;
  std::string in;
};

class BaseSim {
 public:
  BaseSim(const Options& o, CanProfile profile) : o_(o), p_(std::move(profile)) {
    x_ = o.x;
    y_ = o.y;
    th_ = o.theta;
  }

  int run() {
    can_listen_ = listenAt(o_.socket_path, SOCK_SEQPACKET);
    ctl_listen_ = listenAt(o_.control_path, SOCK_STREAM);
    event({{"event", "listening"}, {"socket", o_.socket_path}, {"control", o_.control_path}});
    last_t_ = monotonicS();
    next_odo_ = next_status_ = next_hb_ = last_t_;
    last_odo_sent_ = last_t_;
    while (!g_stop && !quit_) {
      pollOnce();
      const double now = monotonicS();
      integrate(now);
      sendDue(now);
    }
    ::unlink(o_.socket_path.c_str());
    ::unlink(o_.control_path.c_str());
    return 0;
  }

 private:
  // ---- I/O ----

  void pollOnce() {
    std::vector<pollfd> fds;
    fds.push_back({can_listen_, POLLIN, 0});
    fds.push_back({ctl_listen_, POLLIN, 0});
    fds.push_back({can_ ? can_->fd() : -1, POLLIN, 0});
    for (const ControlClient& c : clients_) fds.push_back({c.fd, POLLIN, 0});
    // 1 ms: the physics and the frame schedule are checked about every millisecond.
    if (::poll(fds.data(), fds.size(), 1) <= 0) return;
    if (fds[0].revents & POLLIN) acceptCan();
    if (fds[1].revents & POLLIN) acceptControl();
    if (can_ && (fds[2].revents & (POLLIN | POLLHUP | POLLERR))) receiveCan();
    for (std::size_t i = 0; i < clients_.size(); ++i) {
      if (fds[3 + i].revents & (POLLIN | POLLHUP | POLLERR)) readControl(clients_[i]);
    }
    std::erase_if(clients_, [](const ControlClient& c) { return c.fd < 0; });
  }

  void acceptCan() {
    const int fd = ::accept4(can_listen_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
    if (fd < 0) return;
    // A new host replaces the old one (a restarted daemon).
    if (can_) event({{"event", "replaced"}});
    can_.emplace(staa::hal::adoptSeqPacket(fd, "basesim"));
    command_counter_.reset();
    heartbeat_counter_.reset();
    ++connections_;
    event({{"event", "connected"}, {"connections", connections_}});
  }

  void disconnect() {
    can_.reset();
    event({{"event", "disconnected"}});
  }

  void receiveCan() {
    staa::hal::CanRxFrame rx;
    for (int i = 0; i < 256 && can_; ++i) {
      const staa::hal::CanIo io = can_->receive(rx);
      if (io == staa::hal::CanIo::kWouldBlock) return;
      if (io == staa::hal::CanIo::kGone) {
        disconnect();
        return;
      }
      ++frames_rx_;
      if (io != staa::hal::CanIo::kOk) {
        ++bad_frames_;
        continue;
      }
      // The host's controller is off the bus: its frames never reach the base.
      if (bus_off_) {
        ++lost_bus_off_;
        continue;
      }
      handleFrame(rx.frame, monotonicS());
    }
  }

  void handleFrame(const can_frame& f, double now) {
    const canid_t id = f.can_id & CAN_SFF_MASK;
    if ((f.can_id & (CAN_ERR_FLAG | CAN_RTR_FLAG | CAN_EFF_FLAG)) == 0 && id == p_.command.id) {
      const auto d = staa::hal::decodeCommand(p_, f);
      if (!d.ok()) {
        ++bad_frames_;
        return;
      }
      const auto verdict = command_counter_.check(d.value.counter);
      if (verdict == staa::hal::CanCounterVerdict::kStale) {
        ++bad_frames_;
        return;
      }
      ++commands_;
      if (timed_out_) event({{"event", "commands_resumed"}});
      timed_out_ = false;
      last_cmd_t_ = now;
      cmd_ = d.value;
      return;
    }
    if ((f.can_id & (CAN_ERR_FLAG | CAN_RTR_FLAG | CAN_EFF_FLAG)) == 0 && id == p_.heartbeat.host_id) {
      const auto d = staa::hal::decodeHostHeartbeat(p_, f);
      if (!d.ok() || heartbeat_counter_.check(d.value.counter) == staa::hal::CanCounterVerdict::kStale) {
        ++bad_frames_;
        return;
      }
      ++host_heartbeats_;
      return;
    }
    ++bad_frames_;  // an ID the base does not receive, or a flagged frame
  }

  bool send(const can_frame& f) {
    if (!can_ || bus_off_) return false;
    const staa::hal::CanIo io = can_->send(f);
    if (io == staa::hal::CanIo::kGone) {
      disconnect();
      return false;
    }
    if (io != staa::hal::CanIo::kOk) {
      ++send_failures_;
      return false;
    }
    ++frames_tx_;
    return true;
  }

  can_frame errorFrame(canid_t what) {
    can_frame f{};
    f.can_id = CAN_ERR_FLAG | what;
    f.len = CAN_ERR_DLC;
    return f;
  }

  // ---- the base ----

  void integrate(double now) {
    double dt = now - last_t_;
    if (dt <= 0.0) return;
    last_t_ = now;
    const double since_cmd = last_cmd_t_ < 0.0 ? 1e9 : now - last_cmd_t_;
    if (since_cmd > o_.command_timeout && !timed_out_ && last_cmd_t_ >= 0.0) {
      timed_out_ = true;
      event({{"event", "command_timeout"}, {"since_cmd_s", since_cmd}, {"v", v_}, {"w", w_}});
    }
    double tv = 0.0, tw = 0.0;
    if (!estop_ && since_cmd <= o_.command_timeout && cmd_.enable && !cmd_.brake) {
      tv = cmd_.v;
      tw = cmd_.w;
    }
    // Sub-steps of at most 1 ms: a late wake-up on a loaded machine does not jump.
    while (dt > 0.0) {
      const double h = std::min(dt, 0.001);
      dt -= h;
      v_ = approach(v_, tv, o_.accel, h);
      w_ = approach(w_, tw, o_.alpha, h);
      const double mid = th_ + 0.5 * w_ * h;
      x_ += v_ * std::cos(mid) * h;
      y_ += v_ * std::sin(mid) * h;
      th_ = std::remainder(th_ + w_ * h, 2.0 * M_PI);
    }
    if (v_ == 0.0 && w_ == 0.0 && !standing_) {
      standing_ = true;
      event({{"event", "standstill"}});
    } else if (v_ != 0.0 || w_ != 0.0) {
      standing_ = false;
    }
  }

  void sendDue(double now) {
    // The schedules run whether or not anything is sent (a silenced stream resumes on time).
    if (now >= next_odo_) {
      next_odo_ = std::max(next_odo_ + 1.0 / p_.odometry.rate_hz, now);
      if (!silence_odometry_) sendOdometry(now);
    }
    if (now >= next_status_) {
      next_status_ = std::max(next_status_ + 1.0 / p_.status.rate_hz, now);
      if (!silence_heartbeat_) {
        send(staa::hal::encodeStatus(p_, !estop_, estop_, false, 0, status_counter_++));
      }
    }
    if (now >= next_hb_) {
      next_hb_ = std::max(next_hb_ + 1.0 / p_.heartbeat.rate_hz, now);
      if (!silence_heartbeat_) send(staa::hal::encodeBaseHeartbeat(p_, staa::hal::CanBaseState::kOk, hb_counter_++));
    }
  }

  void sendOdometry(double now) {
    if (!can_ || bus_off_) return;
    const double dt_s = std::clamp(now - last_odo_sent_, 1e-6, 0.065535);
    last_odo_sent_ = now;
    const auto dt_us = static_cast<std::uint16_t>(std::lround(dt_s * 1e6));
    const std::uint8_t counter = odo_counter_++;
    const can_frame good = staa::hal::encodeOdometry(p_, v_, w_, dt_us, counter);
    ++odometry_sent_;
    if (corrupt_left_ == 0) {
      if (held_) {
        // The second half of a reordered pair: the newer frame first, then the held one.
        send(good);
        send(*held_);
        held_.reset();
        return;
      }
      send(good);
      return;
    }
    --corrupt_left_;
    const int kind = corrupt_kind_++ % 5;
    can_frame bad = good;
    switch (kind) {
      case 0: bad.data[7] = static_cast<std::uint8_t>(bad.data[7] ^ 0x5A); break;  // bad checksum
      case 1: bad.len = 6; break;                                                    // wrong DLC
      case 2:  // a counter going back: an older frame, valid in itself
        bad = staa::hal::encodeOdometry(p_, v_, w_, dt_us, static_cast<std::uint8_t>(counter - 3));
        break;
      case 3:  // huge v, well-formed otherwise (the same counter as the valid one before it)
        bad = staa::hal::encodeOdometry(p_, 30.0, w_, dt_us, counter);
        break;
      case 4:  // reordered: this frame is held and sent after the next one
        if (held_) send(*held_);
        held_ = good;
        ++corrupt_sent_[kind];
        return;
    }
    if (held_) {
      send(good);
      send(*held_);
      held_.reset();
    } else {
      send(good);
    }
    if (send(bad)) ++corrupt_sent_[kind];
  }

  // ---- the control socket ----

  void acceptControl() {
    for (;;) {
      const int fd = ::accept4(ctl_listen_, nullptr, nullptr, SOCK_NONBLOCK | SOCK_CLOEXEC);
      if (fd < 0) return;
      clients_.push_back({fd, {}});
    }
  }

  void readControl(ControlClient& c) {
    char buf[1024];
    const ssize_t n = ::read(c.fd, buf, sizeof buf);
    if (n <= 0) {
      if (n < 0 && (errno == EAGAIN || errno == EINTR)) return;
      ::close(c.fd);
      c.fd = -1;
      return;
    }
    c.in.append(buf, static_cast<std::size_t>(n));
    for (std::size_t nl; (nl = c.in.find('\n')) != std::string::npos;) {
      const std::string line = c.in.substr(0, nl);
      c.in.erase(0, nl + 1);
      const std::string reply = handleCommand(line).dump() + "\n";
      (void)!::send(c.fd, reply.data(), reply.size(), MSG_NOSIGNAL);
    }
  }

  static std::optional<bool> onOff(const std::string& word) {
    if (word == "on") return true;
    if (word == "off") return false;
    return std::nullopt;
  }

  Json handleCommand(const std::string& line) {
    std::istringstream in(line);
    std::string cmd, arg;
    in >> cmd >> arg;
    const auto error = [&](const std::string& what) { return Json{{"ok", false}, {"error", what}}; };
    const auto ok = [&] {
      event({{"event", "inject"}, {"what", line}});
      return Json{{"ok", true}};
    };
    if (cmd == "state") return Json{{"ok", true}, {"state", state()}};
    if (cmd == "silence_odometry" || cmd == "silence_heartbeat" || cmd == "estop") {
      const auto on = onOff(arg);
      if (!on) return error(cmd + ": expected on or off, got '" + arg + "'");
      if (cmd == "silence_odometry") silence_odometry_ = *on;
      if (cmd == "silence_heartbeat") silence_heartbeat_ = *on;
      if (cmd == "estop") estop_ = *on;
      return ok();
    }
    if (cmd == "busoff") {
      if (bus_off_) return error("busoff: already off the bus");
      send(errorFrame(CAN_ERR_BUSOFF));  // the controller's last word
      bus_off_ = true;
      return ok();
    }
    if (cmd == "restart") {
      if (!bus_off_) return error("restart: not off the bus");
      bus_off_ = false;
      send(errorFrame(CAN_ERR_RESTARTED));
      return ok();
    }
    if (cmd == "corrupt") {
      char* end = nullptr;
      const long n = std::strtol(arg.c_str(), &end, 10);
      if (arg.empty() || *end != '\0' || n < 1 || n > 100000) return error("corrupt: expected a count 1..100000, got '" + arg + "'");
      corrupt_left_ = static_cast<int>(n);
      return ok();
    }
    if (cmd == "quit") {
      quit_ = true;
      return Json{{"ok", true}};
    }
    return error("unknown command '" + cmd +
                 "' (expected state, silence_odometry, silence_heartbeat, busoff, restart, corrupt N, estop, quit)");
  }

  Json state() const {
    const double now = monotonicS();
    Json corrupt = Json::object();
    const char* names[5] = {"bad_checksum", "wrong_dlc", "counter_back", "huge_v", "reordered"};
    for (int k = 0; k < 5; ++k) corrupt[names[k]] = corrupt_sent_[k];
    return Json{{"t", now},
                {"v", v_},
                {"w", w_},
                {"pose", {x_, y_, th_}},
                {"since_cmd_s", last_cmd_t_ < 0.0 ? Json(nullptr) : Json(now - last_cmd_t_)},
                {"command", {cmd_.v, cmd_.w}},
                {"brake", cmd_.brake},
                {"enable", cmd_.enable},
                {"connected", can_.has_value()},
                {"connections", connections_},
                {"bus_off", bus_off_},
                {"estop", estop_},
                {"commands", commands_},
                {"host_heartbeats", host_heartbeats_},
                {"bad_frames", bad_frames_},
                {"frames_rx", frames_rx_},
                {"frames_tx", frames_tx_},
                {"lost_bus_off", lost_bus_off_},
                {"send_failures", send_failures_},
                {"odometry_sent", odometry_sent_},
                {"corrupt_sent", corrupt},
                {"corrupt_left", corrupt_left_}};
  }

  Options o_;
  CanProfile p_;
  int can_listen_ = -1;
  int ctl_listen_ = -1;
  std::optional<staa::hal::CanTransport> can_;
  std::vector<ControlClient> clients_;
  bool quit_ = false;

  // True motion.
  double x_ = 0.0, y_ = 0.0, th_ = 0.0, v_ = 0.0, w_ = 0.0;
  double last_t_ = 0.0;
  bool standing_ = true;

  // The last valid command.
  staa::hal::CanCommand cmd_;
  double last_cmd_t_ = -1.0;
  bool timed_out_ = false;
  staa::hal::CounterTracker command_counter_, heartbeat_counter_;

  // Schedules and counters of what is sent.
  double next_odo_ = 0.0, next_status_ = 0.0, next_hb_ = 0.0, last_odo_sent_ = 0.0;
  std::uint8_t odo_counter_ = 0, status_counter_ = 0, hb_counter_ = 0;

  // Faults.
  bool silence_odometry_ = false;
  bool silence_heartbeat_ = false;
  bool bus_off_ = false;
  bool estop_ = false;
  int corrupt_left_ = 0;
  int corrupt_kind_ = 0;
  std::optional<can_frame> held_;
  std::uint64_t corrupt_sent_[5] = {0, 0, 0, 0, 0};

  // Counters.
  std::uint64_t connections_ = 0, commands_ = 0, host_heartbeats_ = 0, bad_frames_ = 0, frames_rx_ = 0;
  std::uint64_t frames_tx_ = 0, lost_bus_off_ = 0, send_failures_ = 0, odometry_sent_ = 0;
};

}  // namespace

int main(int argc, char** argv) {
  CLI::App app{"basesim: the simulated HSR base firmware for the HIL tests (CAN profile over SOCK_SEQPACKET)"};
  Options o;
  std::string start;
  app.add_option("--socket", o.socket_path, "the SOCK_SEQPACKET socket staad connects to (unix:PATH)")->required();
  app.add_option("--control", o.control_path, "the control socket (fault injection, state)")->required();
  app.add_option("--profile", o.profile_path, "the CAN profile (staa-can-profile/1)")->required();
  app.add_option("--accel", o.accel, "linear acceleration and deceleration limit, m/s^2")->check(CLI::PositiveNumber);
  app.add_option("--alpha", o.alpha, "angular acceleration limit, rad/s^2")->check(CLI::PositiveNumber);
  app.add_option("--command-timeout", o.command_timeout, "stop by itself after this long without a valid command, s")
      ->check(CLI::PositiveNumber);
  app.add_option("--start", start, "the true start pose X,Y,TH");
  CLI11_PARSE(app, argc, argv);
  if (!start.empty()) {
    char comma1 = 0, comma2 = 0;
    std::istringstream in(start);
    if (!(in >> o.x >> comma1 >> o.y >> comma2 >> o.theta) || comma1 != ',' || comma2 != ',') {
      die("--start: expected X,Y,TH, got '" + start + "'");
    }
  }
  CanProfile profile;
  try {
    profile = staa::hal::loadCanProfile(o.profile_path);
  } catch (const std::exception& e) {
    die(std::string("--profile: ") + e.what());
  }
  std::signal(SIGPIPE, SIG_IGN);
  std::signal(SIGTERM, onSignal);
  std::signal(SIGINT, onSignal);
  return BaseSim(o, std::move(profile)).run();
}
