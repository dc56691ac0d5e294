#include "io/yaml_tree.hpp"

#include "io/config_rules.hpp"

#include <yaml.h>

#include <algorithm>
#include <array>
#include <limits>
#include <unordered_map>

namespace staa::io {

// ---- YamlNode ----

bool YamlNode::IsNull() const { return tree_ != nullptr && tree_->nodes_[index_].kind == YamlTree::Kind::kNull; }
bool YamlNode::IsScalar() const { return tree_ != nullptr && tree_->nodes_[index_].kind == YamlTree::Kind::kScalar; }
bool YamlNode::IsSequence() const { return tree_ != nullptr && tree_->nodes_[index_].kind == YamlTree::Kind::kSequence; }
bool YamlNode::IsMap() const { return tree_ != nullptr && tree_->nodes_[index_].kind == YamlTree::Kind::kMap; }

std::string_view YamlNode::Scalar() const {
  if (!IsScalar()) return {};
  const YamlTree::Node& n = tree_->nodes_[index_];
  return std::string_view(tree_->text_).substr(n.first, n.count);
}

std::size_t YamlNode::size() const {
  if (IsSequence()) return tree_->nodes_[index_].count;
  if (IsMap()) return tree_->nodes_[index_].count / 2;
  return 0;
}

YamlNode YamlNode::operator[](std::size_t i) const {
  if (!IsSequence() || i >= size()) return {};
  return YamlNode(tree_, tree_->children_[tree_->nodes_[index_].first + i]);
}

YamlNode YamlNode::key(std::size_t i) const {
  if (!IsMap() || i >= size()) return {};
  return YamlNode(tree_, tree_->children_[tree_->nodes_[index_].first + 2 * i]);
}

YamlNode YamlNode::value(std::size_t i) const {
  if (!IsMap() || i >= size()) return {};
  return YamlNode(tree_, tree_->children_[tree_->nodes_[index_].first + 2 * i + 1]);
}

int YamlNode::line() const { return tree_ != nullptr ? static_cast<int>(tree_->nodes_[index_].line) : 0; }
int YamlNode::column() const { return tree_ != nullptr ? static_cast<int>(tree_->nodes_[index_].column) : 0; }

bool decodeYamlBool(std::string_view text, bool& out) {
  static constexpr std::array<std::pair<std::string_view, bool>, 8> kWords{
      {{"true", true}, {"false", false}, {"yes", true}, {"no", false}, {"on", true}, {"off", false}, {"y", true}, {"n", false}}};
  for (const auto& [word, value] : kWords) {
    if (text.size() != word.size()) continue;
    // lower, Capitalised or UPPER case, as yaml-cpp takes them
    std::string capital(word), upper(word);
    capital[0] = static_cast<char>(capital[0] - 'a' + 'A');
    for (char& c : upper) c = static_cast<char>(c - 'a' + 'A');
    if (text == word || text == capital || text == upper) {
      out = value;
      return true;
    }
  }
  return false;
}

// ---- parsing ----

namespace {

bool isNullText(std::string_view s) { return s.empty() || s == "~" || s == "null" || s == "Null" || s == "NULL"; }

// Owns the parser and the current event, so that every exit frees them.
struct Parser {
  yaml_parser_t parser;
  yaml_event_t event;
  bool has_event = false;
  Parser() { yaml_parser_initialize(&parser); }
  ~Parser() {
    if (has_event) yaml_event_delete(&event);
    yaml_parser_delete(&parser);
  }
  Parser(const Parser&) = delete;
  Parser& operator=(const Parser&) = delete;
  bool next() {
    if (has_event) yaml_event_delete(&event);
    has_event = yaml_parser_parse(&parser, &event) != 0;
    return has_event;
  }
};

std::string at(const std::string& source, const yaml_mark_t& mark) {
  return source + ":" + std::to_string(mark.line + 1) + ":" + std::to_string(mark.column + 1) + ": ";
}

}  // namespace

std::shared_ptr<const YamlTree> YamlTree::parse(std::string_view text, const std::string& source) {
  auto tree = std::make_shared<YamlTree>();
  YamlTree& t = *tree;
  Parser p;
  yaml_parser_set_input_string(&p.parser, reinterpret_cast<const unsigned char*>(text.data()), text.size());

  struct Open {
    std::uint32_t node;
    std::size_t first_pending;
    std::string anchor;
  };
  std::vector<Open> open;
  std::vector<std::uint32_t> pending;       // children of the open collections, in order
  std::vector<std::uint64_t> expanded;      // per node: its size with aliases expanded
  std::vector<std::uint32_t> height;        // per node: collections nested in it, itself included
  std::unordered_map<std::string, std::uint32_t> anchors;
  bool have_root = false;

  auto addNode = [&](Kind kind, const yaml_mark_t& mark) {
    if (t.nodes_.size() >= std::numeric_limits<std::uint32_t>::max()) throw ConfigError(at(source, mark) + "too many nodes");
    Node n;
    n.kind = kind;
    n.line = static_cast<std::uint32_t>(mark.line + 1);
    n.column = static_cast<std::uint32_t>(mark.column + 1);
    t.nodes_.push_back(n);
    expanded.push_back(1);
    height.push_back(kind == Kind::kSequence || kind == Kind::kMap ? 1 : 0);
    return static_cast<std::uint32_t>(t.nodes_.size() - 1);
  };
  // A complete node joins its parent (or becomes the root).
  auto place = [&](std::uint32_t id) {
    if (open.empty()) {
      if (!have_root) t.root_ = id;
      have_root = true;
    } else {
      pending.push_back(id);
    }
  };
  auto anchorOf = [](const yaml_char_t* a) { return a != nullptr ? std::string(reinterpret_cast<const char*>(a)) : std::string(); };

  bool done = false;
  while (!done) {
    if (!p.next()) {
      std::string msg = at(source, p.parser.problem_mark) + "not valid YAML: ";
      msg += p.parser.problem != nullptr ? p.parser.problem : "out of memory";
      if (p.parser.context != nullptr) {
        msg += std::string(" (") + p.parser.context + " that starts on line " + std::to_string(p.parser.context_mark.line + 1) + ")";
      }
      throw ConfigError(msg);
    }
    const yaml_event_t& e = p.event;
    switch (e.type) {
      case YAML_SCALAR_EVENT: {
        const std::string_view value(reinterpret_cast<const char*>(e.data.scalar.value), e.data.scalar.length);
        const bool null = e.data.scalar.style == YAML_PLAIN_SCALAR_STYLE && e.data.scalar.tag == nullptr && isNullText(value);
        const std::uint32_t id = addNode(null ? Kind::kNull : Kind::kScalar, e.start_mark);
        if (!null) {
          t.nodes_[id].first = static_cast<std::uint32_t>(t.text_.size());
          t.nodes_[id].count = static_cast<std::uint32_t>(value.size());
          t.text_.append(value);
        }
        if (e.data.scalar.anchor != nullptr) anchors[anchorOf(e.data.scalar.anchor)] = id;
        place(id);
        break;
      }
      case YAML_SEQUENCE_START_EVENT:
      case YAML_MAPPING_START_EVENT: {
        if (open.size() + 1 > kMaxYamlDepth) {
          throw ConfigError(at(source, e.start_mark) + "nested too deep: at most " + std::to_string(kMaxYamlDepth) +
                            " levels of lists and mappings");
        }
        const bool seq = e.type == YAML_SEQUENCE_START_EVENT;
        const std::uint32_t id = addNode(seq ? Kind::kSequence : Kind::kMap, e.start_mark);
        open.push_back({id, pending.size(), anchorOf(seq ? e.data.sequence_start.anchor : e.data.mapping_start.anchor)});
        break;
      }
      case YAML_SEQUENCE_END_EVENT:
      case YAML_MAPPING_END_EVENT: {
        Open o = std::move(open.back());
        open.pop_back();
        Node& n = t.nodes_[o.node];
        n.first = static_cast<std::uint32_t>(t.children_.size());
        n.count = static_cast<std::uint32_t>(pending.size() - o.first_pending);
        std::uint64_t size = 1;
        std::uint32_t h = 0;
        for (std::size_t i = o.first_pending; i < pending.size(); ++i) {
          size += expanded[pending[i]];
          h = std::max(h, height[pending[i]]);
        }
        if (size > kMaxYamlNodes) {
          yaml_mark_t mark{};
          mark.line = n.line - 1;
          mark.column = n.column - 1;
          throw ConfigError(at(source, mark) + "aliases expand the document beyond " + std::to_string(kMaxYamlNodes) +
                            " nodes (the bound)");
        }
        expanded[o.node] = size;
        height[o.node] = h + 1;
        t.children_.insert(t.children_.end(), pending.begin() + static_cast<std::ptrdiff_t>(o.first_pending), pending.end());
        pending.resize(o.first_pending);
        if (!o.anchor.empty()) anchors[o.anchor] = o.node;
        place(o.node);
        break;
      }
      case YAML_ALIAS_EVENT: {
        const std::string name = anchorOf(e.data.alias.anchor);
        const auto it = anchors.find(name);
        if (it == anchors.end()) {
          throw ConfigError(at(source, e.start_mark) + "not valid YAML: unknown anchor '" + name +
                            "' (an alias names a complete node before it)");
        }
        if (open.size() + height[it->second] > kMaxYamlDepth) {
          throw ConfigError(at(source, e.start_mark) + "nested too deep through alias *" + name + ": at most " +
                            std::to_string(kMaxYamlDepth) + " levels of lists and mappings");
        }
        place(it->second);
        break;
      }
      case YAML_DOCUMENT_END_EVENT:  // the first document only, as yaml-cpp's Load
      case YAML_STREAM_END_EVENT:
        done = true;
        break;
      default:
        break;
    }
  }
  if (!have_root) {
    yaml_mark_t mark{};
    t.root_ = addNode(Kind::kNull, mark);
    t.nodes_[t.root_].line = 0;
    t.nodes_[t.root_].column = 0;
  }
  return tree;
}

}  // namespace staa::io
