#pragma once
// The one strict reader of every YAML file the project reads: polygon maps, robot profiles,
// scenarios, CAN profiles, ROS map metadata and staad's config. Every value is read through
// a ConfigValue that knows its file, its line and its key path, so every error is one line
//   FILE:LINE: key.path: what is wrong, got VALUE
// and nothing passes silently: an unknown key (a typo) is refused naming the expected ones,
// a key given twice is refused (yaml-cpp keeps both, and which one wins would be an
// accident), a missing key, a wrong type, a non-finite number or a value out of its range
// is refused naming the value as written.
//
// "got" shows a value of the wrong kind quoted or described ('abc', a list of 2 items,
// nothing) and a value out of range as written (got -3, got .inf).

#include "geometry/types.hpp"
#include "io/config_rules.hpp"
#include "io/yaml_tree.hpp"

#include <array>
#include <cstdint>
#include <filesystem>
#include <initializer_list>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

namespace staa::io {

struct Origin;  // the file a value came from (source name, folder)

// One value of a document (present or not) with its file, line and key path.
class ConfigValue {
 public:
  // The key path: "rates.control_hz", "obstacles[2]", "" for the whole document.
  const std::string& keyPath() const { return path_; }
  // Given, with a value (`key:` with nothing after it, or ~, is not present).
  bool present() const { return given_ && !node_.IsNull(); }
  // Given at all, null included.
  bool given() const { return given_; }
  // 1-based; for a missing key the line of the mapping it is missing from; 0: unknown.
  int line() const { return line_; }
  // The line of the key that holds this value (a section's own line), else line().
  int keyLine() const { return key_line_; }
  const YamlNode& node() const { return node_; }
  const std::string& source() const;
  // The value as written (a scalar verbatim, else described), for "got ..." of a range.
  std::string text() const;
  // The value quoted or described ('abc', a list of 2 items, nothing).
  std::string described() const;

  // "SOURCE:LINE: PATH: problem" (no line when unknown, no path for the document).
  [[noreturn]] void fail(const std::string& problem) const;
  // The same at keyLine(): for a problem of a section as a whole.
  [[noreturn]] void failAtKey(const std::string& problem) const;
  // This value's path at the key line of `where`: for a section missing because of another
  // key ("camera: missing (obstacles: depth needs ...)" on the obstacles line).
  [[noreturn]] void failAt(const ConfigValue& where, const std::string& problem) const;
  // "must be RULE, got VALUE".
  [[noreturn]] void failRule(const std::string& rule) const;

  // ---- mappings ----
  // This value as a mapping of (at most) `keys`: anything else, an unknown key or a key
  // given twice is refused. Returns *this for chaining.
  const ConfigValue& mapping(std::initializer_list<std::string_view> keys) const;
  // A mapping with any keys (a format of others, which may grow keys), none given twice.
  const ConfigValue& anyMapping() const;
  // A child of a mapping; not present() when absent (or when this is not present).
  ConfigValue get(std::string_view key) const;
  // The child, which must be present: else "KEY: missing (what)" at this mapping's line.
  ConfigValue required(std::string_view key, std::string_view what = {}) const;
  // An optional section: absent, or a mapping of `keys`.
  ConfigValue section(std::string_view key, std::initializer_list<std::string_view> keys) const;

  // ---- lists ----
  // This value as a list of at least `min_items` items ("expected WHAT, got ...").
  const ConfigValue& list(std::string_view what, std::size_t min_items = 0) const;
  std::size_t size() const { return node_.IsSequence() ? node_.size() : 0; }
  // Item i of a list: path "PATH[i]".
  ConfigValue operator[](std::size_t i) const;

  // ---- scalars ----
  // A finite number ("expected a number, got 'x'", "must be finite, got .inf").
  double number() const;
  // A finite number in `range` ("must be > 0 m, got -1").
  double number(const Range& range) const;
  // A decimal integer (a leading + allowed), no range ("expected an integer, got '2.5'").
  long long integer() const;
  // An integer in lo..hi ("must be an integer in 0..99 NOTE, got 120").
  long long integer(long long lo, long long hi, std::string_view note = {}) const;
  // An integer >= 0 up to 2^64 - 1 (seeds).
  std::uint64_t unsignedInteger() const;
  // true or false (YAML's spellings: true/false, yes/no, on/off).
  bool boolean() const;
  // Any scalar, the empty string included ("expected WHAT, got a list of 2 items").
  std::string string(std::string_view what) const;
  // A scalar that is not empty ("expected WHAT, got ''").
  std::string nonEmptyString(std::string_view what) const;
  // A file path; a relative one is relative to the file's folder (not normalised).
  std::filesystem::path path(std::string_view what = "a file path") const;
  // One of `choices` by name ("expected sim (the simulator) or socketcan, got 'can'").
  template <class E>
  E choice(std::span<const Choice<E>> choices) const;

