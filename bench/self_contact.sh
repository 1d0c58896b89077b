#!/usr/bin/env bash
# Contact between body parts, two builds side by side: demos/arm_flex.toml and the glTF character
# walk (demos/character_walk.toml at edge_length 0.02 m, ~34K tets), each over its first 0.3 s,
# one thread, the runs interleaved in rounds. Prints per scene and build the median wall seconds of
# the solver and its assembly part, IDA's steps, and the largest node distance between the two
# builds' last frames (0 when both take the same steps on the same mesh; the character's mesh can
# differ between builds: docs/characters.md).
#   bench/self_contact.sh OLD_BUILD NEW_BUILD [rounds]
set -euo pipefail
old=$1
new=$2
rounds=${3:-3}
cd "$(dirname "$0")/.."
source bench/lib.sh "$new" "$rounds"
tmp=$(mktemp)
trap 'rm -f "$tmp"' EXIT
scene_args() {
  case $1 in
    arm) echo "demos/arm_flex.toml --set frames.duration=0.3" ;;
    walk) echo "demos/character_walk.toml --set frames.duration=0.3 --set character.edge_length=0.02" ;;
  esac
}
for ((r = 0; r < rounds; ++r)); do
  for s in arm walk; do
    for b in old new; do
      exe=$old/isochor
      [ $b = new ] && exe=$new/isochor
      # shellcheck disable=SC2046
      OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 "$exe" run $(scene_args $s) --overwrite -q -o "out/bench/self_contact_${s}_$b.h5" > /dev/null
      /usr/bin/python3 - "out/bench/self_contact_${s}_$b.h5" "$s" "$b" >> "$tmp" <<'PY'
import sys, h5py
st = h5py.File(sys.argv[1], "r")["/stats"].attrs
print(f"{sys.argv[2]},{sys.argv[3]},wall,{st['wall_seconds']:.3f},{st['steps']:.0f}")
print(f"{sys.argv[2]},{sys.argv[3]},assembly,{st['assembly_seconds']:.3f},{st['steps']:.0f}")
PY
    done
  done
done
echo "scene,build,part,seconds,steps"
median_rows "$tmp" 3 3
/usr/bin/python3 - <<'PY'
import h5py, numpy as np
for s in ("arm", "walk"):
    a = h5py.File(f"out/bench/self_contact_{s}_old.h5", "r")["/frames/positions"]
    b = h5py.File(f"out/bench/self_contact_{s}_new.h5", "r")["/frames/positions"]
    d = np.abs(a[-1] - b[-1]).max() if a.shape == b.shape else float("nan")
    print(f"{s}: largest node distance between the builds' last frames {d:.3g} m")
PY
