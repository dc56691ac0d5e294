#pragma once
// The YAML pieces under the config reader (io/config_reader.hpp) and the map writer: one
// strict, locale-free number reader, the shortest round-trip number writer, and the "got X"
// part of error messages.

#include "geometry/types.hpp"
#include "io/yaml_tree.hpp"

#include <optional>
#include <string>

namespace staa::yaml_support {

// A short, single-line description of what a node holds, for "expected X, got Y" messages.
std::string describe(const io::YamlNode& node);
// Shortest text that reads back to the same double bit for bit; YAML spellings for .nan/.inf.
std::string formatNumber(double v);
std::string formatPoint(const Vec2& p);
// A YAML scalar as a double (std::from_chars: locale-free, subnormals, the exact inverse of
// formatNumber; .nan and .inf spellings too). Callers reject non-finite values themselves.
std::optional<double> readNumber(const io::YamlNode& node);

}  // namespace staa::yaml_support
