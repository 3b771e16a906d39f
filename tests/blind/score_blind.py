#!/usr/bin/python3
"""Scores `rths identify` blind on records of a rig it never modelled (docs/development.md,
"Blind records"; the records from tests/blind/blind_record_writer.cpp, third_set_writer.cpp,
fourth_set_writer.cpp or fifth_set_writer.cpp).

Inputs:
  --rths PATH            the rths program (`rths identify REC --json`, `rths export REC --csv`)
  --records DIR          a folder written by blind_record_writer (<case>.rthsrec, truth.json), or
  --writer PATH --set S --data DIR [--work DIR]
                         write set S (tune|report with blind_record_writer, third with
                         third_set_writer, fourth with fourth_set_writer, fifth with
                         fifth_set_writer) first, into --work (default a temp folder)
  --json                 print the scores as JSON instead of the table
  --require-reads        exit 1 unless every record exports without a warning and identify exits 0
                         on every one (what the suite asserts; scores are never asserted here)
  --timeout S            per identify run (default 900 s)
Outputs: per record and in total (stdout): right part, right description, wrong names, the
library effects found, and the re-run's worst floor NRMSE declared -> identified (%).

Scoring, per record, against its truth (truth.json: part, kinds, frequency_hz, library effects):
  right part         an `unexplained` entry or a named (`undeclared`) effect on the truth's part
  right description  an `unexplained` entry on the truth's part whose kinds include one of the
                     truth's kinds; a periodic truth needs the entry's periodic frequency within
                     5 % of the truth's (a time_varying match needs no frequency)
  wrong names        named effects that are neither among the truth's library effects nor its
                     accepted names (a name that describes the effect itself, e.g.
                     time_varying_stiffness for a softening specimen); a clean record should
                     name nothing
  library found      the truth's library effects that were named on their part
  other descriptions `unexplained` entries on parts the truth does not name (shown, not scored)
  re-run             the residual's worst floor NRMSE before (declared) and after (identified);
                     in total, the records whose identified re-run is worse than the declared
  when (reported, never scored)  for a truth with an event window (truth.json's "window_s":
                     [t0, t1], s), whether a `when` that identify reports on the truth's part (an
                     unexplained entry's or a named effect's, at its top or in its time_varying
                     object: [t0, t1], a list of them, objects with start/end keys or an instant) overlaps it
The `unexplained` key may be absent (identify before the description work): every unexplained
truth then scores "no description".
Exit 0, or 1 with --require-reads when a record did not read or identify failed; 2 on bad usage.
"""
import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

PERIODIC_TOLERANCE = 0.05  # relative, on the frequency


# ---------- reading identify's JSON (keys found by running it; tolerant of their absence) ------

def named_effects(doc):
    """[(part, effect)] of the JSON's `undeclared` list."""
    out = []
    for item in doc.get("undeclared") or []:
        if isinstance(item, dict):
            out.append((str(item.get("part", "")), str(item.get("effect", ""))))
    return out


def unexplained_entries(doc):
    """The `unexplained` list, or None when the key is absent."""
    if "unexplained" not in doc:
        return None
    return [e for e in (doc.get("unexplained") or []) if isinstance(e, dict)]


def _numbers(value):
    if isinstance(value, bool):
        return []
    if isinstance(value, (int, float)):
        return [float(value)]
    if isinstance(value, list):
        return [x for v in value for x in _numbers(v)]
    return []


