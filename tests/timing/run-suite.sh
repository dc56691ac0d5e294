#!/bin/bash
# The timing suite: the cost tier (instructions per cycle under callgrind, gated against
# tests/timing/baseline.json) and the jitter tier (the real staad beside cyclictest). The
# command is a contract (docs/ARCHITECTURE.md, "The timing suite"):
#
#   tests/timing/run-suite.sh [--tier cost|jitter|all] [--duration S] [--stress] \
#       [--baseline FILE] [--config STAAD_YAML] [--out DIR] [--update-baseline]
#
# BUILD names the build folder (default build/release). Exit 0: every gate holds; 1: one
# does not (one line per failed gate on stderr); 2: bad usage or a missing tool.
set -euo pipefail
cd "$(dirname "$0")/../.."
command -v python3 > /dev/null || { echo "run-suite: python3 missing" >&2; exit 2; }
exec python3 tests/timing/suite.py "$@"
