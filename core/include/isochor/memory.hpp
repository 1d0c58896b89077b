// The process's memory, for per-frame statistics and benchmarks (Linux).
#pragma once
#include <sys/resource.h>
#include <unistd.h>

#include <fstream>

namespace isochor {

// Current resident set size in MB (/proc/self/statm); 0 where unavailable.
inline double resident_memory_mb() {
  std::ifstream in("/proc/self/statm");
  long pages = 0, resident = 0;
  if (!(in >> pages >> resident)) return 0.0;
  return static_cast<double>(resident) * static_cast<double>(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

// Peak resident set size in MB so far (getrusage).
inline double peak_memory_mb() {
  rusage ru{};
  getrusage(RUSAGE_SELF, &ru);
  return static_cast<double>(ru.ru_maxrss) / 1024.0;
}

}  // namespace isochor
