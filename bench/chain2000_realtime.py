#!/usr/bin/env python3
"""Runs issue 63's real-time target (configs/chain2000_realtime.textproto: 2,000 DOFs through
`rths launch` at 1024 Hz, 20 s of motion, the model on a substructure node) several times and
prints each case's overruns and step work, then their medians over the runs (each launch's own
output in OUT/run_<i>.log).

Inputs: the study (default the shipped one), the runs (default 3), the rths program, an output
folder (each run in run_<i>/). Outputs on stdout, per run and case: steps run, overruns (count and
% of the steps run), the loop's step work median and p99 (ms), the case's status and the launch's
exit code; then per case the median over the runs of the overrun % and of the step work
median. Exit 1 when a launch did not exit 0 (a run that failed its purpose), else 0.

    bench/chain2000_realtime.py --out /tmp/chain2000_rt
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import sys

ROOT = pathlib.Path(__file__).resolve().parent.parent


def launch(rths, config, out, platform_seconds):
    """One `rths launch`; its exit code and its summary.json's cases (empty when none was
    written)."""
    command = [str(rths), "launch", str(config), "--no-plots", "--force", "--out", str(out),
               "--platform-seconds", str(platform_seconds), "--accept-platform"]
    print("$ " + " ".join(command), flush=True)
    out.parent.mkdir(parents=True, exist_ok=True)
    with open(out.parent / f"{out.name}.log", "w", encoding="utf-8") as log:
        code = subprocess.run(command, stdout=log, stderr=subprocess.STDOUT, check=False).returncode
    summary = out / "summary.json"
    cases = json.loads(summary.read_text())["cases"] if summary.exists() else []
    return code, cases


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--config", type=pathlib.Path,
                        default=ROOT / "configs" / "chain2000_realtime.textproto")
    parser.add_argument("--runs", type=int, default=3)
    parser.add_argument("--rths", type=pathlib.Path, default=ROOT / "build" / "cli" / "rths")
    parser.add_argument("--out", type=pathlib.Path, required=True)
    parser.add_argument("--platform-seconds", type=float, default=5.0)
    args = parser.parse_args()
    if args.runs < 1:
        sys.exit("chain2000_realtime.py: --runs must be >= 1")
    overrun_pct, work_ms, failed = {}, {}, False
    print("run  case       steps  overruns  overrun %  step work median / p99 ms  exit  status")
    for run in range(1, args.runs + 1):
        code, cases = launch(args.rths, args.config, args.out / f"run_{run}", args.platform_seconds)
        failed |= code != 0 or not cases
        for case in cases:
            steps = case["steps"]
            pct = 100.0 * case["overruns"] / steps if steps else float("nan")
            median_ms = 1e3 * case["step_work_median_s"]
            overrun_pct.setdefault(case["name"], []).append(pct)
            work_ms.setdefault(case["name"], []).append(median_ms)
            print(f"{run:<4} {case['name']:<10} {steps:>5}  {case['overruns']:>8}  {pct:>9.2f}  "
                  f"{median_ms:>13.3f} / {1e3 * case['step_work_p99_s']:.3f}  {code:>10}  "
                  f"{case['status']}")
    print("\nmedians over the runs:")
    for name, values in overrun_pct.items():
        print(f"  {name}: overruns {statistics.median(values):.2f} % of steps, step work median "
              f"{statistics.median(work_ms[name]):.3f} ms")
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
