#!/bin/bash
# Measures staad's base I/O path on this machine (issue: base I/O thread wake-up latency and
# command-to-wire latency, p50/p99/max over 10 minutes; bad-frame counts under injected
# corruption): the real staad with `hal: socketcan` over `unix:` against basesim (the
# simulated HSR base firmware of tests/hil), with config/staad.yaml's rates, budget and
# thread priorities (SCHED_FIFO where permitted; without the privilege staad runs its threads
# normally and says so, and the summary shows `realtime: false`), driving the HSR between the
# office's rooms the whole time. Every --corrupt-every seconds basesim puts a bad frame beside
# each of the next --corrupt-frames odometry frames (bad checksum, wrong DLC, counter going
# back, huge v, a reordered pair, in turn). cyclictest runs in the same window at the base
# thread's period and priority, as the anchor for what the platform allows.
#
#   tests/timing/measure-hil.sh [--duration S] [--corrupt-every S] [--corrupt-frames N]
#                               [--build DIR] [--out DIR]
#
#   --duration S        the measuring window (default 600 s)
#   --corrupt-every S   whole seconds between two corruption bursts (default 10; 0: none)
#   --corrupt-frames N  odometry frames with a bad frame beside each, per burst (default 10)
#   --build DIR         the build tree with staad, staactl and basesim (default $BUILD, else
#                       build/release); basesim is built by the test tree (ninja basesim)
#   --out DIR           where everything goes (default /tmp/staad-hil-timing)
#
# Progress: one line every 10 s on stderr. Output: DIR/summary.json and DIR/summary.md
# (printed at the end), DIR/status.json (staactl status --json at the end), DIR/basesim.json
# (basesim's state at the end), DIR/cyclictest.txt (its histogram), DIR/staad.log,
# DIR/basesim.out, DIR/goals.log.
#
# Bad frames: of what basesim injects, a bad checksum, a wrong DLC and a huge v are malformed
# (staad's `base.bad_frames` must count exactly these); a counter going back and a reordered
# frame are valid frames out of order, dropped by the driver as stale (not in bad_frames).
# The times from a fault's injection to standstill are measured by the HIL tests
# (`ctest -L hil -V`, the `HIL fault=...` lines), not here.
set -euo pipefail
cd "$(dirname "$0")/../.."
DURATION=600; CORRUPT_EVERY=10; CORRUPT_FRAMES=10; OUT=/tmp/staad-hil-timing; BUILD=${BUILD:-build/release}
while [ $# -gt 0 ]; do
  case "$1" in
    --duration) DURATION=$2; shift 2 ;;
    --corrupt-every) CORRUPT_EVERY=$2; shift 2 ;;
    --corrupt-frames) CORRUPT_FRAMES=$2; shift 2 ;;
    --build) BUILD=$2; shift 2 ;;
    --out) OUT=$2; shift 2 ;;
    *) echo "measure-hil: unknown argument '$1'" >&2; exit 2 ;;
  esac
done
STAAD="$BUILD/src/app/staad/staad"; STAACTL="$BUILD/src/app/staactl/staactl"; BASESIM="$BUILD/tests/hil/basesim"
for exe in "$STAAD" "$STAACTL" "$BASESIM"; do
  [ -x "$exe" ] || { echo "measure-hil: $exe missing (ninja -C $BUILD staad staactl basesim)" >&2; exit 2; }
done
mkdir -p "$OUT"
ROOT=$(pwd)
START=(1.5 4.5 0.0)  # config/staad.yaml's sim.start: the simulated camera's robot stands there

# The shipped config with hal: socketcan on basesim's socket, absolute paths, our socket.
sed -e "s#^robot: .*#robot: $ROOT/config/robots/hsr.yaml#" -e "s#^map: .*#map: $ROOT/config/maps/office.yaml#" \
    -e "s#^hal: .*#hal: socketcan#" \
    -e "s#^\# socketcan: .*#socketcan: {interface: \"unix:$OUT/base.sock\", profile: $ROOT/config/can/hsr_base.yaml}#" \
    -e "s#^  path: /run/staad/staad.sock#  path: $OUT/staad.sock#" \
    config/staad.yaml > "$OUT/staad.yaml"