def rerun_errors(doc):
    """(before %, after %) of the worst floor from the `residual` object, or (None, None).

    identify writes per floor `declared_nrmse` and `identified_nrmse` as fractions under
    `residual.floors` (the worst also at `residual`'s top); a key ending in `_pct` is taken as a
    percentage. Other nestings are walked for the same names (declared/before, identified/after)."""
    residual = doc.get("residual")
    if not isinstance(residual, (dict, list)):
        return None, None
    before, after = [], []

    def walk(node, path):
        if isinstance(node, dict):
            for key, value in node.items():
                walk(value, path + [str(key)])
        elif isinstance(node, list):
            for value in node:
                walk(value, path)
        else:
            key = path[-1].lower() if path else ""
            if "nrmse" not in key or "removed" in key:
                return
            values = [v if key.endswith("_pct") else 100.0 * v for v in _numbers(node)]
            if re.search(r"declared|before", key):
                before.extend(values)
            elif re.search(r"identified|after", key):
                after.extend(values)

    floors = residual.get("floors") if isinstance(residual, dict) else None
    walk(floors if floors else residual, [])
    return (max(before) if before else None), (max(after) if after else None)


WINDOW_KEYS = (("start_s", "end_s"), ("start", "end"), ("from_s", "to_s"), ("from", "to"),
               ("t0", "t1"), ("begin_s", "end_s"), ("begin", "end"))


def _windows(value):
    """[(t0, t1)] (s) of a `when` value: [t0, t1], a list of them, objects with start/end, or
    one instant t (the window [t, t])."""
    if _numbers(value) and not isinstance(value, list):
        return [(float(value), float(value))]
    if isinstance(value, dict):
        for start, end in WINDOW_KEYS:
            t0, t1 = value.get(start), value.get(end)
            if _numbers(t0) and _numbers(t1):
                return [(float(t0), float(t1))]
        return []
    if isinstance(value, list):
        if len(value) == 2 and all(len(_numbers(v)) == 1 and not isinstance(v, list)
                                   for v in value):
            return [(float(value[0]), float(value[1]))]
        return [w for v in value for w in _windows(v)]
    return []


def reported_windows(doc, part):
    """[(t0, t1)] (s): every `when` identify reports on part, in an unexplained entry or a named
    effect, at its top or inside its time_varying object."""
    items = [e for e in (unexplained_entries(doc) or []) if e.get("part") == part]
    items += [i for i in doc.get("undeclared") or [] if isinstance(i, dict) and
              i.get("part") == part]
    found = []
    for item in items:
        for holder in (item, item.get("time_varying")):
            if isinstance(holder, dict) and "when" in holder:
                found += _windows(holder["when"])
    return found


def window_overlap(truth, doc):
    """(truth window, reported windows, overlaps): overlaps is None without a truth window or
    without a reported `when` on the truth's part, else whether one of them overlaps it."""
    window = truth.get("window_s")
    if not (isinstance(window, list) and len(window) == 2):
        return None, [], None
    reported = reported_windows(doc, truth.get("part"))
    if not reported:
        return window, [], None
    t0, t1 = float(window[0]), float(window[1])
    return window, reported, any(a <= t1 and b >= t0 for a, b in reported)


# ---------- scoring one record ----------

def description_matches(entry, truth):
    """True when an unexplained entry describes the truth: a shared kind, and for a periodic
    match the frequency within PERIODIC_TOLERANCE."""
    kinds = set(entry.get("kinds") or [])
    for kind in truth.get("kinds") or []:
        if kind not in kinds:
            continue
        if kind != "periodic":
            return True
        periodic = entry.get("periodic") or {}
        f = periodic.get("frequency_hz") if isinstance(periodic, dict) else None
        f_true = truth.get("frequency_hz")
        if isinstance(f, (int, float)) and f_true and abs(f - f_true) <= PERIODIC_TOLERANCE * f_true:
            return True
    return False


