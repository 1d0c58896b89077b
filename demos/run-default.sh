#!/usr/bin/env bash
# The default demo: the coarse ball of the CNH paper hitting the ground, on IDA with the krylov
# solver (about 30 s: the ball is damped, docs/demos.md), then its report: cost per frame and volume error, and
# the picture of the README drawn anew into out/ball_drop.png (nothing that git tracks is written).
set -euo pipefail
build=${1:-build}
cd "$(dirname "$0")/.."
"$build/isochor" run demos/ball_drop.toml --overwrite --set integrator.rtol=1e-4 --set integrator.atol=1e-6
/usr/bin/python3 tools/run_report.py out/ball_drop.h5
"$build/isochor" info out/ball_drop.h5
# The README's picture (docs/images/ball_drop.png) drawn from this run: the ball at its flattest,
# coloured by its deformation (the best rigid motion taken out).
"$build/isochor" render out/ball_drop.h5 --frames flattest --out out/ball_drop.png
echo "picture: out/ball_drop.png"
