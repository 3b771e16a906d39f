"""The clone stands on its own: the data it ships is what data/SHA256SUMS says, every data file is
listed there, and no tracked file names a path outside the clone (a lab's clone has nothing beside
it). A missing or altered file is named with its expected checksum.

Environment: RTHS_SOURCE_DIR (the repository root)."""
import hashlib
import os
import subprocess
import sys

SOURCE = os.environ["RTHS_SOURCE_DIR"]
DATA = os.path.join(SOURCE, "data")
MANIFEST = os.path.join(DATA, "SHA256SUMS")
NOT_DATA = {"README.md", "SHA256SUMS"}
OUTSIDE = "../" + "shared"  # spelled apart, so that this file does not name it itself


def sha256(path):
    digest = hashlib.sha256()
    with open(path, "rb") as stream:
        for block in iter(lambda: stream.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def manifest_entries():
    entries = {}
    for number, line in enumerate(open(MANIFEST, encoding="utf-8"), start=1):
        if not line.strip():
            continue
        expected, _, name = line.strip().partition("  ")
        if len(expected) != 64 or not name:
            raise ValueError(f"data/SHA256SUMS:{number}: expected '<sha256>  <path>', got {line.strip()!r}")
        entries[name] = expected
    return entries


def checksum_failures(entries):
    failures = []
    for name, expected in sorted(entries.items()):
        path = os.path.join(DATA, name)
        if not os.path.isfile(path):
            failures.append(f"data/{name}: missing (expected sha256 {expected})")
        elif sha256(path) != expected:
            failures.append(f"data/{name}: altered: sha256 {sha256(path)}, expected {expected}")
    return failures


def unlisted_files(entries):
    unlisted = []
    for folder, _, names in os.walk(DATA):
        for name in names:
            relative = os.path.relpath(os.path.join(folder, name), DATA)
            if relative not in NOT_DATA and relative not in entries:
                unlisted.append(f"data/{relative}: not in data/SHA256SUMS (add its checksum)")
    return unlisted


def paths_outside_the_clone():
    """Tracked files that name the developers' shared folder beside the clone."""
    found = subprocess.run(["git", "grep", "-n", "-I", "-e", OUTSIDE, "--", "."], cwd=SOURCE,
                           stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    if found.returncode not in (0, 1):
        return [] if "not a git repository" in found.stderr else [f"git grep failed: {found.stderr}"]
    return [f"{line}: names a path outside the clone" for line in found.stdout.splitlines()]


if __name__ == "__main__":
    entries = manifest_entries()
    problems = checksum_failures(entries) + unlisted_files(entries) + paths_outside_the_clone()
    print(f"{len(entries)} data files checked against data/SHA256SUMS, {len(problems)} problems")
    for problem in problems:
        print("FAIL " + problem, file=sys.stderr)
    sys.exit(1 if problems else 0)