def score_record(case, doc):
    """Scores one identify JSON against one case of truth.json. Pure: no I/O."""
    truth = case["truth"]
    part = truth.get("part")
    library = {(l["part"], l["effect"]) for l in truth.get("library") or []}
    accepted = {(l["part"], l["effect"]) for l in truth.get("accepted") or []}
    named = named_effects(doc)
    described = unexplained_entries(doc)
    on_part = [e for e in (described or []) if e.get("part") == part]
    score = {
        "case": case["name"],
        "what": case.get("what", ""),
        "truth_part": part,
        "truth_kinds": truth.get("kinds") or [],
        "truth_frequency_hz": truth.get("frequency_hz"),
        "truth_library": sorted(f"{p}: {e}" for p, e in library),
        "named": [f"{p}: {e}" for p, e in named],
        "described": None if described is None else
        [f"{e.get('part')}: {'+'.join(e.get('kinds') or [])}" +
         (f" {e['periodic'].get('frequency_hz'):.3g} Hz"
          if isinstance(e.get("periodic"), dict) and
          isinstance(e["periodic"].get("frequency_hz"), (int, float)) else "")
         for e in described],
        "has_unexplained_key": described is not None,
    }
    if part:
        score["right_part"] = bool(on_part) or any(p == part for p, _ in named)
        score["right_description"] = any(description_matches(e, truth) for e in on_part)
    else:
        score["right_part"] = None
        score["right_description"] = None
    score["wrong_names"] = [f"{p}: {e}" for p, e in named
                            if (p, e) not in library and (p, e) not in accepted]
    score["library_found"] = sorted(f"{p}: {e}" for p, e in library if (p, e) in set(named))
    score["library_missed"] = sorted(f"{p}: {e}" for p, e in library if (p, e) not in set(named))
    score["other_descriptions"] = [f"{e.get('part')}: {'+'.join(e.get('kinds') or [])}"
                                   for e in (described or []) if e.get("part") != part]
    window, reported, overlaps = window_overlap(truth, doc)
    score["truth_window_s"] = window
    score["reported_when_s"] = reported
    score["when_overlaps"] = overlaps
    before, after = rerun_errors(doc)
    score["rerun_before_pct"] = before
    score["rerun_after_pct"] = after
    return score


def totals(scores):
    with_part = [s for s in scores if s["truth_part"]]
    with_library = [s for s in scores if s["truth_library"]]
    return {
        "records": len(scores),
        "read": sum(1 for s in scores if s.get("read", True)),
        "right_part": sum(1 for s in with_part if s["right_part"]),
        "right_description": sum(1 for s in with_part if s["right_description"]),
        "with_unexplained_truth": len(with_part),
        "records_with_wrong_names": sum(1 for s in scores if s["wrong_names"]),
        "wrong_names": sum(len(s["wrong_names"]) for s in scores),
        "library_found": sum(len(s["library_found"]) for s in with_library),
        "library_effects": sum(len(s["truth_library"]) for s in with_library),
        "has_unexplained_key": any(s["has_unexplained_key"] for s in scores),
        # The identified re-run further from the record than the declared one (beyond 5 % of it
        # and 0.01 point): identify put into the study something the rig does not do.
        "rerun_worse": sum(1 for s in scores if s["rerun_before_pct"] is not None and
                           s["rerun_after_pct"] is not None and
                           s["rerun_after_pct"] > 1.05 * s["rerun_before_pct"] + 0.01),
        # Reported, never scored: truths with an event window, and those a `when` overlaps.
        "with_window": sum(1 for s in scores if s.get("truth_window_s")),
        "when_overlaps": sum(1 for s in scores if s.get("when_overlaps")),
    }


# ---------- running rths ----------

def run(args, timeout):
    try:
        done = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
        return done.returncode, done.stdout, done.stderr
    except subprocess.TimeoutExpired:
        return 124, "", f"timed out after {timeout} s"


def read_check(rths, record, work, timeout):
    """'' when `rths export` reads the record with exit 0 and no warning, else why not."""
    csv = os.path.join(work, os.path.basename(record) + ".csv")
    rc, out, err = run([rths, "export", record, "--csv", csv], timeout)
    if os.path.exists(csv):
        os.remove(csv)
    if rc != 0 or re.search(r"warning|damaged|lost|no footer", err + out):
        return f"export exit {rc}: {(err or out).strip()[:300]}"
    return ""


