// One scene split over ranks (ranks.hpp), with the ranks played by threads of this process:
// ThreadRanks has the collectives of the MPI implementation (apps/mpi_ranks.cpp) over shared
// memory, so that the split of the work is checked against one process in the default suite;
// tests/run_mpi.sh runs the same code under mpirun.
#include <gtest/gtest.h>
#include <omp.h>

#include <Eigen/SparseCore>
#include <barrier>
#include <random>
#include <thread>

#include "isochor/integrators/ranks.hpp"
#include "isochor/integrators/sparse_factor.hpp"
#include "isochor/scene/mesh_system.hpp"
#include "block_laplacian.hpp"

using namespace isochor;

namespace {

struct Bus {
  explicit Bus(int n) : size(n), sync(n), slot(n), piece(n, std::vector<std::vector<double>>(n)) {}
  int size;
  std::barrier<> sync;
  std::vector<std::vector<double>> slot;                // each rank's contribution
  std::vector<std::vector<std::vector<double>>> piece;  // piece[from][to]
};

class ThreadRanks : public Ranks {
 public:
  ThreadRanks(Bus& bus, int rank) : bus_(bus), rank_(rank) {}
  int size() const override { return bus_.size; }
  int rank() const override { return rank_; }
  void share(double* x, const std::vector<Index>& off) const override {
    bus_.slot[rank_].assign(x + off[rank_], x + off[rank_ + 1]);
    bus_.sync.arrive_and_wait();
    for (int r = 0; r < bus_.size; ++r)
      if (r != rank_) std::copy(bus_.slot[r].begin(), bus_.slot[r].end(), x + off[r]);
    bus_.sync.arrive_and_wait();
  }
  void sum(double* v, int n) const override {
    bus_.slot[rank_].assign(v, v + n);
    bus_.sync.arrive_and_wait();
    for (int i = 0; i < n; ++i) {
      double s = 0;
      for (int r = 0; r < bus_.size; ++r) s += bus_.slot[r][i];
      v[i] = s;
    }
    bus_.sync.arrive_and_wait();
  }
  int max(int value) const override {
    double v = value;
    bus_.slot[rank_].assign(1, v);
    bus_.sync.arrive_and_wait();
    for (int r = 0; r < bus_.size; ++r) v = std::max(v, bus_.slot[r][0]);
    bus_.sync.arrive_and_wait();
    return static_cast<int>(v);
  }
  void exchange(const double* send, const std::vector<int>& so, double* recv,
                const std::vector<int>& ro) const override {
    for (int r = 0; r < bus_.size; ++r) bus_.piece[rank_][r].assign(send + so[r], send + so[r + 1]);
    bus_.sync.arrive_and_wait();
    for (int r = 0; r < bus_.size; ++r) {
      const auto& p = bus_.piece[r][rank_];
      EXPECT_EQ(static_cast<int>(p.size()), ro[r + 1] - ro[r]) << "from rank " << r << " to " << rank_;
      std::copy(p.begin(), p.end(), recv + ro[r]);
    }
    bus_.sync.arrive_and_wait();
  }
  void broadcast(std::vector<double>& v) const override {
    if (rank_ == 0) bus_.slot[0] = v;
    bus_.sync.arrive_and_wait();
    v = bus_.slot[0];
    bus_.sync.arrive_and_wait();
  }
  void broadcast(std::string& s) const override {
    std::vector<double> v(s.begin(), s.end());
    broadcast(v);
    s.assign(v.begin(), v.end());
  }
  Seconds seconds() const override { return {}; }

 private:
  Bus& bus_;
  int rank_;
};

// f(ranks) on P threads, each its own rank with one OpenMP thread.
template <class F>
void on_ranks(int P, F f) {
  Bus bus(P);
  std::vector<std::thread> threads;
  for (int r = 0; r < P; ++r)
    threads.emplace_back([&bus, &f, r] {
      omp_set_num_threads(1);
      const ThreadRanks ranks(bus, r);
      f(ranks);
    });
  for (auto& t : threads) t.join();
}

}  // namespace

