#!/usr/bin/env bash
# Makes the waistband demo's torso surface (demos/meshes/torso.stl) from demos/meshes/torso.geo with
# Gmsh, and paints its zones (demos/meshes/torso_paint.ply, tools/paint_torso.py).
set -euo pipefail
cd "$(dirname "$0")/../demos/meshes"
# Gmsh reports errors on a periodic patch it then meshes another way, and exits non-zero; the
# surface it writes is closed (isochor checks every surface it meshes): go by the file.
rm -f torso.stl
gmsh torso.geo -2 -format stl -o torso.stl > /tmp/isochor-make-torso.log 2>&1 || true
[ -s torso.stl ] || { tail -5 /tmp/isochor-make-torso.log; exit 1; }
/usr/bin/python3 ../../tools/paint_torso.py torso.stl torso_paint.ply
