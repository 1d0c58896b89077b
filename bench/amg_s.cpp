// One captured effective stiffness S (ISOCHOR_CAPTURE_S) solved with the
// right-hand side the run solved it with, by today's block-Jacobi PCG (linear_solver = "krylov",
// one rank) and by BoomerAMG-preconditioned CG (the "amg" solver's settings) on every rank of
// MPI_COMM_WORLD, rows split by METIS node parts. Prints per solver and round: setup and solve seconds (wall,
// the slowest rank), CG iterations, the true relative residual |b - S x| / |b|, and the resident
// memory of the largest rank before and after the setup; then the medians.
//   mpirun -n 2 build/isochor_bench_amg S.bin [rounds=3] [tol=1e-12] [solvers=pcg,ic,amg]
#define OMPI_SKIP_MPICXX 1
#include <mpi.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <exception>
#include <fstream>
#include <string>
#include <sys/resource.h>
#include <unistd.h>
#include <vector>

#include <Eigen/IterativeLinearSolvers>
#include <Eigen/SparseCore>

#include <metis.h>

#include "isochor/integrators/sparse_factor.hpp"

using namespace isochor;

namespace {

double resident_mb() {  // current resident set, from /proc/self/statm
  std::ifstream f("/proc/self/statm");
  long pages = 0, resident = 0;
  f >> pages >> resident;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / 1048576.0;
}
double max_over_ranks(double v) {
  double m = 0;
  MPI_Allreduce(&v, &m, 1, MPI_DOUBLE, MPI_MAX, MPI_COMM_WORLD);
  return m;
}
double median(std::vector<double> v) {
  std::sort(v.begin(), v.end());
  return v.empty() ? 0 : v[v.size() / 2];
}

// Eigen's CG with an incomplete Cholesky (IC with threshold and fill, Lin & More) on one rank:
// a candidate preconditioner between block-Jacobi and AMG.
class IcPcg : public SymmetricSolver {
 public:
  IcPcg(const SparsePattern& p, double tol) : p_(p) { cg_.setTolerance(tol); }
  bool factor(const double* values) override {
    A_ = Eigen::Map<const Eigen::SparseMatrix<double, Eigen::ColMajor, Index>>(p_.n, p_.n, p_.nnz(), p_.col_ptr.data(),
                                                                               p_.row_ind.data(), values);
    cg_.setMaxIterations(std::max<Index>(1000, p_.n / 10));
    cg_.compute(A_);
    return cg_.info() == Eigen::Success;
  }
  bool solve(const double* b, double* x) override {
    Eigen::Map<Eigen::VectorXd>(x, p_.n) = cg_.solve(Eigen::Map<const Eigen::VectorXd>(b, p_.n));
    its_ += cg_.iterations();
    return cg_.info() == Eigen::Success;
  }
  double factor_nnz() const override { return 0; }
  long iterations() const override { return its_; }

