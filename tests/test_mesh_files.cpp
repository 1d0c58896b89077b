#include <gtest/gtest.h>

#include <cstdlib>
#include <cstring>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/core/scene_file.hpp"
#include "test_util.hpp"

using namespace isochor;
namespace fs = std::filesystem;

namespace {

const char* kCubeObj = R"(# unit cube, quads, outward
v 0 0 0
v 1 0 0
v 1 1 0
v 0 1 0
v 0 0 1
v 1 0 1
v 1 1 1
v 0 1 1
f 1 4 3 2
f 1 2 6 5
f 2 3 7 6
f 3 4 8 7
f 4 1 5 8
f 5 6 7 8
)";

double zone_volume(const Mesh& m, const std::string& zone) {
  double v = 0;
  for (int e : m.zones.at(zone)) v += m.rest_volumes()[e];
  return v;
}

std::string cube_stl_binary() {
  Points x;
  std::vector<Tri> tris;
  // Triangulate the OBJ cube by reading it.
  fs::path d = fs::temp_directory_path() / "isochor_tests";
  fs::create_directories(d);
  read_obj_surface(test::write_file(d / "cube_for_stl.obj", kCubeObj), x, tris);
  std::string out(80, ' ');
  std::uint32_t n = static_cast<std::uint32_t>(tris.size());
  out.append(reinterpret_cast<const char*>(&n), 4);
  for (const Tri& t : tris) {
    float rec[12] = {0};
    for (int k = 0; k < 3; ++k)
      for (int c = 0; c < 3; ++c) rec[3 + 3 * k + c] = static_cast<float>(x(c, t[k]));
    out.append(reinterpret_cast<const char*>(rec), 48);
    out.append(2, '\0');
  }
  return out;
}

}  // namespace

TEST(MeshFiles, HandWrittenMshV2WithPhysicalGroups) {
  fs::path d = test::temp_dir();
  std::string p = test::write_file(d / "two.msh", R"($MeshFormat
2.2 0 8
$EndMeshFormat
$PhysicalNames
3
2 3 "base"
3 1 "left"
3 2 "right"
$EndPhysicalNames
$Nodes
5
1 0 0 0
2 1 0 0
3 0 1 0
4 0 0 1
5 1 1 1
$EndNodes
$Elements
3
1 2 2 3 1 1 2 3
2 4 2 1 1 1 2 3 4
3 4 2 2 2 2 3 4 5
$EndElements
)");
  Mesh m = read_msh(p);
  EXPECT_EQ(m.num_nodes(), 5);
  EXPECT_EQ(m.num_tets(), 2);
  EXPECT_NEAR(zone_volume(m, "left"), 1.0 / 6.0, 1e-15);
  EXPECT_NEAR(zone_volume(m, "right"), 1.0 / 3.0, 1e-15);
  EXPECT_EQ(m.node_sets.at("base").size(), 3u);
  for (int v : m.node_sets.at("base")) EXPECT_EQ(m.rest_positions()(2, v), 0.0);
}

TEST(MeshFiles, GmshWrittenV41AndV22AgreeOnZonesAndSets) {
  fs::path d = test::temp_dir();
  const std::string geo = std::string(ISOCHOR_SOURCE_DIR) + "/tests/data/two_boxes.geo";
  for (const char* format : {"msh41", "msh22"}) {
    const std::string out = (d / (std::string("boxes_") + format + ".msh")).string();
    const std::string cmd = "gmsh -3 -v 0 " + geo + " -format " + format + " -o " + out;
    ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
    Mesh m = read_msh(out);
    EXPECT_NEAR(m.rest_volume(), 2.0, 1e-12) << format;
    EXPECT_NEAR(zone_volume(m, "left"), 1.0, 1e-12) << format;
    EXPECT_NEAR(zone_volume(m, "right"), 1.0, 1e-12) << format;
    EXPECT_EQ(m.zones.at("left").size() + m.zones.at("right").size(), static_cast<std::size_t>(m.num_tets()));
    const auto& bottom = m.node_sets.at("bottom");
    EXPECT_GT(bottom.size(), 10u);
    std::size_t on_plane = 0;
    for (int v = 0; v < m.num_nodes(); ++v) on_plane += std::abs(m.rest_positions()(2, v)) < 1e-12;
    EXPECT_EQ(bottom.size(), on_plane) << format;
  }
}

