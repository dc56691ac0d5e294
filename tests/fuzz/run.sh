#!/usr/bin/env bash
# Runs the libFuzzer targets of the fuzz preset (docs/ARCHITECTURE.md, "Fuzzing"). Builds
# nothing: `cmake --preset fuzz && cmake --build --preset fuzz` first.
#
#   tests/fuzz/run.sh [--seconds N] [--target NAME] [--jobs J]    (BUILD=build/fuzz by default)
#
# For each target (or the one named): replays tests/fuzz/regressions/NAME/* (every crash
# found was fixed and its input kept there), then fuzzes for N seconds (default 20) from the
# committed seeds (tests/fuzz/corpus/NAME), the repository's real files and ../shared/maps/ros
# (copied into BUILD/fuzz/seeds at run time), growing a working corpus in BUILD/fuzz/corpus.
# --jobs J runs J targets at a time (CI: 2, one per core). Exit 0: no target crashed; 1: one
# did (named, with the crash file); 2: bad usage or no build.
set -uo pipefail

ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)"
BUILD="${BUILD:-$ROOT/build/fuzz}"
SHARED="${STAA_SHARED_DIR:-$ROOT/../shared}"
SECONDS_EACH=20
ONLY=""
JOBS=1
usage() { echo "usage: tests/fuzz/run.sh [--seconds N] [--target NAME] [--jobs J]   (BUILD=$BUILD)" >&2; exit 2; }
while [ $# -gt 0 ]; do
  case "$1" in
    --seconds) [ $# -ge 2 ] && [[ "$2" =~ ^[0-9]+$ ]] && [ "$2" -gt 0 ] || usage; SECONDS_EACH="$2"; shift 2 ;;
    --target) [ $# -ge 2 ] || usage; ONLY="$2"; shift 2 ;;
    --jobs) [ $# -ge 2 ] && [[ "$2" =~ ^[0-9]+$ ]] && [ "$2" -gt 0 ] || usage; JOBS="$2"; shift 2 ;;
    -h|--help) usage ;;
    *) usage ;;
  esac
done

ALL=(polygon_map ros_map_yaml pgm robot_profile scenario can_profile can_codec protocol daemon_config
     depth_perception ros_depth_image ros_laser_scan)
if [ -n "$ONLY" ]; then
  [[ " ${ALL[*]} " == *" $ONLY "* ]] || { echo "run.sh: no target '$ONLY' (targets: ${ALL[*]})" >&2; exit 2; }
  TARGETS=("$ONLY")
else
  TARGETS=("${ALL[@]}")
fi
for t in "${TARGETS[@]}"; do
  [ -x "$BUILD/tests/fuzz/fuzz_$t" ] || { echo "run.sh: $BUILD/tests/fuzz/fuzz_$t missing: cmake --preset fuzz && cmake --build --preset fuzz" >&2; exit 2; }
done

