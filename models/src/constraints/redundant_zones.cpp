// Zones whose volume is, for every configuration, a fixed linear combination of other zones'
// volumes: their tet sets' indicator vectors are linearly dependent. Found by Gaussian
// elimination of those 0/1 vectors modulo the prime 2^61 - 1 (a dependency modulo p that is not
// one over the rationals needs p to divide a nonzero minor of the incidence matrix: a chance of
// order (zones) / 2^61).
#include <algorithm>
#include <cstdint>
#include <unordered_map>
#include <utility>
#include <vector>

#include "isochor/models/constraints.hpp"

namespace isochor {

namespace {

using Residue = std::uint64_t;
constexpr Residue kPrime = (Residue{1} << 61) - 1;

Residue mul(Residue a, Residue b) {
  const unsigned __int128 p = static_cast<unsigned __int128>(a) * b;
  const Residue r = static_cast<Residue>(p & kPrime) + static_cast<Residue>(p >> 61);
  return r >= kPrime ? r - kPrime : r;
}

Residue sub(Residue a, Residue b) { return a >= b ? a - b : a + kPrime - b; }

Residue inverse(Residue a) {  // a^(p-2)
  Residue r = 1, e = kPrime - 2;
  for (; e; e >>= 1, a = mul(a, a))
    if (e & 1) r = mul(r, a);
  return r;
}

using SparseRow = std::vector<std::pair<int, Residue>>;  // (tet, coefficient), tets increasing

// v - c * row, both sorted by tet; `work` counts the entries touched.
SparseRow minus(const SparseRow& v, Residue c, const SparseRow& row, std::size_t& work) {
  SparseRow out;
  out.reserve(v.size() + row.size());
  std::size_t i = 0, k = 0;
  while (i < v.size() || k < row.size()) {
    if (k == row.size() || (i < v.size() && v[i].first < row[k].first)) {
      out.push_back(v[i++]);
    } else if (i == v.size() || row[k].first < v[i].first) {
      out.emplace_back(row[k].first, sub(0, mul(c, row[k].second)));
      ++k;
    } else {
      const Residue r = sub(v[i].second, mul(c, row[k].second));
      if (r) out.emplace_back(v[i].first, r);
      ++i, ++k;
    }
  }
  work += v.size() + row.size();
  return out;
}

}  // namespace

std::optional<std::vector<int>> redundant_zones(const std::vector<std::vector<int>>& zone_tets,
                                                std::size_t work_limit) {
  std::unordered_map<int, SparseRow> basis;  // by pivot tet, the pivot's coefficient 1
  std::vector<int> redundant;
  // The basis fills in as a banded elimination does (1-ring zones on 21,870 tets: 4.5M entries
  // kept, 25M touched); its memory is held to a quarter of the work limit's entries.
  std::size_t work = 0, stored = 0;
  for (std::size_t j = 0; j < zone_tets.size(); ++j) {
    std::vector<int> tets = zone_tets[j];
    std::sort(tets.begin(), tets.end());
    SparseRow v;
    for (int e : tets)
      if (v.empty() || v.back().first != e)
        v.emplace_back(e, 1);
      else
        v.back().second += 1;  // a tet listed twice counts twice, as in the zone's volume
    while (!v.empty()) {
      const auto it = basis.find(v.front().first);
      if (it == basis.end()) break;
      v = minus(v, v.front().second, it->second, work);
      if (work > work_limit) return std::nullopt;
    }
    if (v.empty()) {
      redundant.push_back(static_cast<int>(j));
      continue;
    }
    const Residue scale = inverse(v.front().second);
    for (auto& entry : v) entry.second = mul(entry.second, scale);
    stored += v.size();
    if (stored > work_limit / 4) return std::nullopt;
    basis.emplace(v.front().first, std::move(v));
  }
  return redundant;
}

}  // namespace isochor