TEST(MeshFiles, TetGenOneAndZeroBasedWithRealAttributes) {
  fs::path d = test::temp_dir();
  for (int base : {1, 0}) {
    auto idx = [&](int i) { return std::to_string(i + base); };
    std::string node = "# points\n5 3 0 1\n";
    const char* xyz[5] = {"0 0 0", "1 0 0", "0 1 0", "0 0 1", "1 1 1"};
    const int marker[5] = {5, 5, 5, 0, 0};
    for (int i = 0; i < 5; ++i) node += idx(i) + " " + xyz[i] + " " + std::to_string(marker[i]) + "\n";
    std::string ele = "2 4 1\n" + idx(0) + " " + idx(0) + " " + idx(1) + " " + idx(2) + " " + idx(3) + " 1.5\n" +
                      idx(1) + " " + idx(1) + " " + idx(2) + " " + idx(3) + " " + idx(4) + " -2  # comment\n";
    const std::string stem = (d / ("m" + std::to_string(base))).string();
    test::write_file(stem + ".node", node);
    test::write_file(stem + ".ele", ele);
    Mesh m = read_tetgen(stem + ".ele");
    EXPECT_EQ(m.num_tets(), 2);
    EXPECT_NEAR(zone_volume(m, "region_1.5"), 1.0 / 6.0, 1e-15);
    EXPECT_NEAR(zone_volume(m, "region_-2"), 1.0 / 3.0, 1e-15);
    EXPECT_EQ(m.node_sets.at("marker_5"), (std::vector<int>{0, 1, 2}));
  }
}

TEST(MeshFiles, ClosedObjIsTetrahedralisedWithoutChangingItsSurface) {
  fs::path d = test::temp_dir();
  Mesh m = mesh_closed_surface(test::write_file(d / "cube.obj", kCubeObj), 0.0);
  EXPECT_NEAR(m.rest_volume(), 1.0, 1e-12);
  EXPECT_EQ(m.surface().size(), 12u);
  SurfaceCheck c = check_surface(m.surface());
  EXPECT_TRUE(c.closed && c.oriented);
  EXPECT_NEAR(surface_volume(m.rest_positions(), m.surface()), 1.0, 1e-12);
  // Interior refinement by edge length keeps the surface triangles.
  Mesh fine = mesh_closed_surface(d / "cube.obj", 0.2);
  EXPECT_GT(fine.num_tets(), m.num_tets());
  EXPECT_NEAR(fine.rest_volume(), 1.0, 1e-12);
}

// Gmsh's HXT fill of a closed surface depended on the state of the process's heap: the same
// character scene gave meshes of 8,027 to 8,048 nodes as --set keys were added. The fill now runs
// Gmsh's own program in a new process, so the same surface and size give the same tets whatever
// the process allocated before (here blocks of many sizes, some kept, between two fills).
TEST(MeshFiles, AClosedSurfaceFillsToTheSameMeshWhateverTheProcessDidBefore) {
  const Mesh ball = make_sphere(1.0, 0.3, 0, Eigen::Vector3d::Zero());
  std::vector<int> index(ball.num_nodes(), -1);
  Points x(3, static_cast<Eigen::Index>(ball.surface_nodes().size()));
  for (std::size_t i = 0; i < ball.surface_nodes().size(); ++i) {
    index[ball.surface_nodes()[i]] = static_cast<int>(i);
    x.col(static_cast<Eigen::Index>(i)) = ball.rest_positions().col(ball.surface_nodes()[i]);
  }
  std::vector<Tri> tris = ball.surface();
  for (Tri& t : tris)
    for (int& n : t) n = index[n];
  const auto fill = [&] { return mesh_closed_surface(x, tris, 0.12, "ball surface"); };
  const Mesh first = fill();
  std::vector<std::vector<char>> kept;
  for (int i = 0; i < 20000; ++i) {
    std::vector<char> block(static_cast<std::size_t>(16 + (i * 7919) % 5000));
    if (i % 3 == 0) kept.push_back(std::move(block));
  }
  const Mesh second = fill();
  ASSERT_GT(first.num_nodes(), 2 * x.cols());  // the fill added nodes inside
  ASSERT_EQ(second.num_nodes(), first.num_nodes());
  ASSERT_EQ(second.num_tets(), first.num_tets());
  EXPECT_EQ((second.rest_positions() - first.rest_positions()).cwiseAbs().maxCoeff(), 0.0);
  EXPECT_TRUE(second.tets() == first.tets());
}

namespace {
// An environment variable set for the life of the object, then put back as it was.
class ScopedEnv {
 public:
  ScopedEnv(const char* name, const char* value) : name_(name), had_(std::getenv(name) != nullptr) {
    if (had_) saved_ = std::getenv(name);
    ::setenv(name, value, 1);
  }
  ~ScopedEnv() { had_ ? ::setenv(name_.c_str(), saved_.c_str(), 1) : ::unsetenv(name_.c_str()); }
  ScopedEnv(const ScopedEnv&) = delete;
  ScopedEnv& operator=(const ScopedEnv&) = delete;

