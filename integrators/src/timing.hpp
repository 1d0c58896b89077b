// Wall-clock timing of the solver phases (assembly, factorisation, solve).
#pragma once
#include <chrono>

namespace isochor {
using Clock = std::chrono::steady_clock;
inline double seconds_since(Clock::time_point t0) { return std::chrono::duration<double>(Clock::now() - t0).count(); }
}  // namespace isochor