 private:
  const SparsePattern& p_;
  Eigen::SparseMatrix<double, Eigen::ColMajor, Index> A_;
  Eigen::ConjugateGradient<Eigen::SparseMatrix<double, Eigen::ColMajor, Index>, Eigen::Lower | Eigen::Upper,
                           Eigen::IncompleteCholesky<double, Eigen::Lower, Eigen::AMDOrdering<Index>>>
      cg_;
  long its_ = 0;
};

// On more than one rank: the nodes split into `parts` by METIS (k-way, on the node graph of S)
// and renumbered part by part, so each rank's rows are a contiguous range of well-connected nodes
// (the distributed design of docs/scale.md). Returns the first row of each part (parts + 1).
std::vector<Index> partition(CapturedSystem& s, int parts) {
  const Index nodes = s.pattern.n / 3;
  std::vector<idx_t> xadj{0}, adjncy;
  for (Index g = 0; g < nodes; ++g) {
    std::vector<idx_t> nb;
    for (Index k = s.pattern.col_ptr[3 * g]; k < s.pattern.col_ptr[3 * g + 1]; ++k)
      if (s.pattern.row_ind[k] / 3 != g && (nb.empty() || nb.back() != s.pattern.row_ind[k] / 3))
        nb.push_back(static_cast<idx_t>(s.pattern.row_ind[k] / 3));
    std::sort(nb.begin(), nb.end());
    nb.erase(std::unique(nb.begin(), nb.end()), nb.end());
    adjncy.insert(adjncy.end(), nb.begin(), nb.end());
    xadj.push_back(static_cast<idx_t>(adjncy.size()));
  }
  idx_t nv = static_cast<idx_t>(nodes), ncon = 1, np = parts, cut = 0;
  std::vector<idx_t> part(static_cast<std::size_t>(nodes), 0);
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;
  if (METIS_PartGraphKway(&nv, &ncon, xadj.data(), adjncy.data(), nullptr, nullptr, nullptr, &np, nullptr, nullptr,
                          options, &cut, part.data()) != METIS_OK)
    throw std::runtime_error("METIS_PartGraphKway failed");
  // New node numbers, part by part (stable within a part).
  std::vector<Index> first(static_cast<std::size_t>(parts) + 1, 0), perm(static_cast<std::size_t>(nodes));
  for (Index g = 0; g < nodes; ++g) first[static_cast<std::size_t>(part[g]) + 1] += 3;
  for (int r = 0; r < parts; ++r) first[r + 1] += first[r];
  std::vector<Index> next(first.begin(), first.end() - 1);
  for (Index g = 0; g < nodes; ++g) perm[g] = next[static_cast<std::size_t>(part[g])] / 3, next[part[g]] += 3;
  auto dof = [&](Index i) { return 3 * perm[i / 3] + i % 3; };
  // Columns move with their nodes; rows are renamed (hypre's IJ rows need no order).
  const SparsePattern& p = s.pattern;
  SparsePattern q;
  q.n = p.n;
  q.col_ptr.assign(static_cast<std::size_t>(p.n) + 1, 0);
  for (Index c = 0; c < p.n; ++c) q.col_ptr[dof(c) + 1] = p.col_ptr[c + 1] - p.col_ptr[c];
  for (Index c = 0; c < p.n; ++c) q.col_ptr[c + 1] += q.col_ptr[c];
  q.row_ind.resize(p.row_ind.size());
  std::vector<double> values(s.values.size()), b(s.b.size());
  for (Index c = 0; c < p.n; ++c) {
    Index out = q.col_ptr[dof(c)];
    for (Index k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k, ++out)
      q.row_ind[out] = dof(p.row_ind[k]), values[out] = s.values[k];
    b[dof(c)] = s.b[c];
  }
  s.pattern = std::move(q), s.values = std::move(values), s.b = std::move(b);
  int rank = 0;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  if (rank == 0)
    std::printf("METIS: %d parts, %lld edges cut of %lld\n", parts, static_cast<long long>(cut),
                static_cast<long long>(adjncy.size() / 2));
  return first;
}

struct Round {
  double setup, solve, its, residual, mem_before, mem_after;
};

}  // namespace

// One round of a solver on S: setup and solve (wall, the slowest rank), iterations, the true
// relative residual from the whole x, resident memory before and after the setup.
Round one_round(const std::string& kind, const CapturedSystem& s, Index lo, Index hi, double tol,
                std::vector<int>& counts, std::vector<int>& displs, bool& solved) {
  const Index n = s.pattern.n;
  MPI_Barrier(MPI_COMM_WORLD);
  const double m0 = max_over_ranks(resident_mb());
  const double t0 = MPI_Wtime();
  std::unique_ptr<SymmetricSolver> solver;
  if (kind == "pcg")
    solver = make_symmetric_solver(s.pattern, SymmetricSolverKind::pcg, tol);
  else if (kind == "ic")
    solver = std::make_unique<IcPcg>(s.pattern, tol);
  else
    solver = make_distributed_amg_solver(s.pattern, lo, hi, tol);
  if (!solver) throw std::runtime_error("amg: this build has no hypre");
  const bool factored = solver->factor(s.values.data());
  const double t1 = max_over_ranks(MPI_Wtime() - t0);
  const double m1 = max_over_ranks(resident_mb());
  std::vector<double> x(static_cast<std::size_t>(n), 0.0);
  MPI_Barrier(MPI_COMM_WORLD);
  const double t2 = MPI_Wtime();
  solved = factored && solver->solve(s.b.data(), x.data());
  const double t3 = max_over_ranks(MPI_Wtime() - t2);
  MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DOUBLE, x.data(), counts.data(), displs.data(), MPI_DOUBLE, MPI_COMM_WORLD);
  std::vector<double> r = s.b;
  for (Index c = 0; c < n; ++c)
    for (Index k = s.pattern.col_ptr[c]; k < s.pattern.col_ptr[c + 1]; ++k)
      r[static_cast<std::size_t>(s.pattern.row_ind[k])] -= s.values[k] * x[static_cast<std::size_t>(c)];
  double rr = 0, bb = 0;
  for (Index i = 0; i < n; ++i) rr += r[i] * r[i], bb += s.b[i] * s.b[i];
  return Round{t1, t3, static_cast<double>(solver->iterations()), std::sqrt(rr / bb), m0, m1};
}

