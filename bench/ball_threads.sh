#!/usr/bin/env bash
# Threads on the default IDA path: the fine ball (demos/ball_drop.toml at ~64K tets, `krylov`,
# rtol 1e-4, atol 1e-6 m) to 35 ms, through the first 5 ms of its impact, on one OpenMP thread
# and on two (OpenBLAS on one), with a second build run the same way when given; every setting
# once per round, interleaved, and the medians over the rounds of the solver's wall seconds and
# its parts from /stats, with the threads the run had (/stats threads). Writes docs/results/threads_ida.csv (or the CSV named third).
#   bench/ball_threads.sh [build] [rounds] [csv] [other build]
set -euo pipefail
source "$(dirname "$0")/lib.sh"
csv=${3:-docs/results/threads_ida.csv}
other=${4:-}
builds=("$build")
[ -n "$other" ] && builds+=("$other")
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
for ((k = 0; k < rounds; ++k)); do
  for b in "${builds[@]}"; do
    for threads in 1 2; do
      OMP_NUM_THREADS=$threads OPENBLAS_NUM_THREADS=1 "$b/isochor" run demos/ball_drop.toml --overwrite -q \
        -o out/bench/ball_threads.h5 --set mesh.target_tets=64000 --set integrator.rtol=1e-4 \
        --set integrator.atol=1e-6 --set frames.duration=0.035 > /dev/null
      for part in wall assembly factorisation solve; do
        /usr/bin/python3 - out/bench/ball_threads.h5 "$b" "$threads" "$part" >> "$tmp" <<'PY'
import sys, h5py
s = h5py.File(sys.argv[1], "r")["/stats"].attrs
print(f"{sys.argv[2]},{sys.argv[3]},{s['threads']:.0f},{sys.argv[4]},{s[sys.argv[4] + '_seconds']:.3f},{s['steps']:.0f},{s['newton_iterations']:.0f}")
PY
      done
    done
  done
done
echo "build,threads_asked,threads_run,part,seconds,steps,newton" > "$csv"
median_rows "$tmp" 4 4 >> "$csv"
column -s, -t "$csv"
