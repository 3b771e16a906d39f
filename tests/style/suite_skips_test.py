"""scripts/suite_skips.py counts and names the suite's skips and fails past its bound.

A ctest JUnit file with two gtest skips (one with GTEST_SKIP's message, one a script's own line),
a pass and a failure: both skips are printed with their reasons, the pass and failure are not,
and the exit is 0 at --max-skips 2 and 1 at --max-skips 1; a file that is not JUnit is exit 2.
Its skip history: a test that skipped for the machine's load in each of the last 3 runs fails the
third, named; one that skipped for a missing capability (chromium) does not, nor one that skipped
in two of the three; the history keeps 3 runs; a damaged history is exit 2.
"""
import json
import os
import subprocess
import sys
import tempfile

SOURCE = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(
    os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
SCRIPT = os.path.join(SOURCE, "scripts", "suite_skips.py")

JUNIT = """<?xml version="1.0" encoding="UTF-8"?>
<testsuite name="rths" tests="4" failures="1" skipped="2">
  <testcase name="Faults.AStallIsJudged  # GetParam() = 4-byte object" status="notrun">
    <skipped message="SKIP_REGULAR_EXPRESSION_MATCHED"/>
    <system-out>[ RUN      ] Faults.AStallIsJudged
tests/runtime/faults_test.cpp:99: Skipped
the machine could not pace a 1 ms loop: p99 3.6 ms
[  SKIPPED ] Faults.AStallIsJudged (2 ms)
</system-out>
  </testcase>
  <testcase name="view_browser" status="notrun">
    <skipped message="SKIP_RETURN_CODE=77"/>
    <system-out>starting chromium
skipped: chromium is not installed
</system-out>
  </testcase>
  <testcase name="Core.Passes" status="run"><system-out>[       OK ] Core.Passes</system-out></testcase>
  <testcase name="Core.Fails" status="fail"><failure message="Failed"/></testcase>
</testsuite>
"""


def run(path, bound, history=None):
    extra = ["--history", history] if history else []
    return subprocess.run([sys.executable, SCRIPT, path, "--max-skips", str(bound)] + extra,
                          capture_output=True, text=True)


def check_history(tmp, path):
    """Three runs on the same file: the third fails naming the load skip, not the capability one;
    a pass in between clears."""
    history = os.path.join(tmp, "history.json")
    assert run(path, 10, history).returncode == 0
    assert run(path, 10, history).returncode == 0
    third = run(path, 10, history)
    assert third.returncode == 1, third.stdout + third.stderr
    assert ("Faults.AStallIsJudged skipped for the machine's load on each of the last 3 runs"
            in third.stderr and "view_browser" not in third.stderr), third.stderr
    with open(history) as f:
        assert json.load(f) == [["Faults.AStallIsJudged"]] * 3
    passed = os.path.join(tmp, "passed.xml")
    with open(passed, "w") as f:
        f.write(JUNIT.replace("<skipped", "<passed"))
    assert run(passed, 10, history).returncode == 0
    assert run(path, 10, history).returncode == 0, "skipped in 2 of the last 3 runs"
    with open(history) as f:
        assert len(json.load(f)) == 3
    with open(history, "w") as f:
        f.write("{}")
    damaged = run(path, 10, history)
    assert damaged.returncode == 2 and "skip history" in damaged.stderr, damaged.stderr


def main():
    with tempfile.TemporaryDirectory() as tmp:
        path = os.path.join(tmp, "junit.xml")
        with open(path, "w") as f:
            f.write(JUNIT)
        ok = run(path, 2)
        assert ok.returncode == 0, ok.stdout + ok.stderr
        assert "== skipped: 2" in ok.stdout, ok.stdout
        assert ("Faults.AStallIsJudged: the machine could not pace a 1 ms loop: p99 3.6 ms"
                in ok.stdout), ok.stdout
        assert "view_browser: skipped: chromium is not installed" in ok.stdout, ok.stdout
        assert "Core.Passes" not in ok.stdout and "Core.Fails" not in ok.stdout, ok.stdout
        over = run(path, 1)
        assert over.returncode == 1, over.stdout + over.stderr
        assert "2 tests skipped, more than 1" in over.stderr, over.stderr
        check_history(tmp, path)
        with open(path, "w") as f:
            f.write("not xml")
        assert run(path, 2).returncode == 2
    print("suite_skips: ok")


if __name__ == "__main__":
    main()
