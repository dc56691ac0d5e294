#!/bin/bash
# The main job: staad on the simulated robot (config/staad.yaml: the HSR profile in the paper's
# office, three people walking between its rooms), a goal sent with staactl, the status shown
# until the robot arrives, then a clean stop (SIGTERM: brake, STOPPING=1, exit 0).
# Outputs in $OUT (default /tmp/staad-demo): run.svg (the map, the path driven, the goal),
# telemetry.csv (one row per cycle, docs/staad.md), staad.log (the daemon's log).
#
#   bash toolchain/run-demo.sh [X Y THETA]      # default goal: 10.5 4.5 0 (9 m down the corridor)
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD=${BUILD:-build/release}
OUT=${OUT:-/tmp/staad-demo}
STAAD="$BUILD/src/app/staad/staad"
STAACTL="$BUILD/src/app/staactl/staactl"
for exe in "$STAAD" "$STAACTL"; do
  [ -x "$exe" ] || { echo "run-demo: $exe not built (cmake --preset release && cmake --build --preset release)" >&2; exit 2; }
done
GOAL_X=${1:-10.5}; GOAL_Y=${2:-4.5}; GOAL_TH=${3:-0}
mkdir -p "$OUT"
SOCK="$OUT/staad.sock"
rm -f "$OUT/run.svg"

"$STAAD" --config config/staad.yaml --socket "$SOCK" --telemetry "$OUT/telemetry.csv" --svg "$OUT/run.svg" \
  2> "$OUT/staad.log" &
PID=$!
stop() {
  if kill -0 "$PID" 2>/dev/null; then
    kill -TERM "$PID"
    wait "$PID" || true
  fi
}
trap stop EXIT

for _ in $(seq 100); do
  [ -S "$SOCK" ] && "$STAACTL" --socket "$SOCK" status > /dev/null 2>&1 && break
  kill -0 "$PID" 2>/dev/null || { echo "run-demo: staad exited; its log:" >&2; cat "$OUT/staad.log" >&2; exit 1; }
  sleep 0.1
done

echo "== staad is up (socket $SOCK); status:"
"$STAACTL" --socket "$SOCK" status
echo "== goal ($GOAL_X, $GOAL_Y, $GOAL_TH); progress once a second until the robot arrives:"
rc=0
"$STAACTL" --socket "$SOCK" goal "$GOAL_X" "$GOAL_Y" "$GOAL_TH" --wait --timeout 300 || rc=$?
echo "== final status:"
"$STAACTL" --socket "$SOCK" status
stop
trap - EXIT
echo "== the run: $OUT/run.svg (picture), $OUT/telemetry.csv (per cycle), $OUT/staad.log (log)"
exit "$rc"
