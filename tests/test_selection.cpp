#include <gtest/gtest.h>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"
#include "isochor/core/scene_file.hpp"
#include "isochor/core/selection.hpp"
#include "test_util.hpp"

using namespace isochor;

namespace {
Selection parse(const std::string& text) {
  static std::vector<SceneFile> keep;  // sections point into their file
  keep.push_back(SceneFile::parse("select = " + text, "sel.toml"));
  return Selection::parse(keep.back().root().table("select"));
}
}  // namespace

TEST(Selection, NodesByEachKind) {
  // 4x4x4 cells on [0,1]^3: 5 nodes per axis at 0, 0.25, ..., 1.
  Mesh m = make_box(Eigen::Vector3d::Ones(), {4, 4, 4}, Eigen::Vector3d::Constant(0.5), 6);
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"all\" }")).size(), 125u);
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"box\", min = [0, 0, 0], max = [1, 1, 0.1] }")).size(), 25u);
  // Boundaries are inclusive: the box reaches the plane z = 0.25 exactly.
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"box\", min = [0, 0, 0], max = [1, 1, 0.25] }")).size(), 50u);
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"half_space\", point = [0, 0, 0.5], normal = [0, 0, 2] }")).size(), 75u);
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"surface\" }")).size(), 125u - 27u);
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"indices\", indices = [3, 1, 3] }")), (std::vector<int>{1, 3}));
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"k_ring\", node = 62, k = 1 }")).size(), 15u);
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"set\", name = \"zmin\" }")).size(), 25u);
}

TEST(Selection, CylinderAndDisc) {
  // 4x4x4 cells on [0,1]^3. Axis along z through (0.5, 0.5): radius 0.25 holds the centre line
  // and its 4 edge neighbours in each of the 5 node layers.
  Mesh m = make_box(Eigen::Vector3d::Ones(), {4, 4, 4}, Eigen::Vector3d::Constant(0.5), 6);
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"cylinder\", center = [0.5, 0.5, 0], radius = 0.25 }")).size(), 25u);
  // Radius 0.36 adds the 4 diagonal nodes (distance 0.354).
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"cylinder\", center = [0.5, 0.5, 0], radius = 0.36 }")).size(), 45u);
  // length = 0: the disc in the plane z = 1 only.
  EXPECT_EQ(select_nodes(m, parse("{ kind = \"cylinder\", center = [0.5, 0.5, 1], radius = 0.25, length = 0 }")).size(),
            5u);
  // Along x, length 0.5 about x = 0.5: the layers x = 0.25, 0.5, 0.75 of the line y = z = 0.5.
  EXPECT_EQ(
      select_nodes(
          m, parse("{ kind = \"cylinder\", center = [0.5, 0.5, 0.5], axis = [2, 0, 0], radius = 0.1, length = 0.5 }"))
          .size(),
      3u);
  EXPECT_NE(test::error_of([&] { parse("{ kind = \"cylinder\", center = [0, 0, 0] }"); }).find("radius: missing"),
            std::string::npos);
}

TEST(Selection, TetsByEachKind) {
  Mesh m = make_box(Eigen::Vector3d::Ones(), {4, 4, 4}, Eigen::Vector3d::Constant(0.5), 6);
  EXPECT_EQ(select_tets(m, parse("{ kind = \"all\" }")).size(), 384u);
  // Centroids below z = 0.5: the lower two layers of cells.
  EXPECT_EQ(select_tets(m, parse("{ kind = \"box\", min = [0, 0, 0], max = [1, 1, 0.5] }")).size(), 192u);
  EXPECT_EQ(select_tets(m, parse("{ kind = \"half_space\", point = [0.5, 0, 0], normal = [-1, 0, 0] }")).size(), 192u);
  // Tets touching the surface: all but those of the inner 2x2x2 cells that touch no boundary node.
  const auto surf = select_tets(m, parse("{ kind = \"surface\" }"));
  const auto& sn = m.surface_nodes();
  for (int e = 0; e < m.num_tets(); ++e) {
    bool touches = false;
    for (int v : m.tets()[e]) touches |= std::binary_search(sn.begin(), sn.end(), v);
    EXPECT_EQ(touches, std::binary_search(surf.begin(), surf.end(), e));
  }
  EXPECT_EQ(select_tets(m, parse("{ kind = \"k_ring\", node = 62, k = 1 }")).size(), 24u);
  EXPECT_EQ(select_tets(m, parse("{ kind = \"indices\", indices = [0, 383] }")).size(), 2u);
}

TEST(Selection, ErrorsNameTheSelection) {
  Mesh m = make_box(Eigen::Vector3d::Ones(), {2, 2, 2}, Eigen::Vector3d::Zero(), 6);
  std::string msg =
      test::error_of([&] { select_nodes(m, parse("{ kind = \"box\", min = [5, 5, 5], max = [6, 6, 6] }")); });
  EXPECT_NE(msg.find("sel.toml:1: select.kind: the selection contains no nodes"), std::string::npos) << msg;
  msg = test::error_of([&] { select_nodes(m, parse("{ kind = \"indices\", indices = [27] }")); });
  EXPECT_NE(msg.find("node index 27 is out of range (expected 0..26)"), std::string::npos) << msg;
  msg = test::error_of([&] { parse("{ kind = \"cone\" }"); });
  EXPECT_NE(msg.find("select.kind: expected one of"), std::string::npos) << msg;
  msg = test::error_of([&] { parse("{ kind = \"box\", min = [0, 0, 0] }"); });
  EXPECT_NE(msg.find("select.max: missing"), std::string::npos) << msg;
  msg = test::error_of([&] { select_tets(m, parse("{ kind = \"set\", name = \"nothing\" }")); });
  EXPECT_NE(msg.find("has no zone \"nothing\""), std::string::npos) << msg;
}
