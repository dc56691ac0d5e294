"""tests/timing/run-suite.sh: the timing suite (docs/ARCHITECTURE.md, "The timing suite").

  run-suite.sh [--tier cost|jitter|all] [--duration S] [--stress] [--baseline FILE]
               [--config STAAD_YAML] [--out DIR] [--update-baseline] [--workload W ...]

Exit 0 when every gate holds, 1 when one does not (one line per failed gate on stderr), 2 on
bad usage or a missing tool. DIR/report.json holds both tiers' sections.
"""

import argparse
import json
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import cost  # noqa: E402

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))


class Parser(argparse.ArgumentParser):
    def error(self, message):
        self.print_usage(sys.stderr)
        print(f"run-suite: {message}", file=sys.stderr)
        sys.exit(2)


def main(argv):
    p = Parser(prog="run-suite.sh", description="The timing suite: cost (instructions under callgrind) and jitter "
               "(the real staad beside cyclictest). BUILD names the build folder (default build/release).")
    p.add_argument("--tier", choices=["cost", "jitter", "all"], default="all")
    p.add_argument("--duration", type=float, default=60.0, help="the jitter run's length in seconds (default 60)")
    p.add_argument("--stress", action="store_true", help="stress-ng on both cores during the jitter run")
    p.add_argument("--baseline", default=os.path.join(ROOT, "tests/timing/baseline.json"))
    p.add_argument("--config", default=None, help="staad's config for the jitter run (default config/staad.yaml)")
    p.add_argument("--out", default="/tmp/staa-timing")
    p.add_argument("--update-baseline", action="store_true",
                   help="measure the cost tier and write it as the baseline (commit it with why the cost changed)")
    p.add_argument("--workload", action="append", default=None, help="cost: only this workload (repeatable)")
    p.add_argument("--long-run", action="store_true",
                   help="jitter: also gate wake-up p99 against cyclictest's (documented long runs; implied from 600 s)")
    a = p.parse_args(argv)
    if a.duration <= 0 or a.duration != a.duration or a.duration > 86400:
        p.error(f"--duration {a.duration}: expected seconds in (0, 86400]")
    if a.update_baseline and a.tier == "jitter":
        p.error("--update-baseline updates the cost tier's baseline: use it with --tier cost or all")
    if a.config is not None and not os.path.isfile(a.config):
        p.error(f"--config {a.config}: no such file")
    build = os.environ.get("BUILD", "build/release")
    if not os.path.isabs(build):
        build = os.path.join(ROOT, build)
    os.makedirs(a.out, exist_ok=True)
    report, failures = {}, []
    log = lambda line: print(line, flush=True)  # noqa: E731
    try:
        if a.tier in ("cost", "all"):
            report["cost"], f = cost.run_cost(build, a.baseline, a.out, update_baseline=a.update_baseline,
                                              only=a.workload, log=log)
            failures += f
            if a.update_baseline:
                with open(a.baseline, "w", encoding="utf-8") as out:
                    json.dump({"cost": report["cost"]}, out, indent=1)
                    out.write("\n")
                log(f"run-suite: wrote the baseline {a.baseline}: commit it with a message that says why the cost changed")
        if a.tier in ("jitter", "all"):
            import jitter  # noqa: E402  (only the jitter tier needs it)
            report["jitter"], f = jitter.run_jitter(build, a.duration, a.stress, a.config, a.out,
                                                    a.long_run or a.duration >= 600)
            failures += f
    except cost.UsageError as e:
        print(f"run-suite: {e}", file=sys.stderr)
        return 2
    except Exception as e:  # a tier that could not run at all: not a gate's verdict
        if type(e).__name__ in ("UsageError", "ToolError"):
            print(f"run-suite: {e}", file=sys.stderr)
            return 2
        raise
    report["ok"] = not failures
    with open(os.path.join(a.out, "report.json"), "w", encoding="utf-8") as out:
        json.dump(report, out, indent=1)
        out.write("\n")
    for line in failures:
        print(line, file=sys.stderr)
    log(f"run-suite: {'all gates hold' if not failures else f'{len(failures)} gate(s) failed'}; "
        f"report {os.path.join(a.out, 'report.json')}")
    return 0 if not failures else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
