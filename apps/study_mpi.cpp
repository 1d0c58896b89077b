// `mpirun -n N isochor study STUDY --mpi`: the study's cases over MPI ranks.
#include <atomic>
#include <chrono>
#include <cstdio>
#include <functional>
#include <thread>

#include "commands.hpp"
#include "isochor/base/error.hpp"
#ifdef ISOCHOR_MPI
#define OMPI_SKIP_MPICXX 1  // the C interface only
#define MPICH_SKIP_MPICXX 1
#include <mpi.h>
#endif

namespace isochor::cli {

#ifdef ISOCHOR_MPI
namespace {

constexpr int kAsk = 1, kGive = 2;  // message tags: a rank asks for a case; rank 0 gives one (-1: none left)

// Waits polling with a sleep: OpenMPI's blocking calls spin and would take a core from a case.
void wait(MPI_Request& r, MPI_Status* st) {
  for (int done = 0;;) {
    MPI_Test(&r, &done, st);
    if (done) return;
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
}

// The queue of n cases: rank 0 takes its own from its main thread and serves the other ranks'
// asks from `server` (the only thread of rank 0 that calls MPI until it ends); the other ranks
// ask rank 0. next() gives a case's index, or -1 when none is left.
struct Queue {
  std::atomic<int> counter{0};
  std::thread server;
  std::function<int()> next;

  Queue(int rank, int ranks, int n) {
    if (rank != 0) {
      next = [] {
        int ask = 0, i = -1;
        MPI_Send(&ask, 1, MPI_INT, 0, kAsk, MPI_COMM_WORLD);
        MPI_Request r;
        MPI_Irecv(&i, 1, MPI_INT, 0, kGive, MPI_COMM_WORLD, &r);
        wait(r, MPI_STATUS_IGNORE);
        return i;
      };
      return;
    }
    server = std::thread([this, ranks, n] {
      for (int finished = 0; finished < ranks - 1;) {
        int ask = 0;
        MPI_Request r;
        MPI_Status st;
        MPI_Irecv(&ask, 1, MPI_INT, MPI_ANY_SOURCE, kAsk, MPI_COMM_WORLD, &r);
        wait(r, &st);
        int i = counter++;
        if (i >= n) {
          i = -1;
          ++finished;
        }
        MPI_Send(&i, 1, MPI_INT, st.MPI_SOURCE, kGive, MPI_COMM_WORLD);
      }
    });
    next = [this, n] {
      const int i = counter++;
      return i < n ? i : -1;
    };
  }
};

// This rank's share of the queue: the number of its cases that failed; -1 when the study itself
// failed here (the rest of the queue is then taken without running it, so that rank 0 can end).
int run_share(const Study& s, const std::string& exe, Queue& q, int rank) {
  try {
    return run_study_queue(s, exe, q.next, true);
  } catch (const Error& e) {
    std::fprintf(stderr, "isochor (rank %d): %s\n", rank, e.what());
    if (rank != 0)
      while (q.next() >= 0) {
      }
    return -1;
  }
}

}  // namespace
#endif

// `mpirun -n N isochor study STUDY --mpi`: the cases form one queue, handed out in order (the
// reference first) by rank 0 to whichever rank asks next, as the local executor's threads take
// them; each case runs in its own process. Rank 0 then writes the results and the report.
int study_mpi(const Study& s, const std::string& exe, const std::string& study_path) {
#ifdef ISOCHOR_MPI
  int provided = 0;
  MPI_Init_thread(nullptr, nullptr, MPI_THREAD_SERIALIZED, &provided);
  int rank = 0, ranks = 1;
  MPI_Comm_rank(MPI_COMM_WORLD, &rank);
  MPI_Comm_size(MPI_COMM_WORLD, &ranks);
  if (provided < MPI_THREAD_SERIALIZED && ranks > 1) {
    if (rank == 0) std::fprintf(stderr, "isochor: study --mpi: the MPI library offers no MPI_THREAD_SERIALIZED\n");
    MPI_Finalize();
    return 1;
  }
  if (rank == 0)
    std::fprintf(stderr, "%s: %zu cases over %d MPI ranks, into %s\n", study_path.c_str(), s.cases.size(), ranks,
                 s.output.c_str());
  Queue queue(rank, ranks, static_cast<int>(s.cases.size()));
  const int failed = run_share(s, exe, queue, rank);
  if (rank == 0) queue.server.join();
  {
    MPI_Request r;
    MPI_Ibarrier(MPI_COMM_WORLD, &r);
    wait(r, MPI_STATUS_IGNORE);
  }
  int all = 0, error = failed < 0 ? 1 : 0, errors = 0;
  MPI_Reduce(&failed, &all, 1, MPI_INT, MPI_SUM, 0, MPI_COMM_WORLD);
  MPI_Allreduce(&error, &errors, 1, MPI_INT, MPI_SUM, MPI_COMM_WORLD);
  int rc = errors > 0 ? 1 : 0;
  if (rank == 0 && errors == 0) {
    write_study_results(s);
    rc = study_report(s.output.string());
    std::printf("%s: %zu cases on %d ranks, %d failed (reasons in results.csv); wrote %s/report.md\n",
                study_path.c_str(), s.cases.size(), ranks, all, s.output.c_str());
  }
  MPI_Finalize();
  return rc;
#else
  (void)s, (void)exe;
  throw Error(
      study_path +
      ": --mpi needs isochor built with MPI (Debian: apt-get install libopenmpi-dev openmpi-bin, then rebuild)");
#endif
}

}  // namespace isochor::cli
