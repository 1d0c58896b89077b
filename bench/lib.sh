# Sourced by the scene benchmarks: the build, the rounds and the output folder from the
# arguments ([build] [rounds]), and bench_run NAME SCENE OVERRIDES... (one thread, quiet,
# out/bench/NAME.h5; the wall time is read from the run file's /stats).
build=${1:-build}
rounds=${2:-3}
cd "$(dirname "${BASH_SOURCE[0]}")/.."
mkdir -p out/bench
bench_run() {
  local name=$1 scene=$2
  shift 2
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run "$scene" --overwrite -q -o "out/bench/$name.h5" "$@" > /dev/null
}

# median_rows ROWS KEYS COLUMN: the rows of the CSV file ROWS (no header) grouped by their first
# KEYS columns, in first-seen order, each group printed once (its first row) with column COLUMN
# (0-based) replaced by the group's median: the rounds of a benchmark into one line per case.
median_rows() {
  /usr/bin/python3 - "$1" "$2" "$3" <<'PY'
import sys, statistics
path, keys, col = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
rows = [r.strip().split(",") for r in open(path) if r.strip()]
for key in dict.fromkeys(tuple(r[:keys]) for r in rows):
    group = [r for r in rows if tuple(r[:keys]) == key]
    first = list(group[0])
    first[col] = f"{statistics.median(float(r[col]) for r in group):.3f}"
    print(",".join(first))
PY
}
