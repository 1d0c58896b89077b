// Assembly over a mesh, volume constraints and drivers against finite differences.
#include <gtest/gtest.h>

#include <set>
#include <omp.h>

#include <Eigen/Dense>
#include <random>

#include "isochor/base/error.hpp"
#include "isochor/models/assembly.hpp"
#include "isochor/models/constraints.hpp"
#include "isochor/models/drivers.hpp"
#include "isochor/core/meshing.hpp"

using namespace isochor;

namespace {

struct Scene3x2x2 {
  Mesh mesh = make_box(Eigen::Vector3d(1, 0.8, 0.6), {3, 2, 2}, Eigen::Vector3d::Zero(), 5);
  DofMap dofs;
  Points x;
  Scene3x2x2() {
    dofs = DofMap::make(mesh.num_nodes(), mesh.node_sets.at("zmin"));
    std::mt19937 rng(1);
    std::uniform_real_distribution<double> u(-0.08, 0.08);
    x = mesh.rest_positions();
    for (int i = 0; i < x.size(); ++i) x.data()[i] += u(rng);
  }
};

Eigen::MatrixXd dense(const Pattern& p, const std::vector<double>& values) {
  Eigen::MatrixXd A = Eigen::MatrixXd::Zero(p.n, p.n);
  for (Index c = 0; c < p.n; ++c)
    for (Index k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k) A(p.row_ind[k], c) += values[k];
  return A;
}

// Central differences of a gradient function (3 N) over the free dofs.
template <class G>
Eigen::MatrixXd fd_hessian(const Scene3x2x2& s, G&& grad) {
  const int nf = s.dofs.num_free();
  Eigen::MatrixXd H(3 * nf, 3 * nf);
  const double h = 1e-6;
  for (int f = 0; f < nf; ++f)
    for (int d = 0; d < 3; ++d) {
      Points xp = s.x, xm = s.x;
      xp(d, s.dofs.free_nodes[f]) += h;
      xm(d, s.dofs.free_nodes[f]) -= h;
      Eigen::VectorXd gp = grad(xp), gm = grad(xm);
      for (int g = 0; g < nf; ++g)
        for (int e = 0; e < 3; ++e)
          H(3 * g + e, 3 * f + d) = (gp[3 * s.dofs.free_nodes[g] + e] - gm[3 * s.dofs.free_nodes[g] + e]) / (2 * h);
    }
  return H;
}

}  // namespace

// A dof map in a given node order lists the free nodes in that order, skips the Dirichlet ones,
// and refuses an order that is not a permutation of the nodes.
TEST(DofMap, FreeNodesInTheGivenOrder) {
  const DofMap d = DofMap::make(5, {3}, {4, 3, 0, 2, 1});
  EXPECT_EQ(d.free_nodes, (std::vector<int>{4, 0, 2, 1}));
  EXPECT_EQ(d.free_index, (std::vector<int>{1, 3, 2, -1, 0}));
  EXPECT_EQ(DofMap::make(3, {}).free_nodes, (std::vector<int>{0, 1, 2}));
  EXPECT_THROW(DofMap::make(3, {}, {0, 1}), Error);
  EXPECT_THROW(DofMap::make(3, {}, {0, 1, 1}), Error);
  EXPECT_THROW(DofMap::make(3, {}, {0, 1, 3}), Error);
}

