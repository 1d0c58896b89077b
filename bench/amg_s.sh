#!/usr/bin/env bash
# The effective stiffness S of the damped ball (demos/ball_drop.toml) captured
# from a real run (ISOCHOR_CAPTURE_S: the first setup at or after time T, in free flight, where
# IDA's steps are longest and S hardest for CG), then solved with the right-hand side the run
# solved it with: block-Jacobi PCG (today's krylov), Eigen's incomplete Cholesky CG and BoomerAMG
# CG on one rank, and BoomerAMG CG on 2 MPI ranks (rows split by nodes); each 3 rounds, medians.
# The 1M-tet capture takes ~25 min (meshing and 26 ms of flight) and ~6 GB; it is kept in
# out/bench and reused.
#   bench/amg_s.sh [BUILD] [TETS=1000000] [T=0.02] [ROUNDS=3]
set -euo pipefail
cd "$(dirname "$0")/.."
build=${1:-build}
tets=${2:-1000000}
t=${3:-0.02}
rounds=${4:-3}
mkdir -p out/bench
s=out/bench/S_ball_${tets}_t$t.bin
if [ ! -f "$s" ]; then
  ISOCHOR_CAPTURE_S="$t:$s" OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run demos/ball_drop.toml -q \
    --overwrite -o "out/bench/S_ball_${tets}.h5" --set mesh.target_tets="$tets" --set integrator.linear_solver=krylov \
    --set frames.duration="$(/usr/bin/python3 -c "print($t + 0.01)")" > /dev/null
fi
[ -f "$s" ] || { echo "amg_s.sh: no setup at or after t = $t s: nothing captured" >&2; exit 1; }
make -C "$build" isochor_bench_amg > /dev/null
export OMPI_ALLOW_RUN_AS_ROOT=1 OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1 OMP_NUM_THREADS=1
echo "== one rank"
"$build/isochor_bench_amg" "$s" "$rounds" 1e-12 pcg,ic,amg
echo "== two ranks"
mpirun -n 2 -x OMP_NUM_THREADS=1 "$build/isochor_bench_amg" "$s" "$rounds" 1e-12 amg
