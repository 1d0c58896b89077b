#!/usr/bin/env bash
# isochor render's engine, measured: the same frame of the fine ball (~64K tets)
# drawn by tools/render.py (matplotlib, Gouraud triangles back to front) and by VTK offscreen
# (bench/render_vtk.py in ParaView's pvpython under xvfb-run: Debian's VTK needs an X server),
# interleaved, 3 times each; median wall time of the whole command (what a user waits for).
#   bench/render_engines.sh [BUILD]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=out/bench/render
mkdir -p "$out"
h5=$out/ball64k.h5
[ -f "$h5" ] || OMP_NUM_THREADS=1 "$build/isochor" run demos/ball_drop.toml -q --overwrite -o "$h5" \
  --set mesh.target_tets=64000 --set frames.duration=0.002
command -v pvpython > /dev/null && command -v xvfb-run > /dev/null || {
  echo "render_engines: needs ParaView and xvfb (apt-get install -y paraview python3-paraview xvfb xauth)"; exit 1; }
median() { sort -g | sed -n 2p; }
mpl=(); vtk=()
for i in 1 2 3; do
  s=$(date +%s.%N); /usr/bin/python3 tools/render.py "$h5" --frames -1 --out "$out/mpl.png" > /dev/null
  mpl+=("$(echo "$(date +%s.%N) - $s" | bc)")
  s=$(date +%s.%N); xvfb-run -a pvpython bench/render_vtk.py "$h5" 2 "$out/vtk.png" > /dev/null 2>&1
  vtk+=("$(echo "$(date +%s.%N) - $s" | bc)")
done
m=$(printf '%s\n' "${mpl[@]}" | median); v=$(printf '%s\n' "${vtk[@]}" | median)
printf 'one 64K-tet frame, whole command, median of 3:\n  matplotlib (tools/render.py)  %.2f s\n  VTK offscreen (xvfb, pvpython) %.2f s\n  ratio VTK / matplotlib %.2f\n' \
  "$m" "$v" "$(echo "$v / $m" | bc -l)"
echo "pictures: $out/mpl.png $out/vtk.png"
