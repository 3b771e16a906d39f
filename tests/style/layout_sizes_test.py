#!/usr/bin/env python3
"""Rule 5 of layout_test.py (sizes) on C++ written for it, so that a finder that stops seeing
functions, or counts them short, fails here rather than passing every tree:
  a 61-line function is over, a 60-line one is not; a lambda, a local class and a string holding
  braces count within their function; class bodies, namespaces, initialisers and control blocks
  at file scope are not functions; a function listed in OVERSIZE may not grow, and one that fits
  must leave the list.
Exit 0 when all hold; 1 naming each failure."""
import os
import sys
import tempfile

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import layout_test  # noqa: E402


def body(lines):
    return "".join(f"  x += {i};\n" for i in range(lines))


def function(name, lines):
    """A function of exactly `lines` lines, signature to closing brace."""
    return f"int {name}(int x) {{\n" + body(lines - 3) + "  return x;\n}\n"


SOURCE = (
    "namespace a {\nstruct S {\n  int member() const {\n" + body(60) + "    return 1;\n  }\n};\n"
    "const int table[] = {1, 2, 3};\n}  // namespace a\n" +
    function("sixty", 60) + function("sixty_one", 61) +
    "void with_lambda() {\n  auto f = [] {\n" + body(30) + "  };\n  const char* s = \"}}}\";\n" +
    "  struct Local { int g() { return 0; } };\n" + body(30) + "}\n"
)


def main():
    failures = []
    found = {name: lines for name, _, lines in layout_test.functions(SOURCE)}
    expected = {"member": 63, "sixty": 60, "sixty_one": 61, "with_lambda": 66}
    if found != expected:
        failures.append(f"functions found {found}, expected {expected}")
    with tempfile.TemporaryDirectory() as root:
        os.makedirs(os.path.join(root, "room"))
        with open(os.path.join(root, "room", "unit.cpp"), "w") as f:
            f.write(SOURCE)
        layout_test.SOURCE = root
        layout_test.OVERSIZE = {("room/unit.cpp", "member"): 62, ("room/unit.cpp", "sixty"): 70}
        problems = layout_test.size_problems(["room/unit.cpp"])
        wanted = ["room/unit.cpp:3 member() grew to 63 lines",
                  "sixty_one() has 61 lines", "with_lambda() has 66 lines",
                  "room/unit.cpp sixty fits now: take it off OVERSIZE"]
        for w in wanted:
            if not any(w in p for p in problems):
                failures.append(f"no problem saying '{w}' in {problems}")
        if any("sixty()" in p for p in problems):
            failures.append(f"a 60-line function was refused: {problems}")
    for f in failures:
        print("layout_sizes: " + f)
    print(f"layout_sizes: {len(failures)} failures")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