// The ball (one global zone, Rayleigh damping, the ground) at a state away from rest: on 3 ranks
// every rank holds the force, the product of each Jacobian with a vector and the potential of one
// process, each rank having evaluated only the tets at its own nodes. The dofs are numbered rank
// by rank there, so the comparison goes node by node.
TEST(Ranks, MeshSystemOnThreeRanksFillsWhatOneProcessFills) {
  Scene scene = load_scene(std::string(ISOCHOR_SOURCE_DIR) + "/demos/ball_drop.toml",
                           {"mesh.target_tets=1500", "mesh.center=[0,0,0.1005]"});
  const int N = scene.mesh.num_nodes();
  std::mt19937 rng(7);
  std::uniform_real_distribution<double> u(-1, 1);
  Points dx(3, N), w(3, N);
  for (int k = 0; k < N; ++k) dx.col(k) = 3e-3 * Eigen::Vector3d(u(rng), u(rng), u(rng));
  for (int k = 0; k < N; ++k) w.col(k) = Eigen::Vector3d(u(rng), u(rng), u(rng));
  struct Result {
    Points f, Kw, Dw;  // per node
    double V = 0;
  };
  auto evaluate = [&](MeshSystem& sys) {
    const DofMap& d = sys.dofs();
    const int n = sys.num_dofs();
    VectorXd q(n), v(n), wv(n), f;
    for (int k = 0; k < d.num_free(); ++k) {
      const int node = d.free_nodes[k];
      q.segment<3>(3 * k) = scene.mesh.rest_positions().col(node) + dx.col(node);
      v.segment<3>(3 * k) = -2.0 * dx.col(node) / 3e-3;
      wv.segment<3>(3 * k) = w.col(node);
    }
    std::vector<double> K(sys.pattern().nnz(), 0.0), D(sys.pattern().nnz(), 0.0);
    sys.force_and_jacobians(0.0, q, v, f, K.data(), D.data());
    VectorXd Kw = VectorXd::Zero(n), Dw = VectorXd::Zero(n);
    sys.pattern().add_product(K.data(), wv.data(), 1.0, Kw.data());
    sys.pattern().add_product(D.data(), wv.data(), 1.0, Dw.data());
    Result r{Points::Zero(3, N), Points::Zero(3, N), Points::Zero(3, N)};
    for (int k = 0; k < d.num_free(); ++k) {
      r.f.col(d.free_nodes[k]) = f.segment<3>(3 * k);
      r.Kw.col(d.free_nodes[k]) = Kw.segment<3>(3 * k);
      r.Dw.col(d.free_nodes[k]) = Dw.segment<3>(3 * k);
    }
    EXPECT_TRUE(sys.potential(0.0, q, r.V));
    return r;
  };
  MeshSystem one(scene);
  const Result want = evaluate(one);
  ASSERT_GT(want.f.norm(), 0);
  on_ranks(3, [&](const Ranks& ranks) {
    MeshSystem sys(scene, &ranks);
    ASSERT_NE(sys.partition(), nullptr);
    const DofPartition& part = *sys.partition();
    for (int r = 0; r < 3; ++r) EXPECT_GT(part.offsets[r + 1] - part.offsets[r], sys.num_dofs() / 4) << "rank " << r;
    const Result got = evaluate(sys);
    EXPECT_LE((got.f - want.f).norm(), 1e-12 * want.f.norm());
    EXPECT_LE((got.Kw - want.Kw).norm(), 1e-12 * want.Kw.norm());
    EXPECT_LE((got.Dw - want.Dw).norm(), 1e-12 * want.Dw.norm());
    EXPECT_NEAR(got.V, want.V, 1e-12 * std::abs(want.V));
  });
}

// Block-Jacobi PCG with its rows over 3 ranks: each rank multiplies its rows with the direction's
// ghost entries brought by the halo exchange, and every rank ends with the same x, bit for bit,
// solving S x = b to the tolerance (the residual checked with Eigen's own product), in as many
// iterations as on one process give or take one (the dot products are added in another order).
// S: the block Laplacian of block_laplacian.hpp on a 12^3 grid.
TEST(Ranks, PcgOnThreeRanksSolvesAsOneProcess) {
  const Eigen::SparseMatrix<double> S = test::block_laplacian(12);
  const SparsePattern p = test::pattern_of(S);
  const int n = static_cast<int>(p.n);
  const std::vector<double> values(S.valuePtr(), S.valuePtr() + S.nonZeros());
  VectorXd b(n);
  for (int i = 0; i < n; ++i) b[i] = std::sin(0.37 * i) + 0.5;
  const double tol = 1e-10;
  auto serial = make_symmetric_solver(p, SymmetricSolverKind::pcg, tol);
  VectorXd x1(n);
  ASSERT_TRUE(serial->factor(values.data()));
  ASSERT_TRUE(serial->solve(b.data(), x1.data()));
  std::vector<VectorXd> x(3, VectorXd::Zero(n));
  std::vector<long> its(3);
  on_ranks(3, [&](const Ranks& ranks) {
    DofPartition part{&ranks, {0, 3 * 500, 3 * 1100, n}};  // uneven whole-node ranges
    auto s = make_symmetric_solver(p, SymmetricSolverKind::pcg, tol, &part);
    EXPECT_TRUE(s->factor(values.data()));
    EXPECT_TRUE(s->solve(b.data(), x[ranks.rank()].data()));
    its[ranks.rank()] = s->iterations();
  });
  for (int r = 1; r < 3; ++r) EXPECT_TRUE(x[r] == x[0]) << "rank " << r << " ends with another x";
  EXPECT_LE((b - S * x[0]).norm(), tol * b.norm() * 1.0001);
  EXPECT_LE((x[0] - x1).norm(), 1e-8 * x1.norm());
  EXPECT_EQ(its[1], its[0]);
  EXPECT_NEAR(static_cast<double>(its[0]), static_cast<double>(serial->iterations()), 1.0);
}
