#!/usr/bin/env bash
# The house's two include rules (docs/ARCHITECTURE.md, "Layout"), checked on the source tree:
#  1. Includes point down: each folder of src/, rt/ and hal/ includes only the folders listed
#     for it below (its floor and the floors beneath).
#  2. No file under src/ includes a POSIX or Linux system header: the OS is reached through
#     rt/ (threads, clocks, sockets, signals) and hal/ (devices).
# Usage: check-includes.sh [SOURCE_DIR]. Prints one line per violation and the include matrix;
# exits 1 on any violation.
set -euo pipefail
root="${1:-$(cd "$(dirname "$0")/../.." && pwd)}"
cd "$root"

# What each folder may include (besides itself). Bottom floor first.
declare -A allowed=(
  [geometry]=""
  [io]="geometry"
  [rt]=""
  [robot]="geometry io"
  [map]="geometry io"
  [hal]="geometry io robot rt"
  [path]="geometry map"
  [viz]="geometry map"
  [local]="geometry path"
  [planner]="geometry local path robot"
  [perception]="geometry hal io map"
  [control]="geometry local map path planner robot"
  [world]="geometry hal io map path robot rt"
  [record]="control geometry io local map path planner robot"
  [experiment]="control geometry hal map perception planner record robot viz world"
  [app]="control experiment geometry hal io local map path perception planner record robot rt viz world"
)
folder_path() { case "$1" in rt|hal) echo "$1" ;; *) echo "src/$1" ;; esac; }

# POSIX and Linux headers (the C library's .h forms of signals, errno and time included:
# src/ uses the C++ headers).
posix='(sys|linux|net|netinet|arpa|asm|bits)/[A-Za-z0-9_]+\.h|(unistd|fcntl|pthread|signal|poll|sched|semaphore|dirent|termios|dlfcn|spawn|syslog|pwd|grp|mqueue|aio|malloc|execinfo|errno|time|ifaddrs|netdb)\.h'

violations=0
for f in "${!allowed[@]}"; do
  dir=$(folder_path "$f")
  [[ -d "$dir" ]] || { echo "check-includes: folder $dir is missing (the table lists it)"; violations=$((violations + 1)); continue; }
  while IFS=: read -r file line inc; do
    target=$(sed -E 's/.*#include "([a-z_0-9]+)\/.*/\1/' <<<"$inc")
    [[ "$target" == "$f" ]] && continue
    [[ -v "allowed[$target]" ]] || continue  # not a project folder (a third-party header)
    if [[ " ${allowed[$f]} " != *" $target "* ]]; then
      echo "$file:$line: $f includes $target (upward or sideways): $inc"
      violations=$((violations + 1))
    fi
  done < <(grep -rnE '^\s*#\s*include "[a-z_0-9]+/' "$dir" --include='*.hpp' --include='*.cpp' --include='*.h' || true)
done
# Folders the table does not know would escape rule 1.
for d in src/*/; do
  d=$(basename "$d")
  [[ -v "allowed[$d]" ]] || { echo "check-includes: src/$d is not in the layering table"; violations=$((violations + 1)); }
done
while IFS=: read -r file line inc; do
  echo "$file:$line: a POSIX/Linux header under src/ (use rt/ or hal/): $inc"
  violations=$((violations + 1))
done < <(grep -rnE "^\s*#\s*include <(${posix})>" src --include='*.hpp' --include='*.cpp' --include='*.h' || true)

echo "check-includes: who includes whom (row includes column):"
for f in geometry io rt robot map hal path viz local planner perception control world experiment app; do
  used=$(grep -rhoE '^\s*#\s*include "[a-z_0-9]+/' "$(folder_path "$f")" --include='*.hpp' --include='*.cpp' 2>/dev/null |
         sed -E 's/.*"([a-z_0-9]+)\/.*/\1/' | sort -u | grep -vx "$f" | tr '\n' ' ' || true)
  printf '  %-11s %s\n' "$f" "${used:-(nothing)}"
done
if (( violations > 0 )); then
  echo "check-includes: ${violations} violation(s)"
  exit 1
fi
echo "check-includes: no upward include, no POSIX header under src/"
