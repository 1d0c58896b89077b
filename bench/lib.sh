# Sourced by the scene benchmarks: the build, the rounds and the output folder from the
# arguments ([build] [rounds]), and bench_run NAME SCENE OVERRIDES... (one thread, quiet,
# out/bench/NAME.h5; the wall time is read from the run file's /stats).
build=${1:-build}
rounds=${2:-3}
cd "$(dirname "${BASH_SOURCE[0]}")/.."
mkdir -p out/bench
bench_run() {
  local name=$1 scene=$2
  shift 2
  OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$build/isochor" run "$scene" --overwrite -q -o "out/bench/$name.h5" "$@" > /dev/null
}
