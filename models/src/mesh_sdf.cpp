#include "isochor/models/mesh_sdf.hpp"

#include <CGAL/AABB_face_graph_triangle_primitive.h>
#include <CGAL/AABB_traits.h>
#include <CGAL/AABB_tree.h>
#include <CGAL/Exact_predicates_inexact_constructions_kernel.h>
#include <CGAL/Side_of_triangle_mesh.h>
#include <CGAL/Surface_mesh.h>
#include <CGAL/Polygon_mesh_processing/orient_polygon_soup.h>
#include <CGAL/Polygon_mesh_processing/polygon_soup_to_polygon_mesh.h>
#include <CGAL/boost/graph/helpers.h>

#include <algorithm>
#include <array>
#include <cmath>

#include "isochor/base/error.hpp"

namespace isochor {

namespace {
using Kernel = CGAL::Exact_predicates_inexact_constructions_kernel;
using Point = Kernel::Point_3;
using SurfaceMesh = CGAL::Surface_mesh<Point>;
using Primitive = CGAL::AABB_face_graph_triangle_primitive<SurfaceMesh>;
using Tree = CGAL::AABB_tree<CGAL::AABB_traits<Kernel, Primitive>>;
using Side = CGAL::Side_of_triangle_mesh<SurfaceMesh, Kernel, CGAL::Default, Tree>;

// The uniform cubic B-spline's four weights at t in [0, 1] and their first and second derivatives.
void bspline(double t, double w[4], double d[4], double dd[4]) {
  const double s = 1.0 - t, t2 = t * t, t3 = t2 * t;
  w[0] = s * s * s / 6.0;
  w[1] = (3.0 * t3 - 6.0 * t2 + 4.0) / 6.0;
  w[2] = (-3.0 * t3 + 3.0 * t2 + 3.0 * t + 1.0) / 6.0;
  w[3] = t3 / 6.0;
  d[0] = -0.5 * s * s;
  d[1] = 0.5 * (3.0 * t2 - 4.0 * t);
  d[2] = 0.5 * (-3.0 * t2 + 2.0 * t + 1.0);
  d[3] = 0.5 * t2;
  dd[0] = s;
  dd[1] = 3.0 * t - 2.0;
  dd[2] = 1.0 - 3.0 * t;
  dd[3] = t;
}
}  // namespace

struct MeshSdf::Exact {
  SurfaceMesh mesh;
  Tree tree;
  std::unique_ptr<Side> side;
  double signed_distance(const Vec3& l) const {
    const Point p(l.x(), l.y(), l.z());
    const double d = std::sqrt(tree.squared_distance(p));
    const CGAL::Bounded_side where = (*side)(p);
    return where == CGAL::ON_BOUNDED_SIDE ? -d : where == CGAL::ON_BOUNDARY ? 0.0 : d;
  }
};

MeshSdf::MeshSdf(const Points& x, const std::vector<Tri>& tris, double cell, double margin, const std::string& what)
    : x_(x), tris_(tris), h_(cell) {
  if (tris.empty()) throw Error(what + ": the surface has no triangles");
  if (!(cell > 0)) throw Error(what + ": the cell size must be positive");
  auto exact = std::make_shared<Exact>();
  // Through CGAL's polygon soup: orienting it makes the triangles' orientation consistent and
  // splits vertices where the surface is not a manifold, so that the mesh can be built.
  std::vector<Point> points(x.cols());
  for (Eigen::Index i = 0; i < x.cols(); ++i) points[i] = Point(x(0, i), x(1, i), x(2, i));
  std::vector<std::array<std::size_t, 3>> soup(tris.size());
  for (std::size_t t = 0; t < tris.size(); ++t)
    for (int a = 0; a < 3; ++a) {
      if (tris[t][a] < 0 || tris[t][a] >= x.cols())
        throw Error(what + ": triangle " + std::to_string(t) + " has no vertex " + std::to_string(tris[t][a]));
      soup[t][a] = static_cast<std::size_t>(tris[t][a]);
    }
  CGAL::Polygon_mesh_processing::orient_polygon_soup(points, soup);
  if (!CGAL::Polygon_mesh_processing::is_polygon_soup_a_polygon_mesh(soup))
    throw Error(what + ": the triangles do not make a surface (expected a closed surface)");
  CGAL::Polygon_mesh_processing::polygon_soup_to_polygon_mesh(points, soup, exact->mesh);
  if (!CGAL::is_closed(exact->mesh)) {
    std::size_t border = 0;
    for (auto h : exact->mesh.halfedges())
      if (exact->mesh.is_border(h)) ++border;
    throw Error(what + ": the surface is not closed (" + std::to_string(border) +
                " edges with one triangle; expected a closed surface)");
  }
  exact->tree.insert(faces(exact->mesh).first, faces(exact->mesh).second, exact->mesh);
  exact->tree.build();
  exact->tree.accelerate_distance_queries();
  exact->side = std::make_unique<Side>(exact->tree);
  exact_ = exact;

  bound_ = x.colwise().norm().maxCoeff();
  const Vec3 lo = x.rowwise().minCoeff().array() - margin, hi = x.rowwise().maxCoeff().array() + margin;
  // Nodes 0..n-1 per axis; the spline is evaluated where its four nodes exist: [origin + h, origin + (n - 2) h].
  origin_ = lo.array() - h_;
  for (int a = 0; a < 3; ++a) n_[a] = static_cast<int>(std::ceil((hi[a] - lo[a]) / h_)) + 3;
  const long total = static_cast<long>(n_[0]) * n_[1] * n_[2];
  if (total > 200'000'000L)
    throw Error(what + ": the cell size makes " + std::to_string(total) + " samples (expected a larger cell)");
  samples_.resize(total);
  (void)exact->signed_distance(lo);  // any lazily built part of the tree, before the threads
  // Row by row along x. A sample's sign is its neighbour's when either is farther from the surface
  // than the cell (the segment between them then lies in a ball free of the surface; 1.5 cells,
  // so that rounding cannot matter), so the rays that decide inside or outside are cast only
  // within 1.5 cells of the surface (and after a sample on it).
#pragma omp parallel for schedule(dynamic, 1)
  for (int k = 0; k < n_[2]; ++k)
    for (int j = 0; j < n_[1]; ++j) {
      double previous = 0, sign = 1;
      for (int i = 0; i < n_[0]; ++i) {
        const Vec3 p = origin_ + h_ * Vec3(i, j, k);
        const Point q(p.x(), p.y(), p.z());
        const double d = std::sqrt(exact->tree.squared_distance(q));
        if (i == 0 || sign == 0 || (previous <= 1.5 * h_ && d <= 1.5 * h_)) {
          const CGAL::Bounded_side where = (*exact->side)(q);
          sign = where == CGAL::ON_BOUNDED_SIDE ? -1.0 : where == CGAL::ON_BOUNDARY ? 0.0 : 1.0;
        }
        samples_[i + static_cast<long>(n_[0]) * (j + static_cast<long>(n_[1]) * k)] = sign * d;
        previous = d;
      }
    }
}

double MeshSdf::exact_distance(const Vec3& l) const { return exact_->signed_distance(l); }

double MeshSdf::distance(const Vec3& l, Vec3* grad, Mat3* hess) const {
  // The point in grid units, clamped to where the spline is defined.
  Vec3 u = (l - origin_) / h_, q;
  int c[3];
  double w[3][4], d[3][4], dd[3][4];
  for (int a = 0; a < 3; ++a) {
    q[a] = std::clamp(u[a], 1.0, n_[a] - 2.0);
    c[a] = std::min(static_cast<int>(q[a]), n_[a] - 3);
    bspline(q[a] - c[a], w[a], d[a], dd[a]);
  }
  double s = 0;
  Vec3 g = Vec3::Zero();
  Mat3 H = Mat3::Zero();
  for (int k = 0; k < 4; ++k)
    for (int j = 0; j < 4; ++j)
      for (int i = 0; i < 4; ++i) {
        const double v = samples_[(c[0] - 1 + i) + static_cast<long>(n_[0]) *
                                                       ((c[1] - 1 + j) + static_cast<long>(n_[1]) * (c[2] - 1 + k))];
        s += w[0][i] * w[1][j] * w[2][k] * v;
        if (!grad && !hess) continue;
        g += v * Vec3(d[0][i] * w[1][j] * w[2][k], w[0][i] * d[1][j] * w[2][k], w[0][i] * w[1][j] * d[2][k]);
        if (!hess) continue;
        H(0, 0) += v * dd[0][i] * w[1][j] * w[2][k];
        H(1, 1) += v * w[0][i] * dd[1][j] * w[2][k];
        H(2, 2) += v * w[0][i] * w[1][j] * dd[2][k];
        H(0, 1) += v * d[0][i] * d[1][j] * w[2][k];
        H(0, 2) += v * d[0][i] * w[1][j] * d[2][k];
        H(1, 2) += v * w[0][i] * d[1][j] * d[2][k];
      }
  g /= h_;
  H(1, 0) = H(0, 1);
  H(2, 0) = H(0, 2);
  H(2, 1) = H(1, 2);
  H /= h_ * h_;
  const Vec3 out = (u - q) * h_;  // beyond the sampled box: add the distance to it
  if (out.squaredNorm() > 0) {
    const double e = out.norm();
    s += e;
    for (int a = 0; a < 3; ++a)
      if (out[a] != 0) g[a] = 0.0;
    g += out / e;
    H.setZero();
  }
  if (grad) *grad = g;
  if (hess) *hess = H;
  return s;
}

}  // namespace isochor