 private:
  std::string name_, saved_;
  bool had_;
};
}  // namespace

// The fill needs Gmsh's program and a temporary directory: without either, one line naming the
// surface and what is missing; the environment is put back after each.
TEST(MeshFiles, AFillWithoutGmshsProgramOrATemporaryDirectoryIsOneLine) {
  fs::path d = test::temp_dir();
  const std::string cube = test::write_file(d / "cube.obj", kCubeObj);
  const auto with_env = [&](const char* name, const char* value) {
    const ScopedEnv env(name, value);
    return test::error_of([&] { mesh_closed_surface(cube, 0.0); });
  };
  const std::string no_gmsh = with_env("PATH", (d / "empty").c_str());
  EXPECT_EQ(no_gmsh.rfind(cube + ": cannot run Gmsh's program gmsh", 0), 0u) << no_gmsh;
  EXPECT_NE(no_gmsh.find("Debian's package gmsh"), std::string::npos);
  const std::string no_tmp = with_env("TMPDIR", (d / "cube.obj" / "x").c_str());
  EXPECT_EQ(no_tmp.rfind(cube + ": cannot make a temporary directory for Gmsh", 0), 0u) << no_tmp;
  EXPECT_NEAR(mesh_closed_surface(cube, 0.0).rest_volume(), 1.0, 1e-12);  // and with both, as before
}

// Gmsh's program reads the user's option files from HOME; a size factor there must not reach the
// fill: the same tets with such files as without.
TEST(MeshFiles, TheUsersGmshOptionFilesDoNotChangeTheFill) {
  fs::path d = test::temp_dir();
  const std::string cube = test::write_file(d / "cube.obj", kCubeObj);
  const Mesh plain = mesh_closed_surface(cube, 0.2);
  fs::create_directories(d / "home");
  test::write_file(d / "home" / ".gmshrc", "Mesh.MeshSizeFactor = 0.3;\n");
  test::write_file(d / "home" / ".gmsh-options", "Mesh.MeshSizeFactor = 0.3;\n");
  const Mesh with_files = [&] {
    const ScopedEnv home("HOME", (d / "home").c_str());
    return mesh_closed_surface(cube, 0.2);
  }();
  EXPECT_EQ(with_files.num_nodes(), plain.num_nodes());
  EXPECT_TRUE(with_files.tets() == plain.tets());
}

TEST(MeshFiles, InwardObjIsFlippedAndStlReadsTheSame) {
  fs::path d = test::temp_dir();
  std::string inward;
  for (std::string line : {"v 0 0 0", "v 1 0 0", "v 1 1 0", "v 0 1 0", "v 0 0 1", "v 1 0 1", "v 1 1 1", "v 0 1 1",
                           "f 2 3 4 1", "f 5 6 2 1", "f 6 7 3 2", "f 7 8 4 3", "f 8 5 1 4", "f 8 7 6 5"})
    inward += line + "\n";
  EXPECT_NEAR(mesh_closed_surface(test::write_file(d / "in.obj", inward), 0.0).rest_volume(), 1.0, 1e-12);
  EXPECT_NEAR(mesh_closed_surface(test::write_file(d / "cube.stl", cube_stl_binary()), 0.0).rest_volume(), 1.0, 1e-12);
  std::string ascii = "solid cube\n";
  Points x;
  std::vector<Tri> tris;
  read_obj_surface(test::write_file(d / "c.obj", kCubeObj), x, tris);
  for (const Tri& t : tris) {
    ascii += " facet normal 0 0 0\n  outer loop\n";
    for (int k : t)
      ascii +=
          "   vertex " + std::to_string(x(0, k)) + " " + std::to_string(x(1, k)) + " " + std::to_string(x(2, k)) + "\n";
    ascii += "  endloop\n endfacet\n";
  }
  ascii += "endsolid cube\n";
  EXPECT_NEAR(mesh_closed_surface(test::write_file(d / "ascii.stl", ascii), 0.0).rest_volume(), 1.0, 1e-12);
}

