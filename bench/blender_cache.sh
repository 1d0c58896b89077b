#!/usr/bin/env bash
# How a run's motion should go into Blender: a Mesh Cache modifier over a PC2 file
# against one shape key per frame, at 10^2, 10^3 and 10^4 frames of a 1,152-tet block
# (325 surface vertices, demos/swing.toml at 1000 frames per second): the import's time in
# Blender (building the mesh and its motion), the time to show a frame (50 frame changes spread
# over the run, each evaluating the mesh), the saved .blend's size. Shape keys at 10^4 frames are
# stopped after 10 minutes.
#   bench/blender_cache.sh [BUILD]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
out=out/bench/blender
mkdir -p "$out"
h5=$out/swing10k.h5
command -v blender > /dev/null || { echo "blender_cache: needs Blender (apt-get install blender)"; exit 1; }
[ -f "$h5" ] || OMP_NUM_THREADS=1 "$build/isochor" run demos/swing.toml -q --overwrite -o "$h5" \
  --set frames.duration=10 --set frames.rate=1000 --set "mesh.cells=[12,4,4]"
printf '%-10s %-7s %12s %14s %12s\n' cache frames "import (s)" "frame (ms)" ".blend (MB)"
for frames in 100 1000 10000; do
  for cache in pc2 shapekeys; do
    rm -f "$out/$cache.blend"
    s=$(date +%s.%N)
    log=$(timeout 600 blender -b --python-exit-code 1 --python tools/blender/isochor_blender.py -- "$h5" \
          --cache $cache --max-frames $frames --scrub 50 --save "$out/$cache.blend" 2>&1) || {
      printf '%-10s %-7s %12s\n' $cache $frames "> 600 (stopped)"; continue; }
    wall=$(echo "$(date +%s.%N) - $s" | bc)
    setup=$(echo "$log" | sed -n 's/.* set up in \([0-9.]*\) s.*/\1/p')
    frame=$(echo "$log" | sed -n 's/.*scrub 50 frames: \([0-9.]*\) ms.*/\1/p')
    size=$(echo "scale=1; $(stat -c %s "$out/$cache.blend") / 1048576" | bc)
    printf '%-10s %-7s %12s %14s %12s   (whole command %.1f s)\n' $cache $frames "$setup" "$frame" "$size" "$wall"
  done
done
