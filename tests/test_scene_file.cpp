#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <regex>
#include <set>

#include "isochor/base/error.hpp"
#include "isochor/scene/scene.hpp"
#include "test_util.hpp"

using namespace isochor;
namespace fs = std::filesystem;

TEST(SceneFile, TypedKeysRangesAndMessages) {
  SceneFile f = SceneFile::parse("[a]\nx = 2\ny = 1.5\ns = \"box\"\nv = [1, 2, 3]\nb = true\n", "s.toml");
  Section a = f.root().table("a");
  EXPECT_EQ(a.number("x", 0.0), 2.0);  // an integer is a number
  EXPECT_EQ(a.integer("x", 0, 0, 10), 2);
  EXPECT_EQ(a.number("missing", 7.0), 7.0);
  EXPECT_EQ(a.string("s", ""), "box");
  EXPECT_EQ(a.vec3("v", {}), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(a.boolean("b", false));
  EXPECT_EQ(test::error_of([&] { a.integer("y", 0, 0, 10); }),
            "s.toml:3: a.y: expected an integer in [0, 10], got a number");
  EXPECT_EQ(test::error_of([&] { a.number("y", 0, Range::closed(2, 3)); }),
            "s.toml:3: a.y: expected a number in [2, 3], got 1.5");
  EXPECT_EQ(test::error_of([&] { a.number("s", 0, Range::positive()); }),
            "s.toml:4: a.s: expected a number > 0, got a string");
  EXPECT_EQ(test::error_of([&] { a.string("s", "", {"sphere"}); }),
            "s.toml:4: a.s: expected one of \"sphere\", got \"box\"");
  EXPECT_EQ(test::error_of([&] { f.check_unknown_keys(); }), "");
}

TEST(SceneFile, UnknownKeysAreReportedInFileOrder) {
  SceneFile f = SceneFile::parse("[a]\nx = 1\nzz = 2\n[b]\nq = 1\n", "u.toml");
  f.root().table("a").number("x", 0);
  EXPECT_EQ(test::error_of([&] { f.check_unknown_keys(); }), "u.toml:3: a.zz: unknown key (expected one of: x)");
  f.root().table("a").number("zz", 0);
  EXPECT_EQ(test::error_of([&] { f.check_unknown_keys(); }), "u.toml:4: b: unknown key (expected one of: a)");
}

TEST(SceneFile, OverridesReplaceAddAndQuote) {
  SceneFile f = SceneFile::parse(
      "[integrator]\nrtol = 1e-6\n", "o.toml",
      {"integrator.rtol=1e-9", "integrator.kind=backward_euler", "mesh.cells=[2, 3, 4]", "output.path=\"x y.h5\""});
  Section in = f.root().table("integrator");
  EXPECT_EQ(in.number("rtol", 0), 1e-9);
  EXPECT_EQ(in.string("kind", ""), "backward_euler");
  auto cells = f.root().table("mesh").int3("cells", {0, 0, 0}, 1, 10);
  EXPECT_EQ(cells, (std::array<long, 3>{2, 3, 4}));
  EXPECT_EQ(f.root().table("output").string("path", ""), "x y.h5");
  EXPECT_EQ(test::error_of([&] { in.number("kind", 0); }),
            "--set integrator.kind: expected a finite number, got a string");
  EXPECT_NE(test::error_of([&] {
              SceneFile::parse("a = 1\n", "o.toml", {"a.b=2"});
            }).find("a is an integer in o.toml, expected a table"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] { SceneFile::parse("", "o.toml", {"novalue"}); }).find("expected key=value"),
            std::string::npos);
}

TEST(SceneFile, MissingAndUnreadableFiles) {
  fs::path d = test::temp_dir();
  EXPECT_NE(test::error_of([&] { SceneFile::load((d / "no.toml").string()); }).find("no.toml: no such file"),
            std::string::npos);
  EXPECT_NE(test::error_of([&] { SceneFile::load(d.string()); }).find("is a directory"), std::string::npos);
  test::write_file(d / "bin.toml", std::string("\x00\x01\x02 = [", 6));
  EXPECT_NE(test::error_of([&] { SceneFile::load((d / "bin.toml").string()); }).find("expected valid TOML"),
            std::string::npos);
}

TEST(Scene, LameFromYoungMatchesTheDefinitions) {
  auto [mu, lambda] = lame_from_young(46400.0, 0.45);
  EXPECT_NEAR(mu, 16000.0, 1e-9);
  // lambda = 2 mu nu / (1 - 2 nu)
  EXPECT_NEAR(lambda, 2 * 16000.0 * 0.45 / 0.1, 1e-7);
}

