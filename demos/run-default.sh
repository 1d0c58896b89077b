#!/usr/bin/env bash
# The default demo: the coarse ball of the CNH paper, meshed and summarised.
set -euo pipefail
build=${1:-build}
cd "$(dirname "$0")/.."
"$build/isochor" mesh demos/ball_drop.toml
"$build/isochor" info out/ball_drop_mesh.h5
