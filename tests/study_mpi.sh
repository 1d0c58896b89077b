#!/usr/bin/env bash
# The MPI executor against the local one: studies/quick.toml run by `isochor study`
# (2 jobs) and by `mpirun -n 2 isochor study --mpi`, into two directories; the results must list
# the same cases with the same status and frames, and errors equal to 1e-12 (the cases are
# deterministic: one thread each). Then --case and `isochor report` on a third directory: one case
# run, the others reported missing.
#   tests/study_mpi.sh BUILD/isochor SOURCE_DIR WORK_DIR
set -euo pipefail
exe=$1; src=$2; work=$3
rm -rf "$work"; mkdir -p "$work"
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMPI_MCA_rmaps_base_oversubscribe=1
study=$src/studies/quick.toml
"$exe" study "$study" --set study.output="$work/local" > "$work/local.log" 2>&1
mpirun -n 2 "$exe" study "$study" --set study.output="$work/mpi" --mpi > "$work/mpi.log" 2>&1
/usr/bin/python3 - "$work/local/results.csv" "$work/mpi/results.csv" <<'PY'
import csv, math, sys
a, b = (list(csv.DictReader(open(p))) for p in sys.argv[1:3])
assert [r["label"] for r in a] == [r["label"] for r in b], "different cases"
for x, y in zip(a, b):
    assert x["status"] == y["status"] and x["frames"] == y["frames"], (x, y)
    for k in ("error_l2", "volume_error", "error_centroid"):
        u, v = float(x[k]), float(y[k])
        assert (math.isnan(u) and math.isnan(v)) or abs(u - v) <= 1e-12 * max(1.0, abs(u)), (x["label"], k, u, v)
print(f"mpi == local: {len(a)} cases, statuses, frames and errors equal")
PY
# One case by id, then the report: the rest are missing.
first=$("$exe" study "$study" --set study.output="$work/one" --list | sed -n 2p)
"$exe" study "$study" --set study.output="$work/one" --case "$first" > /dev/null 2>&1
"$exe" report "$work/one" > /dev/null 2>&1
/usr/bin/python3 - "$work/one/results.csv" "$first" <<'PY'
import csv, sys
rows = list(csv.DictReader(open(sys.argv[1])))
done = [r for r in rows if r["status"] != "missing"]
assert [r["label"] for r in done] == [sys.argv[2]], done
assert all(r["reason"] == "not run yet" for r in rows if r["status"] == "missing")
print(f"--case and report: 1 case done, {len(rows) - 1} missing")
PY