def identify(rths, record, timeout):
    rc, out, err = run([rths, "identify", record, "--json"], timeout)
    doc = None
    if out.strip():
        try:
            doc = json.loads(out)
        except json.JSONDecodeError:
            doc = None
    problem = ""
    if rc != 0:
        problem = f"identify exit {rc}: {err.strip()[-300:]}"
    elif doc is None:
        problem = "identify wrote no JSON"
    elif re.search(r"damaged|lost entries", err):
        problem = f"identify warned: {err.strip()[-300:]}"
    return doc, problem


# ---------- output ----------

def yes(value):
    return "-" if value is None else ("yes" if value else "no")


def pct(value):
    return "?" if value is None else f"{value:.3g}"


def wrap(text, width):
    """text in lines of at most width characters, broken after ', ' where it can be."""
    lines, current = [], ""
    for piece in text.split(", "):
        candidate = f"{current}, {piece}" if current else piece
        if len(candidate) <= width or not current:
            current = candidate
        else:
            lines.append(current + ",")
            current = piece
    return lines + [current]


def table(set_name, scores, total):
    lines = [f"blind records, set {set_name}: {total['records']} records"]
    if not total["has_unexplained_key"]:
        lines.append("  (identify's JSON has no `unexplained` key: every unexplained truth scores "
                     "no description)")
    header = f"{'case':<28} {'truth':<42} {'part':>4} {'desc':>4} {'wrong names':<44} " \
             f"{'library':<7} {'re-run %':>17}"
    lines += [header, "-" * len(header)]
    for s in scores:
        truth = s["truth_part"] or "(none)"
        if s["truth_kinds"]:
            truth += " " + "/".join(s["truth_kinds"])
        if s["truth_frequency_hz"]:
            truth += f" {s['truth_frequency_hz']:.3g} Hz"
        lib = f"{len(s['library_found'])}/{len(s['truth_library'])}" if s["truth_library"] else "-"
        wrong = ", ".join(s["wrong_names"]) or "none"
        if not s.get("read", True):
            wrong = "NOT READ: " + s.get("problem", "")
        rerun = f"{pct(s['rerun_before_pct'])} -> {pct(s['rerun_after_pct'])}"
        names = wrap(wrong, 44)
        lines.append(f"{s['case']:<28} {truth:<42} {yes(s['right_part']):>4} "
                     f"{yes(s['right_description']):>4} {names[0]:<44} {lib:<7} {rerun:>17}")
        lines += [f"{'':<82}{more}" for more in names[1:]]
        if s.get("other_descriptions"):
            lines.append(f"{'':<28} other descriptions: {', '.join(s['other_descriptions'])}")
        if s.get("truth_window_s"):
            lines.append(f"{'':<28} {when_text(s)}")
    lines.append("-" * len(header))
    n = total["with_unexplained_truth"]
    lines.append("re-run %: the worst floor's NRMSE against the record, declared -> identified")
    lines.append(f"total: right part {total['right_part']}/{n}, right description "
                 f"{total['right_description']}/{n}, records with wrong names "
                 f"{total['records_with_wrong_names']}/{total['records']} "
                 f"({total['wrong_names']} names), library effects found "
                 f"{total['library_found']}/{total['library_effects']}, re-run worse than "
                 f"declared {total['rerun_worse']}, read {total['read']}/{total['records']}")
    if total.get("with_window"):
        lines.append(f"when (reported, not scored): a reported window overlaps the event's in "
                     f"{total['when_overlaps']}/{total['with_window']}")
    return "\n".join(lines)


