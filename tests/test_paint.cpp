// Painted zones (the CNH paper's section 6): a box painted in two halves gives each tet its side,
// hemispheres painted on a sphere give zones of half its volume that converge with the mesh, and
// paint that does not fit the mesh stops with a message naming the zone or the node.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <sstream>

#include "isochor/core/paint.hpp"
#include "isochor/scene/scene.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {

const std::vector<int>& zone(const Scene& s, const std::string& name) {
  for (const auto& [n, tets] : s.zones)
    if (n == name) return tets;
  throw std::runtime_error("no zone " + name);
}

double volume(const Scene& s, const std::vector<int>& tets) {
  double v = 0;
  for (int e : tets) v += s.mesh.rest_volumes()[e];
  return v;
}

Eigen::Vector3d centroid(const Mesh& m, int e) {
  Eigen::Vector3d c = Eigen::Vector3d::Zero();
  for (int v : m.tets()[e]) c += m.rest_positions().col(v) / 4;
  return c;
}

const char* kBox =
    "[mesh]\nshape = \"box\"\nsize = [1.0, 1.0, 1.0]\ncenter = [0.5, 0.5, 0.5]\ncells = %d\n"
    "[material]\nmu = 1.0\nlambda = 1.0\n";

std::string box(int cells) {
  char b[256];
  std::snprintf(b, sizeof b, kBox, cells);
  return b;
}

// Every tet whose centroid is left of x = 0.5 is in "left" only, right of it in "right" only;
// on the plane (a tie: the paint there is 1/2 up to rounding) in one or both.
void expect_halves(const Scene& s) {
  const auto &L = zone(s, "left"), &R = zone(s, "right");
  std::vector<int> side(s.mesh.num_tets(), 0);
  for (int e : L) side[e] |= 1;
  for (int e : R) side[e] |= 2;
  for (int e = 0; e < s.mesh.num_tets(); ++e) {
    const double x = centroid(s.mesh, e).x();
    if (std::abs(x - 0.5) < 1e-12) {
      EXPECT_NE(side[e], 0) << "tet " << e;
    } else {
      EXPECT_EQ(side[e], x < 0.5 ? 1 : 2) << "tet " << e << " centroid x " << x;
    }
  }
}

}  // namespace

TEST(Paint, ABoxPaintedInTwoHalvesGivesEachTetItsSide) {
  const auto dir = test::temp_dir();
  // By labels on a 5-cell box (nodes at x = 0.4 and 0.6 around the plane), from points with
  // positions: label 1 left of x = 0.5, 2 right of it.
  {
    const Scene probe = parse_scene(SceneFile::parse(box(5), "probe.toml"));
    std::ostringstream csv;
    csv.precision(17);
    csv << "x,y,z,label\n";
    for (int v : probe.mesh.surface_nodes()) {
      const Eigen::Vector3d p = probe.mesh.rest_positions().col(v);
      csv << p.x() << "," << p.y() << "," << p.z() << "," << (p.x() < 0.5 ? 1 : 2) << "\n";
    }
    test::write_file(dir / "halves.csv", csv.str());
    const Scene s = parse_scene(SceneFile::parse(
        box(5) + "[zones]\nglobal = false\n[[zones.paint]]\nfile = \"halves.csv\"\nlabels = { left = 1, right = 2 }\n",
        "halves.toml", {}, dir.string()));
    expect_halves(s);
  }
  // By weights on a 4-cell box (nodes on the plane), by mesh node: left = 1 - x, right = x.
  {
    const Scene probe = parse_scene(SceneFile::parse(box(4), "probe.toml"));
    std::ostringstream csv;
    csv.precision(17);
    csv << "node,w_left,w_right\n";
    for (int v : probe.mesh.surface_nodes()) {
      const double x = probe.mesh.rest_positions()(0, v);
      csv << v << "," << 1 - x << "," << x << "\n";
    }
    test::write_file(dir / "weights.csv", csv.str());
    const Scene s = parse_scene(SceneFile::parse(
        box(4) + "[[zones.paint]]\nfile = \"weights.csv\"\nweights = { left = \"w_left\", right = \"w_right\" }\n",
        "weights.toml", {}, dir.string()));
    expect_halves(s);
  }
  // By colours, from an OBJ with vertex colours (red left, blue right).
  {
    const Scene probe = parse_scene(SceneFile::parse(box(5), "probe.toml"));
    std::ostringstream obj;
    obj.precision(17);
    for (int v : probe.mesh.surface_nodes()) {
      const Eigen::Vector3d p = probe.mesh.rest_positions().col(v);
      obj << "v " << p.x() << " " << p.y() << " " << p.z() << (p.x() < 0.5 ? " 1 0 0\n" : " 0 0 1\n");
    }
    test::write_file(dir / "halves.obj", obj.str());
    const Scene s = parse_scene(SceneFile::parse(
        box(5) + "[[zones.paint]]\nfile = \"halves.obj\"\ncolors = { left = [255, 0, 0], right = [0.0, 0.0, 1.0] }\n",
        "colors.toml", {}, dir.string()));
    expect_halves(s);
  }
}