TEST(MeshFiles, BadSurfacesAndFilesAreNamedInErrors) {
  fs::path d = test::temp_dir();
  std::string open = std::string(kCubeObj);
  open = open.substr(0, open.rfind("f 5 6 7 8"));
  std::string msg = test::error_of([&] { mesh_closed_surface(test::write_file(d / "open.obj", open), 0.0); });
  EXPECT_NE(msg.find("open.obj: the surface is not closed"), std::string::npos) << msg;

  std::string twisted = std::string(kCubeObj);
  twisted.replace(twisted.find("f 5 6 7 8"), 9, "f 8 7 6 5");
  msg = test::error_of([&] { mesh_closed_surface(test::write_file(d / "twisted.obj", twisted), 0.0); });
  EXPECT_NE(msg.find("twisted.obj: the triangles are not consistently oriented"), std::string::npos) << msg;

  msg = test::error_of([&] { read_msh((d / "missing.msh").string()); });
  EXPECT_NE(msg.find("missing.msh: no such file"), std::string::npos) << msg;
  msg = test::error_of([&] { read_msh(test::write_file(d / "garbage.msh", "this is not a mesh\n")); });
  EXPECT_NE(msg.find("garbage.msh"), std::string::npos) << msg;
  msg = test::error_of([&] { read_msh(d.string()); });
  EXPECT_NE(msg.find("is a directory"), std::string::npos) << msg;
  msg = test::error_of([&] { read_tetgen((d / "none.node").string()); });
  EXPECT_NE(msg.find("none.node: no such file"), std::string::npos) << msg;
  test::write_file(d / "short.node", "3 3 0 0\n1 0 0 0\n");
  msg = test::error_of([&] { read_tetgen((d / "short.node").string()); });
  EXPECT_NE(msg.find("short.node:2: expected 3 points"), std::string::npos) << msg;
  msg = test::error_of([&] { mesh_closed_surface(test::write_file(d / "bad.obj", "v 0 0 0\nf 1 2 3\n"), 0.0); });
  EXPECT_NE(msg.find("bad.obj:2: vertex 2 is not defined"), std::string::npos) << msg;
}

// A Gmsh .geo script as a mesh source: demos/meshes/cook.geo (Cook's membrane, one element thick)
// has the panel's volume, the shoelace area of (0,0), (48,44), (48,60), (0,44), 1440, times its
// thickness h = 48 / N (planar faces: exact up to rounding); its physical groups become the zone
// and the node sets on their planes; edge_length overrides the script's size. A script with a
// syntax error or without a volume stops with one line, and Gmsh still works after it.
TEST(MeshFiles, GeoScriptIsMeshedWithItsPhysicalGroups) {
  const std::string cook = std::string(ISOCHOR_SOURCE_DIR) + "/demos/meshes/cook.geo";
  const Mesh m = read_geo(cook, 0.0);
  const double h = 48.0 / 8;
  EXPECT_NEAR(m.rest_volume(), 1440.0 * h, 1e-9 * 1440.0 * h);
  ASSERT_EQ(m.zones.count("membrane"), 1u);
  EXPECT_EQ(static_cast<int>(m.zones.at("membrane").size()), m.num_tets());
  for (const auto& [set, axis, value] :
       {std::tuple{"clamp", 0, 0.0}, {"load", 0, 48.0}, {"front", 2, 0.0}, {"back", 2, h}}) {
    ASSERT_EQ(m.node_sets.count(set), 1u) << set;
    for (int n : m.node_sets.at(set)) EXPECT_NEAR(m.rest_positions()(axis, n), value, 1e-9) << set;
  }
  const Mesh fine = read_geo(cook, 3.0);
  EXPECT_GT(fine.num_tets(), 2 * m.num_tets());
  EXPECT_NEAR(fine.rest_volume(), 1440.0 * h, 1e-9 * 1440.0 * h);
  const fs::path d = test::temp_dir();
  const std::string bad = test::write_file(d / "bad.geo", "Point(1) = {0, 0, 0;\n");
  EXPECT_NE(test::error_of([&] { read_geo(bad, 0.0); }).find("bad.geo"), std::string::npos);
  const std::string flat =
      test::write_file(d / "flat.geo", "Point(1) = {0, 0, 0, 1};\nPoint(2) = {1, 0, 0, 1};\nLine(1) = {1, 2};\n");
  EXPECT_NE(test::error_of([&] { read_geo(flat, 0.0); }).find("defines no volume"), std::string::npos);
  EXPECT_EQ(read_geo(cook, 0.0).num_tets(), m.num_tets());  // the same mesh again, Gmsh not locked
}

