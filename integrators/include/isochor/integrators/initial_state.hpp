// The consistent initial state of a ConstrainedSystem, shared by every integrator that runs one:
// q projected onto g = 0 (mass-weighted minimum-norm Newton steps), v onto G v + dg/dt = 0, and
// the accelerations and multipliers of the index-1 system
//   M a + G^T lambda = f,   G a = -d/dt (G v + dg/dt) at a = 0
// (sign convention of constrained_system.hpp).
#pragma once
#include "isochor/integrators/constrained_system.hpp"
#include <string>

namespace isochor {

void consistent_initial_state(ConstrainedSystem& sys, double t0, VectorXd& q, VectorXd& v, VectorXd& a,
                              VectorXd& lambda);

// Projects a state onto the constraints at time t, as the initial state is: q onto g(q, t) = 0
// (each row to 1e-14 of its constraint_scale(), or to where rounding stops it) and then v onto
// G v + dg/dt = 0, both the nearest points in the mass norm. Used on IDA's interpolated frames.
void project_state(ConstrainedSystem& sys, double t, VectorXd& q, VectorXd& v);

// Linearly dependent constraints (e.g. zones.global over zones that partition the mesh) make
// G M^-1 G^T singular; the projections and the initial multipliers then take its least-squares
// solution of smallest norm. True when the rows of G at (t, q) are dependent (a pivot of
// G M^-1 G^T below 1e-12 of the largest).
bool constraints_dependent(ConstrainedSystem& sys, double t, const VectorXd& q);

// max_j |g_j| / constraint_scale(j).
double constraint_error(const ConstrainedSystem& sys, const VectorXd& g);

// Throws Error when the system cannot be integrated as given (dofs_per_group()
// below 1, a mass that is not positive, a constraint row outside the dofs).
void check_system(const ConstrainedSystem& sys);
// Throws Error, naming `who`, when n is not a multiple of dofs_per_group(): only
// the solvers that order the dofs by groups need it (METIS's node ordering for KLU, backward
// Euler's KKT matrix, statics' KLU; Hong's per-node weights).
void check_groups(const ConstrainedSystem& sys, const std::string& who);

}  // namespace isochor
