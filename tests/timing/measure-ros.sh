#!/usr/bin/env bash
# staad over ROS 1 beside staad on the simulated base, for DURATION seconds each, at the
# same time on the same machine: the odometry-to-twist latency through ROS (the stamp of the
# odometry a command was planned on to the twist's publication: staad's status
# ros.odometry_to_twist), both control threads' timing, and the CPU time of staad's ROS
# threads (every thread but its real-time ones and the service thread). Prints one JSON
# object. Needs a release build with ROS (build/release) and ../shared/maps/ros/depot.yaml.
#   bash tests/timing/measure-ros.sh [DURATION_S=600] [BUILD=build/release]
set -euo pipefail
cd "$(dirname "$0")/../.."
duration="${1:-600}"
build="${2:-build/release}"
depot="$(cd .. && pwd)/shared/maps/ros/depot.yaml"
[ -f "$depot" ] || { echo "measure-ros: $depot not found" >&2; exit 2; }
dir="$(mktemp -d /tmp/staa-measure-ros.XXXXXX)"
pids=()
cleanup() { for p in "${pids[@]}"; do kill -TERM -- "-$p" 2>/dev/null || true; done; sleep 1; rm -rf "$dir"; }
trap cleanup EXIT
port=$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1",0)); print(s.getsockname()[1])')
export ROS_MASTER_URI="http://127.0.0.1:${port}" ROS_HOME="$dir/ros" ROS_LOG_DIR="$dir/ros/log" ROS_IP=127.0.0.1
spawn() { setsid "$@" > "$dir/$(basename "$1").$RANDOM.log" 2>&1 & pids+=($!); }
spawn rosmaster --core -p "$port"
sleep 2
spawn "$build/tests/ros/staa-test-map-publisher" "$depot"
spawn "$build/tests/ros/staa-test-hsrb-base" _x:=10 _y:=2.25
cat > "$dir/ros.yaml" <<YAML
format: staad-config/1
robot: $(pwd)/config/robots/hsr.yaml
map: ros
hal: ros
obstacles: none
socket: {path: $dir/ros.sock}
YAML
cat > "$dir/sim.yaml" <<YAML
format: staad-config/1
robot: $(pwd)/config/robots/hsr.yaml
map: $(pwd)/config/maps/office.yaml
hal: sim
obstacles: sim
sim: {start: [1.5, 4.5, 0.0], movers: 3, seed: 1}
socket: {path: $dir/sim.sock}
YAML
spawn "$build/src/app/staad/staad" --config "$dir/ros.yaml"
ros_pid=$!
spawn "$build/src/app/staad/staad" --config "$dir/sim.yaml"
sleep 4
ctl() { "$build/src/app/staactl/staactl" --socket "$1" "${@:2}"; }
# Goals back and forth in each world for the whole duration.
end=$(( $(date +%s) + duration ))
i=0
while [ "$(date +%s)" -lt "$end" ]; do
  if [ $((i % 2)) -eq 0 ]; then
    ctl "$dir/ros.sock" goal 13.0 2.25 0 >/dev/null; ctl "$dir/sim.sock" goal 10.5 4.5 0 >/dev/null
  else
    ctl "$dir/ros.sock" goal 10.0 2.25 3.14159 >/dev/null; ctl "$dir/sim.sock" goal 1.5 4.5 3.14159 >/dev/null
  fi
  i=$((i + 1))
  sleep 20
done
ctl "$dir/ros.sock" status --json > "$dir/ros.json"
ctl "$dir/sim.sock" status --json > "$dir/sim.json"
# CPU time (utime + stime, clock ticks) of staad's threads by name.
for t in /proc/"$ros_pid"/task/*; do
  echo "$(basename "$t") $(cat "$t/comm") $(awk '{print $14 + $15}' "$t/stat")"
done > "$dir/threads.txt"
echo "$ros_pid" > "$dir/ros.pid"
python3 - "$dir" "$duration" "$(getconf CLK_TCK)" <<'PY'
import json, sys, os
d, duration, tck = sys.argv[1], float(sys.argv[2]), float(sys.argv[3])
ros = json.load(open(os.path.join(d, "ros.json")))
sim = json.load(open(os.path.join(d, "sim.json")))
rt_names = {"staad-control", "staad-base", "staad-percept"}
pid = open(os.path.join(d, "ros.pid")).read().strip()
cpu = {"ros_threads_s": 0.0, "ros_threads": 0, "realtime_threads_s": 0.0, "service_thread_s": 0.0}
for line in open(os.path.join(d, "threads.txt")):
    tid, name, ticks = line.split()
    s = float(ticks) / tck
    if name in rt_names: cpu["realtime_threads_s"] += s
    elif tid == pid: cpu["service_thread_s"] += s
    else:  # roscpp's threads (named after the process) and staad-ros-pub
        cpu["ros_threads_s"] += s
        cpu["ros_threads"] += 1
cpu["ros_threads_percent_of_a_core"] = 100.0 * cpu["ros_threads_s"] / duration
def cyc(s): return {"cycle": s["cycle"], "wake": s["wake"], "rt_allocations": s["rt_allocations"]}
print(json.dumps({"duration_s": duration, "odometry_to_twist": ros["ros"]["odometry_to_twist"],
                  "twists_out": ros["ros"]["twists_out"], "ros_control": cyc(ros), "sim_control": cyc(sim),
                  "ros_goals": ros["goal_id"], "cpu": cpu}, indent=1))
PY
