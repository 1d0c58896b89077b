#!/usr/bin/env bash
# How long `isochor view` takes to open a long run: a 48-tet box written at 10^5 frames per second
# for 1 s (100,001 frames, about 190 MB; written once, about 90 s), then ROUNDS launches of
# `isochor view --no-browser`, each timed from the command to the server's first line, to the
# meta (/api/meta: the surface, the charts over every frame) and to the last frame's data
# (/api/frame/K). Prints each round and the medians. docs/viewer.md quotes them.
#   bench/view_open.sh [build] [rounds]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib.sh"
run=out/bench/view_long.h5
[ -f "$run" ] || bench_run view_long tests/data/good_box.toml --set frames.rate=100000 frames.duration=1
/usr/bin/python3 - "$build/isochor" "$run" "$rounds" <<'PY'
import json, re, statistics, subprocess, sys, time, urllib.request
exe, run, rounds = sys.argv[1], sys.argv[2], int(sys.argv[3])
rows = []
for r in range(rounds):
    t0 = time.perf_counter()
    p = subprocess.Popen([exe, "view", run, "--no-browser"], stdout=subprocess.PIPE, text=True)
    try:
        url = re.search(r"(http://\S+/)", p.stdout.readline()).group(1)
        t1 = time.perf_counter()
        meta = json.load(urllib.request.urlopen(url + "api/meta"))
        t2 = time.perf_counter()
        urllib.request.urlopen(url + f"api/frame/{meta['frames'] - 1}").read()
        t3 = time.perf_counter()
    finally:
        p.terminate()
        p.wait()
    rows.append((t1 - t0, t2 - t1, t3 - t2, t3 - t0))
    print(f"round {r + 1}: {meta['frames']} frames; server up {rows[-1][0]:.2f} s, meta {rows[-1][1]:.2f} s, "
          f"last frame {1000 * rows[-1][2]:.1f} ms, command to last frame {rows[-1][3]:.2f} s")
med = [statistics.median(c) for c in zip(*rows)]
print(f"median of {rounds}: server up {med[0]:.2f} s, meta {med[1]:.2f} s, last frame {1000 * med[2]:.1f} ms, "
      f"command to last frame {med[3]:.2f} s")
PY
