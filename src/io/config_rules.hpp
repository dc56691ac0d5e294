#pragma once
// What a config value must be, and the errors when it is not; free of YAML, so that a module
// can state and check its own config's rules without knowing any file format.
//
// Range: the interval a number must lie in, with its unit ("> 0 m", "in (0, 1000] Hz").
// Choice: a name of an enum selector in a file, so that the enum's names live beside it.
//
// ConfigError: a file (or text) that breaks its format; what() is the whole message
// ("FILE:LINE: key.path: what is wrong, got VALUE", io/config_reader.hpp). Each format may
// throw its own type derived from it (MapError, ProfileError, ...).
//
// FieldError: a field of a module's config struct that breaks the module's rule. The module
// validates its own config in one function (perception's DepthObstaclesConfig, the camera
// model's intrinsics and mount) and throws this; a config reader that filled the struct from
// a file catches it and names the key and line the field came from.

#include <charconv>
#include <cmath>
#include <limits>
#include <optional>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>

namespace staa::io {

class ConfigError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// Shortest text that reads back to the same double bit for bit; YAML spellings for .nan/.inf.
inline std::string numberText(double v) {
  if (std::isnan(v)) return ".nan";
  if (std::isinf(v)) return v > 0 ? ".inf" : "-.inf";
  char buf[64];
  const auto res = std::to_chars(buf, buf + sizeof buf, v);
  return std::string(buf, res.ptr);
}

// The values a number may take, with its unit, for the check and its message:
// Range::above(0, "m") is "> 0 m", Range::leftOpen(0, 1000, "Hz") "in (0, 1000] Hz".
struct Range {
  double lo = -std::numeric_limits<double>::infinity();
  double hi = std::numeric_limits<double>::infinity();
  bool lo_open = false;
  bool hi_open = false;
  std::string_view unit;  // "m", "Hz", "pixels"; empty: none
  std::string_view note;  // said after the rule, in parentheses

  static constexpr Range above(double lo, std::string_view unit = {}, std::string_view note = {}) {
    return {lo, std::numeric_limits<double>::infinity(), true, false, unit, note};
  }
  static constexpr Range atLeast(double lo, std::string_view unit = {}, std::string_view note = {}) {
    return {lo, std::numeric_limits<double>::infinity(), false, false, unit, note};
  }
  static constexpr Range atMost(double hi, std::string_view unit = {}, std::string_view note = {}) {
    return {-std::numeric_limits<double>::infinity(), hi, false, false, unit, note};
  }
  static constexpr Range closed(double lo, double hi, std::string_view unit = {}, std::string_view note = {}) {
    return {lo, hi, false, false, unit, note};
  }
  static constexpr Range leftOpen(double lo, double hi, std::string_view unit = {}, std::string_view note = {}) {
    return {lo, hi, true, false, unit, note};
  }
  static constexpr Range rightOpen(double lo, double hi, std::string_view unit = {}, std::string_view note = {}) {
    return {lo, hi, false, true, unit, note};
  }

  bool contains(double v) const {
    const bool above_lo = lo_open ? v > lo : v >= lo;
    const bool below_hi = hi_open ? v < hi : v <= hi;
    return above_lo && below_hi;
  }
  // "> 0 m", ">= 0 m/s", "<= 0", "in (0, 1000] Hz", "in [0, 640) pixels (inside the image)".
  std::string text() const {
    std::string out;
    if (std::isfinite(lo) && std::isfinite(hi)) {
      out = "in ";
      out += lo_open ? '(' : '[';
      out += numberText(lo);
      out += ", ";
      out += numberText(hi);
      out += hi_open ? ')' : ']';
    } else if (std::isfinite(lo)) {
      out = lo_open ? "> " : ">= ";
      out += numberText(lo);
    } else if (std::isfinite(hi)) {
      out = hi_open ? "< " : "<= ";
      out += numberText(hi);
    } else {
      out = "a number";
    }
    if (!unit.empty()) {
      out += ' ';
      out += unit;
    }
    if (!note.empty()) {
      out += " (";
      out += note;
      out += ')';
    }
    return out;
  }
};

// One name of an enum selector in a file, with what it means (said in the error message).
template <class E>
struct Choice {
  std::string_view name;
  E value;
  std::string_view meaning = {};  // "the simulator's movers"; empty: the name says it
};

// The name of `value` in `choices` ("?" when it has none).
template <class E>
std::string_view nameOf(std::span<const Choice<E>> choices, E value) {
  for (const Choice<E>& c : choices) {
    if (c.value == value) return c.name;
  }
  return "?";
}

// The value named `name` in `choices`, if any (a command line's selector, say).
template <class E>
std::optional<E> valueOf(std::span<const Choice<E>> choices, std::string_view name) {
  for (const Choice<E>& c : choices) {
    if (c.name == name) return c.value;
  }
  return std::nullopt;
}

// "in 1..16": an integer's rule.
inline std::string integerRange(long long lo, long long hi) { return "in " + std::to_string(lo) + ".." + std::to_string(hi); }

// what(): "OWNER: FIELD must be RULE, got VALUE" ("depth obstacles: cell_m must be > 0 m,
// got -0.1").
class FieldError : public std::invalid_argument {
 public:
  FieldError(std::string_view owner, std::string field, std::string rule, double value)
      : std::invalid_argument(message(owner, field, rule, value)),
        field_(std::move(field)),
        rule_(std::move(rule)),
        value_(value) {}

  const std::string& field() const { return field_; }  // "cell_m", "mount.z"
  const std::string& rule() const { return rule_; }    // "> 0 m", "in 1..16"
  double value() const { return value_; }

 private:
  static std::string message(std::string_view owner, const std::string& field, const std::string& rule, double value) {
    std::string out(owner);
    out += ": ";
    out += field;
    out += " must be ";
    out += rule;
    out += ", got ";
    out += numberText(value);
    return out;
  }

  std::string field_;
  std::string rule_;
  double value_;
};

// A module's rule for one field: finite and in `range`, else a FieldError.
inline void requireField(std::string_view owner, const char* field, double value, const Range& range) {
  if (!std::isfinite(value)) throw FieldError(owner, field, "finite", value);
  if (!range.contains(value)) throw FieldError(owner, field, range.text(), value);
}

}  // namespace staa::io
