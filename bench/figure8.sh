#!/usr/bin/env bash
# The CNH paper's Figure 8: the potential energy (elastic + gravity) of the settling
# 16^3 cube of demos/cube_gravity.toml over the paper's 1000 frames (8 s), for CNH with backward
# Euler at 8 ms and at 33 ms, Irving's 1-ring zones (backward Euler, 8 ms), the naive global
# volume rescaling with backward Euler at nu = 0.48 and semi-implicit at nu = 0.495, and UNH at
# nu = 0.45 without zones. Each run on one thread; a run that fails keeps its frames and its
# reason. Writes docs/results/figure8/{energy.png,runs.csv,summary.md}.
#   bench/figure8.sh [build] [duration]
set -euo pipefail
build=${1:-build}
duration=${2:-8.0}
cd "$(dirname "$0")/.."
out=docs/results/figure8
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
mkdir -p "$out"
# name | overrides. Irving's 1-rings (4,913 zones: KLU on the whole KKT matrix, ~7 s per step
# here) run the first half second only.
cases=(
  "cnh_be_8ms|integrator.kind=backward_euler integrator.dt=0.008"
  "cnh_be_33ms|integrator.kind=backward_euler integrator.dt=0.033"
  "one_ring_be_8ms|integrator.kind=backward_euler integrator.dt=0.008 zones.global=false zones.rings=1 material.lambda=0 frames.duration=0.5"
  "rescaled_unh_nu0.48_be_8ms|integrator.kind=backward_euler integrator.dt=0.008 integrator.rescale_volume=true material.model=unh material.lambda=2400 zones.global=false"
  "rescaled_unh_nu0.495_semi_implicit_8ms|integrator.kind=semi_implicit integrator.dt=0.008 integrator.rescale_volume=true material.model=unh material.lambda=9900 zones.global=false"
  "unh_nu0.45_be_8ms|integrator.kind=backward_euler integrator.dt=0.008 material.model=unh material.lambda=900 zones.global=false"
)
runs=()
for c in "${cases[@]}"; do
  name=${c%%|*}
  sets=(--set "frames.duration=$duration")
  for s in ${c#*|}; do sets+=(--set "$s"); done  # a later --set of the same key wins
  echo "$name" >&2
  OMP_NUM_THREADS=1 "$build/isochor" run demos/cube_gravity.toml --overwrite -q -o "$tmp/$name.h5" "${sets[@]}" \
    > "$tmp/$name.log" 2>&1 || true
  runs+=("$name=$tmp/$name.h5")
done
/usr/bin/python3 tools/energy_chart.py -o "$out/energy.png" --csv "$out/runs.csv" --zoom-last 1.0 \
  --title "demos/cube_gravity.toml (16^3 cells, mu = 100 Pa, 1 cm), potential energy" "${runs[@]}"
cat "$out/runs.csv"
