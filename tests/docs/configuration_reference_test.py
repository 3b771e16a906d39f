"""docs/configuration.md is the reference of every config file's fields, and stays equal to the protos.

The schemas a user writes by hand are parsed from their .proto files (PROTOS below: the study and
its deployment, the stages and compensation they hold, the OpenSees site, the identification's
declared model, the sites and the joint-lag study). docs/configuration.md holds one section per
message, headed by the message's name in a code span (nested messages as Outer.Inner):

    ### `DelayStage.TimeShift`

    | field | type | unit | default | meaning |
    |---|---|---|---|---|
    | `delay` | double | s | 0 | ... |

The test fails naming every message without a section, every field without a row, every row or
section that the protos no longer have, and every row whose type differs from the proto's
(`repeated T`, `optional T`, `T`; a message type by its short name, an enum by its name).
A message without fields is still a section (it says so).
Environment: RTHS_SOURCE_DIR (default: the repository holding this file).
"""
import os
import re
import sys

SOURCE = os.environ.get("RTHS_SOURCE_DIR",
                        os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__)))))
PROTOS = ["proto/config.proto", "proto/stages.proto", "proto/deployment.proto", "proto/opensees.proto",
          "proto/identify.proto", "deploy/sites.proto", "analysis/joint_lag/joint_lag.proto"]
REFERENCE = "docs/configuration.md"
TOKEN = re.compile(r'"(?:[^"\\]|\\.)*"|[A-Za-z_][\w.]*|-?\d[\w.+-]*|\S')


def tokens(text):
    text = re.sub(r"/\*.*?\*/", " ", text, flags=re.S)
    text = re.sub(r"//[^\n]*", " ", text)
    return TOKEN.findall(text)


def skip_statement(toks, i):
    """Index after the statement starting at toks[i]: up to its `;` or its balanced `{ }`."""
    depth = 0
    while i < len(toks):
        if toks[i] == "{":
            depth += 1
        elif toks[i] == "}":
            depth -= 1
            if depth == 0:
                return i + 1
        elif toks[i] == ";" and depth == 0:
            return i + 1
        i += 1
    return i


def parse_block(toks, i, prefix, messages, fields):
    """Parse a message body from toks[i] (after its `{`) up to its `}`; return the index after it."""
    while i < len(toks) and toks[i] != "}":
        word = toks[i]
        if word == "message":
            name = prefix + "." + toks[i + 1] if prefix else toks[i + 1]
            messages.append(name)
            fields.setdefault(name, [])
            i = parse_block(toks, i + 3, name, messages, fields)
        elif word == "oneof":
            i = parse_block(toks, i + 3, prefix, messages, fields)  # its fields are the message's
        elif word in ("enum", "reserved", "option", "extensions", "extend"):
            i = skip_statement(toks, i)
        elif word == ";":
            i += 1
        elif prefix:
            label = ""
            if word in ("repeated", "optional"):
                label, i = word, i + 1
            if toks[i] == "map":
                end = toks.index(">", i)
                kind, i = "map<" + " ".join(toks[i + 2:end]).replace(" ,", ",") + ">", end + 1
            else:
                kind, i = toks[i], i + 1
            name = toks[i]
            if toks[i + 1] != "=":
                raise ValueError(f"cannot parse a field near '{' '.join(toks[i - 2:i + 4])}'")
            kind = kind.split(".")[-1]
            fields[prefix].append((name, (label + " " + kind).strip()))
            i = skip_statement(toks, i)
        else:
            i = skip_statement(toks, i)
    return i + 1


def parse_proto(path):
    """(messages in file order, {message: [(field, type)]}) of one .proto file."""
    toks = tokens(open(path, encoding="utf-8").read())
    messages, fields, i = [], {}, 0
    while i < len(toks):
        if toks[i] == "message":
            messages.append(toks[i + 1])
            fields.setdefault(toks[i + 1], [])
            i = parse_block(toks, i + 3, toks[i + 1], messages, fields)
        else:
            i = skip_statement(toks, i)
    return messages, fields


def parse_reference(path):
    """{message: [(field, type, line)]} and {message: line} from the reference's sections and tables."""
    documented, headings, current = {}, {}, None
    for number, line in enumerate(open(path, encoding="utf-8"), start=1):
        heading = re.match(r"^#{2,6}\s+`([A-Za-z_][\w.]*)`\s*$", line)
        if heading:
            current = heading.group(1)
            if current in headings:
                raise ValueError(f"{REFERENCE}:{number}: `{current}` has a second section "
                                 f"(first at line {headings[current]})")
            headings[current] = number
            documented[current] = []
            continue
        if re.match(r"^#{1,6}\s", line):
            current = None
            continue
        row = re.match(r"^\|\s*`([A-Za-z_]\w*)`\s*\|\s*([^|]*?)\s*\|", line)
        if row and current:
            documented[current].append((row.group(1), row.group(2).replace("`", ""), number))
    return documented, headings


def check():
    """Problems, one line each."""
    schema, order = {}, []
    for proto in PROTOS:
        messages, fields = parse_proto(os.path.join(SOURCE, proto))
        for name in messages:
            if name in schema:
                return [f"{proto}: message {name} is also in {schema[name][0]}: give the test full names"]
            schema[name] = (proto, fields[name])
            order.append(name)
    if len(order) < 20:
        return [f"only {len(order)} messages parsed from {', '.join(PROTOS)}: the parser broke"]
    if not os.path.isfile(os.path.join(SOURCE, REFERENCE)):
        return [f"{REFERENCE} is missing: it documents every field of {', '.join(PROTOS)}"]
    try:
        documented, headings = parse_reference(os.path.join(SOURCE, REFERENCE))
    except ValueError as e:
        return [str(e)]
    problems = []
    for name in order:
        proto, fields = schema[name]
        if name not in documented:
            problems.append(f"{REFERENCE}: message `{name}` ({proto}) has no section "
                            f"(`### \\`{name}\\``) with its fields: "
                            + (", ".join(f for f, _ in fields) or "(none)"))
            continue
        rows = {field: (kind, line) for field, kind, line in documented[name]}
        for field, kind in fields:
            if field not in rows:
                problems.append(f"{REFERENCE}: field `{name}.{field}` ({kind}, {proto}) is not documented")
            elif rows[field][0] != kind:
                problems.append(f"{REFERENCE}:{rows[field][1]}: field `{name}.{field}` is documented as "
                                f"'{rows[field][0]}', {proto} has '{kind}'")
        names = {field for field, _ in fields}
        for field, _, line in documented[name]:
            if field not in names:
                problems.append(f"{REFERENCE}:{line}: field `{name}.{field}` is documented but "
                                f"{proto} has no such field")
    for name, line in headings.items():
        if name not in schema:
            problems.append(f"{REFERENCE}:{line}: section `{name}` documents a message no proto "
                            f"({', '.join(PROTOS)}) has")
    fields = sum(len(f) for _, f in schema.values())
    print(f"{len(order)} messages, {fields} fields in {len(PROTOS)} protos; {len(problems)} problems")
    return problems


if __name__ == "__main__":
    found = check()
    for problem in found:
        print("FAIL " + problem, file=sys.stderr)
    sys.exit(1 if found else 0)
