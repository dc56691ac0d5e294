#pragma once
// The command lines of the tools (staa-sim, staa-map) on CLI11: checks of numbers, points and
// names whose failure names the option and the value, the budget options, and bad input as
// one line on stderr with exit status 2.

#include "planner/budget.hpp"

#include <CLI/CLI.hpp>

#include <algorithm>
#include <array>
#include <charconv>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <limits>
#include <optional>
#include <stdexcept>
#include <string>
#include <string_view>
#include <type_traits>
#include <utility>
#include <vector>

namespace staa::cli {

constexpr int kExitBadInput = 2;

// Bad command-line input found after parsing: what() is the whole message after "TOOL: ".
class InputError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};

// ---- the tools' syntax of numbers and points ----

// std::from_chars: no locale, no trailing garbage, no hex, octal, inf, nan or overflow (all of
// which CLI11's strtold/strtoull would take), and a leading '+' as people write it.
inline std::optional<double> parseDouble(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  double v = 0.0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc{} || ptr != end || text.empty() || !std::isfinite(v)) return std::nullopt;
  return v;
}

inline std::optional<std::uint64_t> parseUnsigned(std::string_view text) {
  if (!text.empty() && text.front() == '+') text.remove_prefix(1);
  std::uint64_t v = 0;
  const char* end = text.data() + text.size();
  auto [ptr, ec] = std::from_chars(text.data(), end, v);
  if (ec != std::errc{} || ptr != end || text.empty()) return std::nullopt;
  return v;
}

// "X,Y" (N = 2) or "X,Y,TH" (N = 3): N numbers separated by commas.
template <std::size_t N>
std::optional<std::array<double, N>> parsePoint(std::string_view text) {
  std::array<double, N> point{};
  for (std::size_t i = 0; i < N; ++i) {
    const std::size_t end = i + 1 < N ? text.find(',') : text.size();
    if (end == std::string_view::npos) return std::nullopt;
    const auto v = parseDouble(text.substr(0, end));
    if (!v) return std::nullopt;
    point[i] = *v;
    text.remove_prefix(std::min(end + 1, text.size()));
  }
  return point;
}

// ---- checks (CLI11 validators): a failure reads "--OPTION: expected WHAT, got 'TEXT'" ----

namespace detail {

inline CLI::Validator expecting(std::string expected, std::string description,
                                std::function<bool(std::string&)> accepts) {
  return CLI::Validator(
      [expected = std::move(expected), accepts = std::move(accepts)](std::string& text) {
        const std::string given = text;
        return accepts(text) ? std::string() : "expected " + expected + ", got '" + given + "'";
      },
      std::move(description));
}

// CLI11 reads a double with strtold and rounds it again to double, an ulp off from_chars'
// correctly rounded value for some long decimals: those it gets in hex, which it reads exactly.
inline void exactForCli11(std::string& text, double v) {
  if (static_cast<double>(std::strtold(text.c_str(), nullptr)) == v) return;
  char hex[40];
  std::snprintf(hex, sizeof hex, "%a", v);
  text = hex;
}

}  // namespace detail

// A finite number that `range` (CLI::PositiveNumber, CLI::NonNegativeNumber, CLI::Range)
// accepts; `range_text` says the same in words. Add with ->transform() (it may rewrite).
inline CLI::Validator number(const std::string& what, const CLI::Validator& range, const std::string& range_text) {
  return detail::expecting(what + " (" + range_text + ")", range.get_description(), [range](std::string& text) {
    const auto v = parseDouble(text);
    if (!v) return false;
    detail::exactForCli11(text, *v);
    return range(text).empty();
  });
}

// "--rate: expected a control rate in Hz (a finite number > 0), got '0'".
inline CLI::Validator positive(const std::string& what) {
  return number(what, CLI::PositiveNumber, "a finite number > 0");
}
inline CLI::Validator nonNegative(const std::string& what) {
  return number(what, CLI::NonNegativeNumber, "a finite number >= 0");
}