grep -q "^socketcan: {interface: \"unix:$OUT/base.sock\"" "$OUT/staad.yaml" && grep -q "^hal: socketcan" "$OUT/staad.yaml" ||
  { echo "measure-hil: config/staad.yaml changed shape: cannot switch it to hal: socketcan" >&2; exit 2; }
# The base thread's period and priority, from the config (cyclictest runs at the same).
BASE_HZ=$(sed -n 's/^ *base_hz: *\([0-9.]*\).*/\1/p' "$OUT/staad.yaml")
BASE_PRIO=$(sed -n 's/^ *base: *{priority: *\([0-9]*\).*/\1/p' "$OUT/staad.yaml")
PERIOD_US=$(python3 -c "print(round(1e6 / $BASE_HZ))")

PIDS=()
cleanup() {
  for p in "${PIDS[@]}"; do kill -TERM "$p" 2>/dev/null || true; done
  wait 2>/dev/null || true
}
trap cleanup EXIT

# One line to basesim's control socket, its JSON reply on stdout.
basectl() {
  python3 - "$OUT/basesim.ctl" "$1" <<'PY'
import socket, sys
s = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
s.settimeout(3)
s.connect(sys.argv[1])
s.sendall(sys.argv[2].encode() + b"\n")
buf = b""
while not buf.endswith(b"\n"):
    chunk = s.recv(65536)
    if not chunk: break
    buf += chunk
print(buf.decode().strip())
PY
}

"$BASESIM" --socket "$OUT/base.sock" --control "$OUT/basesim.ctl" --profile config/can/hsr_base.yaml \
  --start "${START[0]},${START[1]},${START[2]}" > "$OUT/basesim.out" 2> "$OUT/basesim.err" &
PIDS+=($!)
for _ in $(seq 100); do basectl state > /dev/null 2>&1 && break; sleep 0.1; done
basectl state > /dev/null || { echo "measure-hil: basesim does not answer (see $OUT/basesim.err)" >&2; exit 1; }

"$STAAD" --config "$OUT/staad.yaml" 2> "$OUT/staad.log" &
STAAD_PID=$!
PIDS+=($STAAD_PID)
for _ in $(seq 300); do "$STAACTL" --socket "$OUT/staad.sock" status > /dev/null 2>&1 && break; sleep 0.1; done
"$STAACTL" --socket "$OUT/staad.sock" status > /dev/null || { echo "measure-hil: staad does not answer (see $OUT/staad.log)" >&2; exit 1; }
"$STAACTL" --socket "$OUT/staad.sock" pose "${START[@]}" > /dev/null  # anchor the odometry where basesim is
grep -E "warning|SCHED" "$OUT/staad.log" >&2 || true

