#!/usr/bin/env bash
# interrupt.sh ISOCHOR: the command line under signals. A run interrupted by SIGINT
# or SIGTERM stops at a step boundary, says in one line how far it got and how to continue, exits
# 130 / 143, and marks its file; a SIGKILLed one is reported unfinished by `isochor info`; each is
# continued by --resume, and the finished file has every frame once, in order.
set -uo pipefail
isochor=$1
cd "$(dirname "$0")/.."
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
out=$tmp/run.h5
run=("$isochor" run demos/ball_drop.toml -q -o "$out" --set mesh.target_tets=600 --set frames.duration=0.3)
fail() { echo "FAIL: $*"; exit 1; }
frames() { "$isochor" info "$out" 2>/dev/null | sed -n 's/^  frames *\([0-9]*\).*/\1/p'; }
# Starts the run (fresh, or --resume), waits until the file has $1 frames, sends signal $2.
signal_after() {
  local want=$1 sig=$2; shift 2
  "${run[@]}" "$@" 2> "$tmp/err" & pid=$!
  for _ in $(seq 600); do
    n=$(frames); [ -n "$n" ] && [ "$n" -ge "$want" ] && break
    kill -0 $pid 2>/dev/null || break
    sleep 0.1
  done
  kill -"$sig" $pid
  wait $pid
  rc=$?
}

signal_after 5 INT
[ $rc -eq 130 ] || fail "SIGINT: exit $rc, expected 130 ($(cat "$tmp/err"))"
[ "$(grep -c . "$tmp/err")" -eq 1 ] || fail "SIGINT: expected one line, got: $(cat "$tmp/err")"
grep -Eq "interrupted by SIGINT at t = [0-9.]+ s; [0-9]+ frames kept in $out; continue with: .* --resume$" "$tmp/err" ||
  fail "SIGINT message: $(cat "$tmp/err")"
"$isochor" info "$out" | grep -q "status      interrupted at t = " || fail "info after SIGINT: $("$isochor" info "$out")"
first=$(frames)

signal_after $((first + 5)) TERM --resume
[ $rc -eq 143 ] || fail "SIGTERM: exit $rc, expected 143 ($(cat "$tmp/err"))"
grep -q "interrupted by SIGTERM" "$tmp/err" || fail "SIGTERM message: $(cat "$tmp/err")"
second=$(frames)
[ "$second" -gt "$first" ] || fail "the resumed run added no frames ($first, then $second)"

signal_after $((second + 5)) KILL --resume
[ $rc -eq 137 ] || fail "SIGKILL: exit $rc"
"$isochor" info "$out" | grep -q "status      unfinished: its writer stopped without closing it" ||
  fail "info after SIGKILL: $("$isochor" info "$out")"

"${run[@]}" --resume > "$tmp/out" 2>&1 || fail "the last resume failed: $(cat "$tmp/out")"
"$isochor" info "$out" | grep -q "status      finished" || fail "not finished: $("$isochor" info "$out")"
/usr/bin/python3 - "$out" <<'PY' || fail "frames"
import sys, h5py, numpy as np
t = h5py.File(sys.argv[1], "r")["/frames/time"][()]
assert len(t) == 301, len(t)
assert np.allclose(t, np.arange(301) / 1000.0, rtol=0, atol=1e-12), t
PY
"${run[@]}" > "$tmp/err" 2>&1 && fail "a second run over the finished file was not refused"
grep -q "exists (pass --overwrite to replace it, or --resume to continue the run in it)" "$tmp/err" || fail "$(cat "$tmp/err")"
echo "ok: SIGINT after $first frames, SIGTERM after $second, SIGKILL, resumed to the end"
