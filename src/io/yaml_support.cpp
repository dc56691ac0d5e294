#include "io/yaml_support.hpp"

#include "io/config_rules.hpp"

#include <charconv>
#include <cmath>
#include <limits>
#include <string_view>

namespace staa::yaml_support {

std::string describe(const io::YamlNode& node) {
  if (!node.IsDefined() || node.IsNull()) return "nothing";
  if (node.IsScalar()) {
    // Appended piece by piece: GCC 12 warns falsely (-Wrestrict) on "'" + s + "'".
    const std::string_view scalar = node.Scalar();
    std::string out = "'";
    if (scalar.size() > 40) {
      out.append(scalar.substr(0, 37));
      out += "...";
    } else {
      out += scalar;
    }
    out += '\'';
    return out;
  }
  if (node.IsSequence()) return "a list of " + std::to_string(node.size()) + " items";
  return "a mapping";
}

std::string formatNumber(double v) { return io::numberText(v); }

std::string formatPoint(const Vec2& p) {
  std::string out = "(";  // appended: GCC 12 warns falsely (-Wrestrict) on chained operator+
  out += formatNumber(p.x());
  out += ", ";
  out += formatNumber(p.y());
  out += ')';
  return out;
}

std::optional<double> readNumber(const io::YamlNode& node) {
  if (!node.IsScalar()) return std::nullopt;
  std::string_view s = node.Scalar();
  for (std::string_view nan : {".nan", ".NaN", ".NAN"}) {
    if (s == nan) return std::numeric_limits<double>::quiet_NaN();
  }
  bool negative = false;
  if (!s.empty() && (s.front() == '+' || s.front() == '-')) {
    negative = s.front() == '-';
    s.remove_prefix(1);
  }
  for (std::string_view inf : {".inf", ".Inf", ".INF"}) {
    if (s == inf) return negative ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  }
  // from_chars takes no sign of its own beyond '-', so parse the magnitude and apply it.
  if (s.empty() || s.front() == '+' || s.front() == '-') return std::nullopt;
  double v = 0.0;
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v, std::chars_format::general);
  if (res.ec != std::errc{} || res.ptr != s.data() + s.size()) return std::nullopt;
  return negative ? -v : v;
}

}  // namespace staa::yaml_support
