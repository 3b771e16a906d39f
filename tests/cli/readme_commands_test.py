"""The README is tested: every command it shows runs as written, from a fresh output directory.

Commands are read from README.md itself (never copied here):
  * every line of an indented code block (a trailing backslash continues it; `# ...` ends it), and
  * every inline `code span` that is followed on its line by an expectation comment.
Each command carries its expectation in an HTML comment that the rendered README does not show:
  * inline:       `rths sdof ...` <!-- test: exit 0; has "critical delay" -->
  * code blocks:  the block is followed by one comment per command, in order.
  An expectation is `exit N; has "TEXT"` (the exit code and one text the output, stdout and
  stderr, must contain) or `skip: REASON` (a command the suite cannot run: the whole bootstrap,
  a benchmark, one that needs root and network namespaces). A code-block command without an
  expectation fails the test, so a README change that breaks a command breaks the build.

The commands run in README order, in a copy of the repository's tracked files (a bare clone: data/
included, nothing beside it) inside an otherwise empty temporary folder, with the build linked as
build/ and the build's `rths` and node programs first on PATH (as `cmake --install` puts them after
the set-up). A command that needs anything outside the clone fails here as it would for a lab.
Environment: RTHS_SOURCE_DIR, RTHS_BINARY_DIR.
"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

SOURCE = os.environ["RTHS_SOURCE_DIR"]
BINARY = os.environ["RTHS_BINARY_DIR"]
EXPECT = re.compile(r"<!--\s*test:\s*(.*?)\s*-->")
COMMAND_START = ("rths ", "rths-", "build/", "PYTHONPATH=", "bash ")


def parse_expectation(text):
    if text.startswith("skip:"):
        return {"skip": text[len("skip:"):].strip()}
    match = re.fullmatch(r'exit (\d+); has "(.*)"', text)
    if not match:
        raise ValueError(f"README expectation '{text}': write `exit N; has \"TEXT\"` or `skip: REASON`")
    return {"exit": int(match.group(1)), "has": match.group(2)}


def code_block_commands(lines, start):
    """Commands of the indented block at lines[start], and the index after it."""
    commands, current, i = [], "", start
    while i < len(lines) and (lines[i].startswith("    ") or not lines[i].strip()):
        line = lines[i].strip()
        i += 1
        if not line:
            continue
        line = re.sub(r"\s+#\s.*$", "", line)  # a trailing comment
        current = (current + " " + line.rstrip("\\").strip()).strip()
        if not line.endswith("\\"):
            commands.append(current)
            current = ""
    return commands, i


def readme_commands(readme):
    """(line number, command, expectation text or None) in README order."""
    lines = open(readme, encoding="utf-8").read().split("\n")
    found, i, in_list = [], 0, False
    while i < len(lines):
        line = lines[i]
        block_start = line.startswith("    ") and line.strip().startswith(COMMAND_START) and not in_list
        if block_start and (i == 0 or not lines[i - 1].strip()):
            commands, after = code_block_commands(lines, i)
            expectations = []
            while after < len(lines) and (EXPECT.search(lines[after]) or not lines[after].strip()):
                expectations += EXPECT.findall(lines[after])
                after += 1
                if len(expectations) == len(commands):
                    break
            for k, command in enumerate(commands):
                found.append((i + 1, command, expectations[k] if k < len(expectations) else None))
            i = after
            continue
        in_list = line.lstrip().startswith("- ") or (in_list and line.startswith("  ") and line.strip())
        for span, expectation in re.findall(r"`([^`]+)`\s*<!--\s*test:\s*(.*?)\s*-->", line):
            found.append((i + 1, span, expectation))
        i += 1
    return found


def tracked_files():
    """The repository's files as a clone has them (git ls-files), or every file but the build."""
    listed = subprocess.run(["git", "ls-files", "-z"], cwd=SOURCE, stdout=subprocess.PIPE,
                            stderr=subprocess.DEVNULL)
    if listed.returncode == 0 and listed.stdout:
        return [name for name in listed.stdout.decode().split("\0") if name]
    names = []
    for folder, subfolders, files in os.walk(SOURCE):
        subfolders[:] = [d for d in subfolders if d not in (".git", "build", "out") and
                         os.path.join(folder, d) != BINARY]
        names += [os.path.relpath(os.path.join(folder, f), SOURCE) for f in files]
    return names