// mesh.parameters define a .geo script's DefineConstant numbers: cook.geo at N = 16 is h = 3
// thick, so its volume is 1440 x 3 and its back face at z = 3 (at the script's N = 8: 6); other
// mesh files refuse the key, and a name that is no .geo identifier is named.
TEST(MeshFiles, GeoParametersReplaceTheScriptsConstants) {
  const std::string cook = std::string(ISOCHOR_SOURCE_DIR) + "/demos/meshes/cook.geo";
  const Mesh m = read_geo(cook, 0.0, {{"N", 16.0}});
  EXPECT_NEAR(m.rest_volume(), 1440.0 * 3.0, 1e-9 * 1440.0 * 3.0);
  ASSERT_EQ(m.node_sets.count("back"), 1u);
  for (int n : m.node_sets.at("back")) EXPECT_NEAR(m.rest_positions()(2, n), 3.0, 1e-9);
  EXPECT_NEAR(m.rest_positions().row(2).maxCoeff(), 3.0, 1e-9);
  auto mesh_of = [](const std::string& text) {
    const SceneFile f = SceneFile::parse(text, "p.toml");
    return mesh_from_scene(f.root().table("mesh"), f);
  };
  EXPECT_EQ(mesh_of("[mesh]\nfile = \"" + cook + "\"\nparameters = { N = 16 }\n").num_tets(), m.num_tets());
  std::string msg = test::error_of([&] { mesh_of("[mesh]\nfile = \"x.msh\"\nparameters = { N = 16 }\n"); });
  EXPECT_NE(msg.find("mesh.parameters: applies to a .geo script only"), std::string::npos) << msg;
  msg = test::error_of([&] { mesh_of("[mesh]\nfile = \"" + cook + "\"\nparameters = { 2N = 16 }\n"); });
  EXPECT_NE(msg.find("mesh.parameters.2N: is not a .geo variable name"), std::string::npos) << msg;
  msg = test::error_of([&] { mesh_of("[mesh]\nfile = \"" + cook + "\"\nparameters = { N = 1e300 }\n"); });
  EXPECT_NE(msg.find("p.toml:3: mesh.parameters.N: expected a number in"), std::string::npos) << msg;
  // The parameters travel as a temporary script: without a temporary directory, one line says so.
  const char* tmpdir = std::getenv("TMPDIR");
  const std::string saved = tmpdir ? tmpdir : "";
  ::setenv("TMPDIR", "/nonexistent/isochor", 1);
  msg = test::error_of([&] { read_geo(cook, 0.0, {{"N", 16.0}}); });
  tmpdir ? ::setenv("TMPDIR", saved.c_str(), 1) : ::unsetenv("TMPDIR");
  EXPECT_NE(msg.find("cook.geo: its parameters are written to a temporary script, and there is no temporary directory"),
            std::string::npos)
      << msg;
}

// Before Gmsh fills a .geo script's volume, the tets it will make are bounded from below from its
// curves' mesh: the bound is below the count Gmsh then makes (and not vacuous), and a script far
// too fine for any machine (cook.geo at N = 1e5: at least 3e9 tets, 12 TB) stops with one line
// naming the parameter, within a second instead of meshing until memory runs out.
TEST(MeshFiles, AGeoScriptTooFineForTheMachineStopsBeforeMeshing) {
  const std::string cook = std::string(ISOCHOR_SOURCE_DIR) + "/demos/meshes/cook.geo";
  for (const double n : {8.0, 32.0}) {
    // Gmsh runs in a child process: the bound comes back as the error the check throws.
    const std::string said = test::error_of([&] {
      read_geo(cook, 0.0, {{"N", n}}, [](double tets) { throw Error("bound " + std::to_string(tets)); });
    });
    ASSERT_EQ(said.rfind("bound ", 0), 0u) << said;
    const double bound = std::stod(said.substr(6));
    const Mesh m = read_geo(cook, 0.0, {{"N", n}});
    EXPECT_LE(bound, m.num_tets()) << "N = " << n;
    EXPECT_GT(bound, m.num_tets() / 100.0) << "N = " << n;
  }
  const SceneFile f = SceneFile::parse("[mesh]\nfile = \"" + cook + "\"\nparameters = { N = 1e5 }\n", "p.toml");
  const std::string msg = test::error_of([&] { mesh_from_scene(f.root().table("mesh"), f); });
  EXPECT_NE(msg.find("mesh.parameters.N: makes about"), std::string::npos) << msg;
  EXPECT_NE(msg.find("GB of memory"), std::string::npos) << msg;
  // So fine that its curves' mesh alone would not fit (26 s and 5.5 GB before Gmsh aborted): the
  // estimate from a 1-D mesh at a hundred times the sizes refuses it first.
  const SceneFile g = SceneFile::parse("[mesh]\nfile = \"" + cook + "\"\nparameters = { N = 1e7 }\n", "q.toml");
  const std::string finer = test::error_of([&] { mesh_from_scene(g.root().table("mesh"), g); });
  EXPECT_NE(finer.find("mesh.parameters.N: makes about"), std::string::npos) << finer;
}
