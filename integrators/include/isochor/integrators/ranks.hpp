// The processes of one scene run on P MPI ranks (`mpirun -n P isochor run`). Every rank runs the
// whole integrator on the whole state; the work that grows with the mesh is split: each rank owns
// a contiguous range of the free nodes (a METIS part), evaluates the elements that touch them, and
// fills their rows of the force and of the Jacobians; CG multiplies and preconditions only its
// rows. The ranks then share what each computed, so that every rank holds the same numbers, bit
// for bit, and takes the same decisions (step sizes, Newton's tests, CG's). Sums across ranks are
// added in rank order for that reason. docs/scale.md says why the state is replicated and what it
// costs.
//
// This interface holds no MPI: the command line implements it (apps/mpi_ranks.cpp) and the
// libraries only call it.
#pragma once
#include <string>
#include <vector>

#include "isochor/integrators/sparse_pattern.hpp"

namespace isochor {

class Ranks {
 public:
  virtual ~Ranks() = default;
  virtual int size() const = 0;
  virtual int rank() const = 0;
  // For every rank r, x[offsets[r] .. offsets[r + 1]) as rank r has it, to every rank (x holds
  // offsets.back() values, offsets has size() + 1 entries).
  virtual void share(double* x, const std::vector<Index>& offsets) const = 0;
  // values[i] := the sum over the ranks of their values[i], added in rank order.
  virtual void sum(double* values, int n) const = 0;
  // The largest of the ranks' values.
  virtual int max(int value) const = 0;
  // send[send_offsets[r] .. send_offsets[r + 1]) to rank r, for every r, and rank r's piece for
  // this one into recv[recv_offsets[r] .. recv_offsets[r + 1]) (the counts must match pairwise).
  virtual void exchange(const double* send, const std::vector<int>& send_offsets, double* recv,
                        const std::vector<int>& recv_offsets) const = 0;
  // Rank 0's v (or s) to every rank, sized as rank 0 has it.
  virtual void broadcast(std::vector<double>& v) const = 0;
  virtual void broadcast(std::string& s) const = 0;
  // Wall seconds this rank has spent in the calls above, waiting for the others included: in
  // share(), in exchange(), and in the rest (sums, maxima, broadcasts).
  struct Seconds {
    double share = 0, exchange = 0, reduce = 0;
  };
  virtual Seconds seconds() const = 0;
};

// The rows of a system's unknowns that each rank owns: rank r owns dofs offsets[r] ..
// offsets[r + 1] (whole nodes).
struct DofPartition {
  const Ranks* ranks = nullptr;
  std::vector<Index> offsets;
  Index begin() const { return offsets[ranks->rank()]; }
  Index end() const { return offsets[ranks->rank() + 1]; }
  // The same ranges in the entries of a pattern's values (its columns, which hold its rows).
  std::vector<Index> value_offsets(const SparsePattern& p) const {
    std::vector<Index> v(offsets.size());
    for (std::size_t r = 0; r < offsets.size(); ++r) v[r] = p.col_ptr[offsets[r]];
    return v;
  }
};

// What a rank's rows of a symmetric matrix read of a vector beyond its own range (its ghosts: the
// other rows of its columns), and the exchange that brings them from their owners: a CG product
// needs these entries, not the whole vector.
class Halo {
 public:
  Halo() = default;
  Halo(const SparsePattern& p, const DofPartition& part);
  // x's ghost entries from the ranks that own them (x: the whole vector; its own rows are sent).
  void update(double* x) const;
  Index ghosts() const { return static_cast<Index>(recv_index_.size()); }

 private:
  const Ranks* ranks_ = nullptr;
  std::vector<Index> send_index_, recv_index_;
  std::vector<int> send_offsets_, recv_offsets_;
  mutable std::vector<double> send_, recv_;
};

// METIS's k-way partition of a graph (ptr/adj: each vertex's neighbours, no self loops) into
// `parts` parts of about equal weight (weights: one per vertex, >= 0; empty: 1 each): each
// vertex's part. The same graph gives the same parts on every rank.
std::vector<int> partition_graph(const std::vector<Index>& ptr, const std::vector<Index>& adj, int parts,
                                 const std::vector<int>& weights = {});

}  // namespace isochor
