"""The timing suite's cost tier (docs/ARCHITECTURE.md, "The timing suite").

Runs every workload of staa-cost under callgrind, one dump per measured cycle, and compares
the executed instructions with a baseline in the schema of the suite's report.json. The
counts repeat exactly for the same binary on any x86-64 machine with the same libraries
(valgrind's virtual CPU), unlike the wall clock of a shared virtual machine.
"""

import concurrent.futures
import glob
import json
import math
import os
import re
import shutil
import subprocess
import time

# Measured cycles per workload: a STAA* cycle costs about 0.5 s under callgrind, so the tier
# stays within its 5 minutes on two cores.
CYCLES = {
    "cycle.office_empty": 100,
    "cycle.office_people": 100,
    "cycle.depot": 100,
    "cycle.clutter": 100,
    "path.mc_cycle": 150,
    "path.mc_cold": 40,
    "local.update": 150,
    "perception.depth": 60,
    "can.codec_round": 200,
}
# A workload whose instructions (in all, or in its most expensive cycle) are above the
# baseline by more than this fails; below it by more than this, the report says so.
TOLERANCE = 0.03

VALGRIND = ["valgrind", "--tool=callgrind", "--collect-atstart=no", "--instr-atstart=no",
            "--dump-instr=no", "--dump-line=no"]


class UsageError(Exception):
    """Bad usage or a missing tool: the suite exits 2."""


def percentile(values, p):
    """Nearest rank: the smallest value with at least p of the values at or below it."""
    if not values:
        return 0
    s = sorted(values)
    k = max(0, min(len(s) - 1, math.ceil(p * len(s)) - 1))
    return s[k]


def dump_totals(prefix):
    """Instructions of every dump `prefix.N` in the order written (the final dump, written at
    exit with collection off, has no suffix and is left out)."""
    dumps = []
    for path in glob.glob(prefix + ".*"):
        suffix = path[len(prefix) + 1:]
        if suffix.isdigit():
            dumps.append((int(suffix), path))
    totals = []
    for _, path in sorted(dumps):
        total = None
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                m = re.match(r"^(?:totals|summary):\s+(\d+)", line)
                if m:
                    total = int(m.group(1))
        if total is None:
            raise RuntimeError(f"{path}: no totals line (not a callgrind dump?)")
        totals.append(total)
    return totals


ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


def shared_dir():
    """../shared beside the checkout, or STAA_SHARED_DIR (a missing one: its workloads skip)."""
    return os.environ.get("STAA_SHARED_DIR") or os.path.join(os.path.dirname(ROOT), "shared")


def run_workload(staa_cost, name, cycles, work):
    """One workload under callgrind: its per-cycle instructions and algorithm counts."""
    prefix = os.path.join(work, name)
    for old in glob.glob(prefix + ".*"):
        os.remove(old)
    counts_json = os.path.join(work, name + ".counts.json")
    cmd = VALGRIND + [f"--callgrind-out-file={name}.%p", "./staa-cost", "run", name, "--cycles", str(cycles),
                      "--root", "src", "--shared", "shared", "--scenes", "src/tests/timing/scenes",
                      "--json", name + ".counts.json"]
    env = {"PATH": "/usr/bin:/bin", "LC_ALL": "C", "HOME": "/nonexistent"}
    start = time.monotonic()
    proc = subprocess.run(cmd, cwd=work, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                          check=False)
    seconds = time.monotonic() - start
    if proc.returncode != 0:
        tail = "\n".join(proc.stderr.strip().splitlines()[-5:])
        raise RuntimeError(f"{name}: staa-cost under valgrind exited {proc.returncode}:\n{tail}")
    with open(counts_json, encoding="utf-8") as f:
        doc = json.load(f)
    if "skipped" in doc:
        return {"name": name, "skipped": doc["skipped"], "seconds": round(seconds, 1)}
    pids = {re.sub(r"\.\d+$", "", p) for p in glob.glob(prefix + ".*.*") if re.search(r"\.\d+\.\d+$", p)}
    if len(pids) != 1:
        raise RuntimeError(f"{name}: expected the dumps of one valgrind run under {prefix}.PID.N, found {sorted(pids)}")
    per_cycle = dump_totals(pids.pop())
    if len(per_cycle) != cycles:
        raise RuntimeError(f"{name}: {len(per_cycle)} callgrind dumps for {cycles} cycles")
    return {"name": name, "cycles": cycles, "per_cycle_instructions": per_cycle,
            "algorithm": doc.get("per_cycle", []), "seconds": round(seconds, 1)}


