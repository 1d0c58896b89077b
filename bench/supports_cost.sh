#!/usr/bin/env bash
# What a support costs as constraint rows against the same support as a dof map:
# demos/cantilever_tip.toml's clamped face held once as a full [[boundary]] (its nodes leave the
# unknowns: the dof map) and once as three [[boundary]] blocks with components = ["x"], ["y"],
# ["z"] (three constraint rows per node, the path that rollers and symmetry planes take). Statics
# (KINSOL + KLU on the KKT matrix) and 20 ms of dynamics (IDA, KLU and reduced), CNH with the
# global zone and the local penalty; wall seconds, median of 3, side by side in one run.
#   bench/supports_cost.sh [build] [cells]
set -euo pipefail
build=${1:-build}
cells=${2:-"40, 4, 4"}
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
/usr/bin/python3 - "$tmp" <<'PY'
import sys
tmp = sys.argv[1]
t = open("demos/cantilever_tip.toml").read()
clamp = '[[boundary]]\nselect = { kind = "set", name = "xmin" }   # clamped'
assert clamp in t, "demos/cantilever_tip.toml's clamp changed"
rows = "\n".join(f'[[boundary]]\nselect = {{ kind = "set", name = "xmin" }}\ncomponents = ["{c}"]' for c in "xyz")
statics = '[integrator]\nkind = "static"\n\n[frames]\ncount = 2'
assert statics in t, "demos/cantilever_tip.toml's statics changed"
dynamics = '[integrator]\nkind = "ida"\n\n[damping]\nbeta = 1e-3\n\n[frames]\nduration = 0.02\nrate = 100'
for name, text in (("dofmap", t), ("rows", t.replace(clamp, rows))):
    open(f"{tmp}/{name}_static.toml", "w").write(text)
    open(f"{tmp}/{name}_ida.toml", "w").write(text.replace(statics, dynamics))
PY
median() { sort -g | awk '{a[NR]=$1} END {print a[int((NR+1)/2)]}'; }
run() {  # scene, extra settings... -> wall seconds
  local scene=$1; shift
  OMP_NUM_THREADS=1 "$build/isochor" run "$tmp/$scene.toml" --overwrite -q -o "$tmp/r.h5" --set "mesh.cells=[$cells]" \
    --set material.lambda=9e5 "$@" > /dev/null
  /usr/bin/python3 -c "import h5py,sys; s=h5py.File(sys.argv[1],'r')['/stats'].attrs; print(s['wall_seconds'])" "$tmp/r.h5"
}
printf "%-40s %12s %12s %8s\n" case dofmap_s rows_s ratio
for c in "static:" "ida:integrator.linear_solver=klu" "ida:integrator.linear_solver=reduced"; do
  name=${c%%:*}
  sets=()
  for s in ${c#*:}; do sets+=(--set "$s"); done
  : > "$tmp/rows.txt"
  a=$(for i in 1 2 3; do run "dofmap_$name" "${sets[@]}"; run "rows_$name" "${sets[@]}" >> "$tmp/rows.txt"; done | median)
  b=$(median < "$tmp/rows.txt")
  printf "%-40s %12.3f %12.3f %8.2f\n" "$name ${c#*:}" "$a" "$b" "$(echo "$b / $a" | bc -l)"
done
