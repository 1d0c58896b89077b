#!/bin/sh
# pip install of isochor (docs/python.md) into a fresh virtual environment in a temporary folder,
# from the source tree SRC with its build tree BUILD (ISOCHOR_BUILD_DIR: the built targets are
# reused), then, from another folder with no PYTHONPATH: the installed isochor command and
# python3 -m isochor run a scene; the module imported is the installed one, runs the same scene
# to the same numbers, and its program and tools are the environment's copies.
set -eu
src=$1 build=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
unset PYTHONPATH
export OMP_NUM_THREADS=1 PYTHONDONTWRITEBYTECODE=1
/usr/bin/python3 -m venv --system-site-packages "$tmp/v"
ISOCHOR_BUILD_DIR=$build "$tmp/v/bin/pip" install -q --no-build-isolation --no-index "$src"
cd "$tmp"
scene=$src/tests/data/good_box.toml
"$tmp/v/bin/isochor" --version | grep -q "^tools: $tmp/v/lib/python3[.0-9]*/site-packages/isochor/tools$"
"$tmp/v/bin/isochor" run "$scene" -o cli.h5 -q --set frames.duration=0.02
"$tmp/v/bin/python" -m isochor run "$scene" -o m.h5 -q --set frames.duration=0.02
"$tmp/v/bin/isochor" export cli.h5 --format pc2 --out cli.pc2 > /dev/null
test -s cli.pc2
if [ -f "$build/viewer/static/viewer.js" ]; then  # the page of isochor view, built where npm is
  "$tmp/v/bin/isochor" view cli.h5 --export page > /dev/null
  test -s page/viewer.js && test -s page/data/frame_0.js && test -s page/data/meta.js
  cmp -s page/viewer.js "$(ls -d "$tmp"/v/lib/python3*/site-packages/isochor/viewer)/viewer.js"
fi
"$tmp/v/bin/python" - "$tmp/v" "$scene" <<'PY'
import os
import sys

import numpy as np

import isochor

venv, scene = sys.argv[1:]
for what, path in (("module", isochor.__file__), ("program", isochor.executable),
                   ("tools", isochor._api._core().tools_dir)):
    assert path.startswith(venv + os.sep), f"the {what} is not the installed copy: {path}"
sc = isochor.load(scene, {"frames.duration": 0.02})
r = isochor.run(sc, "py.h5")
with isochor.open("py.h5") as a, isochor.open("cli.h5") as b, isochor.open("m.h5") as c:
    assert a.num_frames == b.num_frames == c.num_frames == r.frames > 1, (a.num_frames, b.num_frames, r.frames)
    assert np.array_equal(a.positions, b.positions) and np.array_equal(b.positions, c.positions)
    assert a.positions[-1].min(axis=0)[2] < a.rest_positions.min(axis=0)[2]  # it fell under gravity
print("pip_install: the installed module, program and tools ran the scene alike")
PY