# The dictionary and the largest input of each target; the real files its seeds come from.
dict_of() {
  case "$1" in
    protocol) echo json.dict ;;
    pgm) echo pgm.dict ;;
    can_codec) echo can.dict ;;
    depth_perception|ros_depth_image|ros_laser_scan) echo depth.dict ;;
    *) echo yaml.dict ;;
  esac
}
max_len_of() {
  case "$1" in
    pgm) echo 16384 ;;  # the shared maps' images are larger: seeds, cut to this while fuzzing
    depth_perception|ros_depth_image|ros_laser_scan) echo 8192 ;;
    protocol) echo 8192 ;;  # beyond kMaxRequestBytes
    *) echo 8192 ;;
  esac
}
real_seeds() {
  case "$1" in
    polygon_map) ls "$ROOT"/config/maps/*.yaml ;;
    robot_profile) ls "$ROOT"/config/robots/*.yaml ;;
    can_profile) ls "$ROOT"/config/can/*.yaml ;;
    daemon_config) ls "$ROOT"/config/staad*.yaml ;;
    ros_map_yaml) ls "$SHARED"/maps/ros/*.yaml 2>/dev/null ;;
    pgm) ls "$SHARED"/maps/ros/*.pgm 2>/dev/null ;;
  esac
}

export ASAN_OPTIONS="${ASAN_OPTIONS:-abort_on_error=1:detect_leaks=1:allocator_may_return_null=1}"
export UBSAN_OPTIONS="${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}"
# One target: its regressions replayed, then fuzzed; its summary line in $BUILD/fuzz/summary/NAME.
# Returns 1 when it crashed.
run_target() {
  local t="$1"
  local exe="$BUILD/tests/fuzz/fuzz_$t"
  local work="$BUILD/fuzz/corpus/$t" seeds="$BUILD/fuzz/seeds/$t" crashes="$BUILD/fuzz/crashes/$t" log="$BUILD/fuzz/logs/$t.log"
  mkdir -p "$work" "$seeds" "$crashes" "$(dirname "$log")" "$BUILD/fuzz/summary"
  rm -f "$BUILD/fuzz/summary/$t"
  real_seeds "$t" | while read -r f; do cp -f "$f" "$seeds/"; done
  [ -d "$ROOT/tests/fuzz/corpus/$t" ] && cp -f "$ROOT/tests/fuzz/corpus/$t"/* "$seeds/" 2>/dev/null

  local regressions=("$ROOT/tests/fuzz/regressions/$t"/*)
  if [ -e "${regressions[0]}" ]; then
    if ! nice -n 10 "$exe" -runs=1 "${regressions[@]}" >"$log.regressions" 2>&1; then
      echo "run.sh: $t: a regression input crashes again (log: $log.regressions)" >&2
      grep -m1 "Running: " "$log.regressions" | tail -1 >&2
      return 1
    fi
  fi

  echo "== $t: ${SECONDS_EACH} s" >&2
  nice -n 10 "$exe" -max_total_time="$SECONDS_EACH" -timeout=10 -rss_limit_mb=2048 -max_len="$(max_len_of "$t")" \
    -dict="$ROOT/tests/fuzz/$(dict_of "$t")" -print_final_stats=1 -artifact_prefix="$crashes/" \
    "$work" "$seeds" >"$log" 2>&1
  local rc=$?
  if [ $rc -ne 0 ]; then
    local crash
    crash="$(grep -o "Test unit written to .*" "$log" | tail -1 | sed 's/Test unit written to //')"
    echo "run.sh: $t crashed (exit $rc): ${crash:-see $log}; log: $log" >&2
    grep -m3 "ERROR: \|runtime error\|contract violated" "$log" >&2
    return 1
  fi
  local last cov ft corp execs runs
  last="$(grep -E "^#[0-9]+[[:space:]]+(DONE|pulse|NEW|REDUCE)" "$log" | tail -1)"
  cov="$(sed -n 's/.* cov: \([0-9]*\).*/\1/p' <<<"$last")"
  ft="$(sed -n 's/.* ft: \([0-9]*\).*/\1/p' <<<"$last")"
  corp="$(sed -n 's/.* corp: \([0-9]*\/[0-9A-Za-z]*\).*/\1/p' <<<"$last")"
  execs="$(sed -n 's/^stat::average_exec_per_sec: *//p' "$log")"
  runs="$(sed -n 's/^stat::number_of_executed_units: *//p' "$log")"
  printf '%-17s %9s %10s %6s %6s %14s\n' "$t" "${execs:-?}" "${runs:-?}" "${cov:-?}" "${ft:-?}" "${corp:-?}" >"$BUILD/fuzz/summary/$t"
}

failed=0
running=0
for t in "${TARGETS[@]}"; do
  if [ "$JOBS" -eq 1 ]; then
    run_target "$t" || exit 1
    continue
  fi
  run_target "$t" &
  running=$((running + 1))
  if [ "$running" -ge "$JOBS" ]; then
    wait -n || failed=1
    running=$((running - 1))
  fi
done
while [ "$running" -gt 0 ]; do
  wait -n || failed=1
  running=$((running - 1))
done
[ "$failed" -eq 0 ] || exit 1
printf '%-17s %9s %10s %6s %6s %14s\n' target exec/s runs cov ft corpus/bytes
for t in "${TARGETS[@]}"; do cat "$BUILD/fuzz/summary/$t"; done
exit 0
