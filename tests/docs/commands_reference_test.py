"""docs/commands.md documents every flag of every installed program, and no flag they lack.

The installed programs are what `cmake --install` installs: the executables named in the build's
cmake_install.cmake files (`rths` and the node programs, each at its build-tree path). Each one's
flags are read from its `--help` (CLI11), and so are its subcommands' (`rths sweep`, then
`rths sweep merge`), recursively. A flag is the first word of a help entry: `--period`,
`-o,--out`, a positional's name (`config`); `--help` itself is left out.

docs/commands.md gives each program or command a table of its arguments:

    ## rths sweep                            a heading naming it, or a line of its own naming
                                             one or several (`rths-a, rths-b and rths-c:`)
    | argument | meaning |
    |---|---|
    | `--shard TEXT` | ... |                 the first word of the code span is the flag

The table belongs to the nearest heading or naming line above it; a heading that names no
program (`## Exit codes`) ends that. The test fails naming the program and the flag for every
flag without a row, every row whose flag the program lacks, every flag documented twice, every
documented program or command that is not installed, and every table that belongs to none.
Environment: RTHS_SOURCE_DIR (default: the repository holding this file), RTHS_BINARY_DIR (the
build folder; default SOURCE/build).
"""
import glob
import os
import re
import subprocess
import sys

SOURCE = os.environ.get("RTHS_SOURCE_DIR",
                        os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
BINARY = os.environ.get("RTHS_BINARY_DIR", os.path.join(SOURCE, "build"))
REFERENCE = "docs/commands.md"
# A program (`rths`, `rths-coordinator`) or a command (`rths sweep merge`) as the page names it.
NAME = re.compile(r"rths(?:-[a-z][a-z0-9-]*)?(?: [a-z][a-z0-9-]*)*")
TABLE_HEADER = re.compile(r"^\|\s*argument\s*\|\s*meaning\s*\|\s*$")
ROW = re.compile(r"^\|\s*`([^`]+)`")


def installed_programs():
    """{program name: build-tree path} of every executable `cmake --install` installs."""
    programs = {}
    for script in glob.glob(os.path.join(BINARY, "**", "cmake_install.cmake"), recursive=True):
        text = open(script, encoding="utf-8").read()
        for files in re.findall(r"TYPE EXECUTABLE FILES((?:\s+\"[^\"]+\")+)", text):
            for path in re.findall(r"\"([^\"]+)\"", files):
                programs[os.path.basename(path)] = path
    return programs


def help_entries(command):
    """(flags, subcommands) of one `--help`: the first word of each entry, by group."""
    done = subprocess.run(command + ["--help"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          text=True, errors="replace", timeout=60)
    if done.returncode != 0:
        raise RuntimeError(f"`{' '.join(command)} --help` exited {done.returncode}:\n{done.stdout}")
    flags, subcommands, group = [], [], None
    for line in done.stdout.split("\n"):
        header = re.match(r"^(\S.*):$", line)
        if header:
            group = header.group(1)
        elif not line.strip() or not line.startswith(" "):
            group = None  # a blank line ends a group; the footer is no entry
        elif group and re.match(r"^  \S", line):  # an entry; its wrapped lines are indented deeper
            word = line.split()[0]
            if group.lower() == "subcommands":
                subcommands.append(word)
            elif "--help" not in word.split(","):
                flags.append(word)
    return flags, subcommands


def program_flags(programs):
    """{`rths sweep merge`: [flags]} for every program and, recursively, its subcommands."""
    found = {}

    def visit(name, command):
        flags, subcommands = help_entries(command)
        found[name] = flags
        for sub in subcommands:
            visit(name + " " + sub, command + [sub])

    for program, path in sorted(programs.items()):
        visit(program, [path])
    return found


def names_in(text):
    """The programs a heading or naming line names (`rths-a, rths-b and rths-c`), or None."""
    parts = re.split(r",\s*|\s+and\s+", text.strip().strip("`").rstrip(":").strip())
    parts = [p.strip().strip("`") for p in parts]
    return parts if all(NAME.fullmatch(p) for p in parts) else None


def parse_reference(path):
    """[(program, flag, line)] of the argument tables, and [(program, line)] of the names given,
    and problems with the page's own structure."""
    rows, named, problems = [], [], []
    current, in_table, fenced = None, False, False
    for number, line in enumerate(open(path, encoding="utf-8"), start=1):
        line = line.rstrip("\n")
        if line.startswith("```"):
            fenced = not fenced
            continue
        if fenced:
            continue
        heading = re.match(r"^#{1,6}\s+(.*)$", line)
        label = re.match(r"^(`?rths[^|]*):$", line)
        if heading or (label and names_in(label.group(1))):
            current = names_in((heading or label).group(1))
            named += [(name, number) for name in current or []]
            in_table = False
            continue
        if TABLE_HEADER.match(line):
            in_table = True
            if current is None:
                problems.append(f"{REFERENCE}:{number}: an argument table under no program: put it "
                                f"under a heading or a line `PROGRAM:` that names its program")
            continue
        if not line.startswith("|"):
            in_table = False
            continue
        row = ROW.match(line)
        if in_table and row and current:
            flag = row.group(1).split()[0]
            rows += [(program, flag, number) for program in current]
    return rows, named, problems


def check():
    """Problems, one line each."""
    programs = installed_programs()
    if "rths" not in programs or len(programs) < 2:
        return [f"the installed programs found in {BINARY}/**/cmake_install.cmake are "
                f"{sorted(programs) or 'none'}: configure and build first (and check the parser)"]
    missing = [f"{name} ({path}) is not built: cmake --build {BINARY} --target {name}"
               for name, path in sorted(programs.items()) if not os.access(path, os.X_OK)]
    if missing:
        return missing
    try:
        flags = program_flags(programs)
    except (RuntimeError, subprocess.TimeoutExpired) as e:
        return [str(e)]
    total = sum(len(f) for f in flags.values())
    if total < 50:
        return [f"only {total} flags read from the --help of {', '.join(sorted(flags))}: "
                f"the help parser broke"]
    rows, named, problems = parse_reference(os.path.join(SOURCE, REFERENCE))
    documented = {}
    for program, flag, line in rows:
        if (program, flag) in documented:
            problems.append(f"{REFERENCE}:{line}: `{program}` flag `{flag}` is documented twice "
                            f"(also at line {documented[(program, flag)]})")
        documented.setdefault((program, flag), line)
    for program, line in named:
        if program not in flags:
            problems.append(f"{REFERENCE}:{line}: `{program}` is documented but no installed program "
                            f"or command has that name (installed: {', '.join(sorted(programs))})")
    for program, program_flag_list in sorted(flags.items()):
        for flag in program_flag_list:
            if (program, flag) not in documented:
                problems.append(f"{REFERENCE}: `{program}` flag `{flag}` is not documented "
                                f"(`{program} --help` has it)")
    for (program, flag), line in sorted(documented.items(), key=lambda item: item[1]):
        if program in flags and flag not in flags[program]:
            problems.append(f"{REFERENCE}:{line}: `{program}` flag `{flag}` is documented but "
                            f"`{program} --help` has no such flag")
    print(f"{len(programs)} installed programs, {len(flags)} programs and commands, {total} flags; "
          f"{len(rows)} documented; {len(problems)} problems")
    return problems


if __name__ == "__main__":
    found = check()
    for problem in found:
        print("FAIL " + problem, file=sys.stderr)
    sys.exit(1 if found else 0)