TEST(Paint, HemispheresPaintedOnASphereHaveHalfItsVolume) {
  // Labels painted on 20,000 points of a sphere (a binary PLY): 1 where z >= 0, 2 below. At 1K,
  // 5K and 20K tets each hemisphere zone holds half the mesh's volume within 3%, and the error
  // shrinks with the mesh (not monotonically: the border's error on an unstructured mesh is O(h)
  // with a random sign; measured 1.4%, 0.15%, 0.22%).
  const auto dir = test::temp_dir();
  {
    const int n = 20000;
    std::ofstream ply(dir / "hemispheres.ply", std::ios::binary);
    ply << "ply\nformat binary_little_endian 1.0\ncomment isochor test\nelement vertex " << n
        << "\nproperty float x\nproperty float y\nproperty float z\nproperty uchar label\nelement face 0\n"
           "property list uchar int vertex_indices\nend_header\n";
    const double golden = M_PI * (3 - std::sqrt(5.0));
    for (int i = 0; i < n; ++i) {  // a Fibonacci sphere of radius 0.1
      const double z = 1 - 2 * (i + 0.5) / n, r = std::sqrt(1 - z * z);
      const float p[3] = {static_cast<float>(0.1 * r * std::cos(golden * i)),
                          static_cast<float>(0.1 * r * std::sin(golden * i)), static_cast<float>(0.1 * z)};
      const unsigned char label = z >= 0 ? 1 : 2;
      ply.write(reinterpret_cast<const char*>(p), sizeof p);
      ply.write(reinterpret_cast<const char*>(&label), 1);
    }
  }
  double coarsest = 1;
  for (int tets : {1000, 5000, 20000}) {
    const Scene s =
        parse_scene(SceneFile::parse("[mesh]\nshape = \"sphere\"\nradius = 0.1\ntarget_tets = " + std::to_string(tets) +
                                         "\n[material]\nmu = 1.0\nlambda = 1.0\n[zones]\nglobal = "
                                         "false\n[[zones.paint]]\nfile = \"hemispheres.ply\"\n"
                                         "labels = { top = 1, bottom = 2 }\n",
                                     "sphere.toml", {}, dir.string()));
    const double half = 0.5 * s.mesh.rest_volume();
    const double top = volume(s, zone(s, "top")), bottom = volume(s, zone(s, "bottom"));
    EXPECT_NEAR(top + bottom, s.mesh.rest_volume(), 1e-12 * half);  // every tet in one of them
    const double error = std::max(std::abs(top / half - 1), std::abs(bottom / half - 1));
    EXPECT_LT(error, 0.03) << s.mesh.num_tets() << " tets";
    if (tets == 1000) coarsest = error;
    if (tets == 20000) {
      EXPECT_LT(error, 0.5 * coarsest);  // converging: the border's error shrinks with h
    }
    std::printf("hemispheres at %d tets: top %.4f, bottom %.4f of half the volume\n", s.mesh.num_tets(), top / half,
                bottom / half);
  }
}