TEST(Scene, AnotherMethodsOptionsAreRefusedUnlessTheKindIsSwitchedOnTheCommandLine) {
  const std::string text = R"(
[mesh]
shape = "box"
size = [0.1, 0.1, 0.1]
cells = 1
[material]
mu = 1000.0
lambda = 1000.0
[integrator]
kind = "backward_euler"
hessian = "hybrid"
substeps_on_failure = 4
)";
  auto scene = [&](const std::string& body, std::vector<std::string> set) {
    return parse_scene(SceneFile::parse(body, "s.toml", std::move(set)));
  };
  EXPECT_TRUE(scene(text, {}).integrator.backward_euler.exact_near_solution);
  // A variant of the scene on IDA or XPBD leaves backward Euler's options unused ...
  EXPECT_EQ(scene(text, {"integrator.kind=ida"}).integrator.kind, IntegratorKind::ida);
  EXPECT_EQ(scene(text, {"integrator.kind=xpbd"}).integrator.kind, IntegratorKind::xpbd);
  // ... but an option given with the kind on the command line, or beside it in the file, is refused.
  EXPECT_THROW(scene(text, {"integrator.kind=ida", "integrator.line_search=false"}), Error);
  std::string ida = text;
  ida.replace(ida.find("\"backward_euler\""), 16, "\"ida\"");
  try {
    scene(ida, {});
    ADD_FAILURE() << "expected integrator.hessian refused";
  } catch (const Error& e) {
    EXPECT_NE(std::string(e.what()).find("s.toml:11: integrator.hessian: is an option of"), std::string::npos)
        << e.what();
  }
  // semi-implicit takes one update per step: a hybrid Hessian has nothing to switch within.
  EXPECT_THROW(scene(text, {"integrator.kind=semi_implicit"}), Error);
}

TEST(Scene, ZonesFromSelectionsAndFrames) {
  fs::path d = test::temp_dir();
  std::string p = test::write_file(d / "z.toml", R"(
[mesh]
shape = "box"
cells = 2
center = [0.5, 0.5, 0.5]
[zones]
global = true
[[zones.zone]]
name = "bottom"
select = { kind = "box", min = [0, 0, 0], max = [1, 1, 0.5] }
[frames]
rate = 10
duration = 0.5
)");
  Scene sc = load_scene(p);
  ASSERT_EQ(sc.zones.size(), 2u);
  EXPECT_EQ(sc.zones[0].first, "global");
  EXPECT_EQ(sc.zones[0].second.size(), 48u);
  EXPECT_EQ(sc.zones[1].second.size(), 24u);
  EXPECT_EQ(sc.frames.times().size(), 6u);
  EXPECT_DOUBLE_EQ(sc.frames.times().back(), 0.5);
  EXPECT_EQ(sc.output.path, "out/z.h5");
  std::string bad = test::write_file(
      d / "bad.toml", "[mesh]\nshape = \"box\"\n[[zones.zone]]\nname = \"a\"\nselect = { kind = \"all\", node = 3 }\n");
  EXPECT_EQ(test::error_of([&] { load_scene(bad); }),
            bad + ":5: zones.zone[0].select.node: unknown key (expected one of: kind)");
}

// Where IDA must end a step (docs/scenes.md, Breakpoints): a ramp's ends, linear knots, the ends of
// cubic keys, a moving plane's start and end, the end of the gravity ramp; none for a sinusoid.
TEST(Scene, BreakpointsWhereThePrescribedMotionIsNotSmooth) {
  fs::path d = test::temp_dir();
  std::string p = test::write_file(d / "b.toml", R"(
[mesh]
shape = "box"
cells = 2
[[boundary]]
select = { kind = "box", min = [-1, -1, -1], max = [1, 1, -0.4] }
kind = "ramp"
displacement = [0, 0, 0.1]
t0 = 0.1
t1 = 0.25
[[boundary]]
select = { kind = "box", min = [-1, -1, 0.4], max = [1, 1, 1] }
kind = "keyframes"
times = [0.0, 0.3, 0.45, 0.7]
values = [0, 0, 0,  0, 0, 0.1,  0, 0, 0,  0, 0, 0.05]
[[boundary]]
select = { kind = "box", min = [-1, 0.4, -0.3], max = [1, 1, 0.3] }
kind = "keyframes"
interpolation = "cubic"
times = [0.05, 0.2, 0.6]
values = [0, 0, 0,  0, 0.1, 0,  0, 0, 0]
[[boundary]]
select = { kind = "box", min = [-1, -1, -0.3], max = [1, -0.4, 0.3] }
kind = "sinusoid"
amplitude = [0.01, 0, 0]
[forces]
gravity_ramp = 0.15
[[contact.plane]]
point = [0, 0, -2]
normal = [0, 0, 1]
displacement = [0, 0, 0.5]
t0 = 0.25
t1 = 0.8
)");
  const std::vector<double> expected{0.0, 0.05, 0.1, 0.15, 0.25, 0.3, 0.45, 0.6, 0.7, 0.8};
  EXPECT_EQ(load_scene(p).breakpoints(), expected);
}

