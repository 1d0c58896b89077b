#!/usr/bin/env bash
# Coefficient of restitution of the coarse ball (600 tets, viscous as the demo; soft as the demo's
# mu = 16 kPa, and stiff, mu = 16 MPa) against the ground's normal damping alpha
# (contact.damping, s/m) and the impact speed: e = rebound speed /
# impact speed of the centre of mass (no gravity: it moves at v0 until the contact and at the
# rebound speed once the ball has left the ground: 0.15 s later for the soft ball, 0.03 s for the
# stiff one). The point-mass prediction
# sqrt(1 - 4/3 alpha v0) (docs/scenes.md) is printed beside it; the ball's own viscosity and the
# elastic energy it keeps ringing take more. Usage: bench/restitution.sh [build]
set -euo pipefail
build=${1:-build}
cd "$(dirname "$0")/.."
out=$(mktemp -d)
trap 'rm -rf "$out"' EXIT
printf "%-22s %-8s %-8s %-10s %-10s\n" "ball" "v0 m/s" "alpha" "e ball" "e point"
for ball in "soft E=46400 0.15" "stiff E=4.64e7 0.03"; do
  read -r name E duration <<< "$ball"
  for v0 in 1 3; do
  for alpha in 0 0.03 0.1 0.3; do
    "$build/isochor" run demos/ball_drop.toml --overwrite -q -o "$out/r.h5" --set mesh.target_tets=600 \
      --set "mesh.center=[0, 0, 0.1021]" --set "initial.velocity=[0, 0, -$v0]" --set forces.gravity=[0,0,0] \
      --set contact.damping=$alpha --set frames.rate=1000 --set frames.duration=$duration --set material.$E \
      --set integrator.rtol=1e-6 --set integrator.atol=1e-9 > /dev/null
    /usr/bin/python3 - "$out/r.h5" "$v0" "$alpha" "$name $E" <<'PY'
import sys, h5py, numpy as np
path, v0, alpha, name = sys.argv[1], float(sys.argv[2]), float(sys.argv[3]), sys.argv[4]
with h5py.File(path, "r") as f:
    t = f["/frames/time"][()]
    tets, vol = f["/mesh/tets"][()], f["/mesh/rest_volumes"][()]
    m = np.zeros(f["/mesh/rest_positions"].shape[0])
    for c in range(4):
        np.add.at(m, tets[:, c], vol / 4)           # lumped mass (uniform density)
    com = lambda k: m @ f["/frames/positions"][k][:, 2] / m.sum()
    low = f["/frames/positions"][len(t) - 1][:, 2].min()
    # No gravity: the centre of mass moves at v0 before the contact and at a constant speed after.
    vout = (com(len(t) - 1) - com(len(t) - 11)) / (t[-1] - t[-11])
point = np.sqrt(max(0.0, 1 - 4 / 3 * alpha * v0))
e = f"{vout / v0:.4f}" if low > 2e-3 else "in contact"
print(f"{name:<22} {v0:<8g} {alpha:<8g} {e:<10} {point:<10.4f}")
PY
  done
  done
done
