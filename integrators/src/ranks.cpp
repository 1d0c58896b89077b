#include "isochor/integrators/ranks.hpp"

#include <metis.h>

#include <algorithm>
#include <mutex>
#include <string>

#include "isochor/base/error.hpp"

namespace isochor {

Halo::Halo(const SparsePattern& p, const DofPartition& part) : ranks_(part.ranks) {
  const int P = ranks_->size();
  const Index lo = part.begin(), hi = part.end();
  std::vector<Index> ghosts;
  for (Index c = lo; c < hi; ++c)
    for (Index k = p.col_ptr[c]; k < p.col_ptr[c + 1]; ++k)
      if (p.row_ind[k] < lo || p.row_ind[k] >= hi) ghosts.push_back(p.row_ind[k]);
  std::sort(ghosts.begin(), ghosts.end());
  ghosts.erase(std::unique(ghosts.begin(), ghosts.end()), ghosts.end());
  // Sorted, so grouped by owner: rank r owns offsets[r] .. offsets[r + 1].
  recv_offsets_.assign(P + 1, 0);
  for (Index g : ghosts) {
    const int owner =
        static_cast<int>(std::upper_bound(part.offsets.begin(), part.offsets.end(), g) - part.offsets.begin()) - 1;
    recv_offsets_[owner + 1]++;
  }
  for (int r = 0; r < P; ++r) recv_offsets_[r + 1] += recv_offsets_[r];
  // Each owner learns how many entries, and which, this rank wants of it.
  std::vector<int> one(P + 1);
  for (int r = 0; r <= P; ++r) one[r] = r;
  std::vector<double> want(P), asked(P);
  for (int r = 0; r < P; ++r) want[r] = recv_offsets_[r + 1] - recv_offsets_[r];
  ranks_->exchange(want.data(), one, asked.data(), one);
  send_offsets_.assign(P + 1, 0);
  for (int r = 0; r < P; ++r) send_offsets_[r + 1] = send_offsets_[r] + static_cast<int>(asked[r]);
  const std::vector<double> wanted(ghosts.begin(), ghosts.end());  // exact below 2^53
  std::vector<double> to_send(send_offsets_[P]);
  ranks_->exchange(wanted.data(), recv_offsets_, to_send.data(), send_offsets_);
  send_index_.assign(to_send.begin(), to_send.end());
  recv_index_ = std::move(ghosts);
  send_.resize(send_index_.size());
  recv_.resize(recv_index_.size());
}

void Halo::update(double* x) const {
  if (!ranks_) return;
  for (std::size_t k = 0; k < send_index_.size(); ++k) send_[k] = x[send_index_[k]];
  ranks_->exchange(send_.data(), send_offsets_, recv_.data(), recv_offsets_);
  for (std::size_t k = 0; k < recv_index_.size(); ++k) x[recv_index_[k]] = recv_[k];
}

std::vector<int> partition_graph(const std::vector<Index>& ptr, const std::vector<Index>& adj, int parts,
                                 const std::vector<int>& weights) {
  const idx_t nv = static_cast<idx_t>(ptr.size()) - 1;
  std::vector<int> part(static_cast<std::size_t>(nv), 0);
  if (parts <= 1 || nv == 0) return part;
  // METIS keeps global state (GKlib's memory and signal handling): one call at a time in a process.
  static std::mutex one_at_a_time;
  const std::lock_guard<std::mutex> lock(one_at_a_time);
  std::vector<idx_t> xadj(ptr.begin(), ptr.end()), adjncy(adj.begin(), adj.end()), where(nv),
      vwgt(weights.begin(), weights.end());
  idx_t nvert = nv, ncon = 1, np = parts, cut = 0;
  idx_t options[METIS_NOPTIONS];
  METIS_SetDefaultOptions(options);
  options[METIS_OPTION_SEED] = 1;  // the same parts on every rank and in every run
  if (METIS_PartGraphKway(&nvert, &ncon, xadj.data(), adjncy.data(), vwgt.empty() ? nullptr : vwgt.data(), nullptr,
                          nullptr, &np, nullptr, nullptr, options, &cut, where.data()) != METIS_OK)
    throw Error("METIS could not split the mesh's " + std::to_string(nv) + " nodes into " + std::to_string(parts) +
                " parts");
  for (idx_t v = 0; v < nv; ++v) part[static_cast<std::size_t>(v)] = static_cast<int>(where[v]);
  return part;
}

}  // namespace isochor