// Every key a parser asks for, over all demo scenes, is documented in docs/scenes.md.
namespace {

// docs/scenes.md's rows: key -> its type and default cells (the second and fourth columns of
// every key table).
struct DocRow {
  std::string type, fallback;
};
std::map<std::string, DocRow> documented_rows(const std::string& text) {
  std::map<std::string, DocRow> out;
  std::istringstream lines(text);
  std::string line;
  while (std::getline(lines, line)) {
    if (line.rfind("| `", 0) != 0) continue;
    std::vector<std::string> cells;
    std::size_t at = 1;
    for (int c = 0; c < 4; ++c) {
      const std::size_t bar = line.find('|', at);
      if (bar == std::string::npos) break;
      cells.push_back(line.substr(at, bar - at));
      at = bar + 1;
    }
    if (cells.size() < 4) continue;
    auto trim = [](std::string v) {
      v.erase(0, v.find_first_not_of(' '));
      v.erase(v.find_last_not_of(' ') + 1);
      return v;
    };
    std::string key = trim(cells[0]);
    if (key.size() < 2 || key.front() != '`' || key.back() != '`') continue;
    out[key.substr(1, key.size() - 2)] = {trim(cells[1]), trim(cells[3])};
  }
  return out;
}

// A default as a value to compare: a number, a list of numbers, true/false or a quoted string
// (the first word of the cell, backticks dropped, U+2212 as '-'); "" for prose, "–" and the like,
// which say what the default is in words and are not compared.
std::string comparable(std::string cell) {
  for (std::size_t p; (p = cell.find("\u2212")) != std::string::npos;) cell.replace(p, 3, "-");
  cell.erase(std::remove(cell.begin(), cell.end(), '`'), cell.end());
  if (cell.empty()) return "";
  if (cell[0] == '"') {
    const std::size_t end = cell.find('"', 1);
    return end == std::string::npos ? "" : cell.substr(0, end + 1);
  }
  if (cell[0] == '[') {
    const std::size_t end = cell.find(']');
    if (end == std::string::npos) return "";
    std::string list = "[", inner = cell.substr(1, end - 1);
    std::istringstream items(inner);
    std::string item;
    while (std::getline(items, item, ',')) {
      char* stop = nullptr;
      const double v = std::strtod(item.c_str(), &stop);
      if (stop == item.c_str()) return "";
      std::ostringstream o;
      o << v;
      list += (list.size() > 1 ? ", " : "") + o.str();
    }
    return list + "]";
  }
  const std::string word = cell.substr(0, cell.find(' '));
  if (word == "true" || word == "false") return word;
  char* stop = nullptr;
  const double v = std::strtod(word.c_str(), &stop);
  if (stop == word.c_str() || *stop != '\0') return "";
  std::ostringstream o;
  o << v;
  return o.str();
}

// A number's type cell ("number > 0", "number in (−1, 0.5]", "number") as Range::describe words it
// ("a number > 0", ...); "" for a cell that is not a number's range in symbols.
std::string range_words(std::string cell) {
  if (cell.rfind("number", 0) != 0) return "";
  if (cell == "number") return "a finite number";
  const std::pair<const char*, const char*> symbols[] = {{"\u2212", "-"},     {"\u2265", ">="},
                                                         {"\u2264", "<="},    {"10\u2076", "1e6"},
                                                         {"10\u2078", "1e8"}, {"10\u00b9\u00b3", "1e13"}};
  for (const auto& [from, to] : symbols)
    for (std::size_t p; (p = cell.find(from)) != std::string::npos;) cell.replace(p, std::strlen(from), to);
  std::string out = "a ";
  for (std::size_t i = 0; i < cell.size();) {  // numbers written as fmt writes them (1e+06)
    const char c = cell[i];
    const bool starts_number =
        std::isdigit(static_cast<unsigned char>(c)) ||
        (c == '-' && i + 1 < cell.size() && std::isdigit(static_cast<unsigned char>(cell[i + 1])));
    if (!starts_number) {
      if (static_cast<unsigned char>(c) >= 0x80) return "";  // another symbol (δ): prose
      out += c;
      ++i;
      continue;
    }
    char* stop = nullptr;
    const double v = std::strtod(cell.c_str() + i, &stop);
    std::ostringstream o;
    o << v;
    out += o.str();
    i = static_cast<std::size_t>(stop - cell.c_str());
  }
  return out;
}

}  // namespace