// An integer from `min` to `max` in decimal (CLI11 alone would read 010 as octal 8). Add with
// ->transform(): the text goes on to CLI11 as plain decimal.
inline CLI::Validator count(const std::string& what, std::uint64_t min, std::uint64_t max) {
  const CLI::Range range(min, max);
  return detail::expecting(
      what + " (an integer from " + std::to_string(min) + " to " + std::to_string(max) + ")", "",
      [range](std::string& text) {
        const auto v = parseUnsigned(text);
        if (!v) return false;
        text = std::to_string(*v);
        return range(text).empty();
      });
}

// "--from: expected X,Y (two finite numbers in metres), got '1,x'".
template <std::size_t N>
CLI::Validator point(const std::string& expected) {
  return detail::expecting(expected, "", [](std::string& text) { return parsePoint<N>(text).has_value(); });
}

// "staa, dwa or pd".
inline std::string orList(const std::vector<std::string>& names) {
  std::string s;
  for (std::size_t i = 0; i < names.size(); ++i) {
    s += (i == 0 ? "" : i + 1 == names.size() ? " or " : ", ") + names[i];
  }
  return s;
}

// One of the names of a table: CLI11's CheckedTransformer, which turns the name into its
// value, with the names only (it would also take the numbers behind an enum's names, "0").
// Add with ->transform(), or through choice().
template <class T>
CLI::Validator oneOf(const std::vector<std::pair<std::string, T>>& table) {
  std::vector<std::string> names;
  for (const auto& entry : table) names.push_back(entry.first);
  const CLI::CheckedTransformer to_value(table);
  return detail::expecting(orList(names), "", [names, to_value](std::string& text) {
    const bool named = std::find(names.begin(), names.end(), text) != names.end();
    return named && to_value(text).empty();
  });
}

// The table of an enum from its values and their toString: the names are the enum's own.
template <class E>
std::vector<std::pair<std::string, E>> namesOf(std::initializer_list<E> values) {
  std::vector<std::pair<std::string, E>> table;
  for (const E v : values) table.emplace_back(toString(v), v);
  return table;
}

// "pd,dwa,staa": a list as it is written on the command line.
template <class T, class Name>
std::string joined(const std::vector<T>& items, Name name) {
  std::string s;
  for (const T& item : items) s += (s.empty() ? "" : ",") + std::string(name(item));
  return s;
}

// `option` (bound to `value`: one T, or a comma-separated list of them) takes the names of
// `table`; --help shows them and the default by name: "--mode {cooperative,ghost}=cooperative".
template <class T, class Value>
CLI::Option* choice(CLI::Option* option, const std::vector<std::pair<std::string, T>>& table, const Value& value) {
  const auto name = [&table](const T& v) {
    const auto it = std::find_if(table.begin(), table.end(), [&v](const auto& entry) { return entry.second == v; });
    return it == table.end() ? std::string() : it->first;
  };
  option->transform(oneOf(table))->type_name("{" + joined(table, [](const auto& e) { return e.first; }) + "}");
  if constexpr (std::is_same_v<Value, T>) {
    option->default_str(name(value));
  } else {
    option->delimiter(',')->default_str(joined(value, name));
  }
  return option;
}

// The items of a list option differ: "--modes: 'ghost' is listed twice".
template <class T, class Name>
void requireDistinct(const std::string& option, const std::vector<T>& items, Name name) {
  for (auto it = items.begin(); it != items.end(); ++it) {
    if (std::find(items.begin(), it, *it) != it) {
      throw InputError(option + ": '" + std::string(name(*it)) + "' is listed twice");
    }
  }
}

// An option's value for messages: as given (numbers in plain decimal), else its default.
inline std::string given(const CLI::Option* option) {
  return option->count() > 0 ? CLI::detail::join(option->results(), ",") : option->get_default_str();
}

// ---- the command line of a tool ----

// CLI11's App with the tools' failure line: "TOOL: MESSAGE" on stderr, exit status 2. The
// checks above say what they expected; options that exclude or need each other are named with
// their values and why; CLI11's other errors (unknown option, missing value) point to --help.
class CommandLine {
 public:
  CommandLine(std::string tool, const std::string& description) : app(description, tool), tool_(std::move(tool)) {
    app.failure_message([this](const CLI::App*, const CLI::Error& e) { return message(e); });
  }
  CommandLine(const CommandLine&) = delete;
  CommandLine& operator=(const CommandLine&) = delete;

