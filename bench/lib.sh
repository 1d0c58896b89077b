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

# beam_scene FILE: the clamped beam of zones_dynamics.sh and dense_border.sh (1.5 x 0.3 x 0.3 m,
# mu = lambda = 1 MPa, 1000 kg/m^3, the x = 0 face held) falling under gravity for 50 ms; the
# mesh's cells, zones and integrator come as overrides.
beam_scene() {
  cat > "$1" <<'TOML'
[mesh]
shape = "box"
size = [1.5, 0.3, 0.3]
center = [0.75, 0.0, 0.0]
[material]
model = "cnh"
density = 1000.0
mu = 1.0e6
lambda = 1.0e6
[[boundary]]
select = { kind = "set", name = "xmin" }
[forces]
gravity = [0.0, 0.0, -9.81]
[frames]
rate = 100
duration = 0.05
TOML
}

# beam_row RUN.h5 LABEL...: one CSV row of a beam run: the labels, tets, zones, wall seconds,
# steps, Newton iterations, fresh factorisations and their seconds, the tip's deflection.
beam_row() {
  /usr/bin/python3 - "$@" <<'PY'
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
X = f["/mesh/rest_positions"][()]
x = f["/frames/positions"][-1]
tip = np.argmin((X[:, 0] - 1.5) ** 2 + X[:, 1] ** 2 + X[:, 2] ** 2)
s = f["/stats"].attrs
zones = len(f["/zones"]) if "zones" in f else 0
print(",".join(sys.argv[2:]) + f",{f['/mesh/tets'].shape[0]},{zones},{s['wall_seconds']:.3f},{s['steps']},"
      f"{s['newton_iterations']},{s['fresh_factorisations']:.0f},{s['factorisation_seconds']:.2f},{x[tip, 2] - X[tip, 2]:.6f}")
PY
}
