// A closed triangle surface as a collider's shape: its signed distance (positive outside),
// smoothed so that contact forces are C^1.
//
// The exact signed distance is computed once, on a regular grid around the surface, through a
// bounding-volume hierarchy (CGAL's AABB tree over the triangles; the sign from CGAL's
// Side_of_triangle_mesh, which shoots rays and so does not depend on the triangles' orientation).
// The shape's distance is the uniform cubic B-spline whose control values are those samples: C^2
// everywhere, so its gradient and Hessian are exact derivatives of the value (the FD tests hold
// to rounding). A cubic B-spline reproduces linear functions, so near a flat face, more than two
// cells from its edges, it is the exact distance to that face; elsewhere it differs from the exact
// distance by about (h^2/6) times the distance's Laplacian (h the cell; h^2/(3 r) near a sphere
// of radius r) and rounds edges and corners over about two cells.
//
// Outside the sampled box (the surface's bounding box grown by `margin`) the distance is the
// spline's value at the nearest point of the box plus the distance to it: continuous, at least
// `margin` - 2 h sqrt(3) there, so beyond any contact thickness below that.
#pragma once
#include <memory>
#include <string>
#include <vector>

#include "isochor/models/elements.hpp"
#include "isochor/core/mesh.hpp"

namespace isochor {

class MeshSdf {
 public:
  // The surface (x: its vertices, tris: its triangles) sampled on cells of size `cell` over its
  // bounding box grown by `margin`. Throws Error (naming `what`) for a surface that is not closed
  // or has no triangles.
  MeshSdf(const Points& x, const std::vector<Tri>& tris, double cell, double margin, const std::string& what);

  // The smoothed signed distance at the point l (the surface's coordinates); gradient and
  // Hessian if asked.
  double distance(const Vec3& l, Vec3* grad, Mat3* hess) const;
  // The exact signed distance at l, through the BVH (for tests and diagnostics).
  double exact_distance(const Vec3& l) const;

  // Every vertex lies within this distance of the origin.
  double bound() const { return bound_; }
  double cell() const { return h_; }
  const Points& vertices() const { return x_; }
  const std::vector<Tri>& triangles() const { return tris_; }

 private:
  Points x_;
  std::vector<Tri> tris_;
  double h_ = 0, bound_ = 0;
  Vec3 origin_ = Vec3::Zero();                   // grid node (0, 0, 0)
  Eigen::Vector3i n_ = Eigen::Vector3i::Zero();  // nodes per axis
  std::vector<double> samples_;                  // node (i, j, k) at i + n_x (j + n_y k)
  struct Exact;                                  // the CGAL surface and tree, kept for exact_distance
  std::shared_ptr<const Exact> exact_;
};

}  // namespace isochor