def fresh_directory():
    root = tempfile.mkdtemp(prefix="rths_readme_")
    work = os.path.join(root, "rths")
    for name in tracked_files():
        source = os.path.join(SOURCE, name)
        if os.path.isfile(source):
            os.makedirs(os.path.dirname(os.path.join(work, name)), exist_ok=True)
            shutil.copy2(source, os.path.join(work, name))
    os.symlink(BINARY, os.path.join(work, "build"))
    return root, work


def path_with_programs():
    folders = ["cli", "coordinator", "substructure_nodes", "actuator_emulator"]
    # `python3` in the README is the interpreter the suite runs (Debian's, with NumPy), not an
    # earlier one on PATH.
    return os.pathsep.join([os.path.dirname(sys.executable)] + [os.path.join(BINARY, f) for f in folders] +
                           [os.environ.get("PATH", "")])


def help_failures(env):
    """`rths --help` and every subcommand's `--help` (the commands the help lists) exit 0."""
    listing = subprocess.run(["rths", "--help"], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if listing.returncode != 0 or "SUBCOMMANDS" not in listing.stdout.upper():
        return [f"`rths --help`: exit {listing.returncode}:\n{listing.stdout}"]
    names = re.findall(r"^  (\w[\w-]*)\s", re.split(r"(?i)subcommands:?", listing.stdout, maxsplit=1)[1], re.M)
    failures = []
    for name in names:
        done = subprocess.run(["rths", name, "--help"], env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        if done.returncode != 0 or "--help" not in done.stdout:
            failures.append(f"`rths {name} --help`: exit {done.returncode}:\n{done.stdout}")
    print(f"--help of rths and its {len(names)} commands: {len(failures)} failed")
    return failures if names else ["`rths --help` lists no commands"]


def run_all():
    commands = readme_commands(os.path.join(SOURCE, "README.md"))
    if len(commands) < 10:
        return [f"only {len(commands)} commands found in README.md: the extraction broke"]
    root, work = fresh_directory()
    env = dict(os.environ, PATH=path_with_programs(), MPLBACKEND="Agg")
    failures, ran = help_failures(env), 0
    try:
        for line, command, expectation in commands:
            if expectation is None:
                failures.append(f"README.md:{line}: `{command}` has no <!-- test: ... --> expectation")
                continue
            expect = parse_expectation(expectation)
            if "skip" in expect:
                print(f"README.md:{line}: skipped ({expect['skip']}): {command}")
                continue
            started = time.monotonic()
            done = subprocess.run(["bash", "-c", command], cwd=work, env=env, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True, errors="replace", timeout=600)
            ran += 1
            seconds = time.monotonic() - started
            print(f"README.md:{line}: exit {done.returncode} in {seconds:.1f} s: {command}")
            if done.returncode != expect["exit"] or expect["has"] not in done.stdout:
                failures.append(f"README.md:{line}: `{command}`: exit {done.returncode} (README: "
                                f"{expect['exit']}), output {'has' if expect['has'] in done.stdout else 'lacks'} "
                                f"\"{expect['has']}\":\n{done.stdout[-3000:]}")
    finally:
        shutil.rmtree(root, ignore_errors=True)
    print(f"{ran} README commands run, {len(failures)} failed")
    return failures


if __name__ == "__main__":
    problems = run_all()
    for problem in problems:
        print("FAIL " + problem, file=sys.stderr)
    sys.exit(1 if problems else 0)
