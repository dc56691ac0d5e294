#!/usr/bin/env bash
# Runs the same reproducible work with the programs of three builds and compares the results
# bit for bit: the x86-64 release build, an x86-64 build with -march=native (FMA) and the
# aarch64 cross build (run under qemu-aarch64 when this machine is not aarch64). Under an
# expansion budget staa-sim and staa-map depend on nothing but their inputs, so any
# difference is the compiled arithmetic (contracted a*b+c, for one) deciding otherwise.
#
#   tests/portability/compare-platforms.sh [RELEASE_DIR NATIVE_DIR AARCH64_DIR]
#
# Defaults: build/release build/native build/aarch64 (each needs staa-sim and staa-map).
# What is compared: the maps each build makes (staa-map generate office, and import of
# ../shared/maps/ros/depot.yaml when it is there) byte for byte, and, on the release build's
# maps, two staa-sim runs and the staa-map path queries as JSON with the wall-clock fields
# (every key ending in _us) taken out; nlohmann-json prints doubles round-trip, so equal text
# is equal bits. Map making and simulations count as runs, path queries as queries.
# Prints "N runs and M queries compared, all identical" (exit 0), or each difference (exit 1).
# The outputs stay in $STAA_COMPARE_OUT (default: a new folder under /tmp, printed).
set -euo pipefail

repo="$(cd "$(dirname "$0")/../.." && pwd)"
labels=(release native aarch64)
dirs=("${1:-$repo/build/release}" "${2:-$repo/build/native}" "${3:-$repo/build/aarch64}")
[ $# -eq 0 ] || [ $# -eq 3 ] || { echo "usage: $0 [RELEASE_DIR NATIVE_DIR AARCH64_DIR]" >&2; exit 2; }
sysroot="${STAA_AARCH64_SYSROOT:-/opt/staa-sysroot-arm64}"
shared="${STAA_SHARED_DIR:-$repo/../shared}"
out="${STAA_COMPARE_OUT:-$(mktemp -d /tmp/staa-compare.XXXXXX)}"
mkdir -p "$out"

# The ELF machine field (bytes 18-19, little-endian) of a program: b700 aarch64, 3e00 x86-64.
elf_machine() { od -An -tx1 -j18 -N2 "$1" | tr -d ' \n'; }
case "$(uname -m)" in
  x86_64) host_machine=3e00 ;;
  aarch64) host_machine=b700 ;;
  *) host_machine=unknown ;;
esac

# How each build's programs are started: directly, or under qemu-aarch64 with the sysroot.
declare -A runner
for i in "${!labels[@]}"; do
  for prog in staa-sim staa-map; do
    exe="${dirs[$i]}/src/app/$prog/$prog"
    [ -x "$exe" ] || { echo "compare-platforms: no $exe (build $prog in ${dirs[$i]})" >&2; exit 2; }
  done
  machine="$(elf_machine "${dirs[$i]}/src/app/staa-map/staa-map")"
  if [ "$machine" = "$host_machine" ]; then
    runner[${labels[$i]}]=""
  elif [ "$machine" = b700 ]; then
    command -v qemu-aarch64 >/dev/null || { echo "compare-platforms: qemu-aarch64 needed for ${dirs[$i]}" >&2; exit 2; }
    runner[${labels[$i]}]="qemu-aarch64 -L $sysroot"
  else
    echo "compare-platforms: cannot run the programs in ${dirs[$i]} (ELF machine $machine)" >&2
    exit 2
  fi
  mkdir -p "$out/${labels[$i]}"
done

# run LABEL NAME PROGRAM ARGS...: stdout, stderr and exit status to $out/LABEL/NAME.*; the
# literal @OUT@ in ARGS stands for $out/LABEL (for files a program writes).
run() {
  local label="$1" name="$2" prog="$3"; shift 3
  local dir="${dirs[0]}" i
  for i in "${!labels[@]}"; do [ "${labels[$i]}" = "$label" ] && dir="${dirs[$i]}"; done
  local args=() a
  for a in "$@"; do args+=("${a//@OUT@/$out/$label}"); done
  local rc=0
  # shellcheck disable=SC2086  # the runner is a command and its options
  ${runner[$label]} "$dir/src/app/$prog/$prog" "${args[@]}" >"$out/$label/$name.out" 2>"$out/$label/$name.err" || rc=$?
  echo "$rc" >"$out/$label/$name.rc"
}
each() { local l; for l in "${labels[@]}"; do run "$l" "$@"; done; }

