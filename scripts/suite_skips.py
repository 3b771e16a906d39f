#!/usr/bin/env python3
"""The suite's skips, counted and named: a skip is green in ctest, so nothing counted them.

Reads the JUnit file ctest writes (--output-junit), prints every skipped test with the reason it
gave (gtest's GTEST_SKIP message, or the last line of a script's output that says why), and exits
1 when more than --max-skips tests skipped: a suite that skips its timing tests whenever the
machine looks loaded cannot fail on timing, so a run that skipped many is not a pass.

    suite_skips.py JUNIT_XML [--max-skips N]     (N default 12; exit 0, 1, or 2 on a bad file)
"""
import argparse
import re
import sys
import xml.etree.ElementTree as ElementTree

GTEST_REASON = re.compile(r": Skipped\n(.*?)\n\[  SKIPPED \]", re.S)


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


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("junit")
    parser.add_argument("--max-skips", type=int, default=12)
    args = parser.parse_args()
    try:
        skips = skipped_tests(args.junit)
    except (OSError, ElementTree.ParseError) as error:
        print(f"suite_skips: cannot read {args.junit}: {error}", file=sys.stderr)
        return 2
    print(f"== skipped: {len(skips)} (at most {args.max_skips} pass)")
    for name, why in skips:
        print(f"  {name}: {why}")
    if len(skips) > args.max_skips:
        print(f"suite_skips: {len(skips)} tests skipped, more than {args.max_skips}: the suite did "
              "not judge what they guard (a loaded machine, or a regression that makes it look "
              "loaded)", file=sys.stderr)
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
