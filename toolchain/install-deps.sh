#!/usr/bin/env bash
# Installs every Debian 12 package that building, testing and running staa needs, and the
# npm package @mcap/core into tests/mcap (the flight recorder's independent reader).
#   --aarch64  also the cross compiler, qemu-user and mmdebstrap, and an arm64 sysroot of the
#              project's own with the arm64 libraries (the `aarch64` preset builds against it):
#              $STAA_AARCH64_SYSROOT, default /opt/staa-sysroot-arm64. Never arm64 packages on
#              the host: libyaml-cpp-dev is not multi-arch, its arm64 package removes the host's.
# Idempotent: installs nothing (and does not touch the network) when all are present.
# Run as root, or with sudo available.
set -euo pipefail

usage() { echo "usage: install-deps.sh [--aarch64]" >&2; exit 2; }
aarch64=0
for arg in "$@"; do
  case "$arg" in
    --aarch64) aarch64=1 ;;
    *) usage ;;
  esac
done

PACKAGES=(
  build-essential cmake ninja-build pkg-config git
  libeigen3-dev libccd-dev libpolyclipping-dev libyaml-cpp-dev
  libyaml-dev  # libyaml: the YAML reader (src/io/yaml_tree.cpp); yaml-cpp writes
  libgtest-dev libgmock-dev libbenchmark-dev
  libcli11-dev nlohmann-json3-dev
  clang-14 libclang-rt-14-dev  # the libFuzzer targets (tests/fuzz, the fuzz preset)
  librsvg2-bin   # rsvg-convert: SVG -> PNG for the README picture and experiment plots
  # The timing measurements (tests/timing): instruction counts, the platform's own wake-up
  # latency beside staad's, and a load on every core.
  valgrind rt-tests stress-ng
  libopenni2-dev # OpenNI2: the HSR's head Xtion (hal/openni2, built only when found)
  # ROS 1 (Noetic-era, Debian 12): staad's ROS link (src/app/staad/ros, built only when found)
  # and its tests, which start a master, roslaunch and rosbag of their own.
  libroscpp-dev ros-core-dev python3-rostopic librosbag-dev python3-rosbag
  libtf2-ros-dev libtf2-geometry-msgs-dev libactionlib-dev
  ros-move-base-msgs libmove-base-msgs-dev libnav-msgs-dev libsensor-msgs-dev libgeometry-msgs-dev
  libvisualization-msgs-dev libdiagnostic-msgs-dev libstd-msgs-dev
)
AARCH64_HOST_PACKAGES=(
  g++-aarch64-linux-gnu qemu-user mmdebstrap
  python3  # tests/portability/compare-platforms.sh reads the JSON results
)
# The arm64 packages in the sysroot. The cross compiler brings its own libc and libstdc++
# headers and link files (/usr/aarch64-linux-gnu); the run-time libc and libstdc++ that qemu
# loads come into the sysroot as dependencies of these.
SYSROOT_PACKAGES=(
  libeigen3-dev libccd-dev libpolyclipping-dev libyaml-cpp-dev libyaml-dev
  libgtest-dev libgmock-dev libcli11-dev nlohmann-json3-dev
)
SYSROOT="${STAA_AARCH64_SYSROOT:-/opt/staa-sysroot-arm64}"
STAMP="${SYSROOT}/.staa-sysroot"  # written last: the package list a complete sysroot holds

SUDO=""
need_root() {
  if [ "$(id -u)" -ne 0 ] && [ -z "$SUDO" ]; then
    command -v sudo >/dev/null 2>&1 || { echo "install-deps: need root (or sudo) to $1" >&2; exit 1; }
    SUDO="sudo"
  fi
}

# Installed for the host's architecture (or "all"): an arm64 instance alone does not count,
# as it would not build anything here.
HOST_ARCH="$(dpkg --print-architecture)"
installed_for_host() {
  dpkg-query -W -f='${Architecture} ${Status}\n' "$1" 2>/dev/null |
    grep -Eq "^(${HOST_ARCH}|all) install ok installed$"
}

wanted=("${PACKAGES[@]}")
[ "$aarch64" -eq 1 ] && wanted+=("${AARCH64_HOST_PACKAGES[@]}")
missing=()
for p in "${wanted[@]}"; do
  installed_for_host "$p" || missing+=("$p")
done
# Node.js and npm for the flight recorder's independent MCAP reader (tests/mcap: the MCAP
# project's @mcap/core reads our recordings). Debian's, unless a node and npm are there already
# (another packaging of them would conflict with Debian's npm).
if ! command -v node >/dev/null 2>&1 || ! command -v npm >/dev/null 2>&1; then
  missing+=(nodejs npm)
fi

