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
#include "isochor/app/study.hpp"
#include "isochor/scene/scene.hpp"
#include "test_util.hpp"

using namespace isochor;
namespace fs = std::filesystem;

namespace {

// The keys of the files below.
const KeyTable& test_keys() {
  using K = KeyKind;
  static const KeyTable t("tests/test_scene_file.cpp",
                          {{.name = "a", .kind = K::table},
                           {.name = "a.x", .kind = K::number},
                           {.name = "a.i", .kind = K::integer, .fallback = "3", .min = 0, .max = 10},
                           {.name = "a.y", .kind = K::number, .fallback = "2.5", .range = Range::closed(2, 3)},
                           {.name = "a.s", .kind = K::string, .choices = "sphere box"},
                           {.name = "a.t", .kind = K::string, .choices = "sphere"},
                           {.name = "a.p", .kind = K::number, .range = Range::positive()},
                           {.name = "a.v", .kind = K::vec3, .fallback = "[0, 0, 1]"},
                           {.name = "a.b", .kind = K::boolean, .fallback = "false"},
                           {.name = "a.zz", .kind = K::number},
                           {.name = "b", .kind = K::table}});
  return t;
}

}  // namespace

TEST(SceneFile, TypedKeysRangesAndMessages) {
  SceneFile f =
      SceneFile::parse("[a]\nx = 2\ni = 1.5\ns = \"box\"\nv = [1, 2, 3]\nb = true\ny = 1.5\nt = \"box\"\np = \"x\"\n",
                       "s.toml", {}, "", test_keys());
  Section a = f.root().table("a");
  EXPECT_EQ(a.number("x", 0.0), 2.0);  // an integer is a number
  EXPECT_EQ(a.string("s"), "box");
  EXPECT_EQ(a.vec3("v"), Eigen::Vector3d(1, 2, 3));
  EXPECT_TRUE(a.boolean("b"));
  EXPECT_EQ(test::error_of([&] { a.integer("i"); }), "s.toml:3: a.i: expected an integer in [0, 10], got a number");
  EXPECT_EQ(test::error_of([&] { a.number("y"); }), "s.toml:7: a.y: expected a number in [2, 3], got 1.5");
  EXPECT_EQ(test::error_of([&] { a.number("p"); }), "s.toml:9: a.p: expected a number > 0, got a string");
  EXPECT_EQ(test::error_of([&] { a.string("t"); }), "s.toml:8: a.t: expected one of \"sphere\", got \"box\"");
  EXPECT_EQ(test::error_of([&] { f.check_unknown_keys(); }), "");
  // Absent keys take the row's default, or the parser's where the row gives none.
  SceneFile g = SceneFile::parse("[a]\n", "g.toml", {}, "", test_keys());
  Section ga = g.root().table("a");
  EXPECT_EQ(ga.integer("i"), 3);
  EXPECT_EQ(ga.number("y"), 2.5);
  EXPECT_EQ(ga.vec3("v"), Eigen::Vector3d(0, 0, 1));
  EXPECT_EQ(ga.number("x", 7.0), 7.0);
  EXPECT_EQ(ga.number("y", 2.5), 2.5);  // the row's own default, repeated: allowed
  // A parser that reads an undeclared key, a key as another type, a default the row does not give
  // or one that is not the row's: a programming error.
  EXPECT_THROW(ga.number("nothing", 0.0), std::logic_error);
  EXPECT_THROW(ga.integer("x", 0), std::logic_error);
  EXPECT_THROW(ga.number("x"), std::logic_error);
  EXPECT_THROW(ga.number("y", 2.0), std::logic_error);
  EXPECT_THROW(ga.boolean("b", true), std::logic_error);
}

TEST(SceneFile, UnknownKeysAreReportedInFileOrder) {
  SceneFile f = SceneFile::parse("[a]\nx = 1\nzz = 2\n[b]\nq = 1\n", "u.toml", {}, "", test_keys());
  f.root().table("a").number("x", 0);
  EXPECT_EQ(test::error_of([&] { f.check_unknown_keys(); }), "u.toml:3: a.zz: unknown key (expected one of: x)");
  f.root().table("a").number("zz", 0);
  EXPECT_EQ(test::error_of([&] { f.check_unknown_keys(); }), "u.toml:4: b: unknown key (expected one of: a)");
}