def summarize_counts(per_cycle):
    """The algorithm's own counts summed over the cycles (the numeric fields)."""
    sums = {}
    for c in per_cycle:
        for k, v in c.items():
            if isinstance(v, (int, float)) and not isinstance(v, bool):
                sums[k] = sums.get(k, 0) + v
    return sums


def load_baseline(path):
    """name -> workload entry of a report.json (or a baseline in its schema)."""
    try:
        with open(path, encoding="utf-8") as f:
            doc = json.load(f)
    except FileNotFoundError as e:
        raise UsageError(f"cost: baseline {path} not found (run-suite.sh --tier cost --update-baseline writes it)") from e
    except json.JSONDecodeError as e:
        raise UsageError(f"cost: baseline {path}: not JSON ({e})") from e
    try:
        return {w["name"]: w for w in doc["cost"]["workloads"]}
    except (KeyError, TypeError) as e:
        raise UsageError(f"cost: baseline {path}: not a report.json with cost.workloads ({e!r} missing)") from e


def machine():
    """What the counts were taken on (they depend on the binary and libraries, not the CPU's speed)."""
    model = ""
    try:
        out = subprocess.run(["lscpu"], stdout=subprocess.PIPE, text=True, check=False).stdout
        m = re.search(r"^Model name:\s*(.+)$", out, re.M)
        model = m.group(1).strip() if m else ""
    except OSError:
        pass
    version = subprocess.run(["valgrind", "--version"], stdout=subprocess.PIPE, text=True, check=False).stdout.strip()
    return {"cpu": model, "valgrind": version}


def compare(entry, base):
    """Fills the entry's baseline fields; returns the failed-gate lines and notes."""
    failures, notes = [], []
    name = entry["name"]
    if base is None or "instructions" not in base:
        entry.update({"baseline": None, "ratio": None, "ok": False})
        failures.append(f"cost: {name}: {entry['instructions']} instructions, no baseline "
                        "(a new workload: run-suite.sh --tier cost --update-baseline)")
        return failures, notes
    ratio = entry["instructions"] / base["instructions"] if base["instructions"] else float("inf")
    base_max = base.get("per_cycle", {}).get("max")
    max_ratio = entry["per_cycle"]["max"] / base_max if base_max else None
    entry.update({"baseline": base["instructions"], "ratio": round(ratio, 4),
                  "baseline_max": base_max, "max_ratio": round(max_ratio, 4) if max_ratio is not None else None})
    ok = True
    if base.get("cycles") not in (None, entry["cycles"]):
        ok = False
        failures.append(f"cost: {name}: {entry['cycles']} cycles measured, the baseline has {base['cycles']} "
                        "(not comparable: update the baseline)")
    if ratio > 1 + TOLERANCE:
        ok = False
        failures.append(f"cost: {name}: {entry['instructions']} instructions, baseline {base['instructions']}, "
                        f"ratio {ratio:.3f} (more than {TOLERANCE:.0%} above)")
    if max_ratio is not None and max_ratio > 1 + TOLERANCE:
        ok = False
        failures.append(f"cost: {name}: its most expensive cycle {entry['per_cycle']['max']} instructions, baseline "
                        f"{base_max}, ratio {max_ratio:.3f} (more than {TOLERANCE:.0%} above)")
    if ok and ratio < 1 - TOLERANCE:
        notes.append(f"cost: {name}: {entry['instructions']} instructions, {1 - ratio:.1%} below the baseline "
                     f"{base['instructions']} (update the baseline: run-suite.sh --tier cost --update-baseline, "
                     "in a commit that says why the cost changed)")
    entry["ok"] = ok
    return failures, notes