# Goals: the office's rooms in turn, a new one whenever the last is reached or unreachable.
GOALS=(4.5,1.5 13.5,1.5 22.5,1.5 4.5,25.5 13.5,25.5 22.5,25.5 25.5,22.5 10.5,4.5 1.5,4.5)
feeder() {
  local i=0
  while true; do
    local g=${GOALS[$((i % ${#GOALS[@]}))]}
    echo "goal ${g%,*} ${g#*,}: $("$STAACTL" --socket "$OUT/staad.sock" goal "${g%,*}" "${g#*,}" 0 --wait --timeout 400 2>>"$OUT/goals.err" | tail -1)"
    i=$((i + 1))
  done
}
feeder > "$OUT/goals.log" 2>&1 &
FEEDER_PID=$!
PIDS+=($FEEDER_PID)

# cyclictest at the base thread's period and priority (normal scheduling when SCHED_FIFO is
# not permitted), for the same window.
if command -v cyclictest > /dev/null; then
  if chrt -f "$BASE_PRIO" true 2>/dev/null; then CT_POLICY=(-p "$BASE_PRIO"); CT_KIND="fifo $BASE_PRIO"
  else CT_POLICY=(--policy=other -p 0); CT_KIND="other"; fi
  cyclictest -m -q "${CT_POLICY[@]}" -i "$PERIOD_US" -D "$DURATION" -t 1 -h 20000 > "$OUT/cyclictest.txt" 2>&1 &
  PIDS+=($!)
else
  echo "measure-hil: cyclictest missing (apt-get install rt-tests): no anchor" >&2; CT_KIND="none"
fi

# The window: a corruption burst every CORRUPT_EVERY s, a progress line every 10 s (whole
# seconds: bash's SECONDS, no process per poll on a machine being measured).
SECONDS=0
next_corrupt=${CORRUPT_EVERY%.*}; next_progress=10; bursts=0
while :; do
  e=$SECONDS
  [ "$e" -ge "$DURATION" ] && break
  if [ "$CORRUPT_EVERY" != 0 ] && [ "$e" -ge "$next_corrupt" ]; then
    basectl "corrupt $CORRUPT_FRAMES" > /dev/null && bursts=$((bursts + 1))
    next_corrupt=$((next_corrupt + ${CORRUPT_EVERY%.*}))
  fi
  if [ "$e" -ge "$next_progress" ]; then
    "$STAACTL" --socket "$OUT/staad.sock" status --json 2>/dev/null | python3 -c '
import json, sys
s = json.load(sys.stdin)
wake, wire = s["threads"]["base"]["wake"], s["base"]["command_to_wire"]
print("measure-hil: %4s/%s s  %-8s pose (%.1f, %.1f)  base wake p99 %.0f us  command-to-wire p50 %.1f ms  bad frames %d"
      "  bursts %s" % (sys.argv[1], sys.argv[2], s["state"], s["pose"][0], s["pose"][1], wake["p99_us"],
                       wire["p50_us"] / 1000, s["base"]["bad_frames"], sys.argv[3]), file=sys.stderr)' \
      "$e" "$DURATION" "$bursts" || true
    next_progress=$((next_progress + 10))
  fi
  sleep 0.2
done
# The last burst's frames are all out and read before the counts are taken.
for _ in $(seq 50); do
  [ "$(basectl state | python3 -c 'import json,sys; print(json.load(sys.stdin)["state"]["corrupt_left"])')" = 0 ] && break
  sleep 0.1
done
sleep 0.2
[ "$CT_KIND" = none ] || wait "${PIDS[-1]}" || true  # cyclictest ends with the window

"$STAACTL" --socket "$OUT/staad.sock" status --json > "$OUT/status.json"
basectl state > "$OUT/basesim.json"
kill -TERM "$FEEDER_PID" 2>/dev/null || true  # no goals into a stopping daemon
wait "$FEEDER_PID" 2>/dev/null || true
kill -TERM "$STAAD_PID"
wait "$STAAD_PID" || echo "measure-hil: staad exited with $?" >&2
cleanup
trap - EXIT

python3 - "$OUT" "$DURATION" "$CT_KIND" "$PERIOD_US" "$bursts" "$CORRUPT_FRAMES" <<'PY'
import json, re, sys
sys.path.insert(0, "tests/timing")  # the scripts run from the checkout's root
import cyclictest_hist
out, duration, ct_kind, period_us, bursts, frames = sys.argv[1], float(sys.argv[2]), sys.argv[3], int(sys.argv[4]), int(sys.argv[5]), int(sys.argv[6])
s = json.load(open(f"{out}/status.json"))  # the status object
b = json.load(open(f"{out}/basesim.json"))["state"]

def trio(h): return {"p50_us": h["p50_us"], "p99_us": h["p99_us"], "max_us": h["max_us"]}

def cyclic(path): return cyclictest_hist.summary(path, period_us)

bt = s["threads"]["base"]
sent = b["corrupt_sent"]
malformed = sent["bad_checksum"] + sent["wrong_dlc"] + sent["huge_v"]
stale = sent["counter_back"] + sent["reordered"]
log = open(f"{out}/staad.log").read()
goals = open(f"{out}/goals.log").read().splitlines()
summary = {
    "duration_s": duration,
    "base_thread": {
        "realtime": bt["realtime"], "cycles": bt["cycle"]["count"],
        "wake": trio(bt["wake"]), "execution": trio(bt["cycle"]),
        "overruns": bt["cycle"]["overruns"], "execution_overruns": bt["execution_overruns"],
        "late_wakeups": bt["late_wakeups"], "preempted": bt["preempted"], "skipped_periods": bt["skipped_periods"]},
    "command_to_wire": dict(trio(s["base"]["command_to_wire"]), count=s["base"]["command_to_wire"]["count"],
                            unsent=s["base"]["command_to_wire"]["unsent"]),
    "control_thread": {"realtime": s["realtime"], "cycles": s["cycle"]["count"], "execution": trio(s["cycle"]),
                       "wake": trio(s["wake"]), "overruns": s["cycle"]["overruns"]},
    "bad_frames": {"bursts": bursts, "frames_per_burst": frames, "injected": sent,
                   "injected_malformed": malformed, "injected_stale": stale,
                   "counted": s["base"]["bad_frames"], "counted_equals_malformed": s["base"]["bad_frames"] == malformed,
                   "refused_by_basesim": b["bad_frames"]},
    "faults_logged": len(re.findall(r"error: fault", log)),
    "goals": {"finished": len(goals), "reached": sum(1 for g in goals if g.endswith("reached"))},
    "rt_allocations": s["rt_allocations"],
    "cyclictest": None,
}
if ct_kind != "none":
    ct = cyclic(f"{out}/cyclictest.txt")
    summary["cyclictest"] = dict(ct, policy=ct_kind, interval_us=period_us) if ct else {"error": open(f"{out}/cyclictest.txt").read()[-300:]}
json.dump(summary, open(f"{out}/summary.json", "w"), indent=2)

def row(name, h): return f"| {name} | {h['p50_us']:.0f} | {h['p99_us']:.0f} | {h['max_us']:.0f} |"
bf = summary["bad_frames"]
lines = [f"measure-hil: {duration:.0f} s, base thread {'SCHED_FIFO' if bt['realtime'] else 'normal scheduling'}, "
         f"{bt['cycle']['count']} base cycles, {summary['goals']['reached']} of {summary['goals']['finished']} finished goals reached",
         "", "| us | p50 | p99 | max |", "|---|---|---|---|",
         row("base wake-up latency", bt["wake"]), row("base execution", bt["cycle"]),
         row("command-to-wire", s["base"]["command_to_wire"]),
         row("control wake-up latency", s["wake"]), row("control execution", s["cycle"])]
if summary["cyclictest"] and "p50_us" in summary["cyclictest"]:
    lines.append(row(f"cyclictest ({ct_kind}, {period_us} us)", summary["cyclictest"]))
lines += ["",
          f"base overruns {bt['cycle']['overruns']} (execution {bt['execution_overruns']}, late wake-ups {bt['late_wakeups']}, "
          f"preempted {bt['preempted']}), periods skipped {bt['skipped_periods']}; control overruns {s['cycle']['overruns']}",
          f"commands on the wire {s['base']['command_to_wire']['count']}, replaced before sent {s['base']['command_to_wire']['unsent']}",
          f"bad frames: {bursts} bursts, injected malformed {malformed} (checksum {sent['bad_checksum']}, DLC {sent['wrong_dlc']}, "
          f"huge v {sent['huge_v']}) + stale {stale}; counted by staad {bf['counted']} "
          f"({'equal' if bf['counted_equals_malformed'] else 'DIFFERENT'}); staad's frames refused by basesim {b['bad_frames']}",
          f"faults logged {summary['faults_logged']}, rt_allocations {s['rt_allocations']}"]
open(f"{out}/summary.md", "w").write("\n".join(lines) + "\n")
print("\n".join(lines))
print()
print(json.dumps(summary, indent=2))
PY
