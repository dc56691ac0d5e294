// The one strict YAML reader (io/config_reader.hpp): every kind of error on real YAML text,
// each with its file, line, key path and the value it got.
#include "io/config_reader.hpp"

#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>
#include <string>
#include <unistd.h>

namespace staa::io {
namespace {

namespace fs = std::filesystem;
using ::testing::HasSubstr;
using ::testing::StartsWith;

// The message of the ConfigError that `read` throws (a failure when it throws none).
template <class Read>
std::string errorOf(Read&& read) {
  try {
    read();
  } catch (const ConfigError& e) {
    return e.what();
  }
  ADD_FAILURE() << "no ConfigError";
  return "";
}

ConfigDocument doc(const std::string& text) { return ConfigDocument::parse(text, "/etc/staa/test.yaml"); }

TEST(ConfigReader, InvalidYamlNamesTheLineAndColumn) {
  const std::string e = errorOf([] { doc("name: x\nlist: [1, 2\nnext: 3\n"); });
  EXPECT_THAT(e, StartsWith("/etc/staa/test.yaml:3:"));
  EXPECT_THAT(e, HasSubstr(": not valid YAML: "));
}

TEST(ConfigReader, UnknownKeyNamesTheExpectedOnesAtItsLine) {
  const ConfigDocument d = doc("rates:\n  control_hz: 30\n  contrl_hz: 20\n");
  EXPECT_EQ(errorOf([&] { d.root().mapping({"rates"}).section("rates", {"control_hz", "base_hz"}); }),
            "/etc/staa/test.yaml:3: rates.contrl_hz: unknown key (expected control_hz, base_hz)");
  // A key that is not a name at all.
  const ConfigDocument odd = doc("[a, b]: 1\n");
  EXPECT_EQ(errorOf([&] { odd.root().mapping({"a"}); }),
            "/etc/staa/test.yaml:1: a key that is not a name, a list of 2 items (expected a)");
}

TEST(ConfigReader, KeyGivenTwiceIsRefusedNamingBothLines) {
  const ConfigDocument d = doc("limits:\n  v_max: 1\n  w_max: 2\n  v_max: 3\n");
  EXPECT_EQ(errorOf([&] { d.root().section("limits", {"v_max", "w_max"}); }),
            "/etc/staa/test.yaml:4: limits.v_max: given twice (first on line 2)");
  // Also in a mapping of any keys (another project's format).
  const ConfigDocument any = doc("image: a.pgm\nextra: 1\nimage: b.pgm\n");
  EXPECT_EQ(errorOf([&] { any.root().anyMapping(); }), "/etc/staa/test.yaml:3: image: given twice (first on line 1)");
  EXPECT_NO_THROW(doc("image: a.pgm\nextra: 1\n").root().anyMapping());
}

TEST(ConfigReader, SectionOfTheWrongKindNamesWhatItGot) {
  const ConfigDocument d = doc("rates: 30\nthreads:\n  - a\n");
  EXPECT_EQ(errorOf([&] { d.root().section("rates", {"control_hz", "base_hz"}); }),
            "/etc/staa/test.yaml:1: rates: expected a mapping {control_hz, base_hz}, got '30'");
  EXPECT_EQ(errorOf([&] { d.root().section("threads", {"control"}); }),
            "/etc/staa/test.yaml:3: threads: expected a mapping {control}, got a list of 1 items");
  // An absent optional section is no error, and neither is anything read from it.
  const ConfigValue goal = d.root().section("goal", {"tolerance_m"});
  EXPECT_FALSE(goal.given());
  EXPECT_FALSE(goal.get("tolerance_m").given());
  EXPECT_EQ(goal.get("tolerance_m").keyPath(), "goal.tolerance_m");
}

TEST(ConfigReader, MissingKeyIsNamedAtItsMappingsLine) {
  const ConfigDocument d = doc("format: x/1\nlimits: {v_max: 1}\n");
  EXPECT_EQ(errorOf([&] { d.root().get("limits").required("w_max", "rad/s"); }),
            "/etc/staa/test.yaml:2: limits.w_max: missing (rad/s)");
  // Missing from the document: the document as a whole has no line.
  EXPECT_EQ(errorOf([&] { d.root().required("robot"); }), "/etc/staa/test.yaml: robot: missing");
  // `key:` with nothing after it is given but has no value.
  const ConfigDocument null = doc("robot:\n");
  EXPECT_TRUE(null.root().get("robot").given());
  EXPECT_FALSE(null.root().get("robot").present());
  EXPECT_EQ(errorOf([&] { null.root().required("robot", "a file"); }), "/etc/staa/test.yaml:1: robot: missing (a file)");
}

TEST(ConfigReader, NumbersAreFiniteAndInTheirRangeWithTheUnitInTheMessage) {
  const ConfigDocument d = doc("a: abc\nb: .inf\nc: -3\nd: 0\ne: 1e3\nf: 0.25\ng:\nh: 640\n");
  const ConfigValue& r = d.root();
  EXPECT_EQ(errorOf([&] { r.get("a").number(); }), "/etc/staa/test.yaml:1: a: expected a number, got 'abc'");
  EXPECT_EQ(errorOf([&] { r.get("b").number(); }), "/etc/staa/test.yaml:2: b: must be finite, got .inf");
  EXPECT_EQ(errorOf([&] { r.get("c").number(Range::leftOpen(0.0, 1000.0, "Hz")); }),
            "/etc/staa/test.yaml:3: c: must be in (0, 1000] Hz, got -3");
  EXPECT_EQ(errorOf([&] { r.get("d").number(Range::above(0.0, "m")); }), "/etc/staa/test.yaml:4: d: must be > 0 m, got 0");
  EXPECT_EQ(r.get("e").number(Range::leftOpen(0.0, 1000.0, "Hz")), 1000.0);  // 1e3 is in (0, 1000]
  EXPECT_EQ(errorOf([&] { r.get("f").number(Range::atMost(0.0, {}, "it is the backward limit")); }),
            "/etc/staa/test.yaml:6: f: must be <= 0 (it is the backward limit), got 0.25");
  EXPECT_EQ(errorOf([&] { r.get("g").number(); }), "/etc/staa/test.yaml:7: g: expected a number, got nothing");
  EXPECT_EQ(errorOf([&] { r.get("h").number(Range::rightOpen(0.0, 640.0, "pixels", "inside the image")); }),
            "/etc/staa/test.yaml:8: h: must be in [0, 640) pixels (inside the image), got 640");
  EXPECT_EQ(errorOf([&] { r.get("absent").number(); }), "/etc/staa/test.yaml: absent: expected a number, got nothing");
}

TEST(ConfigReader, IntegersAreWholeAndInTheirRange) {
  const ConfigDocument d = doc("a: 2.5\nb: 120\nc: +7\nd: -1\ne: 18446744073709551615\nf: many\n");
  const ConfigValue& r = d.root();
  EXPECT_EQ(errorOf([&] { r.get("a").integer(); }), "/etc/staa/test.yaml:1: a: expected an integer, got '2.5'");
  EXPECT_EQ(errorOf([&] { r.get("b").integer(0, 99, " (0: normal scheduling)"); }),
            "/etc/staa/test.yaml:2: b: must be an integer in 0..99 (0: normal scheduling), got 120");
  EXPECT_EQ(r.get("c").integer(0, 99), 7);
  EXPECT_EQ(errorOf([&] { r.get("d").unsignedInteger(); }), "/etc/staa/test.yaml:4: d: must be an integer >= 0, got -1");
  EXPECT_EQ(r.get("e").unsignedInteger(), 18446744073709551615u);
  EXPECT_EQ(errorOf([&] { r.get("f").integer(16, 1 << 20); }),
            "/etc/staa/test.yaml:6: f: must be an integer in 16..1048576, got many");
}

TEST(ConfigReader, StringsBooleansAndPaths) {
  const ConfigDocument d = doc("name: [a, b]\nempty: \"\"\nflag: maybe\nyes_flag: yes\nrel: ../maps/m.yaml\nabs: /var/m.yaml\n");
  const ConfigValue& r = d.root();
  EXPECT_EQ(errorOf([&] { r.get("name").string("a name"); }), "/etc/staa/test.yaml:1: name: expected a name, got a list of 2 items");
  EXPECT_EQ(r.get("empty").string("a name"), "");
  EXPECT_EQ(errorOf([&] { r.get("empty").nonEmptyString("a name"); }), "/etc/staa/test.yaml:2: empty: expected a name, got ''");
  EXPECT_EQ(errorOf([&] { r.get("flag").boolean(); }), "/etc/staa/test.yaml:3: flag: expected true or false, got 'maybe'");
  EXPECT_TRUE(r.get("yes_flag").boolean());
  // Relative to the file's folder, not to the working directory; absolute paths are kept.
  EXPECT_EQ(r.get("rel").path(), fs::path("/etc/staa/../maps/m.yaml"));
  EXPECT_EQ(r.get("abs").path(), fs::path("/var/m.yaml"));
  EXPECT_EQ(ConfigDocument::parse("p: m.pgm\n", "maps/m.yaml", "/srv").root().get("p").path(), fs::path("/srv/m.pgm"));
  EXPECT_EQ(errorOf([&] { r.get("empty").path(); }), "/etc/staa/test.yaml:2: empty: expected a file path, got ''");
}

enum class Backend { kSim, kSocketCan, kMock };
constexpr Choice<Backend> kTwo[] = {{"sim", Backend::kSim}, {"socketcan", Backend::kSocketCan}};
constexpr Choice<Backend> kThree[] = {
    {"sim", Backend::kSim, "the simulator"}, {"socketcan", Backend::kSocketCan, "the CAN bus"}, {"mock", Backend::kMock}};

TEST(ConfigReader, EnumSelectorsListTheAllowedNames) {
  const ConfigDocument d = doc("hal: socketcan\nbad: can\nlist: [sim]\n");
  EXPECT_EQ(d.root().get("hal").choice<Backend>(kTwo), Backend::kSocketCan);
  EXPECT_EQ(errorOf([&] { d.root().get("bad").choice<Backend>(kTwo); }),
            "/etc/staa/test.yaml:2: bad: expected sim or socketcan, got 'can'");
  EXPECT_EQ(errorOf([&] { d.root().get("bad").choice<Backend>(kThree); }),
            "/etc/staa/test.yaml:2: bad: expected sim (the simulator), socketcan (the CAN bus) or mock, got 'can'");
  EXPECT_EQ(errorOf([&] { d.root().get("list").choice<Backend>(kTwo); }),
            "/etc/staa/test.yaml:3: list: expected sim or socketcan, got a list of 1 items");
  EXPECT_EQ(nameOf<Backend>(kThree, Backend::kMock), "mock");
}

TEST(ConfigReader, PointsPosesAndListsOfNumbers) {
  const ConfigDocument d = doc("start: [1, 2]\npose: [1, x, 0]\ngoal: [2.5, 4]\nbox: [0, 0, 1]\nwps: []\n");
  const ConfigValue& r = d.root();
  EXPECT_EQ(errorOf([&] { r.get("start").pose(); }), "/etc/staa/test.yaml:1: start: expected [x, y, theta], got a list of 2 items");
  EXPECT_EQ(errorOf([&] { r.get("pose").pose(); }), "/etc/staa/test.yaml:2: pose[1]: expected a number, got 'x'");
  EXPECT_EQ(r.get("goal").point(), Vec2(2.5, 4.0));
  EXPECT_EQ(errorOf([&] { r.get("box").numbers<4>("[xmin, ymin, xmax, ymax]"); }),
            "/etc/staa/test.yaml:4: box: expected [xmin, ymin, xmax, ymax], got a list of 3 items");
  EXPECT_EQ(errorOf([&] { r.get("wps").list("a list of at least one [x, y] point", 1); }),
            "/etc/staa/test.yaml:5: wps: expected a list of at least one [x, y] point, got a list of 0 items");
}

TEST(ConfigReader, PolygonsAreSimpleAndNamedAtTheirLine) {
  const ConfigDocument d = doc(
      "square: [[0, 0], [1, 0], [1, 1], [0, 1]]\n"
      "bow: [[0, 0], [1, 1], [1, 0], [0, 1]]\n"
      "repeat:\n"
      "  - [0, 0]\n"
      "  - [1, 0]\n"
      "  - [1, 0]\n"
      "  - [0, 1]\n"
      "line: [[0, 0], [1, 1], [2, 2]]\n"
      "two: [[0, 0], [1, 0]]\n"
      "bad: [[0, 0], [1, .nan], [0, 1]]\n");
  const ConfigValue& r = d.root();
  EXPECT_EQ(r.get("square").polygon().size(), 4u);
  EXPECT_EQ(errorOf([&] { r.get("bow").polygon(); }), "/etc/staa/test.yaml:2: bow: self-intersecting (edges 0 and 2 cross)");
  EXPECT_EQ(errorOf([&] { r.get("repeat").polygon(); }),
            "/etc/staa/test.yaml:4: repeat: vertex 2 repeats vertex 1 (1, 0) (zero-length edge 1)");
  EXPECT_EQ(errorOf([&] { r.get("line").polygon(); }), "/etc/staa/test.yaml:8: line: has zero area (all vertices on one line)");
  EXPECT_EQ(errorOf([&] { r.get("two").polygon(); }), "/etc/staa/test.yaml:9: two: has 2 vertices, needs at least 3");
  EXPECT_EQ(errorOf([&] { r.get("bad").polygon(); }), "/etc/staa/test.yaml:10: bad[1][1]: must be finite, got .nan");
  EXPECT_EQ(polygonProblem(Polygon{{0, 0}, {1, 0}, {0, 1}}), "");
}

TEST(ConfigReader, SectionProblemsCanBeNamedAtTheKeyOrTheValue) {
  const ConfigDocument d = doc("hal: sim\nbudget:\n  ms: 19\n  expansions: 10\n");
  const ConfigValue budget = d.root().get("budget");
  EXPECT_EQ(errorOf([&] { budget.failAtKey("not both"); }), "/etc/staa/test.yaml:2: budget: not both");
  EXPECT_EQ(errorOf([&] { budget.fail("not both"); }), "/etc/staa/test.yaml:3: budget: not both");
  EXPECT_EQ(errorOf([&] { d.root().get("camera").failAt(d.root().get("hal"), "missing (hal: sim needs it)"); }),
            "/etc/staa/test.yaml:1: camera: missing (hal: sim needs it)");
  EXPECT_EQ(errorOf([&] { budget.get("ms").failRule("shorter than the period"); }),
            "/etc/staa/test.yaml:3: budget.ms: must be shorter than the period, got 19");
}

TEST(ConfigReader, DocumentsOfAFormat) {
  const std::initializer_list<std::string_view> keys = {"format", "name"};
  EXPECT_EQ(errorOf([&] { doc("name: x\n").root("staa-robot/1", keys); }),
            "/etc/staa/test.yaml: format: missing (expected staa-robot/1)");
  EXPECT_EQ(errorOf([&] { doc("format: staa-robot/2\n").root("staa-robot/1", keys); }),
            "/etc/staa/test.yaml:1: format: unknown format, expected staa-robot/1, got 'staa-robot/2'");
  EXPECT_EQ(errorOf([&] { doc("- a\n- b\n").root("staa-robot/1", keys); }),
            "/etc/staa/test.yaml: expected a mapping {format, name} (a staa-robot/1 document), got a list of 2 items");
  EXPECT_EQ(errorOf([&] { doc("").root("staa-robot/1", keys); }),
            "/etc/staa/test.yaml: expected a mapping {format, name} (a staa-robot/1 document), got nothing");
  EXPECT_EQ(errorOf([&] { doc("format: staa-robot/1\nwheels: 4\n").root("staa-robot/1", keys); }),
            "/etc/staa/test.yaml:2: wheels: unknown key (expected format, name)");
  EXPECT_EQ(doc("format: staa-robot/1\nname: hsr\n").root("staa-robot/1", keys).get("name").string("a name"), "hsr");
}

class FormatError : public ConfigError {
 public:
  using ConfigError::ConfigError;
};

TEST(ConfigReader, ReadAsRethrowsAsTheFormatsOwnError) {
  const ConfigDocument d = doc("v_max: fast\n");
  try {
    readAs<FormatError>("test.yaml", [&] { return d.root().get("v_max").number(); });
    FAIL() << "no error";
  } catch (const FormatError& e) {
    EXPECT_STREQ(e.what(), "/etc/staa/test.yaml:1: v_max: expected a number, got 'fast'");
  }
  // A format's own error passes unchanged.
  EXPECT_THROW(readAs<FormatError>("test.yaml", [] { throw FormatError("x"); }), FormatError);
}

TEST(ConfigReader, ReadFileNamesAMissingFileAndADirectory) {
  const fs::path dir = fs::temp_directory_path() / ("staa-config-reader-" + std::to_string(::getpid()));
  fs::create_directories(dir);
  EXPECT_EQ(errorOf([&] { ConfigDocument::readFile(dir / "none.yaml", "robot profile"); }),
            (dir / "none.yaml").string() + ": robot profile not found");
  EXPECT_EQ(errorOf([&] { ConfigDocument::readFile(dir, "robot profile"); }), dir.string() + ": is a directory, not a robot profile");
  std::ofstream(dir / "r.yaml") << "a: 1\n";
  EXPECT_EQ(ConfigDocument::readFile(dir / "r.yaml", "robot profile"), "a: 1\n");
  fs::remove_all(dir);
}

TEST(ConfigRules, RangesAndFieldErrorsSayTheRuleUnitAndValue) {
  EXPECT_EQ(Range::above(0.0, "m").text(), "> 0 m");
  EXPECT_EQ(Range::atLeast(0.0, "m/s", "0: they stand still").text(), ">= 0 m/s (0: they stand still)");
  EXPECT_EQ(Range::closed(0.0, 1.0).text(), "in [0, 1]");
  EXPECT_TRUE(Range::rightOpen(0.0, 640.0).contains(0.0));
  EXPECT_FALSE(Range::rightOpen(0.0, 640.0).contains(640.0));
  EXPECT_FALSE(Range::leftOpen(0.0, 1000.0).contains(0.0));
  EXPECT_EQ(integerRange(1, 16), "in 1..16");
  const FieldError e("depth obstacles", "cell_m", Range::above(0.0, "m").text(), -0.1);
  EXPECT_STREQ(e.what(), "depth obstacles: cell_m must be > 0 m, got -0.1");
  EXPECT_EQ(e.field(), "cell_m");
  EXPECT_THROW(requireField("camera", "mount.z", std::nan(""), Range::above(0.0)), FieldError);
  try {
    requireField("camera", "mount.z", 0.0, Range::above(0.0, "m", "above the floor"));
    FAIL() << "z = 0 accepted";
  } catch (const std::invalid_argument& err) {  // a FieldError is an invalid_argument
    EXPECT_STREQ(err.what(), "camera: mount.z must be > 0 m (above the floor), got 0");
  }
}


// ---- the YAML tree (libyaml) reads as yaml-cpp did ----

TEST(ConfigReaderYaml, NullSpellingsBooleansAliasesAndTheFirstDocument) {
  const ConfigDocument d = doc("a: ~\nb: null\nc:\nd: \"null\"\ne: ''\nf: NULL\n"
                               "t: [yes, No, TRUE, off, y, on]\n"
                               "p: &p [1.5, -2]\nq: *p\n---\nnext: 1\n");
  const ConfigValue& r = d.root();
  for (const char* key : {"a", "b", "c", "f"}) EXPECT_FALSE(r.get(key).present()) << key;
  EXPECT_TRUE(r.get("c").given());
  EXPECT_EQ(r.get("d").string("a string"), "null");
  EXPECT_TRUE(r.get("e").present());
  EXPECT_EQ(r.get("e").string("a string"), "");
  const ConfigValue t = r.get("t");
  const bool expected[] = {true, false, true, false, true, true};
  for (std::size_t i = 0; i < 6; ++i) EXPECT_EQ(t[i].boolean(), expected[i]) << i;
  EXPECT_EQ(r.get("q").point(), Vec2(1.5, -2.0));
  // An alias is the node it names (shared, as in yaml-cpp): its line is the anchor's.
  EXPECT_EQ(r.get("q").line(), 8);
  EXPECT_FALSE(r.get("next").given());  // only the first document is read
}

// ---- input bounds (docs/ARCHITECTURE.md, "Input bounds"): one input just inside, one past ----

TEST(ConfigReaderBounds, NestingOf64LevelsReadsAnd65IsRefusedNamingTheBound) {
  const auto nested = [](std::size_t levels) { return "a: " + std::string(levels - 1, '[') + "1" + std::string(levels - 1, ']') + "\n"; };
  // The root mapping is one level: 63 lists inside it make 64.
  const ConfigDocument ok = doc(nested(kMaxYamlDepth));
  EXPECT_TRUE(ok.root().get("a").present());
  EXPECT_EQ(errorOf([&] { doc(nested(kMaxYamlDepth + 1)); }),
            "/etc/staa/test.yaml:1:" + std::to_string(kMaxYamlDepth + 3) + ": nested too deep: at most 64 levels of lists and mappings");
}

TEST(ConfigReaderBounds, AliasesExpandingTo8MillionNodesReadAndOneMoreIsRefused) {
  // a: 1000 nodes expanded; b: 7998 aliases of it; pad: p items. The whole document:
  // 6 + 7999 * 1000 + p nodes.
  const auto text = [](std::size_t pad) {
    std::string t = "a: &a [0";
    for (int i = 1; i < 999; ++i) t += ",0";
    t += "]\nb: [*a";
    for (int i = 1; i < 7998; ++i) t += ",*a";
    t += "]\npad: [0";
    for (std::size_t i = 1; i < pad; ++i) t += ",0";
    return t + "]\n";
  };
  const ConfigDocument ok = doc(text(994));
  EXPECT_EQ(ok.root().get("b").size(), 7998u);
  EXPECT_EQ(ok.root().get("b")[7997].size(), 999u);
  EXPECT_EQ(errorOf([&] { doc(text(995)); }), "/etc/staa/test.yaml:1:1: aliases expand the document beyond 8000000 nodes (the bound)");
}

TEST(ConfigReaderBounds, AnAliasMayOnlyNameACompleteNode) {
  EXPECT_THAT(errorOf([&] { doc("a: &a [1, *a]\n"); }), HasSubstr("unknown anchor 'a'"));
  EXPECT_THAT(errorOf([&] { doc("a: *b\n"); }), StartsWith("/etc/staa/test.yaml:1:4: not valid YAML: unknown anchor 'b'"));
}

TEST(ConfigReaderBounds, TextsAndFilesOf64MiBReadAndOneByteMoreIsRefused) {
  std::string text = "a: 1\n#";
  text.resize(kMaxYamlFileBytes, 'x');
  EXPECT_EQ(doc(text).root().get("a").number(), 1.0);
  text += 'x';
  EXPECT_EQ(errorOf([&] { doc(text); }),
            "/etc/staa/test.yaml: 67108865 bytes, beyond the bound of 67108864 bytes for a YAML file");
  // A file is measured before it is read (sparse files: no disk space used).
  const fs::path file = fs::temp_directory_path() / ("staa-bound-" + std::to_string(::getpid()) + ".yaml");
  { std::ofstream(file) << "a: 1\n"; }
  fs::resize_file(file, kMaxYamlFileBytes);
  EXPECT_EQ(ConfigDocument::readFile(file, "map file").size(), kMaxYamlFileBytes);
  fs::resize_file(file, kMaxYamlFileBytes + 1);
  EXPECT_EQ(errorOf([&] { ConfigDocument::readFile(file, "map file"); }),
            file.string() + ": 67108865 bytes, beyond the bound of 67108864 bytes for a map file");
  fs::remove(file);
}

}  // namespace
}  // namespace staa::io
