// Block-Jacobi preconditioned conjugate gradients on the effective stiffness (sparse_factor.hpp).
// On P ranks (ranks.hpp) each rank multiplies and preconditions its own rows, the search
// direction is shared before every product and the dot products are summed across the ranks:
// every rank takes the same iterations and ends with the same x.
#include <Eigen/Dense>
#include <algorithm>
#include <cmath>
#include <vector>

#include "isochor/integrators/sparse_factor.hpp"

namespace isochor {

using VectorXd = Eigen::VectorXd;

namespace {

class BlockJacobiPcg : public SymmetricSolver {
 public:
  BlockJacobiPcg(const SparsePattern& p, double tol, const DofPartition* part)
      : p_(p), tol_(tol), n_(p.n), lo_(part ? part->begin() : 0), hi_(part ? part->end() : p.n) {
    if (part) {
      ranks_ = part->ranks;
      offsets_ = part->offsets;
      halo_ = Halo(p, *part);
    }
    // The slots of each node's 3x3 diagonal block (dofs 3k .. 3k+2 belong to node k).
    slot_.assign(static_cast<std::size_t>(n_) * 3, -1);
    for (Index c = 0; c < n_; ++c)
      for (Index k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k) {
        const Index r = p.row_ind[k];
        if (r / 3 == c / 3) slot_[3 * c + r % 3] = k;
      }
    inv_.resize(n_ / 3 + 1);
    r_.resize(n_), z_.resize(n_), d_.resize(n_), q_.resize(n_);
    build_blocks();
    make_chunks();
  }

  bool factor(const double* values) override {
    vals_ = values;
    if (!block_col_.empty())  // the values as contiguous 3x3 blocks
      for (std::size_t k = 0; k < block_slot_.size(); ++k) block_vals_[k] = values[block_slot_[k]];
    return invert_diagonal_blocks();
  }
  bool refactor(const double* values, const std::vector<Index>& changed) override {
    vals_ = values;
    if (!block_col_.empty())
      for (Index k : changed) block_vals_[block_of_slot_[k]] = values[k];
    return invert_diagonal_blocks();
  }

  bool solve(const double* b, double* x) override {
    Eigen::Map<VectorXd>(x, n_).setZero();
    r_ = Eigen::Map<const VectorXd>(b, n_);
    return finish(iterate(b, x), x);
  }
  bool solve_from(const double* b, double* x) override {
    multiply(x, r_);
    r_.segment(lo_, hi_ - lo_) = Eigen::Map<const VectorXd>(b + lo_, hi_ - lo_) - r_.segment(lo_, hi_ - lo_);
    return finish(iterate(b, x), x);
  }
  double factor_nnz() const override { return 0; }
  long iterations() const override { return iterations_; }
  bool cheap_factor() const override { return true; }

