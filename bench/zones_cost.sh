#!/usr/bin/env bash
# What many zones cost in statics: demos/cook_membrane.toml with no zones (the local penalty
# alone), 2-ring patches and per-node 1-ring zones, on KLU (the whole KKT matrix) and on `reduced`
# (CHOLMOD; above 64 constraints the sparse border, integrators/src/bordered.hpp). A size is an
# edge length (the panel 6 thick, filled with layers: 3, 1.5, 0.75 make 1,945, 12,974 and 97,802
# tets) or N<k> (cook.geo with N = k, as mesh.parameters.N = k: k elements along an edge, one
# thick, the textbook plane-strain mesh: N64 makes 20,149 tets). Wall seconds of the solver (median of the rounds,
# cases interleaved; one round at 0.75), Newton iterations, CG iterations on the border, the
# factor's entries and the corner displacement u_y (the same on both solvers). KLU with 1-ring
# zones or patches at 0.75 is left out (more than 900 s). BASE=DIR (environment) runs every
# `reduced` case with DIR/isochor as well, in the same rounds (column build: this or base).
# Writes docs/results/zones_cost.csv.
#   [BASE=OLD_BUILD] bench/zones_cost.sh [build] [rounds] [sizes] [solvers] [csv]
set -euo pipefail
source "$(dirname "$0")/lib.sh"
sizes=${3:-"3 1.5 0.75"}
solvers=${4:-"klu reduced"}
csv=${5:-docs/results/zones_cost.csv}
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
zones_of() {
  case $1 in
    none) echo "--set zones.patches=0" ;;
    patches2) echo "--set zones.patches=2" ;;
    rings1) echo "--set zones.patches=0 --set zones.rings=1" ;;
  esac
}
# The mesh of a size: N<k> as a copy of cook.geo with N = k (a file, so that a BASE build that
# predates mesh.parameters meshes the same panel).
size_of() {
  case $1 in
    N*)
      sed "s/DefineConstant\[ N = 8 \]/N = ${1#N}/" demos/meshes/cook.geo > "out/bench/cook_$1.geo"
      echo "--set mesh.file=$PWD/out/bench/cook_$1.geo"
      ;;
    *) echo "--set mesh.edge_length=$1" ;;
  esac
}
for h in $sizes; do
  r=$rounds
  [ "$h" = "0.75" ] && r=1
  for ((k = 0; k < r; ++k)); do
    for z in none patches2 rings1; do
      for ls in $solvers; do
        [ "$h" = "0.75" ] && [ "$ls" = klu ] && [ "$z" != none ] && continue
        for which in this ${BASE:+base}; do
          [ "$which" = base ] && [ "$ls" != reduced ] && continue
          exe=$build
          [ "$which" = base ] && exe=$BASE
          # shellcheck disable=SC2046
          build=$exe bench_run zones_cost demos/cook_membrane.toml $(size_of "$h") --set integrator.linear_solver=$ls $(zones_of $z)
          /usr/bin/python3 - out/bench/zones_cost.h5 "$h" "$z" "$ls" "$which" >> "$tmp" <<'PY'
import sys, h5py, numpy as np
f = h5py.File(sys.argv[1], "r")
X = f["/mesh/rest_positions"][()]
x = f["/frames/positions"][-1]
i = np.argmin((X[:, 0] - 48) ** 2 + (X[:, 1] - 60) ** 2 + X[:, 2] ** 2)
s = f["/stats"].attrs
zones = len(f["/zones"]) if "zones" in f else 0
print(f"{sys.argv[2]},{sys.argv[3]},{sys.argv[4]},{sys.argv[5]},{f['/mesh/tets'].shape[0]},{zones},"
      f"{s['wall_seconds']:.3f},{s['newton_iterations']},{s['linear_iterations']},{s['factor_nnz']:.0f},"
      f"{x[i, 1] - X[i, 1]:.5f}")
PY
        done
      done
    done
  done
done
echo "size,zones,solver,build,tets,zone_count,wall_s,newton,border_cg,factor_nnz,corner_uy" > "$csv"
median_rows "$tmp" 4 6 >> "$csv"
column -s, -t "$csv"