runs=() queries=()

# The maps each build makes; the release build's are the input of everything after.
each map-office staa-map generate office -o @OUT@/map-office.yaml
runs+=(map-office)
office="$out/release/map-office.yaml"
depot=""
if [ -f "$shared/maps/ros/depot.yaml" ]; then
  each map-depot staa-map import "$shared/maps/ros/depot.yaml" -o @OUT@/map-depot.yaml --goals 40
  runs+=(map-depot)
  depot="$out/release/map-depot.yaml"
fi
[ -f "$office" ] || { echo "compare-platforms: the release build made no office map (see $out/release)" >&2; exit 1; }

# Short enough for CI: under qemu a cycle costs about 20 times as much (a 20 s
# three-agent run took over ten minutes there). The builds' runs go side by side.
for l in "${labels[@]}"; do
  run "$l" sim-office-3-agents staa-sim --map "$office" --agents 3 --duration 6 --budget-expansions 1000 \
    --seed 3 --quiet --json @OUT@/sim-office-3-agents.json &
  # (1.5,1.5 lies in the office's blocked corner, which staa-sim refuses: 1.5,4.5 is free.)
  run "$l" sim-office-1-robot staa-sim --map "$office" --start 1.5,4.5,0 --goal 22.5,22.5,0 --duration 30 \
    --budget-expansions 1000 --quiet --json @OUT@/sim-office-1-robot.json &
  # The baselines' arithmetic too (their scenario tests run on x86-64 only); the expansion
  # budget also bounds their path queries by work, not time.
  run "$l" sim-office-dwa-ghost staa-sim --map "$office" --agents 3 --mode ghost --controller dwa --duration 6 --budget-expansions 1000 \
    --seed 4 --quiet --json @OUT@/sim-office-dwa-ghost.json &
  run "$l" sim-office-pd staa-sim --map "$office" --agents 3 --controller pd --duration 6 --budget-expansions 1000 \
    --seed 5 --quiet --json @OUT@/sim-office-pd.json &
done
wait
runs+=(sim-office-3-agents sim-office-1-robot sim-office-dwa-ghost sim-office-pd)

office_queries=("1.5,4.5 22.5,1.5" "4.5,1.5 13.5,25.5" "10.5,4.5 1.5,22.5" "2,2 20,11"
                "4.5,4.5 22.5,22.5" "1.5,1.5 22.5,1.5")
for r in 0 0.3; do
  n=0
  for q in "${office_queries[@]}"; do
    n=$((n + 1)); name="path-office-$n-inflate-$r"
    each "$name" staa-map path "$office" --from "${q% *}" --to "${q#* }" --inflate "$r" --json
    queries+=("$name")
  done
done
# Depot: between the first goals the import placed (the release build's map).
if [ -n "$depot" ] && [ -f "$depot" ]; then
  mapfile -t goals < <(sed -n '/^goals:/,$ s/^ *- *\[ *\([-0-9.e]*\), *\([-0-9.e]*\) *\].*/\1,\2/p' "$depot" | head -8)
  for r in 0 0.3; do
    for k in 0 2 4 6; do
      [ -n "${goals[$k]:-}" ] && [ -n "${goals[$((k + 1))]:-}" ] || continue
      name="path-depot-$((k / 2 + 1))-inflate-$r"
      each "$name" staa-map path "$depot" --from "${goals[$k]}" --to "${goals[$((k + 1))]}" --inflate "$r" --json
      queries+=("$name")
    done
  done
fi

# Compares each run's and query's results across the builds (release is the reference).
python3 - "$out" "${#runs[@]}" "${runs[@]}" "${queries[@]}" "--" "${labels[@]}" <<'EOF'
import json, os, sys

