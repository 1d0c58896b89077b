#!/usr/bin/env bash
# Where backward Euler's dense border stops paying: the clamped beam of zones_dynamics.sh (1.5 x
# 0.3 x 0.3 m, mu = lambda = 1 MPa, falling under gravity for 50 ms, dt = 1 ms) at cells [15k, 3k,
# 3k] (810 k^3 tets), k = 2 and 3, with the global zone and 2- to 6-ring patches (1 to 32 rows),
# each solved with the dense border (integrator.dense_border_rows = 100000: the step matrix's
# solver, m + 1 solves per Newton iteration) and with the KKT matrix (dense_border_rows = 0:
# KLU up to 32 rows). Wall seconds (median of the rounds, cases interleaved), steps, Newton
# iterations, factorisations, the tip's deflection. Writes docs/results/dense_border.csv.
#   bench/dense_border.sh [build] [rounds] [csv]
set -euo pipefail
source "$(dirname "$0")/lib.sh"
csv=${3:-docs/results/dense_border.csv}
tmp=$(mktemp)
scene=out/bench/beam_border.toml
trap 'rm -f "$tmp"' EXIT
beam_scene "$scene"
zones_of() {
  case $1 in
    global) echo "--set zones.default=global" ;;
    *) echo "--set zones.patches=${1#patches}" ;;
  esac
}
for ((r = 0; r < rounds; ++r)); do
  for k in 2 3; do
    for z in global patches6 patches5 patches4 patches3 patches2; do
      # 2-ring patches at k = 3 are 108 rows: the KKT path by UMFPACK (zones_dynamics.sh).
      if [ "$k" = 3 ] && [ "$z" = patches2 ]; then continue; fi
      for path in dense kkt; do
        rows=$([ "$path" = dense ] && echo 100000 || echo 0)
        # shellcheck disable=SC2046
        bench_run dense_border "$scene" --set "mesh.cells=[$((15 * k)), $((3 * k)), $((3 * k))]" $(zones_of $z) \
          --set integrator.kind=backward_euler --set integrator.dt=1e-3 --set "integrator.dense_border_rows=$rows"
        beam_row out/bench/dense_border.h5 "$k" "$z" "$path" >> "$tmp"
      done
    done
  done
done
echo "k,zones,path,tets,zone_count,wall_s,steps,newton,factorisations,factor_s,tip_uz" > "$csv"
median_rows "$tmp" 3 5 >> "$csv"
column -s, -t "$csv"
