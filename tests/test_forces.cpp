#include <gtest/gtest.h>

#include <Eigen/Dense>
#include <random>

#include "isochor/models/elements.hpp"
#include "isochor/models/forces.hpp"
#include "isochor/core/meshing.hpp"

using namespace isochor;

TEST(Forces, GravityAndGroundDerivatives) {
  Mesh m = make_box(Eigen::Vector3d(0.4, 0.4, 0.2), {2, 2, 1}, Eigen::Vector3d(0, 0, 0.1), 6);
  DofMap dofs = DofMap::make(m.num_nodes(), {});
  ElasticAssembly a(m, make_snh(1, 1), dofs);
  const Collider ground = Collider::plane(Vec3(0, 0, 0.004), Vec3(0, 0, 2.0), ContactLaw{1e5, 0.01});
  ExternalPotential ext(lumped_mass(m, 1000.0), Vec3(0, 0, -9.81), {ground}, dofs, a.pattern());
  EXPECT_NEAR(ext.mass().sum(), 1000.0 * 0.032, 1e-12);  // lumped mass sums to the total
  Points x = m.rest_positions();
  std::mt19937 rng(4);
  std::uniform_real_distribution<double> u(-0.003, 0.003);
  for (int i = 0; i < x.size(); ++i) x.data()[i] += u(rng);
  Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
  const double E = ext.add_gradient(x, g);
  EXPECT_NEAR(E, ext.energy(x), 1e-15);
  std::vector<double> values(a.pattern().nnz(), 0.0);
  ext.add_hessian(x, 1.0, values.data());
  int touching = 0;
  for (int n = 0; n < m.num_nodes(); ++n) {
    touching += x(2, n) < 0.014;
    for (int d = 0; d < 3; ++d) {
      Points xp = x, xm = x;
      xp(d, n) += 1e-7;
      xm(d, n) -= 1e-7;
      EXPECT_NEAR(g[3 * n + d], (ext.energy(xp) - ext.energy(xm)) / 2e-7, 1e-6 * (1 + std::abs(g[3 * n + d])));
      Eigen::VectorXd gp = Eigen::VectorXd::Zero(x.size()), gm = gp;
      ext.add_gradient(xp, gp);
      ext.add_gradient(xm, gm);
      const double fd = (gp[3 * n + 2] - gm[3 * n + 2]) / 2e-7;
      const Index slot = a.pattern().find(3 * Index(n) + 2, 3 * Index(n) + d);
      EXPECT_NEAR(values[slot], fd, 1e-5 * (1 + std::abs(fd)));
    }
  }
  EXPECT_GT(touching, 0);
}

// The damping force alpha M v + beta K v is computed inside the element pass (MeshSystem; its
// linearity in v is tested in test_ggl.cpp); here its matrix, filled into the pattern, against
// the matrix-free product K v of the element Hessians, and its dissipation.
TEST(Forces, RayleighDampingIsLinearInVelocityAndDissipative) {
  Mesh m = make_box(Eigen::Vector3d::Ones(), {2, 2, 2}, Eigen::Vector3d::Zero(), 6);
  DofMap dofs = DofMap::make(m.num_nodes(), m.node_sets.at("zmin"));
  ElasticAssembly a(m, make_cnh(3, 10, 1, 0.1), dofs);
  const Eigen::VectorXd mass = lumped_mass(m, 10.0);
  RayleighDamping r{0.3, 0.02};
  Points x = m.rest_positions();
  Eigen::VectorXd v = Eigen::VectorXd::Random(x.size());
  for (int n : m.node_sets.at("zmin")) v.segment<3>(3 * n).setZero();
  // -(alpha M v + beta K v), with K v the matrix-free product of the element Hessians.
  Eigen::VectorXd f = Eigen::VectorXd::Zero(x.size());
  for (int i = 0; i < mass.size(); ++i) f.segment<3>(3 * i) -= r.alpha * mass[i] * v.segment<3>(3 * i);
  a.add_hessian_times(x, v, -r.beta, f);
  EXPECT_LT(f.dot(v), 0.0);  // at rest K is positive semi-definite and M positive
  std::vector<double> values(a.pattern().nnz(), 0.0);
  r.add_matrix(a, mass, x, 1.0, values.data());
  // -(alpha M + beta K) v on the free dofs equals the force.
  for (int fr = 0; fr < dofs.num_free(); ++fr)
    for (int d = 0; d < 3; ++d) {
      double s = 0;
      const Index col = 3 * Index(fr) + d;
      for (Index k = a.pattern().col_ptr[col]; k < a.pattern().col_ptr[col + 1]; ++k) {
        const Index row = a.pattern().row_ind[k];
        s += values[k] * v[3 * dofs.free_nodes[row / 3] + row % 3];
      }
      EXPECT_NEAR(-s, f[3 * dofs.free_nodes[fr] + d], 1e-12 * (1 + std::abs(s)));
    }
}

