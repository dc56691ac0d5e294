#include "hal/socketcan/can_profile.hpp"

#include "io/yaml_support.hpp"

#include <yaml-cpp/yaml.h>

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <optional>
#include <set>
#include <sstream>
#include <string_view>
#include <utility>
#include <vector>

namespace staa::hal {
namespace {

constexpr std::string_view kFormat = "staa-can-profile/1";
constexpr std::uint32_t kMaxStandardId = 0x7FF;
constexpr double kInt16Max = 32767.0;

std::string hex(std::uint32_t id) {
  char buf[16];
  buf[0] = '0';
  buf[1] = 'x';
  const auto res = std::to_chars(buf + 2, buf + sizeof buf, id, 16);
  std::string out(buf, res.ptr);
  for (std::size_t k = 2; k < out.size(); ++k) out[k] = static_cast<char>(std::toupper(static_cast<unsigned char>(out[k])));
  return out;
}

// What the file said, as written (a scalar verbatim, else a short description).
std::string valueText(const YAML::Node& node) {
  if (node.IsDefined() && node.IsScalar()) return node.Scalar();
  return yaml_support::describe(node);
}

// Reads one file; every error names "source:line: key: what".
class Reader {
 public:
  explicit Reader(std::string source) : source_(std::move(source)) {}

  [[noreturn]] void fail(const YAML::Node& where, const std::string& key, const std::string& what) const {
    std::string msg = source_;
    const YAML::Mark mark = where.IsDefined() ? where.Mark() : YAML::Mark::null_mark();
    if (mark.line >= 0) msg += ":" + std::to_string(mark.line + 1);
    msg += ": ";
    msg += key;
    msg += ": ";
    msg += what;
    throw CanProfileError(msg);
  }

  // `map` must be a mapping holding exactly `keys` (no unknown, repeated or missing key).
  void checkMapping(const YAML::Node& map, const std::string& prefix, std::initializer_list<std::string_view> keys) const {
    const std::string name = prefix.empty() ? "(top level)" : prefix;
    if (!map.IsDefined() || map.IsNull()) fail(map, name, "missing");
    if (!map.IsMap()) fail(map, name, "expected a mapping, got " + yaml_support::describe(map));
    std::string expected;
    for (std::string_view k : keys) {
      if (!expected.empty()) expected += ", ";
      expected += k;
    }
    std::set<std::string> seen;
    for (const auto& kv : map) {
      const std::string key = kv.first.IsScalar() ? kv.first.Scalar() : yaml_support::describe(kv.first);
      const std::string full = prefix.empty() ? key : prefix + "." + key;
      bool known = false;
      for (std::string_view k : keys) known = known || k == key;
      if (!known) fail(kv.first, full, "unknown key (expected " + expected + ")");
      if (!seen.insert(key).second) fail(kv.first, full, "appears twice");
    }
    for (std::string_view k : keys) {
      if (!seen.count(std::string(k))) fail(map, prefix.empty() ? std::string(k) : prefix + "." + std::string(k), "missing");
    }
  }

  std::string text(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar() || node.Scalar().empty()) fail(node, key, "expected a non-empty string, got " + valueText(node));
    return node.Scalar();
  }

  // A finite number > 0.
  double positive(const YAML::Node& node, const std::string& key) const {
    const std::optional<double> v = yaml_support::readNumber(node);
    if (!v) fail(node, key, "expected a number, got " + valueText(node));
    if (!std::isfinite(*v)) fail(node, key, "must be finite, got " + valueText(node));
    if (*v <= 0.0) fail(node, key, "must be > 0, got " + valueText(node));
    return *v;
  }

  // An 11-bit CAN ID, decimal or 0x-hex.
  std::uint32_t canId(const YAML::Node& node, const std::string& key) const {
    if (!node.IsScalar()) fail(node, key, "expected an 11-bit CAN ID (0..0x7FF), got " + valueText(node));
    std::string_view s = node.Scalar();
    int base = 10;
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
      s.remove_prefix(2);
      base = 16;
    }
    std::uint64_t id = 0;
    const auto res = std::from_chars(s.data(), s.data() + s.size(), id, base);
    if (s.empty() || res.ec != std::errc{} || res.ptr != s.data() + s.size()) {
      fail(node, key, "expected an 11-bit CAN ID (0..0x7FF), got " + valueText(node));
    }
    if (id > kMaxStandardId) fail(node, key, "must be an 11-bit CAN ID (0..0x7FF), got " + valueText(node));
    return static_cast<std::uint32_t>(id);
  }

  // A limit that must fit the int16 field at its scale.
  void fitsInt16(const YAML::Node& node, const std::string& key, double limit, double scale) const {
    if (limit / scale > kInt16Max) {
      fail(node, key,
           "does not fit the int16 field at scale " + yaml_support::formatNumber(scale) + " (at most " +
               yaml_support::formatNumber(kInt16Max * scale) + "), got " + valueText(node));
    }
  }

  // A timeout shorter than one period would time out between every two frames.
  void longerThanPeriod(const YAML::Node& node, const std::string& key, double timeout_s, double rate_hz) const {
    if (timeout_s * rate_hz <= 1.0) {
      fail(node, key,
           "must be longer than one frame period (1/rate_hz = " + yaml_support::formatNumber(1.0 / rate_hz) +
               " s), got " + valueText(node));
    }
  }

 private:
  std::string source_;
};

}  // namespace