  // CLI11's excludes, both ways: "--a 1 and --b 2 exclude each other: WHY".
  void exclude(CLI::Option* a, CLI::Option* b, std::string why) {
    a->excludes(b);
    pairs_.push_back({a, b, " excludes ", std::move(why)});
  }

  // CLI11's needs, one way: "--a 1 needs --b: WHY".
  void need(CLI::Option* a, CLI::Option* b, std::string why) {
    a->needs(b);
    pairs_.push_back({a, b, " requires ", std::move(why)});
  }

  // nullopt: go on; otherwise the exit status, after the help (0) or the failure line (2).
  std::optional<int> parse(int argc, char** argv) {
    try {
      app.parse(argc, argv);
      return std::nullopt;
    } catch (const CLI::ParseError& e) {
      return app.exit(e) == 0 ? 0 : kExitBadInput;
    }
  }

  CLI::App app;

 private:
  // Two options CLI11 relates; `verb` is the word of its message ("--a excludes --b").
  struct Pair {
    const CLI::Option* a;
    const CLI::Option* b;
    std::string verb;
    std::string why;
  };

  // The pair's own message, with the values given, in the order the pair was declared.
  static std::optional<std::string> pairMessage(const Pair& p, const std::string& what) {
    const std::string a = p.a->get_name(), b = p.b->get_name();
    if (p.verb == " excludes ") {
      if (what != a + p.verb + b && what != b + p.verb + a) return std::nullopt;
      return a + " " + given(p.a) + " and " + b + " " + given(p.b) + " exclude each other: " + p.why;
    }
    if (what != a + p.verb + b) return std::nullopt;
    return a + " " + given(p.a) + " needs " + b + ": " + p.why;
  }

  std::string message(const CLI::Error& e) const {
    const std::string what = e.what();
    if (dynamic_cast<const CLI::ValidationError*>(&e) != nullptr) return tool_ + ": " + what + "\n";
    for (const Pair& p : pairs_) {
      if (const auto text = pairMessage(p, what)) return tool_ + ": " + *text + "\n";
    }
    return tool_ + ": " + what + " (see " + tool_ + " --help)\n";
  }

  std::string tool_;
  std::vector<Pair> pairs_;
};

// ---- the budget ----

// --budget-ms and --budget-expansions, which exclude each other; `run` is what a budget in
// pops makes reproducible ("run", "experiment").
class BudgetOptions {
 public:
  BudgetOptions(CommandLine& cl, const std::string& run) {
    ms_option_ = cl.app.add_option("--budget-ms", ms_, "Wall-clock STAA* budget per cycle in ms (default 19 ms at 30 Hz, "
                                                       "scaled with the rate)")
                     ->transform(positive("milliseconds per cycle"));
    expansions_option_ = cl.app.add_option("--budget-expansions", expansions_,
                                           "STAA* budget per cycle in queue pops: a bit-for-bit reproducible " + run)
                             ->transform(count("queue pops per cycle", 1, std::numeric_limits<std::uint32_t>::max()));
    cl.exclude(ms_option_, expansions_option_, "give a wall-clock budget or an expansion budget, not both");
  }

  BudgetOptions(const BudgetOptions&) = delete;  // CLI11 writes into the members
  BudgetOptions& operator=(const BudgetOptions&) = delete;

  // After parsing: the budget given, else the paper's 19 ms at 30 Hz scaled with the rate.
  BudgetSpec spec(double rate_hz) const {
    if (expansions_option_->count() > 0) return BudgetSpec::expansionsOf(expansions_);
    if (ms_option_->count() > 0) return BudgetSpec::wallClockMs(ms_);
    return BudgetSpec::defaultWallClock(rate_hz);
  }

 private:
  double ms_ = 0.0;
  std::uint32_t expansions_ = 0;
  CLI::Option* ms_option_ = nullptr;
  CLI::Option* expansions_option_ = nullptr;
};

}  // namespace staa::cli
