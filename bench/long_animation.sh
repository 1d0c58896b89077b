#!/usr/bin/env bash
# The long animation demo (demos/arm_cycle.toml: the rigged arm flexing every 2 s, 12 s, 360
# frames at 30 fps) on one thread: seconds per frame (median of the runs), steps per frame, peak
# memory, resident memory at 10% and at 100% of the run, and the share of steps that the frames
# force (against one run writing only the first and the last frame: with frames from IDA's
# interpolant it should be ~0).
#   bench/long_animation.sh [build] [runs] [duration]
set -euo pipefail
build=${1:-build}
runs=${2:-3}
duration=${3:-12.0}
cd "$(dirname "$0")/.."
mkdir -p out/bench
export OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
for r in $(seq 1 "$runs"); do
  "$build/isochor" run demos/arm_cycle.toml --overwrite -q --set frames.duration="$duration" -o "out/bench/long_r$r.h5" > /dev/null
done
# Two frames only: the steps the motion itself needs.
"$build/isochor" run demos/arm_cycle.toml --overwrite -q --set frames.duration="$duration" \
  --set frames.rate="$(/usr/bin/python3 -c "print(1 / $duration)")" -o out/bench/long_two.h5 > /dev/null
/usr/bin/python3 - "$runs" <<'PY'
import sys, h5py, numpy as np
runs = int(sys.argv[1])
per_frame, steps, peak, rss10, rss100 = [], [], [], [], []
for r in range(1, runs + 1):
    with h5py.File(f"out/bench/long_r{r}.h5", "r") as f:
        s = f["/stats"]
        n = len(f["/frames/time"]) - 1
        per_frame.append(s.attrs["wall_seconds"] / n)
        steps.append(s.attrs["steps"])
        peak.append(s.attrs["peak_memory_mb"])
        rss = s["resident_mb"][()]
        rss10.append(rss[len(rss) // 10])
        rss100.append(rss[-1])
with h5py.File("out/bench/long_two.h5", "r") as f:
    two = f["/stats"].attrs["steps"]
print(f"arm_cycle: {n} frames, medians over {runs} run(s), one thread")
print(f"  s per frame          {np.median(per_frame):.4f}   (runs: {', '.join(f'{x:.4f}' for x in per_frame)})")
print(f"  steps per frame      {np.median(steps) / n:.2f}")
print(f"  peak memory          {np.median(peak):.1f} MB")
print(f"  resident at 10%      {np.median(rss10):.1f} MB, at 100% {np.median(rss100):.1f} MB")
share = (np.median(steps) - two) / np.median(steps)
print(f"  steps frames force   {100 * share:.1f}% ({np.median(steps):.0f} steps with every frame, {two:.0f} with two)")
PY