CanProfile parseCanProfile(const std::string& yaml_text, const std::string& source) {
  YAML::Node root;
  try {
    root = YAML::Load(yaml_text);
  } catch (const YAML::Exception& e) {
    std::string msg = source;
    if (e.mark.line >= 0) msg += ":" + std::to_string(e.mark.line + 1);
    throw CanProfileError(msg + ": not valid YAML: " + e.msg);
  }
  const Reader r(source);
  if (!root.IsMap()) {
    throw CanProfileError(source + ": expected a mapping with format, name, byte_order, command, odometry, status, "
                                   "heartbeat, bus, got " + yaml_support::describe(root));
  }
  r.checkMapping(root, "", {"format", "name", "byte_order", "command", "odometry", "status", "heartbeat", "bus"});

  const YAML::Node format = root["format"];
  if (!format.IsScalar() || format.Scalar() != kFormat) {
    r.fail(format, "format", "expected " + std::string(kFormat) + ", got " + valueText(format));
  }

  CanProfile p;
  p.name = r.text(root["name"], "name");

  const YAML::Node order = root["byte_order"];
  const std::string order_text = order.IsScalar() ? order.Scalar() : "";
  if (order_text == "little") {
    p.byte_order = CanByteOrder::kLittle;
  } else if (order_text == "big") {
    p.byte_order = CanByteOrder::kBig;
  } else {
    r.fail(order, "byte_order", "expected little or big, got " + valueText(order));
  }

  // Every ID with its key and node, for the duplicate check.
  struct IdUse {
    std::uint32_t id;
    std::string key;
    YAML::Node node;
  };
  std::vector<IdUse> ids;
  const auto readId = [&](const YAML::Node& section, const std::string& prefix, const char* key) {
    const YAML::Node node = section[key];
    const std::string full = prefix + "." + key;
    const std::uint32_t id = r.canId(node, full);
    for (const IdUse& other : ids) {
      if (other.id == id) r.fail(node, full, hex(id) + " is already " + other.key + ", got " + valueText(node));
    }
    ids.push_back({id, full, node});
    return id;
  };
  const auto number = [&](const YAML::Node& section, const std::string& prefix, const char* key) {
    return r.positive(section[key], prefix + "." + key);
  };
  // The velocity fields of the command and odometry frames: scales and limits, each limit
  // within its int16 field.
  const auto velocityFields = [&](const YAML::Node& section, const std::string& prefix, auto& out) {
    out.v_scale = number(section, prefix, "v_scale");
    out.w_scale = number(section, prefix, "w_scale");
    out.v_limit = number(section, prefix, "v_limit");
    out.w_limit = number(section, prefix, "w_limit");
    r.fitsInt16(section["v_limit"], prefix + ".v_limit", out.v_limit, out.v_scale);
    r.fitsInt16(section["w_limit"], prefix + ".w_limit", out.w_limit, out.w_scale);
  };

  const YAML::Node cmd = root["command"];
  r.checkMapping(cmd, "command", {"id", "rate_hz", "v_scale", "w_scale", "v_limit", "w_limit"});
  p.command.id = readId(cmd, "command", "id");
  p.command.rate_hz = number(cmd, "command", "rate_hz");
  velocityFields(cmd, "command", p.command);

  const YAML::Node odo = root["odometry"];
  r.checkMapping(odo, "odometry", {"id", "rate_hz", "v_scale", "w_scale", "v_limit", "w_limit", "max_dt_s", "timeout_s"});
  p.odometry.id = readId(odo, "odometry", "id");
  p.odometry.rate_hz = number(odo, "odometry", "rate_hz");
  velocityFields(odo, "odometry", p.odometry);
  p.odometry.max_dt_s = number(odo, "odometry", "max_dt_s");
  p.odometry.timeout_s = number(odo, "odometry", "timeout_s");
  r.longerThanPeriod(odo["timeout_s"], "odometry.timeout_s", p.odometry.timeout_s, p.odometry.rate_hz);

  const YAML::Node st = root["status"];
  r.checkMapping(st, "status", {"id", "rate_hz", "timeout_s"});
  p.status.id = readId(st, "status", "id");
  p.status.rate_hz = number(st, "status", "rate_hz");
  p.status.timeout_s = number(st, "status", "timeout_s");
  r.longerThanPeriod(st["timeout_s"], "status.timeout_s", p.status.timeout_s, p.status.rate_hz);

  const YAML::Node hb = root["heartbeat"];
  r.checkMapping(hb, "heartbeat", {"host_id", "base_id", "rate_hz", "timeout_s"});
  p.heartbeat.host_id = readId(hb, "heartbeat", "host_id");
  p.heartbeat.base_id = readId(hb, "heartbeat", "base_id");
  p.heartbeat.rate_hz = number(hb, "heartbeat", "rate_hz");
  p.heartbeat.timeout_s = number(hb, "heartbeat", "timeout_s");
  r.longerThanPeriod(hb["timeout_s"], "heartbeat.timeout_s", p.heartbeat.timeout_s, p.heartbeat.rate_hz);

  const YAML::Node bus = root["bus"];
  r.checkMapping(bus, "bus", {"recovery_interval_s"});
  p.bus.recovery_interval_s = number(bus, "bus", "recovery_interval_s");
  return p;
}

CanProfile loadCanProfile(const std::filesystem::path& path) {
  std::ifstream in(path);
  if (!in) throw CanProfileError(path.string() + ": cannot open CAN profile");
  std::ostringstream text;
  text << in.rdbuf();
  return parseCanProfile(text.str(), path.string());
}

}  // namespace staa::hal
