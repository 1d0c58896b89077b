#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/alpha_wrap_3.h>

#include <Eigen/Geometry>
#include <array>
#include <string>
#include <vector>

#include "isochor/base/error.hpp"
#include "isochor/core/meshing.hpp"

namespace isochor {

void alpha_wrap(const Points& x, const std::vector<Tri>& tris, double alpha, double offset, Points& out_x,
                std::vector<Tri>& out_tris, const std::string& what) {
  using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
  if (!(alpha > 0) || !(offset > 0)) throw Error(what + ": the wrap needs a positive alpha and offset");
  if (tris.empty()) throw Error(what + ": no triangles to wrap");
  std::vector<Kernel::Point_3> points;
  points.reserve(static_cast<std::size_t>(x.cols()));
  for (Eigen::Index v = 0; v < x.cols(); ++v) points.emplace_back(x(0, v), x(1, v), x(2, v));
  // CGAL's oracle leaves out degenerate triangles and fails on a soup left empty: only triangles
  // with an area (relative to the soup's size) are wrapped, and none is an error.
  const double size = x.cols() ? (x.rowwise().maxCoeff() - x.rowwise().minCoeff()).norm() : 0.0;
  std::vector<std::array<std::size_t, 3>> faces;
  faces.reserve(tris.size());
  for (const Tri& t : tris) {
    for (int v : t)
      if (v < 0 || v >= x.cols())
        throw Error(what + ": a triangle names vertex " + std::to_string(v) + " of " + std::to_string(x.cols()));
    const double area = (x.col(t[1]) - x.col(t[0])).cross(x.col(t[2]) - x.col(t[0])).norm();
    if (area > 1e-12 * size * size)
      faces.push_back({static_cast<std::size_t>(t[0]), static_cast<std::size_t>(t[1]), static_cast<std::size_t>(t[2])});
  }
  if (faces.empty()) throw Error(what + ": every triangle is degenerate (no area; expected a surface to wrap)");
  CGAL::Surface_mesh<Kernel::Point_3> wrap;
  CGAL::alpha_wrap_3(points, faces, alpha, offset, wrap);
  if (wrap.number_of_faces() == 0) throw Error(what + ": the alpha wrap is empty (expected a surface to wrap)");
  out_x.resize(3, static_cast<Eigen::Index>(wrap.number_of_vertices()));
  std::vector<int> index(wrap.number_of_vertices() + wrap.number_of_removed_vertices(), -1);
  int k = 0;
  for (auto v : wrap.vertices()) {
    const auto& p = wrap.point(v);
    out_x.col(k) = Eigen::Vector3d(p.x(), p.y(), p.z());
    index[static_cast<std::size_t>(v)] = k++;
  }
  out_tris.clear();
  for (auto f : wrap.faces()) {
    Tri t{};
    int c = 0;
    for (auto v : CGAL::vertices_around_face(wrap.halfedge(f), wrap)) {
      if (c == 3) throw Error(what + ": the alpha wrap has a face that is not a triangle");
      t[c++] = index[static_cast<std::size_t>(v)];
    }
    out_tris.push_back(t);
  }
}

}  // namespace isochor