if [ ${#missing[@]} -eq 0 ]; then
  echo "install-deps: all ${#wanted[@]} packages present"
else
  need_root "install: ${missing[*]}"
  echo "install-deps: installing ${missing[*]}"
  export DEBIAN_FRONTEND=noninteractive
  # Another apt (an unattended upgrade) may hold the lock for a while: wait, do not fail.
  $SUDO apt-get -o DPkg::Lock::Timeout=300 update -qq
  # Plain names: apt takes the host's architecture (and replaces an arm64 instance of a
  # package that is not multi-arch).
  $SUDO apt-get -o DPkg::Lock::Timeout=300 install -y -qq --no-install-recommends "${missing[@]}"
fi

# @mcap/core at the version tests/mcap/package-lock.json pins, into tests/mcap/node_modules
# (the tests look for it there and skip with a message without it).
mcap_dir="$(cd "$(dirname "$0")/.." && pwd)/tests/mcap"
if [ -d "$mcap_dir/node_modules/@mcap/core" ]; then
  echo "install-deps: @mcap/core present in tests/mcap"
else
  echo "install-deps: npm ci in tests/mcap (@mcap/core)"
  npm ci --prefix "$mcap_dir" --no-audit --no-fund --loglevel=error
fi

[ "$aarch64" -eq 1 ] || exit 0

# ---- the arm64 sysroot ----
sysroot_id="bookworm arm64: ${SYSROOT_PACKAGES[*]}"
if [ -f "$STAMP" ] && [ "$(cat "$STAMP")" = "$sysroot_id" ]; then
  echo "install-deps: arm64 sysroot present in ${SYSROOT} (${#SYSROOT_PACKAGES[@]} packages), nothing fetched"
  exit 0
fi

# The Debian mirrors the host's apt uses for bookworm, its updates and security suites (one
# `deb URI SUITE main` line each), so the sysroot gets the host's versions from a mirror that
# is reachable here. Reads deb822 .sources and one-line .list files.
host_mirrors() {
  local files=()
  [ -f /etc/apt/sources.list ] && files+=(/etc/apt/sources.list)
  for f in /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources; do
    [ -f "$f" ] && files+=("$f")
  done
  [ ${#files[@]} -gt 0 ] || return 0
  awk '
    function emit(uri, suite, comps) {
      if (suite ~ /^bookworm(-updates|-security)?$/ && (" " comps " ") ~ / main /)
        print "deb " uri " " suite " main"
    }
    function flush(   n, m, i, j, U, S) {
      if ((" " types " ") ~ / deb / && tolower(enabled) != "no") {
        n = split(uris, U, " "); m = split(suites, S, " ")
        for (i = 1; i <= n; i++) for (j = 1; j <= m; j++) emit(U[i], S[j], comps)
      }
      types = uris = suites = comps = enabled = ""
    }
    FILENAME ~ /\.sources$/ {
      if (FNR == 1) flush()
      if ($0 ~ /^[ \t]*#/) next
      if ($0 ~ /^[ \t]*$/) { flush(); next }
      key = tolower($1); sub(/:$/, "", key); val = $0; sub(/^[^:]*:[ \t]*/, "", val)
      if (key == "types") types = val; else if (key == "uris") uris = val
      else if (key == "suites") suites = val; else if (key == "components") comps = val
      else if (key == "enabled") enabled = val
      next
    }
    FILENAME !~ /\.sources$/ && $1 == "deb" {
      line = $0; sub(/^deb[ \t]+/, "", line); gsub(/\[[^]]*\][ \t]*/, "", line)
      n = split(line, F, /[ \t]+/); c = ""
      for (i = 3; i <= n; i++) c = c " " F[i]
      emit(F[1], F[2], c)
    }
    END { flush() }
  ' "${files[@]}" | awk '!seen[$0]++'
}

mirrors=()
while IFS= read -r line; do mirrors+=("$line"); done < <(host_mirrors)
if [ ${#mirrors[@]} -eq 0 ]; then
  mirrors=("deb http://deb.debian.org/debian bookworm main"
           "deb http://deb.debian.org/debian bookworm-updates main"
           "deb http://deb.debian.org/debian-security bookworm-security main")
fi

need_root "create the sysroot ${SYSROOT}"
echo "install-deps: creating the arm64 sysroot ${SYSROOT} from: $(IFS=';'; echo "${mirrors[*]}")"
start=$(date +%s)
# Built beside the target and moved into place at the end: an interrupted run leaves no
# half-made sysroot that a later run would take as present.
tmp="${SYSROOT}.new"
$SUDO rm -rf "$tmp"
$SUDO mkdir -p "$(dirname "$SYSROOT")"
# The extract variant unpacks the packages and their dependencies without running any
# maintainer script: nothing runs arm64 code, so no binfmt_misc or qemu is needed here.
include="$(IFS=,; echo "${SYSROOT_PACKAGES[*]}")"
$SUDO mmdebstrap --quiet --arch=arm64 --variant=extract --include="$include" \
  bookworm "$tmp" "${mirrors[@]}"
# Absolute symlinks (libc6-dev's libm.so -> /lib/...) would point into the host when the
# cross linker follows them: make them relative to the sysroot.
$SUDO find "$tmp/usr" "$tmp/lib"* -type l -lname '/*' -print0 |
  while IFS= read -r -d '' link; do
    target="$(readlink "$link")"
    $SUDO ln -sfn "$(realpath -m --relative-to="$(dirname "$link")" "$tmp$target")" "$link"
  done
# qemu-aarch64 -L looks up every absolute path in the sysroot first: the empty /tmp and /dev
# that mmdebstrap made would hide the host's from the programs under test.
$SUDO rm -rf "$tmp/tmp" "$tmp/dev"
echo "$sysroot_id" | $SUDO tee "$tmp/.staa-sysroot" >/dev/null
$SUDO rm -rf "$SYSROOT"
$SUDO mv "$tmp" "$SYSROOT"
echo "install-deps: arm64 sysroot ready in ${SYSROOT} ($(( $(date +%s) - start )) s, $(du -sh "$SYSROOT" | cut -f1))"
