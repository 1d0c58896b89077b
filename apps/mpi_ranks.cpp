#include "mpi_ranks.hpp"

#include <omp.h>

#include <climits>
#include <cstdio>
#include <cstdlib>

#include "isochor/base/error.hpp"
#include "isochor/integrators/interrupt.hpp"
#include "isochor/integrators/ranks.hpp"

#ifdef ISOCHOR_MPI
#define OMPI_SKIP_MPICXX 1  // the C interface only
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace isochor::cli {

bool launched_by_mpi() {
  for (const char* v : {"OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK", "MPI_LOCALNRANKS"})
    if (std::getenv(v)) return true;
  return false;
}

#ifdef ISOCHOR_MPI
namespace {

class MpiRanks : public Ranks {
  // Adds the wall time of its scope to one of seconds_.
  struct Timed {
    explicit Timed(double& s) : total(s), start(MPI_Wtime()) {}
    ~Timed() { total += MPI_Wtime() - start; }
    double& total;
    double start;
  };

 public:
  MpiRanks() {
    MPI_Comm_rank(MPI_COMM_WORLD, &rank_);
    MPI_Comm_size(MPI_COMM_WORLD, &size_);
  }
  int size() const override { return size_; }
  int rank() const override { return rank_; }
  void share(double* x, const std::vector<Index>& offsets) const override {
    const Timed timed(seconds_.share);
    std::vector<int> counts(size_), displs(size_);
    for (int r = 0; r < size_; ++r) {
      if (offsets[r + 1] > INT_MAX)
        throw Error("a rank's share of a vector ends past 2^31 entries, more than one MPI message holds");
      displs[r] = static_cast<int>(offsets[r]);
      counts[r] = static_cast<int>(offsets[r + 1] - offsets[r]);
    }
    MPI_Allgatherv(MPI_IN_PLACE, 0, MPI_DATATYPE_NULL, x, counts.data(), displs.data(), MPI_DOUBLE, MPI_COMM_WORLD);
  }
  void sum(double* values, int n) const override {
    const Timed timed(seconds_.reduce);
    std::vector<double> all(static_cast<std::size_t>(n) * size_);
    MPI_Allgather(values, n, MPI_DOUBLE, all.data(), n, MPI_DOUBLE, MPI_COMM_WORLD);
    for (int i = 0; i < n; ++i) {
      double s = 0;
      for (int r = 0; r < size_; ++r) s += all[static_cast<std::size_t>(r) * n + i];
      values[i] = s;
    }
  }
  int max(int value) const override {
    const Timed timed(seconds_.reduce);
    int m = value;
    MPI_Allreduce(&value, &m, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
    return m;
  }
  void exchange(const double* send, const std::vector<int>& send_offsets, double* recv,
                const std::vector<int>& recv_offsets) const override {
    const Timed timed(seconds_.exchange);
    std::vector<int> sc(size_), rc(size_);
    for (int r = 0; r < size_; ++r) {
      sc[r] = send_offsets[r + 1] - send_offsets[r];
      rc[r] = recv_offsets[r + 1] - recv_offsets[r];
    }
    MPI_Alltoallv(send, sc.data(), send_offsets.data(), MPI_DOUBLE, recv, rc.data(), recv_offsets.data(), MPI_DOUBLE,
                  MPI_COMM_WORLD);
  }
  void broadcast(std::vector<double>& v) const override {
    const Timed timed(seconds_.reduce);
    long long n = static_cast<long long>(v.size());
    MPI_Bcast(&n, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
    v.resize(static_cast<std::size_t>(n));
    if (n > 0) MPI_Bcast(v.data(), static_cast<int>(n), MPI_DOUBLE, 0, MPI_COMM_WORLD);
  }
  void broadcast(std::string& s) const override {
    const Timed timed(seconds_.reduce);
    long long n = static_cast<long long>(s.size());
    MPI_Bcast(&n, 1, MPI_LONG_LONG, 0, MPI_COMM_WORLD);
    s.resize(static_cast<std::size_t>(n));
    if (n > 0) MPI_Bcast(s.data(), static_cast<int>(n), MPI_CHAR, 0, MPI_COMM_WORLD);
  }

  Seconds seconds() const override { return seconds_; }

 private:
  int rank_ = 0, size_ = 1;
  mutable Seconds seconds_;
};

// Every rank stops at the step where any of them was asked to (the signal of the largest number).
int agree_on_stop(int signal) {
  int agreed = signal;
  MPI_Allreduce(&signal, &agreed, 1, MPI_INT, MPI_MAX, MPI_COMM_WORLD);
  return agreed;
}

}  // namespace

int cmd_run_on_ranks(const RunCommand& c, int argc, char** argv) {
  int provided = 0;
  MPI_Init_thread(&argc, &argv, MPI_THREAD_FUNNELED, &provided);
  const MpiRanks ranks;
  const bool many = ranks.size() > 1;
  // One OpenMP thread per rank unless OMP_NUM_THREADS says otherwise: the ranks are the cores.
  if (many && !std::getenv("OMP_NUM_THREADS")) omp_set_num_threads(1);
  if (many) set_stop_agreement(agree_on_stop);
  int rc = 0;
  try {
    rc = cmd_run(c, argc, argv, many ? &ranks : nullptr);
  } catch (const Error& e) {
    // Bad input and solver failures reach every rank alike, and a failure to write reaches rank 0
    // first and then the others (run.cpp): rank 0 says it once.
    if (ranks.rank() == 0) std::fprintf(stderr, "isochor: %s\n", e.what());
    rc = 1;
  } catch (const std::exception& e) {
    std::fprintf(stderr, "isochor (rank %d of %d): internal error: %s\n", ranks.rank(), ranks.size(), e.what());
    MPI_Abort(MPI_COMM_WORLD, 2);  // the other ranks may wait for this one in a collective
  }
  set_stop_agreement(nullptr);
  MPI_Finalize();
  return rc;
}
#else
int cmd_run_on_ranks(const RunCommand& c, int argc, char** argv) {
  if (std::getenv("OMPI_COMM_WORLD_SIZE") && std::atoi(std::getenv("OMPI_COMM_WORLD_SIZE")) > 1)
    throw Error(c.scene_path +
                ": started by mpirun, but isochor was built without MPI (Debian: apt-get install libopenmpi-dev "
                "openmpi-bin, then rebuild)");
  return cmd_run(c, argc, argv, nullptr);
}
#endif

}  // namespace isochor::cli
