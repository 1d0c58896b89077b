// The discrete inf-sup constant of a zone choice: the numerical inf-sup test of Chapelle and
// Bathe (1993) for linear tets (P1 displacements) against pressures constant on each zone
//   beta_h = min over q of max over v of (q, div v) / (||q||_L2 ||v||_H1),
// q = sum_j q_j chi_j (zones may overlap), v on the free dofs. beta_h^2 is the smallest eigenvalue
// of G K^-1 G^T q = beta^2 M q: row j of G is the integral of div v over zone j (the gradient of
// zone j's volume at rest), K the matrix of ||v||^2_H1 = |grad v|^2 + |v|^2 / L^2 (L twice the
// largest distance of a node from the centroid: a norm even on a body held nowhere, and the same
// beta for the body rotated or scaled),
// M_ij = |z_i and z_j|. A zone choice whose beta_h stays bounded away from 0 as the mesh is refined
// is stable (Brezzi's condition): no locking; one whose beta_h falls with h locks, and an
// eigenvalue at 0 is a pressure mode the displacements cannot see (a spurious mode).
#pragma once
#include <Eigen/Core>
#include <utility>
#include <vector>

#include "isochor/core/mesh.hpp"

namespace isochor {

struct InfSup {
  double beta = 0;       // beta_h
  double beta_next = 0;  // the next one (sqrt of the second eigenvalue)
  int zero_modes = 0;    // eigenvalues below 1e-10 of the largest: pressures no displacement sees
  int zones = 0, dofs = 0;
};

// fixed: nodes held in every direction; held: (node, unit direction) held along that direction
// only (rollers). Zones must be linearly independent (the global zone beside zones that cover
// the body is their sum): Error otherwise, as for more than max_zones zones (a dense eigenproblem).
InfSup infsup_constant(const Mesh& mesh, const std::vector<std::vector<int>>& zones, const std::vector<int>& fixed,
                       const std::vector<std::pair<int, Eigen::Vector3d>>& held, int max_zones = 6000);

}  // namespace isochor