TEST(Paint, PaintThatDoesNotFitStopsWithAMessage) {
  const auto dir = test::temp_dir();
  // A 3 m bar whose two ends are painted with one label; the middle unpainted.
  const std::string bar =
      "[mesh]\nshape = \"box\"\nsize = [3.0, 1.0, 1.0]\ncenter = [1.5, 0.5, 0.5]\ncells = [12, 4, 4]\n"
      "[material]\nmu = 1.0\nlambda = 1.0\n";
  const Scene probe = parse_scene(SceneFile::parse(bar, "probe.toml"));
  std::ostringstream csv;
  csv << "node,label\n";
  for (int v : probe.mesh.surface_nodes()) {
    const double x = probe.mesh.rest_positions()(0, v);
    csv << v << "," << (x < 0.2 || x > 2.8 ? 7 : 0) << "\n";
  }
  test::write_file(dir / "ends.csv", csv.str());
  auto err = [&](const std::string& paint) {
    return test::error_of(
        [&] { parse_scene(SceneFile::parse(bar + "[[zones.paint]]\n" + paint, "paint.toml", {}, dir.string())); });
  };
  EXPECT_NE(err("file = \"ends.csv\"\nlabels = { ends = 7 }\n")
                .find("zones.paint[0].labels.ends: zone \"ends\" is painted in 2 disconnected pieces"),
            std::string::npos);
  EXPECT_NE(
      err("file = \"ends.csv\"\nlabels = { belly = 3 }\n").find("zones.paint[0].labels.belly: no tet is painted belly"),
      std::string::npos);
  EXPECT_NE(err("file = \"ends.csv\"\nproperty = \"zone\"\nlabels = { ends = 7 }\n")
                .find("no vertex property \"zone\" (it has: node, label)"),
            std::string::npos);
  EXPECT_NE(err("file = \"ends.csv\"\nlabels = { ends = 7 }\nweights = { x = \"label\" }\n")
                .find("expected exactly one of labels, colors or weights"),
            std::string::npos);
  EXPECT_NE(err("file = \"missing.ply\"\nlabels = { a = 1 }\n").find("zones.paint[0].file: "), std::string::npos);
  // Malformed PLY: a vertex that is not a number, a list whose count is not a count.
  test::write_file(dir / "nan.ply",
                   "ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
                   "property int label\nend_header\n0 0 0 1\nnan 0 0 1\n");
  EXPECT_NE(err("file = \"nan.ply\"\nlabels = { a = 1 }\n").find("vertex 1 has a position that is not a finite number"),
            std::string::npos);
  test::write_file(
      dir / "list.ply",
      "ply\nformat ascii 1.0\nelement face 1\nproperty list uchar int vertex_indices\n"
      "element vertex 1\nproperty float x\nproperty float y\nproperty float z\nend_header\nnan 1 2 3\n0 0 0\n");
  EXPECT_NE(err("file = \"list.ply\"\nlabels = { a = 1 }\n").find("a PLY list of nan items"), std::string::npos);
  // The paint of another surface: the box's nodes moved by 0.5 m.
  std::ostringstream far;
  far << "x,y,z,label\n";
  for (int v : probe.mesh.surface_nodes()) {
    const Eigen::Vector3d p = probe.mesh.rest_positions().col(v);
    far << p.x() + 0.5 << "," << p.y() << "," << p.z() << ",1\n";
  }
  test::write_file(dir / "far.csv", far.str());
  EXPECT_NE(err("file = \"far.csv\"\nlabels = { a = 1 }\n").find("m from the nearest painted vertex"),
            std::string::npos);
  // Split: the two ends as two zones.
  const Scene s = parse_scene(SceneFile::parse(bar + "[zones]\nglobal = false\n[[zones.paint]]\nfile = "
                                                     "\"ends.csv\"\nlabels = { ends = 7 }\ndisconnected = \"split\"\n",
                                               "split.toml", {}, dir.string()));
  ASSERT_EQ(s.zones.size(), 2u);
  EXPECT_EQ(s.zones[0].first, "ends_1");
  EXPECT_EQ(s.zones[1].first, "ends_2");
  for (const auto& [name, tets] : s.zones)
    for (int e : tets)
      EXPECT_EQ(centroid(s.mesh, e).x() < 1.5, centroid(s.mesh, tets[0]).x() < 1.5) << name;  // one end each
  EXPECT_NE(centroid(s.mesh, s.zones[0].second[0]).x() < 1.5, centroid(s.mesh, s.zones[1].second[0]).x() < 1.5);
}

TEST(Paint, AGmshSurfaceGroupPaintsTheTetsNearestIt) {
  // tests/data/two_boxes.geo: the slab [0, 2] x [0, 1] x [0, 1] with its bottom face (z = 0) a 2-D
  // physical group. Painted by that group, a tet is in the zone when the surface point nearest
  // its centroid is on the bottom face: z < x, 2 - x, y, 1 - y, 1 - z. Away (by a cell) from where
  // the bottom face stops being the nearest, membership must follow that rule exactly; the paint's
  // interpolation and the tets' size decide only within a cell of it.
  const auto dir = test::temp_dir();
  const double h = 0.15;
  const std::string msh = (dir / "slab.msh").string();
  const std::string cmd = "gmsh -3 -v 0 " + std::string(ISOCHOR_SOURCE_DIR) + "/tests/data/two_boxes.geo -clmax " +
                          std::to_string(h) + " -o " + msh;
  ASSERT_EQ(std::system(cmd.c_str()), 0) << cmd;
  const std::string scene =
      "[mesh]\nfile = \"" + msh + "\"\n[material]\nmu = 1.0\nlambda = 1.0\n[zones]\nglobal = false\n";
  const Scene sc = parse_scene(SceneFile::parse(scene + "[[zones.paint]]\ngroups = [\"bottom\"]\n", "slab.toml"));
  ASSERT_EQ(sc.zones.size(), 1u);
  EXPECT_EQ(sc.zones[0].first, "bottom");
  std::vector<char> in(sc.mesh.num_tets(), 0);
  for (int e : sc.zones[0].second) in[e] = 1;
  int decided = 0;
  for (int e = 0; e < sc.mesh.num_tets(); ++e) {
    Eigen::Vector3d c = Eigen::Vector3d::Zero();
    for (int n : sc.mesh.tets()[e]) c += 0.25 * sc.mesh.rest_positions().col(n);
    const double others = std::min({c.x(), 2 - c.x(), c.y(), 1 - c.y(), 1 - c.z()});
    if (c.z() < others - h) {
      EXPECT_TRUE(in[e]) << "tet " << e << " at " << c.transpose();
      ++decided;
    } else if (c.z() > others + h) {
      EXPECT_FALSE(in[e]) << "tet " << e << " at " << c.transpose();
      ++decided;
    }
  }
  EXPECT_GT(decided, sc.mesh.num_tets() / 2);
  const std::string err = test::error_of(
      [&] { parse_scene(SceneFile::parse(scene + "[[zones.paint]]\ngroups = [\"belly\"]\n", "slab.toml")); });
  EXPECT_NE(err.find("zones.paint[0].groups: the mesh has no group \"belly\" (its groups: bottom"), std::string::npos)
      << err;
}
