#include "isochor/core/selection.hpp"

#include <algorithm>
#include <cmath>

#include "isochor/base/error.hpp"
#include "isochor/core/scene_file.hpp"

namespace isochor {

Selection Selection::parse(const Section& s) {
  Selection sel;
  sel.where = s.where("kind");
  const std::string kind = s.string("kind", "");
  if (kind.empty())
    s.fail("kind",
           "missing, expected one of \"all\", \"box\", \"half_space\", \"cylinder\", \"surface\", \"indices\", "
           "\"k_ring\", \"set\"");
  if (kind == "all") sel.kind = Kind::all;
  if (kind == "surface") sel.kind = Kind::surface;
  if (kind == "box") {
    sel.kind = Kind::box;
    if (!s.has("min") || !s.has("max"))
      s.fail(s.has("min") ? "max" : "min", "missing, a box selection needs min and max");
    sel.min = s.vec3("min", {});
    sel.max = s.vec3("max", {});
    for (int d = 0; d < 3; ++d)
      if (sel.min[d] > sel.max[d]) s.fail("max", "expected max >= min in every coordinate");
  }
  if (kind == "half_space") {
    sel.kind = Kind::half_space;
    sel.point = s.vec3("point", Eigen::Vector3d::Zero());
    if (!s.has("normal")) s.fail("normal", "missing, a half_space selection needs a normal");
    sel.normal = s.vec3("normal", {});
    if (sel.normal.norm() == 0) s.fail("normal", "expected a non-zero vector");
    sel.normal.normalize();
  }
  if (kind == "cylinder") {
    sel.kind = Kind::cylinder;
    if (!s.has("radius")) s.fail("radius", "missing, a cylinder selection needs a radius (m)");
    sel.point = s.vec3("center");
    sel.normal = s.vec3("axis", Eigen::Vector3d::UnitZ());
    if (sel.normal.norm() == 0) s.fail("axis", "expected a non-zero vector");
    sel.normal.normalize();
    sel.radius = s.number("radius", 0.0);
    sel.length = s.has("length") ? s.number("length", 0.0) : -1.0;
  }
  if (kind == "indices") {
    sel.kind = Kind::indices;
    if (!s.has("indices")) s.fail("indices", "missing, expected a list of indices");
    for (long i : s.integers("indices")) sel.indices.push_back(static_cast<int>(i));
  }
  if (kind == "k_ring") {
    sel.kind = Kind::k_ring;
    if (!s.has("node")) s.fail("node", "missing, a k_ring selection needs the centre node index");
    sel.node = static_cast<int>(s.integer("node", 0));
    sel.k = static_cast<int>(s.integer("k"));
  }
  if (kind == "set") {
    sel.kind = Kind::set;
    sel.name = s.string("name", "");
    if (sel.name.empty()) s.fail("name", "missing, expected the name of a node set or zone of the mesh");
  }
  return sel;
}

namespace {

std::vector<int> finish(std::vector<int> v, const Selection& sel, const char* what) {
  std::sort(v.begin(), v.end());
  v.erase(std::unique(v.begin(), v.end()), v.end());
  if (v.empty()) throw Error(sel.where + ": the selection contains no " + what + " (expected at least one)");
  return v;
}

// For the geometric kinds (box, half_space, cylinder): is p inside (boundaries inclusive)?
bool contains(const Selection& s, const Eigen::Vector3d& p, double tol) {
  switch (s.kind) {
    case Selection::Kind::box:
      return (p.array() >= s.min.array() - tol).all() && (p.array() <= s.max.array() + tol).all();
    case Selection::Kind::half_space:
      return (p - s.point).dot(s.normal) >= -tol;
    case Selection::Kind::cylinder: {
      const double along = (p - s.point).dot(s.normal);
      const double across = (p - s.point - along * s.normal).norm();
      return across <= s.radius + tol && (s.length < 0 || std::abs(along) <= s.length / 2 + tol);
    }
    default:
      return false;
  }
}

double tolerance(const Mesh& m) {
  const Points& X = m.rest_positions();
  return 1e-9 * (X.rowwise().maxCoeff() - X.rowwise().minCoeff()).norm();
}

std::vector<int> checked_indices(const Selection& sel, int count, const char* what) {
  for (int i : sel.indices)
    if (i >= count)
      throw Error(sel.where + ": " + what + " index " + std::to_string(i) + " is out of range (expected 0.." +
                  std::to_string(count - 1) + ")");
  return sel.indices;
}

}  // namespace

std::vector<int> select_nodes(const Mesh& mesh, const Selection& sel) {
  const Points& X = mesh.rest_positions();
  const double tol = tolerance(mesh);
  std::vector<int> out;
  switch (sel.kind) {
    case Selection::Kind::all:
      for (int i = 0; i < mesh.num_nodes(); ++i) out.push_back(i);
      break;
    case Selection::Kind::box:
    case Selection::Kind::half_space:
    case Selection::Kind::cylinder:
      for (int i = 0; i < mesh.num_nodes(); ++i)
        if (contains(sel, X.col(i), tol)) out.push_back(i);
      break;
    case Selection::Kind::surface:
      out = mesh.surface_nodes();
      break;
    case Selection::Kind::indices:
      out = checked_indices(sel, mesh.num_nodes(), "node");
      break;
    case Selection::Kind::k_ring:
      if (sel.node >= mesh.num_nodes())
        throw Error(sel.where + ": node " + std::to_string(sel.node) + " is out of range");
      out = mesh.node_ring(sel.node, sel.k);
      break;
    case Selection::Kind::set: {
      auto it = mesh.node_sets.find(sel.name);
      if (it != mesh.node_sets.end()) {
        out = it->second;
      } else {
        auto z = mesh.zones.find(sel.name);
        if (z == mesh.zones.end()) throw Error(sel.where + ": the mesh has no node set or zone \"" + sel.name + "\"");
        for (int e : z->second)
          for (int v : mesh.tets()[e]) out.push_back(v);
      }
      break;
    }
  }
  return finish(std::move(out), sel, "nodes");
}

std::vector<int> select_tets(const Mesh& mesh, const Selection& sel) {
  const Points& X = mesh.rest_positions();
  const double tol = tolerance(mesh);
  const auto& tets = mesh.tets();
  auto centroid = [&](const Tet& t) {
    return Eigen::Vector3d((X.col(t[0]) + X.col(t[1]) + X.col(t[2]) + X.col(t[3])) / 4.0);
  };
  std::vector<int> out;
  switch (sel.kind) {
    case Selection::Kind::all:
      for (int e = 0; e < mesh.num_tets(); ++e) out.push_back(e);
      break;
    case Selection::Kind::box:
    case Selection::Kind::half_space:
    case Selection::Kind::cylinder:
      for (int e = 0; e < mesh.num_tets(); ++e)
        if (contains(sel, centroid(tets[e]), tol)) out.push_back(e);
      break;
    case Selection::Kind::surface:
      for (int v : mesh.surface_nodes()) out.insert(out.end(), mesh.node_tets().begin(v), mesh.node_tets().end(v));
      break;
    case Selection::Kind::indices:
      out = checked_indices(sel, mesh.num_tets(), "tet");
      break;
    case Selection::Kind::k_ring:
      if (sel.node >= mesh.num_nodes())
        throw Error(sel.where + ": node " + std::to_string(sel.node) + " is out of range");
      out = mesh.tet_ring(sel.node, sel.k);
      break;
    case Selection::Kind::set: {
      auto z = mesh.zones.find(sel.name);
      if (z == mesh.zones.end()) throw Error(sel.where + ": the mesh has no zone \"" + sel.name + "\"");
      out = z->second;
      break;
    }
  }
  return finish(std::move(out), sel, "tets");
}

}  // namespace isochor
