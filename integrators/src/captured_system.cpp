// A captured system S x = b written by a run (ISOCHOR_CAPTURE_S) and read back by a benchmark
// (sparse_factor.hpp gives the layout).
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <memory>
#include <stdexcept>

#include "isochor/integrators/sparse_factor.hpp"
#include "isochor/base/error.hpp"

namespace isochor {

namespace {

constexpr char kMagic[8] = {'I', 'S', 'O', 'C', 'H', 'O', 'R', 'S'};

using File = std::unique_ptr<std::FILE, int (*)(std::FILE*)>;

template <class T>
void put(std::FILE* f, const T* data, std::size_t count, const std::string& path) {
  if (std::fwrite(data, sizeof(T), count, f) != count) throw Error(path + ": cannot write the captured system");
}
template <class T>
void get(std::FILE* f, T* data, std::size_t count, const std::string& path) {
  if (std::fread(data, sizeof(T), count, f) != count)
    throw Error(path + ": not a captured system (the file ends early)");
}

}  // namespace

void write_system(const std::string& path, const SparsePattern& p, const double* values, const double* b, double cj,
                  double t) {
  // Written beside and renamed: a reader never sees half a file.
  const std::string part = path + ".part";
  {
    File f(std::fopen(part.c_str(), "wb"), &std::fclose);
    if (!f) throw Error(path + ": cannot open for writing");
    const std::int64_t head[2] = {p.n, p.nnz()};
    const double ct[2] = {cj, t};
    put(f.get(), kMagic, 8, path);
    put(f.get(), head, 2, path);
    put(f.get(), ct, 2, path);
    put(f.get(), p.col_ptr.data(), p.col_ptr.size(), path);
    put(f.get(), p.row_ind.data(), p.row_ind.size(), path);
    put(f.get(), values, static_cast<std::size_t>(p.nnz()), path);
    put(f.get(), b, static_cast<std::size_t>(p.n), path);
    if (std::fflush(f.get()) != 0) throw Error(path + ": cannot write the captured system");
  }
  if (std::rename(part.c_str(), path.c_str()) != 0) throw Error(path + ": cannot rename " + part);
}

CapturedSystem read_system(const std::string& path) {
  File f(std::fopen(path.c_str(), "rb"), &std::fclose);
  if (!f) throw Error(path + ": cannot open");
  char magic[8];
  get(f.get(), magic, 8, path);
  if (std::memcmp(magic, kMagic, 8) != 0) throw Error(path + ": not a captured system (no ISOCHORS header)");
  std::int64_t head[2];
  double ct[2];
  get(f.get(), head, 2, path);
  get(f.get(), ct, 2, path);
  const std::int64_t n = head[0], nnz = head[1];
  if (n <= 0 || nnz < n || nnz / n > 100000)
    throw Error(path + ": not a captured system (n = " + std::to_string(n) + ", nnz = " + std::to_string(nnz) + ")");
  CapturedSystem s;
  s.cj = ct[0], s.t = ct[1];
  s.pattern.n = n;
  s.pattern.col_ptr.resize(static_cast<std::size_t>(n + 1));
  s.pattern.row_ind.resize(static_cast<std::size_t>(nnz));
  s.values.resize(static_cast<std::size_t>(nnz));
  s.b.resize(static_cast<std::size_t>(n));
  get(f.get(), s.pattern.col_ptr.data(), s.pattern.col_ptr.size(), path);
  get(f.get(), s.pattern.row_ind.data(), s.pattern.row_ind.size(), path);
  get(f.get(), s.values.data(), s.values.size(), path);
  get(f.get(), s.b.data(), s.b.size(), path);
  if (std::fgetc(f.get()) != EOF) throw Error(path + ": not a captured system (bytes after the right-hand side)");
  const auto& cp = s.pattern.col_ptr;
  bool ok = cp[0] == 0 && cp[static_cast<std::size_t>(n)] == nnz;
  for (std::int64_t c = 0; ok && c < n; ++c) ok = cp[c] <= cp[c + 1];
  for (std::int64_t k = 0; ok && k < nnz; ++k) ok = s.pattern.row_ind[k] >= 0 && s.pattern.row_ind[k] < n;
  if (!ok) throw Error(path + ": not a captured system (its column pointers or row indices are out of range)");
  return s;
}

}  // namespace isochor
