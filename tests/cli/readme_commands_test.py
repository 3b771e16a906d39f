"""The README and docs/ are tested: every command they show runs as written, from a fresh copy.

Commands are read from README.md and from every docs/*.md (never copied here), each file's in
order: README.md first, then the pages of docs/ by name, all in one copy of the repository:
  * every line of an indented code block (a trailing backslash continues it; `# ...` ends it), and
  * every inline `code span` that is followed on its line by an expectation comment.
Fenced blocks (```text ... ```) show output and are not run.
Each command carries its expectation in an HTML comment that the rendered page does not show:
  * inline:       `rths sdof ...` <!-- test: exit 0; has "critical delay" -->
  * code blocks:  the block is followed by one comment per command, in order.
  An expectation is `exit N; has "TEXT"` (the exit code and one text the output, stdout and
  stderr, must contain; `exit 0,1` allows either, for a verdict that is the machine's) or
  `skip: REASON` (a command the suite cannot run: the whole bootstrap, a benchmark, one that
  needs root and network namespaces). A code-block command without an expectation fails the
  test, so a change that breaks a command breaks the build. Failures are named FILE:LINE.

The commands run in order, in a copy of the repository's tracked files (a bare clone: data/
included, nothing beside it) inside an otherwise empty temporary folder, with the build linked as
build/ and the build's `rths` and node programs first on PATH (as `cmake --install` puts them after
the set-up). A command that needs anything outside the clone fails here as it would for a lab.
The test also keeps README.md under 300 lines and checks that every relative link of README.md and
docs/*.md names a file of the repository (and, with #anchor, a heading of that page).
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
COMMAND_START = ("rths ", "rths-", "build/", "PYTHONPATH=", "bash ", "python3 ", "printf ", "cp ", "mkdir ",
                 "truncate ")
README_MAX_LINES = 300


def parse_expectation(text):
    if text.startswith("skip:"):
        return {"skip": text[len("skip:"):].strip()}
    match = re.fullmatch(r'exit (\d+(?:,\d+)*); has "(.*)"', text)
    if not match:
        raise ValueError(f"expectation '{text}': write `exit N; has \"TEXT\"` or `skip: REASON`")
    return {"exit": [int(code) for code in match.group(1).split(",")], "has": match.group(2)}


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
    """(line number, command, expectation text or None) in the page's order."""
    lines = open(readme, encoding="utf-8").read().split("\n")
    found, i, in_list = [], 0, False
    while i < len(lines):
        line = lines[i]
        if line.startswith("```"):  # a fenced block shows output: skip to its end
            i += 1
            while i < len(lines) and not lines[i].startswith("```"):
                i += 1
            i += 1
            continue
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
    folders = ["cli", "coordinator", "substructure_nodes", "actuator_emulator", "controller_node",
               "controller_emulator"]
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


def pages():
    """README.md, then docs/*.md by name: (path relative to the source, absolute path)."""
    docs = os.path.join(SOURCE, "docs")
    names = sorted(n for n in os.listdir(docs) if n.endswith(".md")) if os.path.isdir(docs) else []
    return [("README.md", os.path.join(SOURCE, "README.md"))] + \
        [("docs/" + n, os.path.join(docs, n)) for n in names]


def slug(heading):
    """GitHub's anchor of a heading: lower case, punctuation dropped, spaces as hyphens."""
    text = re.sub(r"[`*_]", "", heading.strip().lower())
    text = re.sub(r"[^\w\- ]", "", text)
    return text.replace(" ", "-")