 private:
  int max_iterations() const { return static_cast<int>(std::max<Index>(1000, n_ / 10)); }
  // On P ranks: every rank's rows of x to every rank, and the same verdict everywhere.
  bool finish(bool ok, double* x) const {
    if (!ranks_) return ok;
    ranks_->share(x, offsets_);
    return ranks_->max(ok ? 0 : 1) == 0;
  }
  // The sums over the ranks of n partial sums (in place); nothing on one process.
  void across_ranks(double* v, int n) const {
    if (ranks_) ranks_->sum(v, n);
  }
  double global(double v) const {
    across_ranks(&v, 1);
    return v;
  }
  // CG from x with its residual r_ = b - S x. One parallel region for the whole iteration: the
  // rows are cut into fixed chunks of whole nodes, and every vector update, product row and
  // preconditioner block of a chunk is done by the thread that owns the chunk in every loop
  // (the same static schedule), so each thread's share of S and of the vectors stays in its
  // core's cache. Dot products are sums of the chunks' partial sums in chunk order: the same
  // numbers for any thread count.
  bool iterate(const double* b, double* x) {
    Eigen::Map<const VectorXd> bb(b, n_);
    const double bnorm = bb.norm();
    if (bnorm == 0) {
      Eigen::Map<VectorXd>(x, n_).setZero();
      return true;
    }
    if (std::sqrt(global(r_.segment(lo_, hi_ - lo_).squaredNorm())) <= tol_ * bnorm) return true;
    const int K = static_cast<int>(chunk_.size()) - 1;
    double rz = 0, alpha = 0, beta = 0;
    bool done = false, failed = false;
    const int max_it = max_iterations();
    double sums[2];
    // MPI is called by the master thread only (MPI_THREAD_FUNNELED); a barrier follows every call.
#pragma omp parallel if (K > 1)  // one chunk: no other thread would have work, only barriers
    {
#pragma omp for schedule(static)
      for (int c = 0; c < K; ++c) {
        const Index lo = chunk_[c], len = chunk_[c + 1] - lo;
        precondition_rows(r_, z_, lo, chunk_[c + 1]);
        d_.segment(lo, len) = z_.segment(lo, len);
        part1_[c] = r_.segment(lo, len).dot(z_.segment(lo, len));
      }
#pragma omp master
      rz = global(ordered_sum(part1_));
#pragma omp barrier
      for (int it = 0; it < max_it; ++it) {
        if (ranks_) {
#pragma omp master
          halo_.update(d_.data());
#pragma omp barrier
        }
#pragma omp for schedule(static)
        for (int c = 0; c < K; ++c) {
          const Index lo = chunk_[c], len = chunk_[c + 1] - lo;
          multiply_rows(d_.data(), q_, lo, chunk_[c + 1]);
          part1_[c] = d_.segment(lo, len).dot(q_.segment(lo, len));
        }
#pragma omp barrier
#pragma omp master
        {
          const double dq = global(ordered_sum(part1_));
          failed = !(dq > 0);  // S is not positive definite along d
          alpha = failed ? 0 : rz / dq;
        }
#pragma omp barrier
        if (failed) break;
#pragma omp for schedule(static)
        for (int c = 0; c < K; ++c) {
          const Index lo = chunk_[c], len = chunk_[c + 1] - lo;
          Eigen::Map<VectorXd>(x + lo, len) += alpha * d_.segment(lo, len);
          r_.segment(lo, len) -= alpha * q_.segment(lo, len);
          part1_[c] = r_.segment(lo, len).squaredNorm();
          precondition_rows(r_, z_, lo, chunk_[c + 1]);
          part2_[c] = r_.segment(lo, len).dot(z_.segment(lo, len));
        }
#pragma omp barrier
#pragma omp master
        {
          ++iterations_;
          sums[0] = ordered_sum(part1_);
          sums[1] = ordered_sum(part2_);
          across_ranks(sums, 2);
          done = std::sqrt(sums[0]) <= tol_ * bnorm;
          beta = sums[1] / rz;
          rz = sums[1];
        }
#pragma omp barrier
        if (done) break;
#pragma omp for schedule(static)
        for (int c = 0; c < K; ++c) {
          const Index lo = chunk_[c], len = chunk_[c + 1] - lo;
          d_.segment(lo, len) = z_.segment(lo, len) + beta * d_.segment(lo, len);
        }
      }
    }
    return done && !failed;
  }
  static double ordered_sum(const std::vector<double>& parts) {
    double s = 0;
    for (double p : parts) s += p;
    return s;
  }
  // Chunks of whole nodes (3 dofs) of this rank's rows, their number fixed by the size alone:
  // about 1,536 dofs each, at most 256.
  void make_chunks() {
    const Index nodes = (hi_ - lo_ + 2) / 3;
    const Index K = std::max<Index>(1, std::min<Index>(256, nodes / 512));
    chunk_.resize(K + 1);
    for (Index c = 0; c <= K; ++c) chunk_[c] = std::min<Index>(hi_, lo_ + 3 * (nodes * c / K));
    part1_.assign(K, 0.0);
    part2_.assign(K, 0.0);
  }
  bool invert_diagonal_blocks() {
    bool ok = true;
    for (Index k = lo_ / 3; 3 * k < hi_ && ok; ++k) {
      Eigen::Matrix3d B = Eigen::Matrix3d::Identity();
      for (int a = 0; a < 3 && 3 * k + a < n_; ++a)
        for (int b = 0; b < 3 && 3 * k + b < n_; ++b) {
          const Index s = slot_[3 * (3 * k + b) + a];
          B(a, b) = s >= 0 ? vals_[s] : (a == b ? 1.0 : 0.0);
        }
      Eigen::LLT<Eigen::Matrix3d> llt(B);
      ok = llt.info() == Eigen::Success;  // a non-positive diagonal block: S is indefinite
      if (ok) inv_[k] = llt.solve(Eigen::Matrix3d::Identity());
    }
    return !ranks_ ? ok : ranks_->max(ok ? 0 : 1) == 0;
  }
  // out = S v, in parallel over the chunks.
  void multiply(const double* v, VectorXd& out) const {
    const int K = static_cast<int>(chunk_.size()) - 1;
#pragma omp parallel for schedule(static)
    for (int c = 0; c < K; ++c) multiply_rows(v, out, chunk_[c], chunk_[c + 1]);
  }
  // Rows [lo, hi) of out = S v (lo a multiple of 3). S is symmetric (both triangles stored): row
  // c of S is its column c, so each entry of out is a gather over one column.
  void multiply_rows(const double* v, VectorXd& out, Index lo, Index hi) const {
    if (!block_col_.empty()) {
      // Block form: out_c = sum over the blocks B of block column c of B^T v_r (S symmetric).
      for (Index c = lo / 3; c < hi / 3; ++c) {
        Eigen::Vector3d sum = Eigen::Vector3d::Zero();
        for (Index b = block_col_[c]; b < block_col_[c + 1]; ++b)
          sum.noalias() += Eigen::Map<const Eigen::Matrix3d>(block_vals_.data() + 9 * b).transpose() *
                           Eigen::Map<const Eigen::Vector3d>(v + 3 * static_cast<Index>(block_row_[b]));
        out.segment<3>(3 * c) = sum;
      }
      return;
    }
    const Index* cp = p_.col_ptr.data();
    const Index* ri = p_.row_ind.data();
    for (Index c = lo; c < hi; ++c) {
      double sum = 0;
      for (Index k = cp[c]; k < cp[c + 1]; ++k) sum += vals_[k] * v[ri[k]];
      out[c] = sum;
    }
  }
  // z = P r on rows [lo, hi) (lo a multiple of 3).
  void precondition_rows(const VectorXd& r, VectorXd& z, Index lo, Index hi) const {
    for (Index k = lo / 3; 3 * k < hi; ++k) {
      const Index m = std::min<Index>(3, n_ - 3 * k);
      if (m == 3) {
        z.segment<3>(3 * k) = inv_[k] * r.segment<3>(3 * k);
      } else {  // a last partial block, padded with the identity: its inverse is the top-left corner
        z.segment(3 * k, m) = inv_[k].topLeftCorner(m, m) * r.segment(3 * k, m);
      }
    }
  }
  // When the pattern is made of full 3x3 node blocks (mesh systems), a block copy of the values
  // (block column c: block rows, 9 values each in column order) halves the index traffic of a
  // product and lets it use 3x3 arithmetic.
  void build_blocks() {
    if (n_ % 3 != 0) return;
    const Index nb = n_ / 3;
    std::vector<Index> cols{0};
    std::vector<int> rows;
    std::vector<Index> slots;
    for (Index c = 0; c < nb; ++c) {
      const Index k0 = p_.col_ptr[3 * c], len = p_.col_ptr[3 * c + 1] - k0;
      if (len % 3 != 0) return;
      for (int b = 1; b < 3; ++b)
        if (p_.col_ptr[3 * c + b + 1] - p_.col_ptr[3 * c + b] != len) return;
      for (Index k = k0; k < k0 + len; k += 3) {
        const Index r = p_.row_ind[k];
        if (r % 3 != 0) return;
        rows.push_back(static_cast<int>(r / 3));
        for (int b = 0; b < 3; ++b)
          for (int a = 0; a < 3; ++a) {
            const Index kk = p_.col_ptr[3 * c + b] + (k - k0) + a;
            if (p_.row_ind[kk] != r + a) return;
            slots.push_back(kk);
          }
      }
      cols.push_back(static_cast<Index>(rows.size()));
    }
    block_of_slot_.assign(static_cast<std::size_t>(p_.nnz()), -1);
    for (std::size_t b = 0; b < slots.size(); ++b) block_of_slot_[slots[b]] = static_cast<Index>(b);
    block_col_ = std::move(cols);
    block_row_ = std::move(rows);
    block_slot_ = std::move(slots);
    block_vals_.resize(block_slot_.size());
  }
  std::vector<Index> block_col_, block_slot_, block_of_slot_;
  std::vector<int> block_row_;
  std::vector<double> block_vals_;
  const SparsePattern& p_;
  double tol_;
  Index n_;
  Index lo_, hi_;                 // this rank's rows (all of them on one process)
  const Ranks* ranks_ = nullptr;  // null on one process
  std::vector<Index> offsets_;
  Halo halo_;  // the entries of the search direction that this rank's rows read of the other ranks' rows
  const double* vals_ = nullptr;
  std::vector<Index> slot_;
  std::vector<Index> chunk_;           // first dof of each chunk, and n
  std::vector<double> part1_, part2_;  // a chunk's share of a dot product
  std::vector<Eigen::Matrix3d> inv_;
  VectorXd r_, z_, d_, q_;
  long iterations_ = 0;
};

// A solver that each rank runs on its own rows (hypre's BoomerAMG-preconditioned CG across the
// ranks): after a solve every rank's rows of x go to every rank, and every rank takes the same
// verdict, as with PCG on ranks.
class RowsOnRanks : public SymmetricSolver {
 public:
  RowsOnRanks(std::unique_ptr<SymmetricSolver> rows, const DofPartition& part) : rows_(std::move(rows)), part_(part) {}
  bool factor(const double* values) override { return agreed(rows_->factor(values)); }
  bool solve(const double* b, double* x) override {
    const bool ok = rows_->solve(b, x);
    part_.ranks->share(x, part_.offsets);
    return agreed(ok);
  }
  double factor_nnz() const override { return 0; }
  long iterations() const override { return rows_->iterations(); }

 private:
  bool agreed(bool ok) const { return part_.ranks->max(ok ? 0 : 1) == 0; }
  std::unique_ptr<SymmetricSolver> rows_;
  DofPartition part_;
};

}  // namespace

std::unique_ptr<SymmetricSolver> make_symmetric_solver(const SparsePattern& pattern, SymmetricSolverKind kind,
                                                       double tol, const DofPartition* partition) {
  const bool ranks = partition && partition->ranks && partition->ranks->size() > 1;
  switch (kind) {
    case SymmetricSolverKind::pcg:
      return std::make_unique<BlockJacobiPcg>(pattern, tol, partition && partition->ranks ? partition : nullptr);
    case SymmetricSolverKind::amg:
      if (ranks) {
        auto rows = make_distributed_amg_solver(pattern, partition->begin(), partition->end(), tol);
        return rows ? std::make_unique<RowsOnRanks>(std::move(rows), *partition) : nullptr;
      }
      return make_amg_solver(pattern, tol);
    case SymmetricSolverKind::cholmod:
      return std::make_unique<SymmetricFactor>(pattern);
  }
  return nullptr;
}

}  // namespace isochor