// The contact's normal damping through ExternalPotential, on a plane moving mid-way through its
// motion: force and both Jacobians against finite differences, the force zero for a node that
// moves with the plane, and dissipative.
TEST(Forces, ContactDampingDerivativesOnAMovingPlane) {
  Mesh m = make_box(Eigen::Vector3d(0.4, 0.4, 0.2), {2, 2, 1}, Eigen::Vector3d(0, 0, 0.1), 6);
  DofMap dofs = DofMap::make(m.num_nodes(), {});
  ElasticAssembly a(m, make_snh(1, 1), dofs);
  Collider plane = Collider::plane(Vec3(0, 0, -0.002), Vec3(0.1, 0.2, 1.0).normalized(), ContactLaw{1e5, 0.01});
  plane.law.damping = 0.3;
  plane.motion.kind = Driver::Kind::ramp;
  plane.motion.vector = Vec3(0.01, 0.0, 0.02);
  plane.motion.t0 = 0.0;
  plane.motion.t1 = 0.1;
  ExternalPotential ext(lumped_mass(m, 1000.0), Vec3::Zero(), {plane}, dofs, a.pattern());
  ext.set_time(0.05);
  ASSERT_TRUE(ext.damped());
  Points x = m.rest_positions();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-0.003, 0.003);
  for (int i = 0; i < x.size(); ++i) x.data()[i] += u(rng);
  Eigen::VectorXd v(x.size());
  for (int i = 0; i < v.size(); ++i) v[i] = 100 * u(rng);
  auto force = [&](const Points& xx, const Eigen::VectorXd& vv) {
    Eigen::VectorXd g = Eigen::VectorXd::Zero(xx.size());
    ext.add_damping(xx, vv, g);
    return Eigen::VectorXd(-g);
  };
  std::vector<double> Dx(a.pattern().nnz(), 0.0), Dv(a.pattern().nnz(), 0.0);
  ext.add_damping_jacobians(x, v, Dx.data(), Dv.data());
  const Eigen::VectorXd f = force(x, v);
  int touching = 0;
  for (int n = 0; n < m.num_nodes(); ++n) {
    touching += f.segment<3>(3 * n).norm() > 0;
    for (int d = 0; d < 3; ++d) {
      Points xp = x, xm = x;
      xp(d, n) += 1e-7;
      xm(d, n) -= 1e-7;
      Eigen::VectorXd vp = v, vm = v;
      vp[3 * n + d] += 1e-5;
      vm[3 * n + d] -= 1e-5;
      const Eigen::Vector3d fdx = (force(xp, v) - force(xm, v)).segment<3>(3 * n) / 2e-7;
      const Eigen::Vector3d fdv = (force(x, vp) - force(x, vm)).segment<3>(3 * n) / 2e-5;
      for (int r = 0; r < 3; ++r) {
        const Index slot = a.pattern().find(3 * Index(n) + r, 3 * Index(n) + d);
        EXPECT_NEAR(-Dx[slot], fdx[r], 1e-6 * (1 + std::abs(fdx[r]))) << n << " " << r << " " << d;
        EXPECT_NEAR(-Dv[slot], fdv[r], 1e-8 * (1 + std::abs(fdv[r]))) << n << " " << r << " " << d;
      }
    }
  }
  EXPECT_GT(touching, 0);
  EXPECT_LT(f.dot(v - plane.motion.velocity(0.05).replicate(m.num_nodes(), 1)), 0.0);  // it dissipates
  // A body moving with the plane feels no damping.
  EXPECT_EQ(force(x, plane.motion.velocity(0.05).replicate(m.num_nodes(), 1)).norm(), 0.0);
}

// Restitution of a point mass on the damped ground, integrated finely (RK4) with the production
// force law: e against sqrt(1 - 4/3 alpha v0), derived to first order in alpha v0 (docs/scenes.md:
// the work of the damping along the undamped contact, (2/3) alpha m v0^3). The neglected term is
// second order: its share falls four times when alpha v0 halves.
TEST(Forces, ContactDampingRestitutionMatchesTheFirstOrderFormula) {
  const double k = 1e8, delta = 1e-3, mass = 0.01, v0 = 2.0;
  const Vec3 n = Vec3::UnitZ(), origin = Vec3::Zero();
  auto restitution = [&](double alpha) {
    auto acc = [&](double z, double vz) {
      Vec3 g;
      ground_energy(k, delta, origin, n, Vec3(0, 0, z), &g, nullptr);
      const Vec3 f =
          -g + ground_damping_force(k, alpha, delta, origin, n, Vec3(0, 0, z), Vec3(0, 0, vz), nullptr, nullptr);
      return f.z() / mass;
    };
    double z = delta, vz = -v0;
    const double h = 1e-8;
    do {
      const double k1 = vz, l1 = acc(z, vz);
      const double k2 = vz + 0.5 * h * l1, l2 = acc(z + 0.5 * h * k1, vz + 0.5 * h * l1);
      const double k3 = vz + 0.5 * h * l2, l3 = acc(z + 0.5 * h * k2, vz + 0.5 * h * l2);
      const double k4 = vz + h * l3, l4 = acc(z + h * k3, vz + h * l3);
      z += h / 6 * (k1 + 2 * k2 + 2 * k3 + k4);
      vz += h / 6 * (l1 + 2 * l2 + 2 * l3 + l4);
    } while (z < delta);
    return vz / v0;
  };
  double last_gap = 0;
  for (double alpha : {0.04, 0.02, 0.01}) {
    const double e = restitution(alpha), predicted = std::sqrt(1 - 4.0 / 3.0 * alpha * v0);
    const double gap = std::abs(e - predicted);
    std::printf("alpha v0 = %.2f: restitution %.5f, first-order formula %.5f\n", alpha * v0, e, predicted);
    EXPECT_LT(gap, std::pow(alpha * v0, 2)) << alpha;
    if (last_gap > 0) {
      EXPECT_GT(last_gap / gap, 3.0);
      EXPECT_LT(last_gap / gap, 5.0);
    }
    last_gap = gap;
  }
  EXPECT_NEAR(restitution(0.0), 1.0, 1e-6);  // undamped: the contact is elastic
}

