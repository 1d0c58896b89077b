#!/usr/bin/env bash
# threads.sh ISOCHOR: `isochor run` keeps OpenBLAS (inside CHOLMOD) on one thread unless
# OPENBLAS_NUM_THREADS says otherwise (README, "Threads"), and records the threads in /stats;
# a body that Gmsh meshed (which meshes on one thread) still runs on the threads OMP_NUM_THREADS asks.
set -uo pipefail
isochor=$1
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail() { echo "FAIL: $*"; exit 1; }
stat() { "$isochor" info "$tmp/run.h5" | sed -n "s/^ *$1 *\([0-9]*\)\$/\1/p"; }
run() { env "$@" "$isochor" run demos/two_tets.toml -q --overwrite -o "$tmp/run.h5" > /dev/null || fail "the run failed"; }
run -u OPENBLAS_NUM_THREADS OMP_NUM_THREADS=2
[ "$(stat threads)" = 2 ] || fail "OMP_NUM_THREADS=2: /stats threads is '$(stat threads)', expected 2"
[ "$(stat blas_threads)" = 1 ] || fail "OPENBLAS_NUM_THREADS unset: /stats blas_threads is '$(stat blas_threads)', expected 1"
run OPENBLAS_NUM_THREADS=2
[ "$(stat blas_threads)" = 2 ] || fail "OPENBLAS_NUM_THREADS=2: /stats blas_threads is '$(stat blas_threads)', expected 2"
env -u OPENBLAS_NUM_THREADS OMP_NUM_THREADS=2 "$isochor" run demos/ball_drop.toml --set mesh.target_tets=300 \
  --set frames.duration=0.002 -q --overwrite -o "$tmp/run.h5" > /dev/null || fail "the Gmsh-meshed run failed"
[ "$(stat threads)" = 2 ] || fail "a Gmsh-meshed ball with OMP_NUM_THREADS=2: /stats threads is '$(stat threads)', expected 2"
echo "threads: OpenBLAS on one thread by default, as many as OPENBLAS_NUM_THREADS asks otherwise"
