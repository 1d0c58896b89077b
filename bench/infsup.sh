#!/usr/bin/env bash
# Which zones lock: the discrete inf-sup constant beta_h (`isochor infsup`, models/infsup.hpp;
# Chapelle and Bathe's numerical test) of per-node 1-ring zones and of patches the size of a 1-,
# 2- and 3-ring, under refinement, on Cook's membrane (demos/cook_membrane.toml, plane strain by
# rollers, mesh.edge_length 6 .. 1.5) and on a unit cube clamped on one face (bench/infsup/block.toml,
# three-dimensional, 1/4 .. 1/16). A choice whose beta_h stays away from 0 as h falls is stable;
# one whose beta_h falls locks. 1-ring zones on the two finest cubes are left out (a dense
# eigenproblem of more than 4,000 rows). Writes docs/results/infsup/infsup.csv and infsup.png.
#   bench/infsup.sh [build] [outdir]
set -euo pipefail
build=${1:-build}
cd "$(dirname "${BASH_SOURCE[0]}")/.."
dir=${2:-docs/results/infsup}
mkdir -p "$dir"
csv=$dir/infsup.csv
echo "scene,zones,edge_length,tets,zone_count,free_dofs,beta,beta_next,zero_modes,seconds" > "$csv"
zones_of() {
  case $1 in
    rings1) echo "zones.patches=0 zones.rings=1" ;;
    patches*) echo "zones.patches=${1#patches}" ;;
  esac
}
measure() {  # scene-name scene-file h choice
  local t0 line
  t0=$(date +%s.%N)
  # shellcheck disable=SC2046
  line=$(OMP_NUM_THREADS=1 "$build/isochor" infsup "$2" --set mesh.edge_length="$3" zones.global=false $(zones_of "$4"))
  /usr/bin/python3 - "$1" "$4" "$3" "$line" "$t0" >> "$csv" <<'PY'
import re, sys, time
name, zones, h, line, t0 = sys.argv[1:]
m = re.search(r"(\d+) tets, (\d+) zones, (\d+) free dofs: inf-sup beta_h = (\S+) \(next (\S+)\), (\d+) zero", line)
print(",".join([name, zones, h, *m.groups(), f"{time.time() - float(t0):.1f}"]))
PY
  tail -1 "$csv"
}
for h in 6 4 3 2 1.5; do
  for z in rings1 patches1 patches2 patches3; do measure cook demos/cook_membrane.toml $h $z; done
done
for h in 0.25 0.1667 0.125 0.0833 0.0625; do
  for z in rings1 patches1 patches2 patches3; do
    [ $z = rings1 ] && [ "$h" != 0.25 ] && [ "$h" != 0.1667 ] && [ "$h" != 0.125 ] && continue
    measure block bench/infsup/block.toml $h $z
  done
done
/usr/bin/python3 - "$csv" "$dir/infsup.png" <<'PY'
import csv, sys
import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt
import matplotlib.ticker
rows = list(csv.DictReader(open(sys.argv[1])))
labels = {"rings1": "1-ring zones (one per node)", "patches1": "1-ring patches",
          "patches2": "2-ring patches", "patches3": "3-ring patches"}
fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
for ax, scene, title in zip(axes, ["cook", "block"], ["Cook's membrane (plane strain)", "unit cube, one face clamped"]):
    for z, label in labels.items():
        rr = [r for r in rows if r["scene"] == scene and r["zones"] == z]
        ax.plot([float(r["edge_length"]) for r in rr], [float(r["beta"]) for r in rr], "o-", label=label)
    ax.set_xscale("log")
    ax.xaxis.set_major_formatter(matplotlib.ticker.ScalarFormatter())
    ax.xaxis.set_minor_formatter(matplotlib.ticker.NullFormatter())
    ax.set_xticks(sorted({float(r["edge_length"]) for r in rows if r["scene"] == scene}))
    ax.invert_xaxis()
    ax.set_xlabel("edge length h (refining to the right)")
    ax.set_title(title)
    ax.grid(True, which="both", alpha=0.3)
axes[0].set_ylabel("inf-sup constant beta_h")
axes[0].set_ylim(bottom=0)
axes[1].legend(loc="center right", bbox_to_anchor=(1.0, 0.45))
fig.tight_layout()
fig.savefig(sys.argv[2], dpi=110)
PY
column -s, -t "$csv"
