#!/usr/bin/env bash
# The soak benchmark: 10^5 frames of a small scene (demos/swing.toml: a soft block
# clamped at one end, swinging; backward Euler with a step per frame), run once straight through and once
# killed (SIGKILL) twice along the way and resumed each time. Prints resident memory at 10%, 50%
# and 100% of the run and frames per second per decile (both from the file's per-frame /stats),
# and how far the resumed file's frames are from the uninterrupted one's (backward Euler repeats
# the same steps from a resumed frame: expected at the Newton tolerance, not zero).
#   bench/soak.sh [build] [frames]
set -euo pipefail
build=$(cd "${1:-build}" && pwd)
frames=${2:-100000}
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
# demos/swing.toml, on backward Euler with a step per frame.
duration=$(echo "($frames - 1) / 1000" | bc -l)
# (With integrator.newton_tol = 1e-10 a resume once failed at once with "the step matrix is
# singular", when resumed steps started from multipliers computed afresh; frames now store the
# multipliers, and the same soak at 1e-10 went through both resumes.)
sets=(--set integrator.kind=backward_euler --set integrator.dt=1e-3 --set frames.rate=1000 --set "frames.duration=$duration")
export OMP_NUM_THREADS=1  # a small scene: one thread (spinning OpenMP threads only contend)
isochor=$build/isochor
frames_in() { "$isochor" info "$1" 2>/dev/null | sed -n 's/^  frames *\([0-9]*\).*/\1/p'; }
echo "straight run: $frames frames"
"$isochor" run demos/swing.toml "${sets[@]}" -q -o "$tmp/straight.h5" > /dev/null
kills=0
for at in 30 70; do
  [ $kills -eq 0 ] && args=() || args=(--resume)
  "$isochor" run demos/swing.toml "${sets[@]}" -q -o "$tmp/killed.h5" "${args[@]}" > /dev/null 2>&1 & pid=$!
  while :; do
    n=$(frames_in "$tmp/killed.h5" || true); [ -n "$n" ] && [ "$n" -ge $((frames * at / 100)) ] && break
    kill -0 $pid 2> /dev/null || break
    sleep 0.5
  done
  kill -KILL $pid 2> /dev/null || true
  wait $pid 2> /dev/null || true
  kills=$((kills + 1))
  echo "killed at $(frames_in "$tmp/killed.h5") frames; $("$isochor" info "$tmp/killed.h5" | grep status | sed 's/^ *//' | cut -c1-60)"
done
"$isochor" run demos/swing.toml "${sets[@]}" -q -o "$tmp/killed.h5" --resume > /dev/null
/usr/bin/python3 - "$tmp/straight.h5" "$tmp/killed.h5" <<'PY'
import sys, h5py, numpy as np
a, b = h5py.File(sys.argv[1], "r"), h5py.File(sys.argv[2], "r")
for name, f in (("straight", a), ("killed twice, resumed", b)):
    mem = f["/stats/resident_mb"][()]
    wall = f["/stats/wall_seconds"][()]
    n = len(mem)
    d = [int(n * k / 10) for k in range(11)]
    d[-1] = n - 1
    rates = [(d[k + 1] - d[k]) / (wall[d[k + 1]] - wall[d[k]]) for k in range(10)]
    newton = f["/stats/newton_iterations"][()]
    per_step = [(newton[d[k + 1]] - newton[d[k]]) / (d[k + 1] - d[k]) for k in range(10)]
    print(f"{name}: {n} frames, status {f.attrs['status']}; resident MB at 10/50/100%: "
          f"{mem[n // 10]:.1f} / {mem[n // 2]:.1f} / {mem[-1]:.1f}")
    print("  frames per second per decile: " + " ".join(f"{r:.0f}" for r in rates))
    print("  Newton iterations per step per decile: " + " ".join(f"{r:.2f}" for r in per_step))
pa, pb = a["/frames/positions"], b["/frames/positions"]
assert pa.shape == pb.shape, (pa.shape, pb.shape)
worst = 0.0
for s in range(0, pa.shape[0], 10000):
    worst = max(worst, float(np.abs(pa[s:s + 10000] - pb[s:s + 10000]).max()))
ta, tb = a["/frames/time"][()], b["/frames/time"][()]
print(f"resumed against straight: times equal {np.array_equal(ta, tb)}, positions at most {worst:.3e} m apart "
      f"(block 0.3 m; Newton stops at 1e-6 of a step's displacement)")
PY