TEST(Forces, SpringNetworkOnAClosedSurface) {
  Mesh m = make_sphere(1.0, 0.0, 800, Eigen::Vector3d::Zero());
  auto springs = surface_springs(m.rest_positions(), m.surface());
  std::size_t structural = 0, shear = 0, bending = 0;
  for (const Spring& s : springs) {
    EXPECT_GT(s.rest_length, 0.0);
    structural += s.kind == Spring::structural;
    shear += s.kind == Spring::shear;
    bending += s.kind == Spring::bending;
  }
  // A closed triangle surface has E = 3F/2 edges, one structural spring each.
  EXPECT_EQ(structural, 3 * m.surface().size() / 2);
  EXPECT_GT(shear, structural / 2);
  EXPECT_GT(bending, 0u);
}

TEST(Forces, CnhPressureIsThePenaltyStress) {
  // The F-bar deviatoric term is traceless (for J > epsilon), so -tr(sigma)/3 = -lambda U'(J).
  auto cnh = make_cnh(3.0, 50.0, 2.0, 0.1);
  std::mt19937 rng(8);
  std::uniform_real_distribution<double> u(-0.3, 0.3);
  for (int t = 0; t < 10; ++t) {
    Mat3 F = Mat3::Identity();
    for (int i = 0; i < 9; ++i) F(i % 3, i / 3) += u(rng);
    EXPECT_NEAR(cnh->pressure(F), -50.0 * penalty_U(F.determinant(), 2.0).dU, 1e-10 * 50.0);
  }
}

TEST(Forces, PerAreaContactIsTheSameGroundAtEveryResolution) {
  // A box (0.4 x 0.3 x 0.2) lowered until its bottom is p below the contact thickness: with the
  // per-area law the ground pushes k p^2 times the bottom nodes' surface areas. Those areas add up
  // to the bottom (A = 0.12) plus half of the first row of side cells (each side quad is two
  // triangles, one with two corners on the bottom edge and one with one: w h / 2 per quad), so
  // the force is k p^2 (A + P h / 2) with P the perimeter and h the cell height: independent of
  // the resolution as h -> 0. The per-node law pushes k p^2 per bottom node instead.
  const double k = 1e9, delta = 0.01, p = 0.004;
  for (int cells : {2, 4, 8}) {
    Mesh m = make_box(Eigen::Vector3d(0.4, 0.3, 0.2), {cells, cells, cells}, Eigen::Vector3d(0, 0, 0.1), 6);
    const Eigen::VectorXd area = surface_areas(m);
    EXPECT_NEAR(area.sum(), 2 * (0.4 * 0.3 + 0.3 * 0.2 + 0.4 * 0.2), 1e-12);  // the whole surface
    DofMap dofs = DofMap::make(m.num_nodes(), {});
    ElasticAssembly a(m, make_snh(1, 1), dofs);
    Points x = m.rest_positions();
    x.row(2).array() += delta - p;  // the bottom (z = 0 at rest) at delta - p
    int bottom = 0;
    for (int n = 0; n < m.num_nodes(); ++n) bottom += m.rest_positions()(2, n) == 0.0;
    for (bool per_area : {true, false}) {
      Collider ground = Collider::plane(Vec3::Zero(), Vec3::UnitZ(), ContactLaw{k, delta});
      ground.law.per_area = per_area;
      ExternalPotential ext(Eigen::VectorXd::Zero(m.num_nodes()), Vec3::Zero(), {ground}, dofs, a.pattern(), area);
      Eigen::VectorXd g = Eigen::VectorXd::Zero(x.size());
      ext.add_gradient(x, g);
      double force = 0;
      for (int n = 0; n < m.num_nodes(); ++n) force -= g[3 * n + 2];
      const double h = 0.2 / cells, expected = per_area ? k * p * p * (0.12 + 1.4 * h / 2) : k * p * p * bottom;
      EXPECT_NEAR(force, expected, 1e-9 * expected) << cells << " cells, per area " << per_area;
    }
  }
}
