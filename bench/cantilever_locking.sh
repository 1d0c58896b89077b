#!/usr/bin/env bash
# The locking figure: the tip deflection of demos/cantilever_tip.toml (an
# incompressible cantilever under a small end load, E = 3 mu) against the mesh (10 x 1 x 1 to
# 80 x 8 x 8 cells), for UNH at nu = 0.45 and 0.499 (no zones), CNH with 1-ring zones, with
# 2-ring patches, and with the global zone plus the local penalty at nu = 0.45; each divided by
# Timoshenko's beam theory (1.009 mm). Writes docs/results/cantilever_locking/{tip.png,tip.csv}.
#   bench/cantilever_locking.sh [build] [meshes]
set -euo pipefail
build=${1:-build}
meshes=${2:-"10,1,1 20,2,2 40,4,4 80,8,8"}
cd "$(dirname "$0")/.."
out=docs/results/cantilever_locking
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
declare -A cases=(
  [unh_nu0.45]="material.model=unh material.lambda=9e5 zones.global=false"
  [unh_nu0.499]="material.model=unh material.lambda=4.99e7 zones.global=false"
  [cnh_rings1]="zones.global=false zones.rings=1"
  [cnh_patches2]="zones.global=false zones.patches=2"
  [cnh_global_penalty]="material.lambda=9e5"
)
echo "case,cells,tets,tip_mm,wall_s" > "$tmp/tip.csv"
for name in unh_nu0.45 unh_nu0.499 cnh_rings1 cnh_patches2 cnh_global_penalty; do
  for m in $meshes; do
    sets=(--set "mesh.cells=[$m]")
    for s in ${cases[$name]}; do sets+=(--set "$s"); done
    OMP_NUM_THREADS=1 "$build/isochor" run demos/cantilever_tip.toml --overwrite -q -o "$tmp/r.h5" "${sets[@]}" > /dev/null
    /usr/bin/python3 - "$tmp/r.h5" "$name" "$m" >> "$tmp/tip.csv" <<'PY'
import sys, h5py
f = h5py.File(sys.argv[1], "r")
X = f["/mesh/rest_positions"][()]
x = f["/frames/positions"][-1]
end = X[:, 0] > 1 - 1e-9
tip = -(x[end, 2] - X[end, 2]).mean() * 1000
print(f"{sys.argv[2]},{sys.argv[3].replace(',', 'x')},{f['/mesh/tets'].shape[0]},{tip:.6f},{f['/stats'].attrs['wall_seconds']:.3f}")
PY
  done
done
mkdir -p "$out"
cp "$tmp/tip.csv" "$out/tip.csv"
cat "$out/tip.csv"
/usr/bin/python3 - "$out" <<'PY'
import sys, csv
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
out = sys.argv[1]
rows = list(csv.DictReader(open(f"{out}/tip.csv")))
beam = 1.009  # mm, Timoshenko
fig, ax = plt.subplots(figsize=(6.4, 4.2))
for name in dict.fromkeys(r["case"] for r in rows):
    rr = [r for r in rows if r["case"] == name]
    h = [1.0 / int(r["cells"].split("x")[0]) for r in rr]
    ax.plot(h, [float(r["tip_mm"]) / beam for r in rr], "o-", label=name)
ax.axhline(1.0, color="k", lw=0.8, ls="--", label="beam theory (Timoshenko)")
ax.set_xscale("log")
ax.set_xlabel("cell size along the beam (m)")
ax.set_ylabel("tip deflection / beam theory")
ax.set_title("Incompressible cantilever: locking against mesh size")
ax.invert_xaxis()
ax.legend(fontsize=8)
fig.tight_layout()
fig.savefig(f"{out}/tip.png", dpi=120)
PY
echo "wrote $out/tip.png"
