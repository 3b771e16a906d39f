#!/usr/bin/env python3
"""The suite's skips, counted and named: a skip is green in ctest, so nothing counted them.

Reads the JUnit file ctest writes (--output-junit), prints every skipped test with the reason it
gave (gtest's GTEST_SKIP message, or the last line of a script's output that says why), and exits
1 when more than --max-skips tests skipped: a suite that skips its timing tests whenever the
machine looks loaded cannot fail on timing, so a run that skipped many is not a pass.

It also keeps the names the last RUNS_KEPT runs skipped for the machine's load (a reason naming
one of LOAD_WORDS; --history, a JSON list of lists, oldest first; by default
suite-skip-history.json beside the JUnit file, so in the build folder) and exits 1 naming each
test that skipped so in every one of them: a timing test that skips on every run judges nothing.
A skip for a missing capability is printed, never held against the run.

    suite_skips.py JUNIT_XML [--max-skips N] [--history PATH]
        N default 10; exit 0, 1 (too many skips, or a test that skipped on each of the last
        RUNS_KEPT runs), or 2 on a JUnit or history file that cannot be read
"""
import argparse
import json
import os
import re
import sys
import xml.etree.ElementTree as ElementTree

GTEST_REASON = re.compile(r": Skipped\n(.*?)\n\[  SKIPPED \]", re.S)
RUNS_KEPT = 3


def reason(output):
    """Why a test skipped, from its output: gtest's message, else the last line naming a skip."""
    found = GTEST_REASON.search(output)
    if found and found.group(1).strip():
        return " ".join(found.group(1).split())
    for line in reversed(output.splitlines()):
        if "skip" in line.lower() and line.strip():
            return line.strip()
    return "(no reason printed)"


def skipped_tests(path):
    """(name, reason) of every test the JUnit file marks skipped, in file order."""
    out = []
    for case in ElementTree.parse(path).getroot().iter("testcase"):
        if case.find("skipped") is None:
            continue
        name = case.attrib.get("name", "?").split("  # GetParam()")[0]
        text = case.find("system-out")
        out.append((name, reason(text.text or "" if text is not None else "")))
    return out


def read_history(path):
    """The kept runs' skipped names, oldest first; [] when the file does not exist yet."""
    if not os.path.exists(path):
        return []
    with open(path) as f:
        runs = json.load(f)
    if not (isinstance(runs, list) and all(isinstance(run, list) for run in runs)):
        raise ValueError("not a JSON list of lists of test names")
    return runs


# A skip whose reason names one of these is put down to the machine's load (tests/support/
# real_time_run.h words its reasons so); any other (not root, no CAP_SYS_NICE, one CPU, a missing
# tool) says what the machine cannot do, which repeats on every run without hiding a regression.
# ("\bstall": "installed" is not a stall).
LOAD_WORDS = re.compile(r"\bstall|could not pace|was loaded|cpu share", re.IGNORECASE)


def for_load(reason):
    """Whether a skip's reason puts it down to the machine's load."""
    return LOAD_WORDS.search(reason) is not None


def record_run(path, names):
    """Appends this run's skipped names to the history, keeps the last RUNS_KEPT, returns them."""
    runs = (read_history(path) + [sorted(set(names))])[-RUNS_KEPT:]
    with open(path, "w") as f:
        json.dump(runs, f, indent=1)
    return runs


def always_skipped(runs):
    """The tests that skipped in each of the kept runs, once RUNS_KEPT runs are kept."""
    if len(runs) < RUNS_KEPT:
        return []
    return sorted(set.intersection(*(set(run) for run in runs)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("junit")
    parser.add_argument("--max-skips", type=int, default=10)
    parser.add_argument("--history", help="default: suite-skip-history.json beside JUNIT_XML")
    args = parser.parse_args()
    history = args.history or os.path.join(os.path.dirname(os.path.abspath(args.junit)),
                                           "suite-skip-history.json")
    try:
        skips = skipped_tests(args.junit)
    except (OSError, ElementTree.ParseError) as error:
        print(f"suite_skips: cannot read {args.junit}: {error}", file=sys.stderr)
        return 2
    try:
        runs = record_run(history, [name for name, why in skips if for_load(why)])
    except (OSError, ValueError) as error:
        print(f"suite_skips: cannot use the skip history {history}: {error}", file=sys.stderr)
        return 2
    print(f"== skipped: {len(skips)} (at most {args.max_skips} pass)")
    for name, why in skips:
        print(f"  {name}: {why}")
    status = 0
    if len(skips) > args.max_skips:
        print(f"suite_skips: {len(skips)} tests skipped, more than {args.max_skips}: the suite did "
              "not judge what they guard (a loaded machine, or a regression that makes it look "
              "loaded)", file=sys.stderr)
        status = 1
    for name in always_skipped(runs):
        print(f"suite_skips: {name} skipped for the machine's load on each of the last {RUNS_KEPT} "
              f"runs ({history}): a test that always skips judges nothing", file=sys.stderr)
        status = 1
    return status


if __name__ == "__main__":
    sys.exit(main())
