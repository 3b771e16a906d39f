#!/usr/bin/env python3
"""The house's rules on its rooms, checked on the tree as it is (docs/development.md):

1. core/ is pure numerics: no file under core/ includes a generated header (rths/...), a study/
   or util/ header or any room above it, and core's library links Eigen alone (no file format).
2. No two units include each other anywhere (a unit is a .h with its .cpp): rooms form layers.
3. Every folder with sources has one library target of its own (its CMakeLists.txt adds one).
4. Arrows point down: results/ (tables and their writers) and identify/ do not include analysis/,
   which builds on both.

Exit 0 when all hold; 1 naming each break."""
import os
import re
import sys

SOURCE = sys.argv[1] if len(sys.argv) > 1 else os.path.dirname(os.path.dirname(os.path.dirname(
    os.path.abspath(__file__))))
# (room, room it must not include): the studies build on the tables and on identification.
DOWNWARD_ONLY = [("results/", "analysis/"), ("identify/", "analysis/")]
SKIP = {"build", "tests", "fuzz", "bench", "docs", "data", "configs", "examples", "docker",
        "scripts", "node_modules", "python"}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def sources():
    for folder, dirs, files in os.walk(SOURCE):
        rel = os.path.relpath(folder, SOURCE)
        dirs[:] = [d for d in dirs if not d.startswith((".", "build")) and
                   (rel != "." or d not in SKIP)]
        for name in files:
            if name.endswith((".h", ".cpp")):
                yield os.path.relpath(os.path.join(folder, name), SOURCE)


def includes(path):
    with open(os.path.join(SOURCE, path), errors="replace") as f:
        return INCLUDE.findall(f.read())


def main():
    problems = []
    graph = {}
    files = list(sources())
    for path in files:
        unit = os.path.splitext(path)[0]
        for target in includes(path):
            if path.startswith("core/") and not target.startswith("core/"):
                problems.append(f"{path} includes {target}: core/ includes only core/")
            for room, above in DOWNWARD_ONLY:
                if path.startswith(room) and target.startswith(above):
                    problems.append(f"{path} includes {target}: {room} is below {above}")
            target_unit = os.path.splitext(target)[0]
            if target_unit != unit and os.path.exists(os.path.join(SOURCE, target)):
                graph.setdefault(unit, set()).add(target_unit)
    for unit, targets in sorted(graph.items()):
        for other in sorted(targets):
            if unit < other and unit in graph.get(other, set()):
                problems.append(f"{unit} and {other} include each other")
    with open(os.path.join(SOURCE, "core", "CMakeLists.txt")) as f:
        links = re.findall(r"target_link_libraries\(rths_core([^)]*)\)", f.read())
    if [l.split() for l in links] != [["PUBLIC", "Eigen3::Eigen"]]:
        problems.append(f"core/CMakeLists.txt links {links}: rths_core links Eigen alone")
    folders = sorted({os.path.dirname(p) for p in files if p.endswith(".cpp")})
    for folder in folders:
        cmake = os.path.join(SOURCE, folder, "CMakeLists.txt")
        text = open(cmake).read() if os.path.exists(cmake) else ""
        if not re.search(r"add_library\(\s*\w+\s+(STATIC|SHARED)", text) and \
                "rths_node_program(" not in text:
            problems.append(f"{folder}/ has sources but no library target of its own")
    for p in problems:
        print("layout: " + p)
    print(f"layout: {len(files)} sources checked, {len(problems)} problems")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())