  // ---- lists of numbers ----
  // Exactly N finite numbers; `shape` names them ("[xmin, ymin, xmax, ymax]").
  template <std::size_t N>
  std::array<double, N> numbers(std::string_view shape) const;
  Vec2 point() const;   // [x, y]
  Pose2 pose() const;   // [x, y, theta]
  // A list of at most `max_items` [x, y] points ("expected WHAT, got ..."; "has N points,
  // beyond the bound of MAX NOTE"). Read without a ConfigValue per point (a 200,000-vertex
  // polygon), the same messages as point() where one is not a point.
  std::vector<Vec2> points(std::string_view what, std::size_t max_items, std::string_view bound_note) const;
  // A list of [x, y] vertices: a simple polygon (polygonProblem()), either winding.
  Polygon polygon() const;

 private:
  friend class ConfigDocument;
  ConfigValue(std::shared_ptr<const Origin> origin, bool given, YamlNode node, std::string path, int line, int key_line);
  // The entry `key: value` of this mapping, as a value named `name`.
  ConfigValue child(const YamlNode& key, const YamlNode& value, std::string_view name) const;
  // A value not in the file, at `path`: its line is this value's.
  ConfigValue absent(std::string path) const;
  std::string childPath(std::string_view key) const;
  static std::string joinedChoices(std::span<const std::string_view> names, std::span<const std::string_view> meanings);

  std::shared_ptr<const Origin> origin_;
  bool given_ = false;
  YamlNode node_;  // read only when given_
  std::string path_;
  int line_ = 0;
  int key_line_ = 0;
};

// A parsed YAML document and where it came from.
class ConfigDocument {
 public:
  // `source` names the text in messages; relative paths in it are relative to `directory`
  // (default: source's folder). Invalid YAML: "SOURCE:LINE:COLUMN: not valid YAML: why".
  static ConfigDocument parse(const std::string& text, const std::string& source);
  static ConfigDocument parse(const std::string& text, const std::string& source, const std::filesystem::path& directory);
  // The text of `file`, or a ConfigError: "FILE: WHAT not found", "FILE: is a directory,
  // not a WHAT", "FILE: cannot open WHAT: why".
  static std::string readFile(const std::filesystem::path& file, std::string_view what);

  const ConfigValue& root() const { return root_; }
  // The document as a mapping of `keys` whose `format` key is `format` (checked first: a
  // file of another format is named as such, not as a pile of unknown keys).
  const ConfigValue& root(std::string_view format, std::initializer_list<std::string_view> keys) const;

 private:
  explicit ConfigDocument(ConfigValue root) : root_(std::move(root)) {}
  ConfigValue root_;
};

// Runs `read` (a parser written with ConfigValue) and rethrows a ConfigError as the
// format's own error type.
template <class Error, class Read>
auto readAs(const std::string& /*source*/, Read&& read) -> decltype(read()) {
  try {
    return read();
  } catch (const Error&) {
    throw;
  } catch (const ConfigError& e) {
    throw Error(e.what());
  }
}

// Why `polygon` is not a simple polygon, or "" when it is one: fewer than 3 vertices, a
// vertex not finite, a repeated vertex, two edges that cross, touch or fold back, zero area.
// Shared by the readers (with the line) and by checks of polygons built in memory.
std::string polygonProblem(PolygonView polygon);

// A finite number, or nothing (a ConfigValue's number() then says why).
std::optional<double> readFiniteNumber(const YamlNode& node);

// ---- templates ----

template <class E>
E ConfigValue::choice(std::span<const Choice<E>> choices) const {
  std::vector<std::string_view> names, meanings;
  for (const Choice<E>& c : choices) {
    if (node_.IsScalar() && node_.Scalar() == std::string_view(c.name)) return c.value;
    names.push_back(c.name);
    meanings.push_back(c.meaning);
  }
  fail("expected " + joinedChoices(names, meanings) + ", got " + described());
}

template <std::size_t N>
std::array<double, N> ConfigValue::numbers(std::string_view shape) const {
  if (!node_.IsSequence() || node_.size() != N) fail("expected " + std::string(shape) + ", got " + described());
  std::array<double, N> out{};
  for (std::size_t k = 0; k < N; ++k) {
    // Straight from the node; a ConfigValue (its key path) only to name a bad item.
    const std::optional<double> v = readFiniteNumber(node_[k]);
    out[k] = v ? *v : (*this)[k].number();
  }
  return out;
}

}  // namespace staa::io
