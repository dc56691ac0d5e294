#!/usr/bin/env python3
"""The jitter tier proves it can fail (issue 15): staad with debug.extra_cycle_us: 20000 (the
control cycle busy-waits 20 ms before its 19 ms planner budget starts, so every driving cycle
runs past the 33.3 ms period on its own work) must make tests/timing/jitter.py exit 1 with a
failure line naming the control thread's overruns as ours. Exit 77 (ctest's skip) without
root, cyclictest or rsvg-convert. BUILD: the build folder (ctest sets it)."""

import os
import re
import shutil
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import jitter  # noqa: E402

SKIP = 77
DURATION_S = "20"


def main():
    if os.geteuid() != 0:
        print("skipped: the jitter tier needs root (SCHED_FIFO, mlockall)")
        return SKIP
    for tool in ("cyclictest", "rsvg-convert"):
        if shutil.which(tool) is None:
            print(f"skipped: {tool} missing (toolchain/install-deps.sh installs it)")
            return SKIP
    out = tempfile.mkdtemp(prefix="staa-jitter-selftest-")
    text = open(jitter.shipped_config(out)).read()
    slow = text.replace("debug:\n  faults: false\n", "debug:\n  faults: true\n  extra_cycle_us: 20000\n")
    assert slow != text, "config/staad.yaml's debug section changed: update this test"
    config = os.path.join(out, "slow.yaml")
    with open(config, "w") as f:
        f.write(slow)
    env = dict(os.environ, BUILD=os.environ.get("BUILD", "build/release"))
    r = subprocess.run([sys.executable, os.path.join(HERE, "jitter.py"), "--duration", DURATION_S, "--config", config,
                        "--out", out], capture_output=True, text=True, env=env, timeout=180)
    print(r.stdout, end="")
    print(r.stderr, end="", file=sys.stderr)
    ok = True
    if r.returncode != 1:
        print(f"FAIL: jitter.py exited {r.returncode}, want 1 (a failed gate)", file=sys.stderr)
        ok = False
    ours = [line for line in r.stderr.splitlines()
            if re.match(r"^jitter: control: [1-9][0-9]* overruns ours \(execution past the 33\.3 ms period\)$", line)]
    if not ours:
        print("FAIL: no stderr line 'jitter: control: N overruns ours (execution past the 33.3 ms period)'",
              file=sys.stderr)
        ok = False
    if ok:
        shutil.rmtree(out, ignore_errors=True)
        print("ok: the jitter tier failed and named the overruns as ours: " + ours[0])
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