TEST(SceneFile, OverridesReplaceAddAndQuote) {
  SceneFile f = SceneFile::parse("[integrator]\nrtol = 1e-6\n", "o.toml",
                                 {"integrator.rtol=1e-9", "integrator.kind=backward_euler", "mesh.cells=[2, 3, 4]",
                                  "output.path=\"x y.h5\"", "integrator.atol=fast"});
  Section in = f.root().table("integrator");
  EXPECT_EQ(in.number("rtol"), 1e-9);
  EXPECT_EQ(in.string("kind"), "backward_euler");
  auto cells = f.root().table("mesh").int3("cells");
  EXPECT_EQ(cells, (std::array<long, 3>{2, 3, 4}));
  EXPECT_EQ(f.root().table("output").string("path", ""), "x y.h5");
  EXPECT_EQ(test::error_of([&] { in.number("atol"); }),
            "--set integrator.atol: expected a number in (0, 1e+06], got a string");
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
  // The rows up to which backward Euler's border is dense: 8 unless set (the measured crossover,
  // BackwardEulerOptions), an option of backward Euler alone.
  EXPECT_EQ(scene(text, {}).integrator.backward_euler.schur_max_constraints, 8);
  EXPECT_EQ(scene(text, {"integrator.dense_border_rows=0"}).integrator.backward_euler.schur_max_constraints, 0);
  EXPECT_THROW(scene(text, {"integrator.kind=ida", "integrator.dense_border_rows=4"}), Error);
  EXPECT_THROW(scene(text, {"integrator.dense_border_rows=-1"}), Error);
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

// The key tables: every key the parsers read is declared once, and the docs' tables are the table.
namespace {

std::string read_text(const fs::path& p) {
  std::ifstream in(p);
  return std::string((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
}

}  // namespace

// docs/scenes.md and docs/studies.md hold each key table as KeyTable::markdown writes it from the
// rows (`make docs` rewrites them): a row changed in the code and not in the docs fails here.
TEST(SceneKeys, TheDocsKeyTablesAreGeneratedFromTheKeyTables) {
  const std::pair<const char*, const KeyTable*> docs[] = {{"docs/scenes.md", &scene_keys()},
                                                          {"docs/studies.md", &study_keys()}};
  for (const auto& [name, keys] : docs) {
    const std::string text = read_text(fs::path(ISOCHOR_SOURCE_DIR) / name);
    ASSERT_FALSE(text.empty()) << name;
    EXPECT_EQ(keys->update_docs(text), text) << name << " differs from " << keys->source() << ": run `make docs`";
  }
  // Every row is in some generated table.
  const std::string scenes = read_text(fs::path(ISOCHOR_SOURCE_DIR) / "docs/scenes.md");
  for (const KeySpec& k : scene_keys().keys())
    EXPECT_NE(scenes.find("| `" + std::string(k.name) + "` |"), std::string::npos) << k.name;
}

// Every demo and study loads: a key a parser reads that no row declares, or a parser's default
// that is not its row's, stops the load with a std::logic_error.
TEST(SceneKeys, EveryDemoAndStudyReadsOnlyDeclaredKeys) {
  int scenes = 0;
  for (const auto& e : fs::directory_iterator(std::string(ISOCHOR_SOURCE_DIR) + "/demos")) {
    if (e.path().extension() != ".toml") continue;
    EXPECT_NO_THROW(load_scene(e.path().string())) << e.path();
    ++scenes;
  }
  EXPECT_GT(scenes, 20);
}

// The parsers name their keys in the source (`s.number("rtol")`): each such name is the last part
// of some row, so a key read only on a path the tests do not take is declared as well.
TEST(SceneKeys, EveryKeyNamedInTheParsersIsDeclared) {
  std::set<std::string> leaves;
  for (const KeyTable* t : {&scene_keys(), &study_keys()})
    for (const KeySpec& k : t->keys()) {
      const std::string name(k.name);
      leaves.insert(name.substr(name.rfind('.') + 1));
    }
  const std::regex call(
      R"re(\.(number|number_opt|integer|integer_opt|boolean|string|string_opt|vec3|vec3_opt|numbers|integers|strings|int3|table|tables)\("([a-z_0-9]+)")re");
  int calls = 0;
  for (const char* dir : {"core/src", "scene/src", "scene/src/methods", "apps/src"})
    for (const auto& e : fs::directory_iterator(fs::path(ISOCHOR_SOURCE_DIR) / dir)) {
      if (e.path().extension() != ".cpp") continue;
      const std::string text = read_text(e.path());
      for (auto it = std::sregex_iterator(text.begin(), text.end(), call); it != std::sregex_iterator(); ++it) {
        ++calls;
        EXPECT_TRUE(leaves.count((*it)[2]))
            << (*it)[2] << " (" << e.path().filename() << ") is read but no row declares it";
      }
    }
  EXPECT_GT(calls, 150);
}

// A row's default must parse as its kind and lie in its range; a name may be declared once.
TEST(SceneKeys, ATableWithABadRowIsRefusedWhenBuilt) {
  EXPECT_NO_THROW(scene_keys());
  EXPECT_NO_THROW(study_keys());
  using K = KeyKind;
  EXPECT_THROW(KeyTable("t", {{.name = "a", .kind = K::number, .fallback = "-1", .range = Range::positive()}}),
               std::logic_error);
  EXPECT_THROW(KeyTable("t", {{.name = "a", .kind = K::integer, .fallback = "1.5", .min = 0, .max = 3}}),
               std::logic_error);
  EXPECT_THROW(KeyTable("t", {{.name = "a", .kind = K::string, .fallback = "cnh"}}), std::logic_error);
  EXPECT_THROW(KeyTable("t", {{.name = "a", .kind = K::boolean}, {.name = "a", .kind = K::boolean}}), std::logic_error);
}

// Keys inside tables declared `like` another (selections, a collider's motion) and named keys
// (`<zone>`) find their rows.
TEST(SceneKeys, NamedKeysAndTablesLikeAnotherFindTheirRows) {
  const KeyTable& k = scene_keys();
  ASSERT_NE(k.find("zones.zone.select.kind"), nullptr);
  EXPECT_EQ(k.find("zones.zone.select.kind"), k.find("select.kind"));
  EXPECT_EQ(k.find("muscle.insertion.radius"), k.find("select.radius"));
  EXPECT_EQ(k.find("collider.motion.t1"), k.find("boundary.t1"));
  ASSERT_NE(k.find("zones.paint.labels.belly"), nullptr);
  EXPECT_EQ(std::string(k.find("zones.paint.labels.belly")->name), "zones.paint.labels.<zone>");
  EXPECT_EQ(k.find("zones.paint.belly"), nullptr);
  ASSERT_NE(study_keys().find("method.sweep.integrator.rtol"), nullptr);
  EXPECT_EQ(std::string(study_keys().find("method.sweep.integrator.rtol")->name), "method.sweep.<key>");
  EXPECT_EQ(k.find("material.nonsense"), nullptr);
  EXPECT_EQ(k.find("collider.motion.components"), k.find("boundary.components"));
}

TEST(Scene, RingZonesOnePerNode) {
  Scene sc = parse_scene(
      SceneFile::parse("[mesh]\nshape = \"box\"\ncells = 2\n[zones]\nglobal = false\nrings = 1\n", "r.toml"));
  ASSERT_EQ(sc.zones.size(), 27u);
  // The centre node of a 2x2x2 Kuhn box is interior: its 1-ring holds 24 tets.
  EXPECT_EQ(sc.zones[13].first, "ring1_13");
  EXPECT_EQ(sc.zones[13].second.size(), 24u);
}