int main(int argc, char** argv) {
  MPI_Init(&argc, &argv);
  int rank = 0, size = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &size);
  int code = 0;
  try {
    if (argc < 2) throw std::runtime_error("usage: isochor_bench_amg S.bin [rounds] [tol] [solvers]");
    const int rounds = argc > 2 ? std::atoi(argv[2]) : 3;
    const double tol = argc > 3 ? std::atof(argv[3]) : 1e-12;
    const std::string solvers = argc > 4 ? argv[4] : "pcg,amg";
    CapturedSystem s = read_system(argv[1]);
    const Index n = s.pattern.n;
    // Every rank reads the file and computes the same partition (METIS is deterministic).
    std::vector<Index> first = {0, n};
    if (size > 1) {
      if (n % 3) throw std::runtime_error("S is not of 3-dof nodes: cannot split it by nodes");
      first = partition(s, size);
    }
    const Index lo = first[static_cast<std::size_t>(rank)], hi = first[static_cast<std::size_t>(rank) + 1];
    const double read_mb = max_over_ranks(resident_mb());
    if (rank == 0)
      std::printf(
          "S: n = %lld, nnz = %lld, c_j = %.6g, t = %.6g s; %d rank(s), tol %.1e; resident after reading %.0f MB "
          "(largest rank)\n",
          static_cast<long long>(n), static_cast<long long>(s.pattern.nnz()), s.cj, s.t, size, tol, read_mb);
    std::vector<int> counts(size), displs(size);
    for (int r = 0; r < size; ++r)
      counts[r] = static_cast<int>(first[r + 1] - first[r]), displs[r] = static_cast<int>(first[r]);
    for (const std::string kind : {"pcg", "ic", "amg"}) {
      if (solvers.find(kind) == std::string::npos) continue;
      if (kind != "amg" && size > 1) {
        if (rank == 0) std::printf("%s: one rank only; run with -n 1\n", kind.c_str());
        continue;
      }
      std::vector<Round> all;
      for (int round = 0; round < rounds; ++round) {
        bool solved = false;
        const Round d = one_round(kind, s, lo, hi, tol, counts, displs, solved);
        all.push_back(d);
        if (rank == 0)
          std::printf(
              "%s round %d: setup %.3f s, solve %.3f s, %g CG iterations (%.2f ms each), residual %.2e%s, resident "
              "%.0f -> %.0f MB\n",
              kind.c_str(), round + 1, d.setup, d.solve, d.its, 1000 * d.solve / std::max(1.0, d.its), d.residual,
              solved ? "" : " (FAILED)", d.mem_before, d.mem_after);
      }
      auto med = [&](double Round::*f) {
        std::vector<double> v;
        for (const Round& d : all) v.push_back(d.*f);
        return median(v);
      };
      // Memory: round 1's growth over the setup (later rounds reuse what round 1 freed).
      if (rank == 0)
        std::printf(
            "%s median (%d ranks): setup %.3f s, solve %.3f s, total %.3f s, %g iterations, memory of the setup %.0f "
            "MB\n",
            kind.c_str(), size, med(&Round::setup), med(&Round::solve), med(&Round::setup) + med(&Round::solve),
            med(&Round::its), all.front().mem_after - all.front().mem_before);
    }
    struct rusage ru;
    getrusage(RUSAGE_SELF, &ru);
    const double peak = max_over_ranks(static_cast<double>(ru.ru_maxrss) / 1024.0);
    if (rank == 0) std::printf("peak resident memory: %.0f MB (largest rank)\n", peak);
  } catch (const std::exception& e) {
    if (rank == 0) std::fprintf(stderr, "isochor_bench_amg: %s\n", e.what());
    code = 1;
  }
  MPI_Finalize();
  return code;
}
