#!/bin/bash
# Measures staad's real-time behaviour on this machine (issue: the daemon's closing figures):
# two daemons on the simulated base at 30 Hz side by side, one with SCHED_FIFO threads
# (config/staad.yaml's priorities) and one with normal scheduling (priorities 0), both driving
# the HSR between the office's rooms the whole time, and cyclictest at the same period and
# priority (and at normal scheduling) in the same window, as the anchor for what the platform
# allows. With --stress, stress-ng loads both cores (--cpu 2) during the window.
#
#   tests/timing/measure-staad.sh [--duration S] [--stress] [--out DIR]
#
# Output: DIR/summary.md (a table), DIR/{fifo,other}.json (staactl status --json at the end),
# DIR/cyclictest-{fifo,other}.txt (histograms). Needs root for SCHED_FIFO and mlockall, and
# Debian's rt-tests (cyclictest) and stress-ng.
set -euo pipefail
cd "$(dirname "$0")/../.."
DURATION=600; STRESS=0; OUT=/tmp/staad-timing; BUILD=${BUILD:-build/release}
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) DURATION=$2; shift 2 ;;
    --stress) STRESS=1; shift ;;
    --out) OUT=$2; shift 2 ;;
    *) echo "measure-staad: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
STAAD="$BUILD/src/app/staad/staad"; STAACTL="$BUILD/src/app/staactl/staactl"
command -v cyclictest > /dev/null || { echo "measure-staad: cyclictest missing (apt-get install rt-tests)" >&2; exit 2; }
[ "$STRESS" = 0 ] || command -v stress-ng > /dev/null || { echo "measure-staad: stress-ng missing" >&2; exit 2; }
mkdir -p "$OUT"
ROOT=$(pwd)
PERIOD_US=33333

# Two configs: the shipped one with absolute paths, and the same with normal scheduling.
sed -e "s#^robot: .*#robot: $ROOT/config/robots/hsr.yaml#" -e "s#^map: .*#map: $ROOT/config/maps/office.yaml#" \
  config/staad.yaml > "$OUT/fifo.yaml"
sed -e 's/priority: [0-9]*/priority: 0/' "$OUT/fifo.yaml" > "$OUT/other.yaml"

PIDS=()
cleanup() { for p in "${PIDS[@]}"; do kill -TERM "$p" 2>/dev/null || true; done; wait 2>/dev/null || true; }
trap cleanup EXIT

for kind in fifo other; do
  "$STAAD" --config "$OUT/$kind.yaml" --socket "$OUT/$kind.sock" 2> "$OUT/$kind.log" &
  PIDS+=($!)
done
for kind in fifo other; do
  for _ in $(seq 100); do "$STAACTL" --socket "$OUT/$kind.sock" status > /dev/null 2>&1 && break; sleep 0.1; done
done

# Goals: the office's rooms in turn, a new one whenever the last is reached or unreachable.
GOALS=(4.5,1.5 13.5,1.5 22.5,1.5 4.5,25.5 13.5,25.5 22.5,25.5 25.5,22.5 10.5,4.5 1.5,4.5)
feeder() {
  local sock=$1 i=0
  while true; do
    local g=${GOALS[$((i % ${#GOALS[@]}))]}
    "$STAACTL" --socket "$sock" goal "${g%,*}" "${g#*,}" 0 --wait --timeout 400 > /dev/null 2>&1 || true
    i=$((i + 1))
  done
}
for kind in fifo other; do feeder "$OUT/$kind.sock" & PIDS+=($!); done

if [ "$STRESS" = 1 ]; then stress-ng --cpu 2 --timeout "${DURATION}s" > "$OUT/stress.log" 2>&1 & PIDS+=($!); fi
cyclictest -m -q -p 80 -i "$PERIOD_US" -D "$DURATION" -t 1 -h 40000 > "$OUT/cyclictest-fifo.txt" 2>&1 &
CT1=$!
cyclictest -m -q --policy=other -p 0 -i "$PERIOD_US" -D "$DURATION" -t 1 -h 40000 > "$OUT/cyclictest-other.txt" 2>&1 &
CT2=$!
wait $CT1 $CT2 || true

for kind in fifo other; do "$STAACTL" --socket "$OUT/$kind.sock" status --json > "$OUT/$kind.json"; done
cleanup
trap - EXIT

python3 - "$OUT" "$DURATION" "$STRESS" <<'PY'
import json, sys
sys.path.insert(0, "tests/timing")  # the scripts run from the checkout's root
import cyclictest_hist
out, duration, stress = sys.argv[1], sys.argv[2], sys.argv[3] == "1"
def cyclic(path): return cyclictest_hist.summary(path, 33333)
rows = []
for kind in ("fifo", "other"):
    s = json.load(open(f"{out}/{kind}.json"))
    c = s["cycle"]; w = s.get("wake", {})
    rows.append((kind, s, c, w))
with open(f"{out}/summary.md", "w") as f:
    f.write(f"duration {duration} s, load: {'stress-ng --cpu 2' if stress else 'none'}\n\n")
    f.write("| | cycles | exec p50 / p99 / max (us) | wake p50 / p99 / max (us) | overruns | execution overruns (ours) | late wake-ups | preempted | rt_allocations | realtime |\n|---|---|---|---|---|---|---|---|---|---|\n")
    for kind, s, c, w in rows:
        f.write(f"| staad {kind} | {c['count']} | {c['p50_us']:.0f} / {c['p99_us']:.0f} / {c['max_us']:.0f} | {w.get('p50_us',0):.0f} / {w.get('p99_us',0):.0f} / {w.get('max_us',0):.0f} | {c['overruns']} | {s.get('execution_overruns')} | {s.get('late_wakeups')} | {s.get('preempted')} | {s['rt_allocations']} | {s.get('realtime')} |\n")
    for kind in ("fifo", "other"):
        ct = cyclic(f"{out}/cyclictest-{kind}.txt")
        if ct is None:
            f.write(f"| cyclictest {kind} | no histogram (see {out}/cyclictest-{kind}.txt) | | | | | | | | |\n")
            continue
        f.write(f"| cyclictest {kind} | {ct['count']} | | {ct['p50_us']} / {ct['p99_us']} / {ct['max_us']} | wake-ups later than a period: {ct['over_period']} | | | | | |\n")
print(open(f"{out}/summary.md").read())
PY