TEST(Assembly, GradientAndHessianMatchFiniteDifferences) {
  Scene3x2x2 s;
  ElasticAssembly a(s.mesh, make_cnh(2.0, 30.0, 1.0, 0.1), s.dofs, {5.0, 1.0});
  Eigen::VectorXd g;
  a.gradient(s.x, g);
  const double h = 1e-6;
  for (int i = 0; i < s.x.size(); i += 7) {
    Points xp = s.x, xm = s.x;
    xp.data()[i] += h;
    xm.data()[i] -= h;
    EXPECT_NEAR(g[i], (a.energy(xp) - a.energy(xm)) / (2 * h), 1e-6 * (1 + std::abs(g[i])));
  }
  std::vector<double> values(a.pattern().nnz(), 0.0);
  a.add_hessian(s.x, 1.0, values.data());
  const Eigen::MatrixXd H = dense(a.pattern(), values);
  const Eigen::MatrixXd Hfd = fd_hessian(s, [&](const Points& y) {
    Eigen::VectorXd gy;
    a.gradient(y, gy);
    return gy;
  });
  EXPECT_LT((H - Hfd).norm() / Hfd.norm(), 1e-6);
  EXPECT_LT((H - H.transpose()).norm(), 1e-10 * H.norm());
  // K v through element products equals the assembled Hessian times v on the free dofs.
  Eigen::VectorXd v = Eigen::VectorXd::Random(3 * s.mesh.num_nodes()), Kv = Eigen::VectorXd::Zero(v.size());
  for (int n = 0; n < s.mesh.num_nodes(); ++n)
    if (s.dofs.free_index[n] < 0) v.segment<3>(3 * n).setZero();
  a.add_hessian_times(s.x, v, 1.0, Kv);
  Eigen::VectorXd vf(H.rows()), Kvf(H.rows());
  for (int f = 0; f < s.dofs.num_free(); ++f) {
    vf.segment<3>(3 * f) = v.segment<3>(3 * s.dofs.free_nodes[f]);
    Kvf.segment<3>(3 * f) = Kv.segment<3>(3 * s.dofs.free_nodes[f]);
  }
  EXPECT_LT((H * vf - Kvf).norm() / Kvf.norm(), 1e-12);
}

TEST(Assembly, GradientPassEqualsTheGeneralPath) {
  // A pass that asks for the gradient alone (every residual) has its own lean kernel, and CNH its
  // own first derivatives (Material::first_invariants); both must equal the general path, the
  // gradient computed beside the Hessian, to rounding. Stretched and sheared tets, tets squashed
  // below CNH's epsilon (J ~ 0.05 < 0.1), and inverted ones (J < 0) for the invertible models.
  Scene3x2x2 s;
  const std::shared_ptr<const Material> models[3] = {make_cnh(2.0, 30.0, 1.0, 0.1), make_snh(2.0, 30.0),
                                                     make_unh(2.0, 30.0)};
  for (const auto& m : models)
    for (double squash : {1.3, 0.05, -0.5}) {
      if (squash < 0 && !m->invertible()) continue;
      Points x = s.x;
      x.row(2) *= squash;
      ElasticAssembly a(s.mesh, m, s.dofs);
      Eigen::VectorXd lean, general = Eigen::VectorXd::Zero(s.x.size());
      const double E_lean = a.gradient(x, lean);
      std::vector<double> values(a.pattern().nnz(), 0.0);
      ElementPass p;
      p.grad = &general;
      p.values = values.data();
      const double E_general = a.evaluate(x, p);
      EXPECT_GT(general.norm(), 0.0);
      EXPECT_LT((lean - general).norm(), 1e-13 * general.norm()) << m->name() << " squash " << squash;
      EXPECT_NEAR(E_lean, E_general, 1e-13 * std::abs(E_general)) << m->name() << " squash " << squash;
    }
}

TEST(Assembly, ColoursShareNoNodeAndThreadsAgree) {
  Mesh m = make_sphere(0.1, 0.0, 3000, Eigen::Vector3d::Zero());
  std::vector<std::vector<int>> tets;
  for (const Tet& t : m.tets()) tets.emplace_back(t.begin(), t.end());
  Points centres(3, m.num_tets());
  for (int e = 0; e < m.num_tets(); ++e)
    centres.col(e) = gather(m.rest_positions(), m.tets()[e]).reshaped(3, 4).rowwise().mean();
  const ElementSchedule s = colour_elements(m.num_nodes(), tets, &centres);
  std::vector<int> visits(tets.size(), 0);
  int serial = 0;  // elements in colours of one chunk (no work for a second thread)
  for (const auto& colour : s.colours) {
    if (colour.size() == 1) serial += s.chunk_start[colour[0] + 1] - s.chunk_start[colour[0]];
    std::vector<char> seen(m.num_nodes(), 0);
    for (int c : colour) {
      std::set<int> mine;  // a chunk's own elements may share nodes; two chunks of a colour not
      for (int k = s.chunk_start[c]; k < s.chunk_start[c + 1]; ++k) {
        visits[s.order[k]]++;
        for (int v : tets[s.order[k]]) {
          if (!mine.count(v)) {
            EXPECT_FALSE(seen[v]);
          }
          mine.insert(v);
        }
      }
      for (int v : mine) seen[v] = 1;
    }
  }
  for (int n : visits) EXPECT_EQ(n, 1);  // every element once
  EXPECT_LT(serial, 0.1 * m.num_tets());
  DofMap dofs = DofMap::make(m.num_nodes(), {});
  ElasticAssembly a(m, make_snh(1.0, 10.0), dofs);
  Points x = m.rest_positions() * 1.1;
  x.row(2) *= 0.8;
  std::vector<double> v1(a.pattern().nnz(), 0.0), v2(a.pattern().nnz(), 0.0);
  Eigen::VectorXd g1, g2;
  omp_set_num_threads(1);
  a.add_hessian(x, 1.0, v1.data());
  a.gradient(x, g1);
  omp_set_num_threads(2);
  a.add_hessian(x, 1.0, v2.data());
  a.gradient(x, g2);
  // Colouring makes each entry's sum order independent of the thread count: bitwise equal.
  EXPECT_EQ(v1, v2);
  EXPECT_EQ((g1 - g2).cwiseAbs().maxCoeff(), 0.0);
}

