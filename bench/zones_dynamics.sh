#!/usr/bin/env bash
# What many zones cost in dynamics: a clamped beam (1.5 x 0.3 x 0.3 m, mu = lambda = 1 MPa) falling
# under gravity for 50 ms, at cells [15k, 3k, 3k] (810 k^3 tets), with the global zone (one row),
# 2-ring patches and per-node 1-ring zones, under backward Euler (dt = 1 ms, 50 steps) and IDA
# (rtol 1e-4), each with its automatic linear solver (backward Euler: the dense border up to 32
# rows, else the KKT matrix by UMFPACK; IDA: krylov up to 256 rows, else `klu`, which above 32
# rows solves the GGL system through its KKT matrix, refined: integrators/src/ggl_kkt.hpp).
# Three of the 1-ring zones on this mesh are sums and differences of
# the others and get no row (docs/decisions.md). Wall seconds of
# the solver (median of the rounds, cases interleaved), steps, Newton iterations, fresh
# factorisations and their seconds, and the tip's deflection. Writes docs/results/zones_dynamics.csv.
#   bench/zones_dynamics.sh [build] [rounds] [ks] [csv]
set -euo pipefail
source "$(dirname "$0")/lib.sh"
ks=${3:-"1 2 3"}
csv=${4:-docs/results/zones_dynamics.csv}
tmp=$(mktemp)
scene=out/bench/beam_dynamic.toml
trap 'rm -f "$tmp"' EXIT
beam_scene "$scene"
zones_of() {
  case $1 in
    global) echo "--set zones.default=global" ;;
    patches2) echo "--set zones.patches=2" ;;
    rings1) echo "--set zones.rings=1 --set zones.global=false" ;;
  esac
}
method_of() {
  case $1 in
    be) echo "--set integrator.kind=backward_euler --set integrator.dt=1e-3" ;;
    ida) echo "--set integrator.kind=ida --set integrator.rtol=1e-4 --set integrator.atol=1e-7" ;;
  esac
}
for k in $ks; do
  for ((r = 0; r < rounds; ++r)); do
    for z in global patches2 rings1; do
      for m in be ida; do
        # shellcheck disable=SC2046
        bench_run zones_dynamics "$scene" --set "mesh.cells=[$((15 * k)), $((3 * k)), $((3 * k))]" $(zones_of $z) \
          $(method_of $m)
        beam_row out/bench/zones_dynamics.h5 "$k" "$z" "$m" >> "$tmp"
      done
    done
  done
done
echo "k,zones,method,tets,zone_count,wall_s,steps,newton,factorisations,factor_s,tip_uz" > "$csv"
median_rows "$tmp" 3 5 >> "$csv"
column -s, -t "$csv"
