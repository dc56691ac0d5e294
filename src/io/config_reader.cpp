#include "io/config_reader.hpp"

#include "io/yaml_support.hpp"

#include "geometry/polygon.hpp"

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <fstream>
#include <optional>
#include <sstream>
#include <system_error>
#include <unordered_map>
#include <utility>

namespace staa::io {

namespace fs = std::filesystem;

struct Origin {
  std::string source;
  fs::path directory;
  std::shared_ptr<const YamlTree> tree;  // the nodes every value of the document points into
};

namespace {

int lineOf(const YamlNode& node) { return node.line(); }

std::string joined(std::initializer_list<std::string_view> keys) {
  std::string out;
  for (std::string_view k : keys) {
    if (!out.empty()) out += ", ";
    out += k;
  }
  return out;
}

// A decimal integer, a leading + allowed.
template <class T>
std::optional<T> parseInteger(const YamlNode& node) {
  if (!node.IsScalar()) return std::nullopt;
  std::string_view s = node.Scalar();
  if (!s.empty() && s.front() == '+') s.remove_prefix(1);
  T v{};
  const auto res = std::from_chars(s.data(), s.data() + s.size(), v);
  if (s.empty() || res.ec != std::errc{} || res.ptr != s.data() + s.size()) return std::nullopt;
  return v;
}

std::string pointText(const Vec2& p) { return yaml_support::formatPoint(p); }

}  // namespace

// ---- ConfigValue ----

ConfigValue::ConfigValue(std::shared_ptr<const Origin> origin, bool given, YamlNode node, std::string path, int line,
                         int key_line)
    : origin_(std::move(origin)), given_(given), node_(std::move(node)), path_(std::move(path)), line_(line), key_line_(key_line) {}

ConfigValue ConfigValue::absent(std::string path) const { return ConfigValue(origin_, false, YamlNode(), std::move(path), line_, line_); }

std::string ConfigValue::childPath(std::string_view key) const {
  std::string out = path_;
  if (!out.empty()) out += '.';
  out += key;
  return out;
}

const std::string& ConfigValue::source() const { return origin_->source; }

std::string ConfigValue::text() const {
  if (given_ && node_.IsScalar()) return std::string(node_.Scalar());
  return described();
}

std::string ConfigValue::described() const { return given_ ? yaml_support::describe(node_) : std::string("nothing"); }

void ConfigValue::fail(const std::string& problem) const {
  std::string msg = origin_->source;
  if (line_ > 0) msg += ":" + std::to_string(line_);
  msg += ": ";
  if (!path_.empty()) msg += path_ + ": ";
  msg += problem;
  throw ConfigError(msg);
}

void ConfigValue::failAtKey(const std::string& problem) const {
  ConfigValue at = *this;
  at.line_ = key_line_;
  at.fail(problem);
}

void ConfigValue::failAt(const ConfigValue& where, const std::string& problem) const {
  ConfigValue at = *this;
  at.line_ = where.key_line_;
  at.fail(problem);
}

void ConfigValue::failRule(const std::string& rule) const { fail("must be " + rule + ", got " + text()); }

const ConfigValue& ConfigValue::anyMapping() const {
  if (!given_ || !node_.IsMap()) fail("expected a mapping, got " + described());
  // A hash of the keys seen: linear in the mapping's size (a pairwise scan would make a
  // mapping of 100,000 keys cost 5 billion comparisons).
  std::unordered_map<std::string_view, int> seen;
  seen.reserve(node_.size());
  for (std::size_t i = 0; i < node_.size(); ++i) {
    const YamlNode key = node_.key(i);
    if (!key.IsScalar()) continue;
    const auto [it, fresh] = seen.emplace(key.Scalar(), lineOf(key));
    if (!fresh) {
      ConfigValue at = child(key, node_.value(i), key.Scalar());
      at.failAtKey("given twice (first on line " + std::to_string(it->second) + ")");
    }
  }
  return *this;
}

const ConfigValue& ConfigValue::mapping(std::initializer_list<std::string_view> keys) const {
  if (!given_ || !node_.IsMap()) fail("expected a mapping {" + joined(keys) + "}, got " + described());
  for (std::size_t i = 0; i < node_.size(); ++i) {
    const YamlNode key = node_.key(i);
    if (!key.IsScalar()) {
      ConfigValue at = *this;
      at.line_ = lineOf(key);
      at.fail("a key that is not a name, " + yaml_support::describe(key) + " (expected " + joined(keys) + ")");
    }
    if (std::find(keys.begin(), keys.end(), key.Scalar()) == keys.end()) {
      child(key, node_.value(i), key.Scalar()).failAtKey("unknown key (expected " + joined(keys) + ")");
    }
  }
  return anyMapping();
}

ConfigValue ConfigValue::child(const YamlNode& key, const YamlNode& value, std::string_view name) const {
  const int key_line = lineOf(key);
  // A null value (`key:` and nothing) has yaml-cpp's mark of whatever follows it.
  const int line = value.IsNull() ? 0 : lineOf(value);
  return ConfigValue(origin_, true, value, childPath(name), line > 0 ? line : key_line, key_line > 0 ? key_line : line);
}

ConfigValue ConfigValue::get(std::string_view key) const {
  if (given_ && node_.IsMap()) {
    for (std::size_t i = 0; i < node_.size(); ++i) {
      const YamlNode k = node_.key(i);
      if (k.IsScalar() && k.Scalar() == key) return child(k, node_.value(i), key);
    }
  }
  return absent(childPath(key));
}

ConfigValue ConfigValue::required(std::string_view key, std::string_view what) const {
  ConfigValue v = get(key);
  if (!v.present()) v.fail(what.empty() ? std::string("missing") : "missing (" + std::string(what) + ")");
  return v;
}

ConfigValue ConfigValue::section(std::string_view key, std::initializer_list<std::string_view> keys) const {
  ConfigValue v = get(key);
  if (v.given()) v.mapping(keys);
  return v;
}

const ConfigValue& ConfigValue::list(std::string_view what, std::size_t min_items) const {
  if (!given_ || !node_.IsSequence() || node_.size() < min_items) fail("expected " + std::string(what) + ", got " + described());
  return *this;
}

ConfigValue ConfigValue::operator[](std::size_t i) const {
  std::string path = path_ + "[" + std::to_string(i) + "]";
  if (!given_ || !node_.IsSequence() || i >= node_.size()) return absent(std::move(path));
  const YamlNode item = node_[i];
  const int line = lineOf(item);
  return ConfigValue(origin_, true, item, std::move(path), line > 0 ? line : line_, line > 0 ? line : line_);
}

double ConfigValue::number() const {
  const std::optional<double> v = given_ ? yaml_support::readNumber(node_) : std::nullopt;
  if (!v) fail("expected a number, got " + described());
  if (!std::isfinite(*v)) fail("must be finite, got " + text());
  return *v;
}

double ConfigValue::number(const Range& range) const {
  const double v = number();
  if (!range.contains(v)) failRule(range.text());
  return v;
}

long long ConfigValue::integer() const {
  const std::optional<long long> v = given_ ? parseInteger<long long>(node_) : std::nullopt;
  if (!v) fail("expected an integer, got " + described());
  return *v;
}

long long ConfigValue::integer(long long lo, long long hi, std::string_view note) const {
  const std::optional<long long> v = given_ ? parseInteger<long long>(node_) : std::nullopt;
  if (!v || *v < lo || *v > hi) {
    fail("must be an integer in " + std::to_string(lo) + ".." + std::to_string(hi) + std::string(note) + ", got " + text());
  }
  return *v;
}

std::uint64_t ConfigValue::unsignedInteger() const {
  const std::optional<std::uint64_t> v = given_ ? parseInteger<std::uint64_t>(node_) : std::nullopt;
  if (!v) fail("must be an integer >= 0, got " + text());
  return *v;
}

bool ConfigValue::boolean() const {
  bool on = false;
  if (!given_ || !node_.IsScalar() || !decodeYamlBool(node_.Scalar(), on)) fail("expected true or false, got " + described());
  return on;
}

std::string ConfigValue::string(std::string_view what) const {
  if (!given_ || !node_.IsScalar()) fail("expected " + std::string(what) + ", got " + described());
  return std::string(node_.Scalar());
}

std::string ConfigValue::nonEmptyString(std::string_view what) const {
  std::string s = string(what);
  if (s.empty()) fail("expected " + std::string(what) + ", got ''");
  return s;
}

fs::path ConfigValue::path(std::string_view what) const {
  const fs::path p(nonEmptyString(what));
  return p.is_absolute() ? p : origin_->directory / p;
}

std::string ConfigValue::joinedChoices(std::span<const std::string_view> names, std::span<const std::string_view> meanings) {
  std::string out;
  for (std::size_t i = 0; i < names.size(); ++i) {
    if (i > 0) out += i + 1 == names.size() ? " or " : ", ";
    out += names[i];
    if (!meanings[i].empty()) {
      out += " (";
      out += meanings[i];
      out += ')';
    }
  }
  return out;
}

Vec2 ConfigValue::point() const {
  const auto v = numbers<2>("[x, y]");
  return {v[0], v[1]};
}

Pose2 ConfigValue::pose() const {
  const auto v = numbers<3>("[x, y, theta]");
  return {v[0], v[1], v[2]};
}

std::vector<Vec2> ConfigValue::points(std::string_view what, std::size_t max_items, std::string_view bound_note) const {
  list(what);
  if (size() > max_items) {
    fail("has " + std::to_string(size()) + " points, beyond the bound of " + std::to_string(max_items) + std::string(bound_note));
  }
  std::vector<Vec2> out;
  out.reserve(size());
  for (std::size_t k = 0; k < size(); ++k) {
    const YamlNode item = node_[k];
    const std::optional<double> x = item.IsSequence() && item.size() == 2 ? readFiniteNumber(item[0]) : std::nullopt;
    const std::optional<double> y = x ? readFiniteNumber(item[1]) : std::nullopt;
    out.push_back(y ? Vec2(*x, *y) : (*this)[k].point());
  }
  return out;
}

Polygon ConfigValue::polygon() const {
  list("a list of [x, y] vertices");
  Polygon poly;
  poly.reserve(size());
  for (std::size_t k = 0; k < size(); ++k) poly.push_back((*this)[k].point());
  if (const std::string problem = polygonProblem(poly); !problem.empty()) fail(problem);
  return poly;
}

// ---- ConfigDocument ----

ConfigDocument ConfigDocument::parse(const std::string& text, const std::string& source) {
  return parse(text, source, fs::path(source).parent_path());
}

ConfigDocument ConfigDocument::parse(const std::string& text, const std::string& source, const fs::path& directory) {
  if (text.size() > kMaxYamlFileBytes) {
    throw ConfigError(source + ": " + std::to_string(text.size()) + " bytes, beyond the bound of " +
                      std::to_string(kMaxYamlFileBytes) + " bytes for a YAML file");
  }
  std::shared_ptr<const YamlTree> tree = YamlTree::parse(text, source);
  const YamlNode root = tree->root();
  auto origin = std::make_shared<const Origin>(Origin{source, directory, std::move(tree)});
  // The document as a whole has no line: a key missing from it is missing from the file.
  return ConfigDocument(ConfigValue(std::move(origin), true, root, "", 0, 0));
}

const ConfigValue& ConfigDocument::root(std::string_view format, std::initializer_list<std::string_view> keys) const {
  if (!root_.node().IsMap()) {
    root_.fail("expected a mapping {" + joined(keys) + "} (a " + std::string(format) + " document), got " + root_.described());
  }
  const ConfigValue f = root_.get("format");
  if (!f.present()) f.fail("missing (expected " + std::string(format) + ")");
  if (!f.node().IsScalar() || f.node().Scalar() != format) {
    f.fail("unknown format, expected " + std::string(format) + ", got " + f.described());
  }
  root_.mapping(keys);
  return root_;
}

std::string ConfigDocument::readFile(const fs::path& file, std::string_view what) {
  const std::string name = file.string();
  std::error_code ec;
  const auto status = fs::status(file, ec);
  if (!fs::exists(status)) throw ConfigError(name + ": " + std::string(what) + " not found");
  if (fs::is_directory(status)) throw ConfigError(name + ": is a directory, not a " + std::string(what));
  // Refused before reading: a file beyond the bound is not read into memory at all.
  if (const auto size = fs::file_size(file, ec); !ec && size > kMaxYamlFileBytes) {
    throw ConfigError(name + ": " + std::to_string(size) + " bytes, beyond the bound of " + std::to_string(kMaxYamlFileBytes) +
                      " bytes for a " + std::string(what));
  }
  std::ifstream in(file, std::ios::binary);
  if (!in) throw ConfigError(name + ": cannot open " + std::string(what) + ": " + std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) throw ConfigError(name + ": read error");
  return std::move(text).str();
}

std::optional<double> readFiniteNumber(const YamlNode& node) {
  const std::optional<double> v = yaml_support::readNumber(node);
  return v && std::isfinite(*v) ? v : std::nullopt;
}

// ---- polygons ----

std::string polygonProblem(PolygonView poly) {
  const std::size_t n = poly.size();
  if (n < 3) return "has " + std::to_string(n) + " vertices, needs at least 3";
  for (std::size_t k = 0; k < n; ++k) {
    if (!std::isfinite(poly[k].x()) || !std::isfinite(poly[k].y())) return "vertex " + std::to_string(k) + " is not finite " + pointText(poly[k]);
  }
  // Edge k runs from vertex k to vertex k+1 (the last one back to vertex 0). A repeated
  // vertex is checked first: findSelfIntersection would report it as touching edges.
  for (std::size_t i = 0; i < n; ++i) {
    if (poly[i] == poly[(i + 1) % n]) {
      return "vertex " + std::to_string((i + 1) % n) + " repeats vertex " + std::to_string(i) + " " + pointText(poly[i]) +
             " (zero-length edge " + std::to_string(i) + ")";
    }
  }
  if (const auto e = findSelfIntersection(poly)) {
    const std::size_t i = e->first, j = e->second;
    const bool adjacent = (j == i + 1) || (i == 0 && j == n - 1);
    const char* how = adjacent ? " fold back over each other)"
                      : segmentsCrossProperly(poly[i], poly[(i + 1) % n], poly[j], poly[(j + 1) % n])
                          ? " cross)"
                          : " touch)";
    return "self-intersecting (edges " + std::to_string(i) + " and " + std::to_string(j) + how;
  }
  // Collinear vertices pass the edge test when no two edges overlap (a triangle on a line);
  // the area, relative to the polygon's size, catches them.
  const Box box = boundingBox(poly);
  const double size = std::max(box.width(), box.height());
  if (std::abs(signedArea(poly)) <= 1e-12 * size * size) return "has zero area (all vertices on one line)";
  return "";
}

}  // namespace staa::io