TEST(VolumeConstraints, ZoneVolumesDerivativesAndTimeDerivative) {
  Scene3x2x2 s;
  ElasticAssembly a(s.mesh, make_cnh(2.0, 30.0, 1.0, 0.1), s.dofs);
  std::vector<int> all(s.mesh.num_tets()), half;
  for (int e = 0; e < s.mesh.num_tets(); ++e) {
    all[e] = e;
    if (e % 2) half.push_back(e);
  }
  VolumeConstraints c = VolumeConstraints::zones(s.mesh, {all, half}, s.dofs, a.pattern());
  Eigen::VectorXd vol;
  c.volumes(s.x, vol);
  EXPECT_NEAR(vol[0], tets_volume(s.x, s.mesh.tets()), 1e-14);
  EXPECT_NEAR(vol[0], surface_volume(s.x, s.mesh.surface()), 1e-13);  // the whole mesh: divergence theorem
  EXPECT_NEAR(c.rest_volumes()[0], 0.48, 1e-14);
  // The zone of every other tet (scattered): the sum of exactly those tets' volumes.
  std::vector<Tet> odd;
  for (int e : half) odd.push_back(s.mesh.tets()[e]);
  EXPECT_NEAR(vol[1], tets_volume(s.x, odd), 1e-14);
  // The face terms are taken about an origin that follows the zone, so a body far from where it
  // started keeps every digit: the volume of a translated copy is the same to rounding. (About a
  // fixed origin 500 m away, the face terms are ~1e4 m^3 and cancel to ~1e-10.)
  {
    Points far = s.x;
    far.colwise() += Eigen::Vector3d(300, -200, 500);
    Eigen::VectorXd vfar;
    c.volumes(far, vfar);
    EXPECT_NEAR(vfar[0], vol[0], 1e-13);
    EXPECT_NEAR(vfar[1], vol[1], 1e-13);
  }
  // Zones are evaluated on their boundary faces: no row entry for a node inside the whole-mesh
  // zone (its contributions cancel), an entry for every free node on the surface.
  std::vector<char> on_surface(s.mesh.num_nodes(), 0);
  for (const Tri& f : s.mesh.surface())
    for (int v : f) on_surface[v] = 1;
  int free_surface = 0, interior = 0;
  for (int v = 0; v < s.mesh.num_nodes(); ++v)
    if (s.dofs.free_index[v] >= 0) (on_surface[v] ? free_surface : interior)++;
  EXPECT_GT(interior, 0);
  EXPECT_EQ(c.row_dofs(0).size(), static_cast<std::size_t>(3 * free_surface));
  // Gradient rows against central differences of the volume.
  std::vector<std::vector<double>> rows;
  c.gradient(s.x, rows);
  for (int j = 0; j < 2; ++j) {
    const Eigen::VectorXd full = c.full_gradient(s.x, j);
    for (std::size_t k = 0; k < c.row_dofs(j).size(); ++k) {
      const Index d = c.row_dofs(j)[k];
      const int node = s.dofs.free_nodes[d / 3];
      Points xp = s.x, xm = s.x;
      xp(d % 3, node) += 1e-6;
      xm(d % 3, node) -= 1e-6;
      Eigen::VectorXd vp, vm;
      c.volumes(xp, vp);
      c.volumes(xm, vm);
      EXPECT_NEAR(rows[j][k], (vp[j] - vm[j]) / 2e-6, 1e-9);
      EXPECT_EQ(rows[j][k], full[3 * node + d % 3]);
    }
  }
  // Contracted Hessian lambda_0 H_0 + lambda_1 H_1 against differences of the gradients.
  const Eigen::Vector2d lambda(0.7, -1.9);
  std::vector<double> values(a.pattern().nnz(), 0.0);
  c.add_hessian(s.x, lambda, 1.0, values.data());
  const Eigen::MatrixXd H = dense(a.pattern(), values);
  const Eigen::MatrixXd Hfd = fd_hessian(s, [&](const Points& y) {
    return Eigen::VectorXd(lambda[0] * c.full_gradient(y, 0) + lambda[1] * c.full_gradient(y, 1));
  });
  EXPECT_LT((H - Hfd).norm() / Hfd.norm(), 1e-6);
  // dg/dt from Dirichlet velocities: move the fixed nodes by a sinusoid and difference in time.
  Driver d;
  d.kind = Driver::Kind::sinusoid;
  d.nodes = s.mesh.node_sets.at("zmin");
  d.vector = Eigen::Vector3d(0.02, -0.01, 0.05);
  d.frequency = 3.0;
  auto g_at = [&](double t) {
    Points y = s.x;
    d.apply(s.mesh.rest_positions(), t, y, nullptr);
    Eigen::VectorXd g;
    c.value(y, g);
    return g;
  };
  const double t = 0.13;
  Points y = s.x;
  Eigen::VectorXd v = Eigen::VectorXd::Zero(3 * s.mesh.num_nodes());
  d.apply(s.mesh.rest_positions(), t, y, &v);
  Eigen::VectorXd gt;
  c.time_derivative(y, v, gt);
  const Eigen::VectorXd fd = (g_at(t + 1e-6) - g_at(t - 1e-6)) / 2e-6;
  EXPECT_LT((gt - fd).norm(), 1e-8 * (1 + fd.norm()));
  EXPECT_GT(fd.norm(), 1e-3);  // the check is not vacuous
}