def link_failures():
    """Every relative link of the pages names a tracked file, and its #anchor a heading there."""
    failures = []
    anchors = {}
    for name, path in pages():
        fenced, found = False, set()
        for line in open(path, encoding="utf-8"):
            fenced = fenced != line.startswith("```")
            if not fenced and re.match(r"^#{1,6} ", line):
                found.add(slug(line.lstrip("#")))
        anchors[os.path.normpath(name)] = found
    for name, path in pages():
        for number, line in enumerate(open(path, encoding="utf-8"), start=1):
            for target in re.findall(r"\]\(([^)\s]+)\)", line):
                if re.match(r"^[a-z]+:", target):
                    continue
                file_part, _, anchor = target.partition("#")
                linked = os.path.normpath(os.path.join(os.path.dirname(name), file_part)) if file_part \
                    else os.path.normpath(name)
                if not os.path.exists(os.path.join(SOURCE, linked)):
                    failures.append(f"{name}:{number}: link '{target}': no file {linked}")
                elif anchor and linked in anchors and anchor not in anchors[linked]:
                    failures.append(f"{name}:{number}: link '{target}': {linked} has no heading "
                                    f"with anchor #{anchor}")
    return failures


def length_failures():
    lines = len(open(os.path.join(SOURCE, "README.md"), encoding="utf-8").read().rstrip("\n").split("\n"))
    print(f"README.md: {lines} lines (at most {README_MAX_LINES - 1})")
    if lines >= README_MAX_LINES:
        return [f"README.md has {lines} lines: keep it under {README_MAX_LINES}; move detail into docs/"]
    return []


def run_all():
    listed = [(name, readme_commands(path)) for name, path in pages()]
    if len(listed[0][1]) < 8:
        return [f"only {len(listed[0][1])} commands found in README.md: the extraction broke"]
    root, work = fresh_directory()
    # `python3 -c "import rths"` as after the set-up, which installs the module: here the build's.
    env = dict(os.environ, PATH=path_with_programs(), MPLBACKEND="Agg",
               PYTHONPATH=os.path.join(BINARY, "python"))
    failures = length_failures() + link_failures() + help_failures(env)
    ran, skipped, total_started = 0, 0, time.monotonic()
    try:
        for name, commands in listed:
            file_started, file_ran = time.monotonic(), 0
            for line, command, expectation in commands:
                where = f"{name}:{line}"
                if expectation is None:
                    failures.append(f"{where}: `{command}` has no <!-- test: ... --> expectation")
                    continue
                try:
                    expect = parse_expectation(expectation)
                except ValueError as e:
                    failures.append(f"{where}: {e}")
                    continue
                if "skip" in expect:
                    skipped += 1
                    print(f"{where}: skipped ({expect['skip']}): {command}")
                    continue
                started = time.monotonic()
                try:
                    done = subprocess.run(["bash", "-c", command], cwd=work, env=env, stdout=subprocess.PIPE,
                                          stderr=subprocess.STDOUT, text=True, errors="replace", timeout=600)
                    code, output = done.returncode, done.stdout
                except subprocess.TimeoutExpired as e:
                    output = e.output or ""
                    code, output = "timeout (600 s)", output.decode(errors="replace") if isinstance(output, bytes) else output
                ran += 1
                file_ran += 1
                seconds = time.monotonic() - started
                print(f"{where}: exit {code} in {seconds:.1f} s: {command}", flush=True)
                if code not in expect["exit"] or expect["has"] not in output:
                    wanted = " or ".join(str(c) for c in expect["exit"])
                    failures.append(f"{where}: `{command}`: exit {code} (expected {wanted}), output "
                                    f"{'has' if expect['has'] in output else 'lacks'} "
                                    f"\"{expect['has']}\":\n{output[-3000:]}")
            print(f"{name}: {file_ran} commands run in {time.monotonic() - file_started:.1f} s", flush=True)
    finally:
        shutil.rmtree(root, ignore_errors=True)
    print(f"{ran} commands run ({skipped} skipped) from {len(listed)} files in "
          f"{time.monotonic() - total_started:.1f} s, {len(failures)} failed")
    return failures


if __name__ == "__main__":
    problems = run_all()
    for problem in problems:
        print("FAIL " + problem, file=sys.stderr)
    sys.exit(1 if problems else 0)
