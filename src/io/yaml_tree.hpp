#pragma once
// A parsed YAML document as a compact tree, read by libyaml's event parser (the C reference
// parser: a 200,000-vertex map, 4.5 MB, takes 0.08 s where yaml-cpp's Load took 1.2 s).
// The tree is what io::ConfigValue reads; the accessors keep yaml-cpp's names (IsScalar,
// Scalar, IsMap, ...), so that readers written against those read on unchanged.
//
// Bounds (docs/ARCHITECTURE.md, "Input bounds"): a text of more than kMaxYamlFileBytes
// (ConfigDocument), nesting deeper than kMaxYamlDepth and a
// document whose aliases expand it beyond kMaxYamlNodes nodes are refused while parsing,
// naming the bound; an alias is shared, never copied, and may only name a complete node (no
// cycles). Only the first document of a stream is read.

#include <cstdint>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

namespace staa::io {

inline constexpr std::size_t kMaxYamlFileBytes = 64u << 20;  // a YAML file or text
inline constexpr std::size_t kMaxYamlDepth = 64;           // nested collections
inline constexpr std::uint64_t kMaxYamlNodes = 8'000'000;  // nodes, aliases expanded

class YamlTree;

// One node of a YamlTree (or an undefined one: a missing key, an item past the end). Cheap
// to copy; valid while its tree lives.
class YamlNode {
 public:
  YamlNode() = default;

  bool IsDefined() const { return tree_ != nullptr; }
  // `~`, `null`, `Null`, `NULL` and an empty plain scalar (`key:` with nothing after it).
  bool IsNull() const;
  bool IsScalar() const;
  bool IsSequence() const;
  bool IsMap() const;
  // The scalar's text ("" for anything else).
  std::string_view Scalar() const;
  // Items of a sequence, entries of a mapping, 0 otherwise.
  std::size_t size() const;
  // Item i of a sequence (undefined past the end or for anything else).
  YamlNode operator[](std::size_t i) const;
  // Entry i of a mapping: its key and its value.
  YamlNode key(std::size_t i) const;
  YamlNode value(std::size_t i) const;
  // 1-based line and column of the node's first character; 0 when undefined.
  int line() const;
  int column() const;

 private:
  friend class YamlTree;
  YamlNode(const YamlTree* tree, std::uint32_t index) : tree_(tree), index_(index) {}
  const YamlTree* tree_ = nullptr;
  std::uint32_t index_ = 0;
};

// YAML's booleans as yaml-cpp reads them: true/false, yes/no, on/off, y/n in lower case,
// Capitalised or UPPER case. False when the text is none of them.
bool decodeYamlBool(std::string_view text, bool& out);

class YamlTree {
 public:
  // Parses the first document of `text`. Invalid YAML or a bound passed: ConfigError
  // "SOURCE:LINE:COLUMN: not valid YAML: why" / "SOURCE:LINE:COLUMN: ...: at most N ...".
  static std::shared_ptr<const YamlTree> parse(std::string_view text, const std::string& source);

  // The document's root (a null node for an empty stream).
  YamlNode root() const { return YamlNode(this, root_); }

 private:
  friend class YamlNode;
  enum class Kind : std::uint8_t { kNull, kScalar, kSequence, kMap };
  struct Node {
    Kind kind = Kind::kNull;
    std::uint32_t line = 0;    // 1-based
    std::uint32_t column = 0;  // 1-based
    // Scalar: its text in text_; collections: their children in children_ (a mapping's as
    // key, value, key, value, ...).
    std::uint32_t first = 0;
    std::uint32_t count = 0;
  };
  std::vector<Node> nodes_;
  std::vector<std::uint32_t> children_;
  std::string text_;
  std::uint32_t root_ = 0;
};

}  // namespace staa::io