def run_cost(build, baseline, out_dir, update_baseline=False, only=None, jobs=None, log=print):
    """Runs the tier. Returns (the report's "cost" section, failed-gate lines)."""
    if shutil.which("valgrind") is None:
        raise UsageError("cost: valgrind missing (apt-get install valgrind, or toolchain/install-deps.sh)")
    staa_cost = os.path.join(build, "tests/timing/staa-cost")
    if not os.access(staa_cost, os.X_OK):
        raise UsageError(f"cost: {staa_cost} not found (build the release preset first; BUILD= names another build)")
    names = subprocess.run([staa_cost, "list"], stdout=subprocess.PIPE, text=True, check=True).stdout.split()
    if only:
        unknown = sorted(set(only) - set(names))
        if unknown:
            raise UsageError(f"cost: unknown workload(s) {', '.join(unknown)} (staa-cost list: {', '.join(names)})")
        names = [n for n in names if n in only]
    missing = [n for n in names if n not in CYCLES]
    if missing:
        raise UsageError(f"cost: no cycle count for workload(s) {', '.join(missing)} in tests/timing/cost.py")
    work = os.path.join(out_dir, "callgrind")
    os.makedirs(work, exist_ok=True)
    base = {} if update_baseline else load_baseline(baseline)
    # The same argv and environment wherever the checkout and the output are: the program's
    # allocations before the measured cycles, and so the heap's layout, then stay the same
    # (a longer path moved buffers and changed memset's instructions by 0.1 %). Made once,
    # before the workloads run in parallel.
    for link, target in {"staa-cost": staa_cost, "src": ROOT, "shared": shared_dir()}.items():
        path = os.path.join(work, link)
        if os.path.islink(path) or os.path.exists(path):
            os.remove(path)
        os.symlink(os.path.realpath(target), path)

    start = time.monotonic()
    jobs = jobs or max(1, min(2, os.cpu_count() or 1))
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        futures = {n: pool.submit(run_workload, staa_cost, n, CYCLES[n], work) for n in names}
        results = {n: f.result() for n, f in futures.items()}
    failures, notes, workloads = [], [], []
    for n in names:
        r = results[n]
        if "skipped" in r:
            workloads.append({"name": n, "skipped": r["skipped"], "ok": True})
            notes.append(f"cost: {n}: skipped ({r['skipped']})")
            continue
        ir = r["per_cycle_instructions"]
        entry = {"name": n, "cycles": r["cycles"], "instructions": sum(ir),
                 "per_cycle": {"p50": percentile(ir, 0.5), "p99": percentile(ir, 0.99), "max": max(ir)},
                 "algorithm": summarize_counts(r["algorithm"]), "seconds": r["seconds"]}
        if not update_baseline:
            f, nt = compare(entry, base.get(n))
            failures += f
            notes += nt
        else:
            entry["ok"] = True
        workloads.append(entry)
        log(f"cost: {n}: {entry['instructions']} instructions in {r['cycles']} cycles, per cycle p50 "
            f"{entry['per_cycle']['p50']} p99 {entry['per_cycle']['p99']} max {entry['per_cycle']['max']}"
            + (f", ratio {entry['ratio']:.3f}" if entry.get("ratio") is not None else "") + f" ({r['seconds']} s)")
    if not update_baseline:
        ran = {w["name"] for w in workloads}
        for n in sorted(set(base) - ran):
            if not only:
                failures.append(f"cost: {n}: in the baseline but not measured (a workload was removed: update the baseline)")
    for line in notes:
        log(line)
    section = {"ok": not failures, "tolerance": TOLERANCE, "seconds": round(time.monotonic() - start, 1),
               "machine": machine(), "workloads": workloads}
    return section, failures