out, nruns = sys.argv[1], int(sys.argv[2])
rest = sys.argv[3:]
sep = rest.index("--")
names, labels = rest[:sep], rest[sep + 1:]
ref = labels[0]

def strip(v):
    # Wall-clock figures differ run to run on any machine.
    if isinstance(v, dict):
        return {k: strip(x) for k, x in v.items() if not k.endswith("_us")}
    if isinstance(v, list):
        return [strip(x) for x in v]
    return v

def result(label, name):
    d = os.path.join(out, label)
    with open(os.path.join(d, name + ".rc")) as f:
        rc = f.read().strip()
    for ext, kind in ((".yaml", "text"), (".json", "json"), (".out", "json")):
        p = os.path.join(d, name + ext)
        if not os.path.exists(p):
            continue
        with open(p, "rb") as f:
            data = f.read()
        if kind == "json":
            try:
                # parse_float=str keeps each double's digits exactly as printed
                return rc, strip(json.loads(data, parse_float=str, parse_int=str))
            except ValueError:
                pass
        return rc, data.decode(errors="replace")
    return rc, None

def diffs(a, b, path="$"):
    if type(a) is not type(b):
        yield path, a, b
    elif isinstance(a, dict):
        for k in list(a) + [k for k in b if k not in a]:
            if k not in a or k not in b:
                yield path + "." + k, a.get(k, "<absent>"), b.get(k, "<absent>")
            else:
                yield from diffs(a[k], b[k], path + "." + k)
    elif isinstance(a, list):
        if len(a) != len(b):
            yield path + ".length", len(a), len(b)
        for i, (x, y) in enumerate(zip(a, b)):
            yield from diffs(x, y, "%s[%d]" % (path, i))
    elif a != b:
        if isinstance(a, str) and "\n" in a:
            la, lb = a.splitlines(), b.splitlines()
            i = next((i for i, (x, y) in enumerate(zip(la, lb)) if x != y), min(len(la), len(lb)))
            x, y = (la[i] if i < len(la) else "<end>"), (lb[i] if i < len(lb) else "<end>")
            # Long lines (a polygon's vertices): from just before the first character that differs.
            c = next((c for c, (p, q) in enumerate(zip(x, y)) if p != q), min(len(x), len(y)))
            c = max(0, c - 20)
            yield "%s line %d, column %d" % (path, i + 1, c + 1), "'%s'" % x[c:c + 60], "'%s'" % y[c:c + 60]
        else:
            yield path, a, b

problems = 0
for name in names:
    results = {label: result(label, name) for label in labels}
    if results[ref][0] != "0":
        # A refused or crashed run would compare equal and prove nothing.
        err = os.path.join(out, ref, name + ".err")
        with open(err, errors="replace") as f:
            first = (f.readline().strip() or "no message")
        print("NOT RUN: %s: exit status %s in %s: %s" % (name, results[ref][0], ref, first))
        problems += 1
        continue
    # The builds grouped by equal results, the reference's group first.
    groups = []
    for label in labels:
        for g in groups:
            if results[g[0]] == results[label]:
                g.append(label)
                break
        else:
            groups.append([label])
    if len(groups) == 1:
        continue
    problems += 1
    print("DIFFERENT: %s: %s" % (name, " | ".join(" = ".join(g) for g in groups)))
    r = results[ref]
    for g in groups[1:]:
        o = results[g[0]]
        if o[0] != r[0]:
            print("  %s exit status %s, %s %s" % (ref, r[0], g[0], o[0]))
        found = list(diffs(r[1], o[1]))
        for path, x, y in found[:5]:
            print("  %s: %s %s, %s %s" % (path, ref, x, g[0], y))
        if len(found) > 5:
            print("  ... %d differences in all" % len(found))

summary = "%d runs and %d queries compared" % (nruns, len(names) - nruns)
if problems == 0:
    print(summary + ", all identical")
    sys.exit(0)
print("%s: %d not identical (outputs in %s)" % (summary, problems, out))
sys.exit(1)
EOF