// Every key a demo reads is in docs/scenes.md, and where the docs give its default as a value
// (a number, list, boolean or quoted string), it is the default the parser gave when it read the
// key (SceneFile::key_defaults: the parsers' own fallbacks, recorded as they read).
TEST(Scene, EveryKeyReadByTheDemosIsDocumented) {
  std::ifstream doc(std::string(ISOCHOR_SOURCE_DIR) + "/docs/scenes.md");
  ASSERT_TRUE(doc) << "docs/scenes.md is missing";
  std::string text((std::istreambuf_iterator<char>(doc)), std::istreambuf_iterator<char>());
  std::set<std::string> documented;
  std::regex row(R"(\|\s*`([a-z_A-Z0-9.\[\]<>]+)`\s*\|)");
  std::vector<std::string> named;  // rows like `zones.paint.labels.<zone>`: any one name after the prefix
  for (auto it = std::sregex_iterator(text.begin(), text.end(), row); it != std::sregex_iterator(); ++it) {
    const std::string k = (*it)[1];
    if (k.find('<') != std::string::npos)
      named.push_back(k.substr(0, k.find('<')));
    else
      documented.insert(k);
  }
  auto is_documented = [&](const std::string& k) {
    if (documented.count(k)) return true;
    for (const std::string& prefix : named)
      if (k.rfind(prefix, 0) == 0 && k.find('.', prefix.size()) == std::string::npos) return true;
    return false;
  };
  const std::map<std::string, DocRow> rows = documented_rows(text);
  std::map<std::string, std::set<std::string>> code_defaults, code_ranges;
  int scenes = 0;
  for (const auto& e : fs::directory_iterator(std::string(ISOCHOR_SOURCE_DIR) + "/demos")) {
    if (e.path().extension() != ".toml") continue;
    Scene sc = load_scene(e.path().string());
    scenes++;
    for (const std::string& k : sc.file.queried_keys())
      EXPECT_TRUE(is_documented(k)) << k << " (read by " << e.path().filename() << ") is not in docs/scenes.md";
    for (const auto& [k, values] : sc.file.key_defaults()) code_defaults[k].insert(values.begin(), values.end());
    for (const auto& [k, values] : sc.file.key_ranges()) code_ranges[k].insert(values.begin(), values.end());
  }
  EXPECT_GT(scenes, 0);
  int compared = 0, ranges = 0;
  for (const auto& [key, row] : rows) {
    const auto code = code_defaults.find(key);
    const std::string doc_value = comparable(row.fallback);
    if (code != code_defaults.end() && !doc_value.empty()) {
      std::set<std::string> values;
      for (const std::string& v : code->second) values.insert(comparable(v));
      ++compared;
      EXPECT_TRUE(values.count(doc_value))
          << key << ": docs/scenes.md gives the default " << row.fallback << ", the parser " << *code->second.begin()
          << (code->second.size() > 1 ? " (and others)" : "");
    }
    const auto range = code_ranges.find(key);
    const std::string doc_range = range_words(row.type);
    if (range != code_ranges.end() && !doc_range.empty()) {
      ++ranges;
      EXPECT_TRUE(range->second.count(doc_range))
          << key << ": docs/scenes.md gives the type " << row.type << ", the parser checks " << *range->second.begin();
    }
  }
  EXPECT_GT(compared, 100);
  EXPECT_GT(ranges, 50);
}

TEST(Scene, RingZonesOnePerNode) {
  Scene sc = parse_scene(
      SceneFile::parse("[mesh]\nshape = \"box\"\ncells = 2\n[zones]\nglobal = false\nrings = 1\n", "r.toml"));
  ASSERT_EQ(sc.zones.size(), 27u);
  // The centre node of a 2x2x2 Kuhn box is interior: its 1-ring holds 24 tets.
  EXPECT_EQ(sc.zones[13].first, "ring1_13");
  EXPECT_EQ(sc.zones[13].second.size(), 24u);
}
