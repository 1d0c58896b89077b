// A stop asked for from outside the run (SIGINT, SIGTERM): the command line's signal handler
// records it, and every integrator checks it at each step boundary (statics: at each frame) and
// throws Interrupted, which the run turns into a clean stop with the frames written so far.
#pragma once
#include "isochor/integrators/run_stats.hpp"

namespace isochor {

// Async-signal-safe: called from a signal handler.
void request_stop(int signal) noexcept;
// The signal that asked for the stop, or 0.
int stop_requested() noexcept;
void clear_stop_request() noexcept;
// Called by the integrators at every step boundary (statics: every load increment): records the
// time reached (for progress lines between frames) and throws Interrupted(t, signal) when a stop
// was asked for.
void step_boundary(double t);
// On P ranks (ranks.hpp) a signal may reach the ranks at different steps: `agree` (set while a
// run lasts, null after) takes each rank's own request at every step boundary and returns the
// one all of them act on, so that they stop at the same step.
void set_stop_agreement(int (*agree)(int signal));
// The time of the last step boundary (NaN before the first).
double last_step_time() noexcept;

}  // namespace isochor
