#include "isochor/interrupt.hpp"

#include <atomic>

namespace isochor {

namespace {
std::atomic<int> requested{0};
static_assert(std::atomic<int>::is_always_lock_free, "a signal handler may only touch lock-free atomics");
}  // namespace

void request_stop(int signal) noexcept { requested.store(signal, std::memory_order_relaxed); }
int stop_requested() noexcept { return requested.load(std::memory_order_relaxed); }
void clear_stop_request() noexcept { requested.store(0, std::memory_order_relaxed); }

void throw_if_stop_requested(double t) {
  if (const int s = stop_requested()) throw Interrupted(t, s);
}

}  // namespace isochor