TEST(VolumeConstraints, SurfaceVolumeByDivergenceTheorem) {
  Scene3x2x2 s;
  ElasticAssembly a(s.mesh, make_snh(1.0, 1.0), s.dofs);
  VolumeConstraints c = VolumeConstraints::surface(s.mesh, s.dofs, a.pattern());
  Eigen::VectorXd vol;
  c.volumes(s.x, vol);
  EXPECT_NEAR(vol[0], tets_volume(s.x, s.mesh.tets()), 1e-13);
  const Eigen::VectorXd full = c.full_gradient(s.x, 0);
  for (int n = 0; n < s.mesh.num_nodes(); n += 3)
    for (int d = 0; d < 3; ++d) {
      Points xp = s.x, xm = s.x;
      xp(d, n) += 1e-6;
      xm(d, n) -= 1e-6;
      Eigen::VectorXd vp, vm;
      c.volumes(xp, vp);
      c.volumes(xm, vm);
      EXPECT_NEAR(full[3 * n + d], (vp[0] - vm[0]) / 2e-6, 1e-9);
    }
  std::vector<double> values(a.pattern().nnz(), 0.0);
  c.add_hessian(s.x, Eigen::VectorXd::Constant(1, 1.3), 1.0, values.data());
  const Eigen::MatrixXd Hfd =
      fd_hessian(s, [&](const Points& y) { return Eigen::VectorXd(1.3 * c.full_gradient(y, 0)); });
  EXPECT_LT((dense(a.pattern(), values) - Hfd).norm() / Hfd.norm(), 1e-6);
}

TEST(VolumeConstraints, OneRingZonePerFreeVertex) {
  Mesh m = make_box(Eigen::Vector3d::Ones(), {4, 4, 4}, Eigen::Vector3d::Zero(), 6);
  DofMap dofs = DofMap::make(m.num_nodes(), m.node_sets.at("zmin"));
  auto zones = ring_zones(m, 1, dofs);
  EXPECT_EQ(zones.size(), static_cast<std::size_t>(dofs.num_free()));
  EXPECT_EQ(zones[dofs.free_index[2 + 5 * (2 + 5 * 2)]].size(), 24u);  // interior Kuhn vertex
}