def when_text(s):
    """The event's window beside what identify reported on its part, for the table."""
    t0, t1 = s["truth_window_s"]
    text = f"event at {t0:.3f}-{t1:.3f} s: "
    if not s["reported_when_s"]:
        return text + "no `when` reported on the part"
    reported = ", ".join(f"{a:.3f}-{b:.3f} s" for a, b in s["reported_when_s"][:4])
    return text + ("overlapped by " if s["when_overlaps"] else "not overlapped by ") + reported


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--rths", required=True)
    ap.add_argument("--records")
    ap.add_argument("--writer")
    ap.add_argument("--set", choices=["tune", "report", "third", "fourth", "fifth"])
    ap.add_argument("--data")
    ap.add_argument("--work")
    ap.add_argument("--duration")
    ap.add_argument("--json", action="store_true")
    ap.add_argument("--require-reads", action="store_true")
    ap.add_argument("--timeout", type=float, default=900.0)
    # Floors and ceilings on the totals (KEY=N, a key of the total: right_description=5), so a
    # suite can hold identify to what it scored on the tune set; never set from the report set.
    ap.add_argument("--at-least", action="append", default=[], metavar="KEY=N")
    ap.add_argument("--at-most", action="append", default=[], metavar="KEY=N")
    args = ap.parse_args(argv)
    cleanup = []
    try:
        return score(ap, args, cleanup)
    finally:
        for folder in cleanup:
            shutil.rmtree(folder, ignore_errors=True)


def score(ap, args, cleanup):
    if bool(args.records) == bool(args.writer):
        ap.error("give --records DIR or --writer PATH --set S --data DIR")
    if args.writer:
        if not args.set or not args.data:
            ap.error("--writer needs --set and --data")
        folder = args.work or tempfile.mkdtemp(prefix=f"blind_{args.set}_")
        if not args.work:
            cleanup.append(folder)
        command = [args.writer, "--set", args.set, "--out", folder, "--data", args.data]
        if args.duration:
            command += ["--duration", args.duration]
        rc, out, err = run(command, args.timeout)
        if rc != 0:
            print(f"score_blind: the writer failed (exit {rc}): {err.strip()}", file=sys.stderr)
            return 1
    else:
        folder = args.records
    with open(os.path.join(folder, "truth.json")) as f:
        truth = json.load(f)
    set_name = args.set or (truth["cases"][0].get("set") if truth["cases"] else "?")
    scores = []
    failed = []
    for case in truth["cases"]:
        record = os.path.join(folder, case["record"])
        problem = read_check(args.rths, record, folder, args.timeout)
        doc, identify_problem = identify(args.rths, record, args.timeout)
        problem = "; ".join(p for p in (problem, identify_problem) if p)
        score = score_record(case, doc or {})
        score["read"] = not problem
        score["problem"] = problem
        scores.append(score)
        if problem:
            failed.append(f"{case['name']}: {problem}")
        print(f"score_blind: {case['name']}: {'read' if not problem else problem}", file=sys.stderr)
    total = totals(scores)
    if args.json:
        print(json.dumps({"set": set_name, "records": folder, "scores": scores, "total": total},
                         indent=1))
    else:
        print(table(set_name, scores, total))
    if args.require_reads and failed:
        print("score_blind: records that did not read or identify:\n  " + "\n  ".join(failed),
              file=sys.stderr)
        return 1
    missed = bounds_missed(total, args.at_least, args.at_most)
    if missed:
        print("score_blind: " + "; ".join(missed), file=sys.stderr)
        return 1
    return 0


def bounds_missed(total, at_least, at_most):
    """The --at-least / --at-most bounds the totals miss, each named with its value."""
    missed = []
    for bounds, below in ((at_least, True), (at_most, False)):
        for bound in bounds:
            key, _, value = bound.partition("=")
            if key not in total:
                raise SystemExit(f"score_blind: no total named {key!r}")
            limit = int(value)
            if (total[key] < limit) if below else (total[key] > limit):
                missed.append(f"{key} {total[key]}, {'at least' if below else 'at most'} {limit}")
    return missed


if __name__ == "__main__":
    sys.exit(main())
