// The CAN profile loader (config/can/hsr_base.yaml): the shipped file, and errors that name
// the file, the line, the key and the value.
#include "hal/socketcan/can_profile.hpp"

#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>

namespace staa::hal {
namespace {

const std::string kShippedPath = std::string(STAA_SOURCE_DIR) + "/config/can/hsr_base.yaml";

std::string shippedText() {
  std::ifstream in(kShippedPath);
  std::ostringstream s;
  s << in.rdbuf();
  return s.str();
}

// The 1-based line of the first occurrence of `needle` in `text`.
int lineOf(const std::string& text, const std::string& needle) {
  const std::size_t at = text.find(needle);
  if (at == std::string::npos) return -1;
  int line = 1;
  for (std::size_t k = 0; k < at; ++k) line += text[k] == '\n';
  return line;
}

// The shipped file with the first `from` replaced by `to` (which must be found).
std::string edited(const std::string& from, const std::string& to) {
  std::string text = shippedText();
  const std::size_t at = text.find(from);
  EXPECT_NE(at, std::string::npos) << "the shipped profile has no '" << from << "'";
  if (at != std::string::npos) text.replace(at, from.size(), to);
  return text;
}

std::string errorOf(const std::string& text) {
  try {
    parseCanProfile(text, "hsr_base.yaml");
  } catch (const CanProfileError& e) {
    return e.what();
  }
  return "(no error)";
}

TEST(CanProfile, ShippedFileEqualsTheDefaults) {
  const CanProfile p = loadCanProfile(kShippedPath);
  const CanProfile d{};
  EXPECT_EQ(p.name, "hsr-base-bridge");
  EXPECT_EQ(p.byte_order, CanByteOrder::kLittle);
  EXPECT_EQ(p.command.id, 0x110u);
  EXPECT_EQ(p.command.rate_hz, 30.0);
  EXPECT_EQ(p.command.v_scale, 0.001);
  EXPECT_EQ(p.command.w_scale, 0.001);
  EXPECT_EQ(p.command.v_limit, 2.0);
  EXPECT_EQ(p.command.w_limit, 3.0);
  EXPECT_EQ(p.odometry.id, 0x210u);
  EXPECT_EQ(p.odometry.rate_hz, 100.0);
  EXPECT_EQ(p.odometry.max_dt_s, 0.1);
  EXPECT_EQ(p.odometry.timeout_s, 0.1);
  EXPECT_EQ(p.status.id, 0x220u);
  EXPECT_EQ(p.status.rate_hz, 50.0);
  EXPECT_EQ(p.status.timeout_s, 0.2);
  EXPECT_EQ(p.heartbeat.host_id, 0x100u);
  EXPECT_EQ(p.heartbeat.base_id, 0x200u);
  EXPECT_EQ(p.heartbeat.rate_hz, 10.0);
  EXPECT_EQ(p.heartbeat.timeout_s, 0.3);
  EXPECT_EQ(p.bus.recovery_interval_s, 1.0);
  // Field by field against the struct's defaults, which tests build frames with.
  EXPECT_EQ(p.name, d.name);
  EXPECT_EQ(p.command.id, d.command.id);
  EXPECT_EQ(p.odometry.v_scale, d.odometry.v_scale);
  EXPECT_EQ(p.odometry.w_scale, d.odometry.w_scale);
  EXPECT_EQ(p.odometry.v_limit, d.odometry.v_limit);
  EXPECT_EQ(p.odometry.w_limit, d.odometry.w_limit);
  EXPECT_EQ(p.odometry.max_dt_s, d.odometry.max_dt_s);
  EXPECT_EQ(p.status.timeout_s, d.status.timeout_s);
  EXPECT_EQ(p.heartbeat.timeout_s, d.heartbeat.timeout_s);
  EXPECT_EQ(p.bus.recovery_interval_s, d.bus.recovery_interval_s);
}

TEST(CanProfile, ReadsBigEndianAndDecimalIds) {
  const CanProfile p = parseCanProfile(edited("byte_order: little", "byte_order: big"), "x.yaml");
  EXPECT_EQ(p.byte_order, CanByteOrder::kBig);
  const CanProfile q = parseCanProfile(edited("id: 0x110", "id: 272"), "x.yaml");
  EXPECT_EQ(q.command.id, 0x110u);
}

struct BadCase {
  const char* from;       // text in the shipped file
  const char* to;         // what it becomes
  const char* line_of;    // the error's line is where this text is in the edited file
  const char* expected;   // the rest of the message after "hsr_base.yaml:<line>: "
};

TEST(CanProfile, ErrorsNameFileLineKeyAndValue) {
  const BadCase cases[] = {
      {"rate_hz: 100", "rate_hz: -5", "rate_hz: -5", "odometry.rate_hz: must be > 0, got -5"},
      {"id: 0x110", "id: 0x800", "id: 0x800", "command.id: must be an 11-bit CAN ID (0..0x7FF), got 0x800"},
      {"id: 0x110", "id: 2048", "id: 2048", "command.id: must be an 11-bit CAN ID (0..0x7FF), got 2048"},
      {"id: 0x220", "id: 0x210", "id: 0x210\n  rate_hz: 50", "status.id: 0x210 is already odometry.id, got 0x210"},
      {"base_id: 0x200", "base_id: 0x100", "base_id: 0x100", "heartbeat.base_id: 0x100 is already heartbeat.host_id"},
      {"id: 0x110", "id: fast", "id: fast", "command.id: expected an 11-bit CAN ID (0..0x7FF), got 'fast'"},
      {"v_scale: 0.001", "v_scale: 0", "v_scale: 0", "command.v_scale: must be > 0, got 0"},
      {"recovery_interval_s: 1.0", "recovery_interval_s: soon", "recovery_interval_s: soon",
       "bus.recovery_interval_s: expected a number, got 'soon'"},
      {"timeout_s: 0.3", "timeout_s: -0.3", "timeout_s: -0.3", "heartbeat.timeout_s: must be > 0, got -0.3"},
      {"timeout_s: 0.3", "timeout_s: 0.05", "timeout_s: 0.05",
       "heartbeat.timeout_s: must be longer than one frame period (1/rate_hz = 0.1 s), got 0.05"},
      {"  v_limit: 2.0                # |v| above this is out", "  v_limit: 40 # out", "v_limit: 40",
       "odometry.v_limit: does not fit the int16 field at scale 0.001 (at most 32.767), got 40"},
      {"format: staa-can-profile/1", "format: staa-can-profile/2", "format:",
       "format: unknown format, expected staa-can-profile/1, got 'staa-can-profile/2'"},
      {"byte_order: little", "byte_order: middle", "byte_order:", "byte_order: expected little or big, got 'middle'"},
      {"  rate_hz: 30", "  rate_hzz: 30", "rate_hzz", "command.rate_hzz: unknown key (expected id, rate_hz, v_scale"},
      {"bus:", "buss:", "buss:", "buss: unknown key (expected format, name, byte_order"},
      {"  max_dt_s: 0.1", "  # max_dt_s: 0.1", "  id: 0x210", "odometry.max_dt_s: missing"},
      {"  w_scale: 0.001\n", "  w_scale: 0.001\n  w_scale: 0.002\n", "  w_scale: 0.002", "command.w_scale: given twice (first on line 30)"},
  };
  for (const BadCase& c : cases) {
    const std::string text = edited(c.from, c.to);
    const std::string message = errorOf(text);
    const std::string prefix = "hsr_base.yaml:" + std::to_string(lineOf(text, c.line_of)) + ": ";
    EXPECT_EQ(message.rfind(prefix + c.expected, 0), 0u) << "case '" << c.to << "'\n  got:      " << message
                                                         << "\n  expected: " << prefix << c.expected;
  }
}

TEST(CanProfile, InvalidYamlAndMissingFileNameThePlace) {
  EXPECT_NE(errorOf("command: [1, 2").find("hsr_base.yaml"), std::string::npos);
  EXPECT_NE(errorOf("command: [1, 2").find("not valid YAML"), std::string::npos);
  EXPECT_EQ(errorOf("- 1\n- 2\n").rfind("hsr_base.yaml: expected a mapping", 0), 0u);
  // A section that is not a mapping: the whole status block becomes "status: 5".
  std::string text = shippedText();
  const std::size_t from = text.find("\nstatus:\n") + 1;
  const std::size_t to = text.find("\n\n", from);
  ASSERT_NE(to, std::string::npos);
  text.replace(from, to - from, "status: 5");
  EXPECT_EQ(errorOf(text), "hsr_base.yaml:" + std::to_string(lineOf(text, "status: 5")) +
                               ": status: expected a mapping {id, rate_hz, timeout_s}, got '5'");
  try {
    loadCanProfile("/nonexistent/base.yaml");
    FAIL() << "loaded a missing file";
  } catch (const CanProfileError& e) {
    EXPECT_EQ(std::string(e.what()), "/nonexistent/base.yaml: CAN profile not found");
  }
}

}  // namespace
}  // namespace staa::hal
