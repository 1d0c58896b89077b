#!/usr/bin/env bash
# One scene on 1 and 2 MPI ranks (docs/scale.md): the pinned cube at 26^3 cells (105K tets,
# backward Euler on PCG, 0.25 s: 15 steps) and the fine ball (64K tets, IDA with `krylov`, rtol
# 1e-4, atol 1e-6 m, to 35 ms: the first 5 ms of its impact), each on one process without
# mpirun and on `mpirun -n 2`, one OpenMP thread per rank; the settings interleaved in every
# round. Per case the medians over the rounds of the process's wall seconds (meshing and set-up
# included), the solver's (/stats wall_seconds) and its parts, the seconds rank 0 spent in MPI
# calls (waiting for the other rank included) and rank 0's peak memory, with the steps, Newton
# and CG iterations (the same on 1 and 2 ranks where the runs agree). Writes
# docs/results/distributed.csv (or the CSV named third). SCENES (environment) picks among cube,
# ball, ball125k and ball253k (the fine ball's window at 125K and 253K tets), cube_amg and ball_amg
# (linear_solver = "amg": hypre's BoomerAMG across the ranks); default "cube ball".
# BASE=DIR (environment) adds, in the same
# rounds, one process of the build in DIR (one built without MPI ranks: is P = 1 any slower?).
#   [BASE=OLD_BUILD] bench/mpi_ranks.sh [build] [rounds] [csv]
set -euo pipefail
source "$(dirname "$0")/lib.sh"
csv=${3:-docs/results/distributed.csv}
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
cube=(demos/pinned_cube.toml --set mesh.cells=26 frames.duration=0.25)
ball=(demos/ball_drop.toml --set mesh.target_tets=64000 integrator.rtol=1e-4 integrator.atol=1e-6
  frames.duration=0.035)
ball125k=("${ball[@]}" mesh.target_tets=125000)
ball253k=("${ball[@]}" mesh.target_tets=253000)
ball_amg=("${ball[@]}" integrator.linear_solver=amg)
cube_amg=("${cube[@]}" integrator.linear_solver=amg)
for ((k = 0; k < rounds; ++k)); do
  for name in ${SCENES:-cube ball}; do
    declare -n args=$name
    for setting in this:1 this:2 ${BASE:+base:1}; do
      ranks=${setting#*:}
      exe=$build/isochor
      [ "${setting%:*}" = base ] && exe=$BASE/isochor
      launch=()
      [ $ranks -gt 1 ] && launch=(mpirun -n $ranks)
      rm -f out/bench/mpi_ranks.h5 out/bench/mpi_ranks.xdmf
      start=$(date +%s.%N)
      "${launch[@]}" "$exe" run "${args[@]}" -q -o out/bench/mpi_ranks.h5 > /dev/null
      end=$(date +%s.%N)
      /usr/bin/python3 - out/bench/mpi_ranks.h5 "$name" "$setting" "$start" "$end" >> "$tmp" <<'PY'
import sys, h5py
s = h5py.File(sys.argv[1], "r")["/stats"].attrs
name, ranks, start, end = sys.argv[2], sys.argv[3], float(sys.argv[4]), float(sys.argv[5])
ranks = ranks.split(":")[1] if ranks.startswith("this:") else "1 (base build)"
counts = f"{s['steps']:.0f},{s['newton_iterations']:.0f},{s['linear_iterations']:.0f}"
values = {"process": end - start, "solver": s["wall_seconds"], "assembly": s["assembly_seconds"],
          "solve": s["solve_seconds"], "mpi": s.get("mpi_seconds", 0.0), "peak_memory_mb": s["peak_memory_mb"]}
for part, v in values.items():
    print(f"{name},{ranks},{part},{v:.3f},{counts}")
PY
    done
  done
done
echo "scene,ranks,part,seconds_or_mb,steps,newton,cg" > "$csv"
median_rows "$tmp" 3 3 >> "$csv"
column -s, -t "$csv"
