#include "isochor/integrators/interrupt.hpp"

#include <atomic>
#include <limits>

namespace isochor {

namespace {
std::atomic<int> requested{0};
std::atomic<double> reached{std::numeric_limits<double>::quiet_NaN()};
int (*agreement)(int) = nullptr;
static_assert(std::atomic<int>::is_always_lock_free, "a signal handler may only touch lock-free atomics");
}  // namespace

void request_stop(int signal) noexcept { requested.store(signal, std::memory_order_relaxed); }
int stop_requested() noexcept { return requested.load(std::memory_order_relaxed); }
void clear_stop_request() noexcept { requested.store(0, std::memory_order_relaxed); }

void step_boundary(double t) {
  reached.store(t, std::memory_order_relaxed);
  const int own = stop_requested();
  if (const int s = agreement ? agreement(own) : own) throw Interrupted(t, s);
}

void set_stop_agreement(int (*agree)(int)) { agreement = agree; }

double last_step_time() noexcept { return reached.load(std::memory_order_relaxed); }

}  // namespace isochor
