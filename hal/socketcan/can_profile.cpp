#include "hal/socketcan/can_profile.hpp"

#include "io/config_reader.hpp"
#include "io/yaml_support.hpp"

#include <cctype>
#include <charconv>
#include <optional>
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

constexpr io::Choice<CanByteOrder> kByteOrders[] = {{"little", CanByteOrder::kLittle}, {"big", CanByteOrder::kBig}};
constexpr io::Range kPositive = io::Range::above(0.0);

// An 11-bit CAN ID, decimal or 0x-hex.
std::uint32_t canId(const io::ConfigValue& node) {
  std::optional<std::uint64_t> id;
  if (node.node().IsScalar()) {
    std::string_view s = node.node().Scalar();
    int base = 10;
    if (s.size() > 2 && s[0] == '0' && (s[1] == 'x' || s[1] == 'X')) {
      s.remove_prefix(2);
      base = 16;
    }
    std::uint64_t v = 0;
    const auto res = std::from_chars(s.data(), s.data() + s.size(), v, base);
    if (!s.empty() && res.ec == std::errc{} && res.ptr == s.data() + s.size()) id = v;
  }
  if (!id) node.fail("expected an 11-bit CAN ID (0..0x7FF), got " + node.described());
  if (*id > kMaxStandardId) node.fail("must be an 11-bit CAN ID (0..0x7FF), got " + node.text());
  return static_cast<std::uint32_t>(*id);
}

// A limit must fit its int16 field at its scale.
void checkFitsInt16(const io::ConfigValue& node, double limit, double scale) {
  if (limit / scale > kInt16Max) {
    node.fail("does not fit the int16 field at scale " + yaml_support::formatNumber(scale) + " (at most " +
              yaml_support::formatNumber(kInt16Max * scale) + "), got " + node.text());
  }
}

// A timeout shorter than one period would time out between every two frames.
double timeoutOf(const io::ConfigValue& section, double rate_hz) {
  const io::ConfigValue node = section.required("timeout_s");
  const double timeout_s = node.number(kPositive);
  if (timeout_s * rate_hz <= 1.0) {
    node.fail("must be longer than one frame period (1/rate_hz = " + yaml_support::formatNumber(1.0 / rate_hz) + " s), got " +
              node.text());
  }
  return timeout_s;
}

// Every ID of the profile with its key, for the duplicate check.
class IdTable {
 public:
  std::uint32_t read(const io::ConfigValue& section, std::string_view key) {
    const io::ConfigValue node = section.required(key);
    const std::uint32_t id = canId(node);
    for (const auto& [other, path] : ids_) {
      if (other == id) node.fail(hex(id) + " is already " + path + ", got " + node.text());
    }
    ids_.emplace_back(id, node.keyPath());
    return id;
  }

 private:
  std::vector<std::pair<std::uint32_t, std::string>> ids_;
};

// The velocity fields of the command and odometry frames: scales and limits, each limit
// within its int16 field.
template <class Frame>
void readVelocityFields(const io::ConfigValue& section, Frame& out) {
  out.v_scale = section.required("v_scale").number(kPositive);
  out.w_scale = section.required("w_scale").number(kPositive);
  const io::ConfigValue v_limit = section.required("v_limit");
  const io::ConfigValue w_limit = section.required("w_limit");
  out.v_limit = v_limit.number(kPositive);
  out.w_limit = w_limit.number(kPositive);
  checkFitsInt16(v_limit, out.v_limit, out.v_scale);
  checkFitsInt16(w_limit, out.w_limit, out.w_scale);
}

CanProfile readProfile(const io::ConfigValue& root) {
  CanProfile p;
  p.name = root.required("name").nonEmptyString("a non-empty string");
  p.byte_order = root.required("byte_order").choice<CanByteOrder>(kByteOrders);
  IdTable ids;

  const io::ConfigValue cmd = root.required("command");
  cmd.mapping({"id", "rate_hz", "v_scale", "w_scale", "v_limit", "w_limit"});
  p.command.id = ids.read(cmd, "id");
  p.command.rate_hz = cmd.required("rate_hz").number(kPositive);
  readVelocityFields(cmd, p.command);

  const io::ConfigValue odo = root.required("odometry");
  odo.mapping({"id", "rate_hz", "v_scale", "w_scale", "v_limit", "w_limit", "max_dt_s", "timeout_s"});
  p.odometry.id = ids.read(odo, "id");
  p.odometry.rate_hz = odo.required("rate_hz").number(kPositive);
  readVelocityFields(odo, p.odometry);
  p.odometry.max_dt_s = odo.required("max_dt_s").number(kPositive);
  p.odometry.timeout_s = timeoutOf(odo, p.odometry.rate_hz);

  const io::ConfigValue st = root.required("status");
  st.mapping({"id", "rate_hz", "timeout_s"});
  p.status.id = ids.read(st, "id");
  p.status.rate_hz = st.required("rate_hz").number(kPositive);
  p.status.timeout_s = timeoutOf(st, p.status.rate_hz);

  const io::ConfigValue hb = root.required("heartbeat");
  hb.mapping({"host_id", "base_id", "rate_hz", "timeout_s"});
  p.heartbeat.host_id = ids.read(hb, "host_id");
  p.heartbeat.base_id = ids.read(hb, "base_id");
  p.heartbeat.rate_hz = hb.required("rate_hz").number(kPositive);
  p.heartbeat.timeout_s = timeoutOf(hb, p.heartbeat.rate_hz);

  const io::ConfigValue bus = root.required("bus");
  bus.mapping({"recovery_interval_s"});
  p.bus.recovery_interval_s = bus.required("recovery_interval_s").number(kPositive);
  return p;
}

}  // namespace

CanProfile parseCanProfile(const std::string& yaml_text, const std::string& source) {
  return io::readAs<CanProfileError>(source, [&] {
    const io::ConfigDocument doc = io::ConfigDocument::parse(yaml_text, source);
    return readProfile(doc.root(kFormat, {"format", "name", "byte_order", "command", "odometry", "status", "heartbeat", "bus"}));
  });
}

CanProfile loadCanProfile(const std::filesystem::path& path) {
  const std::string source = path.string();
  return io::readAs<CanProfileError>(source, [&] { return parseCanProfile(io::ConfigDocument::readFile(path, "CAN profile"), source); });
}

}  // namespace staa::hal