TEST(VolumeConstraints, PatchesPartitionTheTets) {
  Mesh m = make_box(Eigen::Vector3d::Ones(), {12, 8, 8}, Eigen::Vector3d::Constant(0.5), 6);
  std::size_t previous = m.num_tets() + 1;
  for (int k : {1, 2, 3}) {
    const auto patches = patch_zones(m, k);
    std::vector<int> count(m.num_tets(), 0);
    for (const auto& p : patches)
      for (int e : p) count[e]++;
    for (int c : count) EXPECT_EQ(c, 1);  // every tet in exactly one patch
    std::printf("k = %d: %zu patches\n", k, patches.size());
    EXPECT_LT(patches.size(), previous);  // larger k: fewer, larger patches
    previous = patches.size();
  }
}

TEST(Drivers, VelocityIsTheTimeDerivativeOfPosition) {
  std::vector<Driver> drivers(5);
  drivers[0].kind = Driver::Kind::fixed;
  drivers[1].kind = Driver::Kind::ramp;
  drivers[1].vector = Eigen::Vector3d(0, 0, -0.5);
  drivers[1].t0 = 0.1;
  drivers[1].t1 = 0.6;
  drivers[2].kind = Driver::Kind::sinusoid;
  drivers[2].vector = Eigen::Vector3d(1, 2, 0);
  drivers[2].frequency = 2;
  drivers[2].phase = 0.3;
  for (int k : {3, 4}) {
    drivers[k].kind = k == 3 ? Driver::Kind::keyframes_linear : Driver::Kind::keyframes_cubic;
    drivers[k].times = {0.0, 0.2, 0.5, 1.0};
    drivers[k].values = {Eigen::Vector3d(0, 0, 0), Eigen::Vector3d(1, 0, 0), Eigen::Vector3d(1, 1, 0),
                         Eigen::Vector3d(0, 1, 2)};
  }
  for (const Driver& d : drivers)
    for (double t : {0.05, 0.15, 0.33, 0.7, 0.95}) {
      const double h = 1e-6;
      const Eigen::Vector3d fd = (d.displacement(t + h) - d.displacement(t - h)) / (2 * h);
      EXPECT_LT((d.velocity(t) - fd).norm(), 1e-7) << static_cast<int>(d.kind) << " t = " << t;
    }
  // Keyframes pass through their values; the cubic is C^1 at the keys.
  for (int k : {3, 4})
    for (std::size_t i = 0; i < drivers[k].times.size(); ++i)
      EXPECT_LT((drivers[k].displacement(drivers[k].times[i]) - drivers[k].values[i]).norm(), 1e-15);
  EXPECT_LT((drivers[4].velocity(0.2 - 1e-9) - drivers[4].velocity(0.2 + 1e-9)).norm(), 1e-6);
  // ... and at the first and last keys, where the value is held: the velocity goes to zero.
  EXPECT_LT(drivers[4].velocity(1e-9).norm(), 1e-6);
  EXPECT_LT(drivers[4].velocity(1.0 - 1e-9).norm(), 1e-6);
  EXPECT_GT(drivers[4].velocity(0.1).norm(), 1.0);
  EXPECT_LT((drivers[1].displacement(0.35) - Eigen::Vector3d(0, 0, -0.25)).norm(), 1e-15);
}

TEST(VolumeConstraints, MultiplierPressureOnOverlappingZones) {
  Mesh m = make_two_tets(1.0);
  DofMap dofs = DofMap::make(m.num_nodes(), {});
  ElasticAssembly a(m, make_cnh(1, 1, 1, 0.1), dofs);
  const std::vector<std::vector<int>> zones{{0, 1}, {1}};
  VolumeConstraints c = VolumeConstraints::zones(m, zones, dofs, a.pattern());
  std::vector<double> p(2, 0.0);
  c.add_pressure(Eigen::Vector2d(2.0, 5.0).data(), p);
  EXPECT_EQ(p, (std::vector<double>{-2.0, -7.0}));
}
