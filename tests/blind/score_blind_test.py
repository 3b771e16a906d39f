#!/usr/bin/python3
"""The blind scorer's own logic (score_blind.py) on fabricated identify JSON: it must credit a
right part and description, refuse a periodic frequency off by more than 5 %, count a wrong name
(on a clean record, and a library effect the truth lacks), score "no description" when the
`unexplained` key is absent, read the re-run's worst floor before -> after, and report (never
score) whether a `when` identify gives on the truth's part overlaps an event's window. With
BLIND_RTHS, BLIND_WRITER and BLIND_DATA set (ctest sets them) also end to end: a record of the
writer's reads, and the same record with 8 bytes overwritten fails --require-reads. Exit 0 when all
hold (unittest)."""
import contextlib
import io
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import score_blind  # noqa: E402


def case(part=None, kinds=(), frequency=None, library=(), accepted=(), window=None):
    c = {"name": "c", "what": "", "truth": {
        "part": part, "kinds": list(kinds), "frequency_hz": frequency,
        "library": [{"part": p, "effect": e} for p, e in library],
        "accepted": [{"part": p, "effect": e} for p, e in accepted]}}
    if window:
        c["truth"]["window_s"] = list(window)
    return c


def entry(part, kinds, frequency=None):
    return {"part": part, "channel": "force", "share_pct": 80.0, "kinds": list(kinds),
            "periodic": {"frequency_hz": frequency, "amplitude": 1.0, "unit": "N"}
            if frequency else None,
            "amplitude": None, "direction": None, "time_varying": None, "text": "unexplained"}


class ScoreBlind(unittest.TestCase):
    def test_bounds_name_each_total_they_miss(self):
        total = {"right_description": 4, "rerun_worse": 2, "right_part": 7}
        missed = score_blind.bounds_missed(total, ["right_description=5", "right_part=7"],
                                  ["rerun_worse=1"])
        self.assertEqual(missed, ["right_description 4, at least 5", "rerun_worse 2, at most 1"])
        self.assertEqual(score_blind.bounds_missed(total, ["right_part=7"], ["rerun_worse=2"]), [])
        with self.assertRaises(SystemExit):
            score_blind.bounds_missed(total, ["no_such_total=1"], [])

    def test_right_part_and_periodic_description(self):
        s = score_blind.score_record(case("load cell 1", ["periodic"], 13.0),
                                     {"undeclared": [], "unexplained": [
                                         entry("load cell 1", ["periodic"], 13.4)]})
        self.assertTrue(s["right_part"])
        self.assertTrue(s["right_description"])
        self.assertEqual(s["wrong_names"], [])

    def test_periodic_frequency_off_by_more_than_5_pct(self):
        s = score_blind.score_record(case("load cell 1", ["periodic"], 13.0),
                                     {"unexplained": [entry("load cell 1", ["periodic"], 13.7)]})
        self.assertTrue(s["right_part"])
        self.assertFalse(s["right_description"])

    def test_wrong_kind_and_wrong_part(self):
        s = score_blind.score_record(case("specimen 1", ["direction"]),
                                     {"unexplained": [entry("specimen 1", ["amplitude"]),
                                                      entry("load cell 1", ["direction"])]})
        self.assertTrue(s["right_part"])
        self.assertFalse(s["right_description"])
        self.assertEqual(s["other_descriptions"], ["load cell 1: direction"])
        s = score_blind.score_record(case("specimen 1", ["direction"]),
                                     {"unexplained": [entry("load cell 1", ["direction"])]})
        self.assertFalse(s["right_part"])
        self.assertFalse(s["right_description"])

    def test_either_accepted_kind(self):
        s = score_blind.score_record(case("load cell 1", ["periodic", "time_varying"], 0.2),
                                     {"unexplained": [entry("load cell 1", ["time_varying"])]})
        self.assertTrue(s["right_description"])

    def test_named_effect_on_the_part_is_the_right_part_but_a_wrong_name(self):
        s = score_blind.score_record(case("specimen 1", ["time_varying"]),
                                     {"undeclared": [{"part": "specimen 1",
                                                      "effect": "stiffness change"}]})
        self.assertTrue(s["right_part"])
        self.assertFalse(s["right_description"])
        self.assertEqual(s["wrong_names"], ["specimen 1: stiffness change"])
        self.assertFalse(s["has_unexplained_key"])

    def test_accepted_name_is_not_wrong(self):
        s = score_blind.score_record(
            case("specimen 1", ["time_varying"], accepted=[("specimen 1", "time_varying_stiffness")]),
            {"undeclared": [{"part": "specimen 1", "effect": "time_varying_stiffness"},
                            {"part": "specimen 1", "effect": "stiffness change"}]})
        self.assertTrue(s["right_part"])
        self.assertEqual(s["wrong_names"], ["specimen 1: stiffness change"])

    def test_clean_record_naming_anything_is_wrong(self):
        s = score_blind.score_record(case(), {"undeclared": [
            {"part": "actuator 1", "effect": "backlash"}], "unexplained": []})
        self.assertIsNone(s["right_part"])
        self.assertEqual(s["wrong_names"], ["actuator 1: backlash"])
        self.assertEqual(score_blind.totals([s])["records_with_wrong_names"], 1)

    def test_library_effect_found_missed_and_extra(self):
        lib = [("actuator 1", "first_order")]
        s = score_blind.score_record(case(library=lib), {"undeclared": [
            {"part": "actuator 1", "effect": "first_order"}]})
        self.assertEqual(s["wrong_names"], [])
        self.assertEqual(s["library_found"], ["actuator 1: first_order"])
        s = score_blind.score_record(case(library=lib), {"undeclared": [
            {"part": "actuator 1", "effect": "delay change"}]})
        self.assertEqual(s["wrong_names"], ["actuator 1: delay change"])
        self.assertEqual(s["library_missed"], ["actuator 1: first_order"])

    def test_absent_unexplained_key_scores_no_description(self):
        s = score_blind.score_record(case("load cell 1", ["periodic"], 13.0), {"undeclared": []})
        self.assertFalse(s["right_part"])
        self.assertFalse(s["right_description"])
        self.assertIsNone(s["described"])
        self.assertFalse(score_blind.totals([s])["has_unexplained_key"])

    def test_rerun_worst_floor(self):
        doc = {"residual": {"floors": [
            {"floor": 1, "declared_nrmse_pct": 12.0, "identified_nrmse_pct": 0.5},
            {"floor": 2, "declared_nrmse_pct": 30.0, "identified_nrmse_pct": 0.2}]}}
        self.assertEqual(score_blind.rerun_errors(doc), (30.0, 0.5))
        self.assertEqual(score_blind.rerun_errors({}), (None, None))
        # As identify writes it: fractions per floor, the worst at the top too.
        doc = {"residual": {"declared_nrmse": 0.5, "identified_nrmse": 0.001, "floors": [
            {"dof": 1, "declared_nrmse": 0.5, "identified_nrmse": 0.001}],
            "links": [{"link": "actuator 1", "nrmse_removed": 0.4}]}}
        self.assertEqual(score_blind.rerun_errors(doc), (50.0, 0.1))
        worse = score_blind.score_record(case("displacement sensor 1", ["amplitude"]), {
            "residual": {"floors": [{"declared_nrmse": 0.001, "identified_nrmse": 0.06}]}})
        self.assertEqual(score_blind.totals([worse])["rerun_worse"], 1)

    def test_when_overlapping_the_event_window_is_reported_not_scored(self):
        crack = case("specimen 1", ["time_varying"], window=(8.95, 9.0))
        described = entry("specimen 1", ["time_varying"])
        plain = score_blind.score_record(crack, {"unexplained": [described]})
        self.assertIsNone(plain["when_overlaps"])
        timed = dict(described, time_varying={"when": [[8.9, 9.4], [12.0, 12.5]]})
        s = score_blind.score_record(crack, {"unexplained": [timed]})
        self.assertTrue(s["when_overlaps"])
        self.assertEqual(s["reported_when_s"], [(8.9, 9.4), (12.0, 12.5)])
        for key in ("right_part", "right_description", "wrong_names"):
            self.assertEqual(s[key], plain[key])
        apart = dict(described, when={"start_s": 2.0, "end_s": 3.0})
        self.assertFalse(score_blind.score_record(crack, {"unexplained": [apart]})
                         ["when_overlaps"])
        named = {"part": "specimen 1", "effect": "stiffness change", "when": 8.97}
        self.assertTrue(score_blind.score_record(crack, {"undeclared": [named]})["when_overlaps"])
        elsewhere = dict(timed, part="load cell 1")
        self.assertIsNone(score_blind.score_record(crack, {"unexplained": [elsewhere]})
                          ["when_overlaps"])
        total = score_blind.totals([s, plain])
        self.assertEqual((total["with_window"], total["when_overlaps"]), (2, 1))
        self.assertEqual(total["right_description"], 2)
        text = score_blind.table("third", [s], score_blind.totals([s]))
        self.assertIn("event at 8.950-9.000 s: overlapped by 8.900-9.400 s", text)
        self.assertIn("overlaps the event's in 1/1", text)

    def test_no_window_no_when_line(self):
        s = score_blind.score_record(case("specimen 1", ["time_varying"]), {
            "unexplained": [dict(entry("specimen 1", ["time_varying"]), when=[1.0, 2.0])]})
        self.assertIsNone(s["when_overlaps"])
        text = score_blind.table("tune", [s], score_blind.totals([s]))
        self.assertNotIn("when", text)

    def test_table_states_a_missing_unexplained_key(self):
        s = score_blind.score_record(case("load cell 1", ["periodic"], 13.0), {"undeclared": []})
        text = score_blind.table("tune", [s], score_blind.totals([s]))
        self.assertIn("no `unexplained` key", text)
        self.assertIn("right part 0/1", text)


@unittest.skipUnless(os.environ.get("BLIND_RTHS") and os.environ.get("BLIND_WRITER"),
                     "BLIND_RTHS and BLIND_WRITER not set")
class RequireReads(unittest.TestCase):
    def setUp(self):
        self.folder = tempfile.mkdtemp(prefix="blind_self_check_")
        subprocess.run([os.environ["BLIND_WRITER"], "--set", "tune", "--case", "tune_clean",
                        "--duration", "3", "--out", self.folder, "--data",
                        os.environ["BLIND_DATA"]], check=True, capture_output=True)

    def tearDown(self):
        shutil.rmtree(self.folder, ignore_errors=True)

    def score(self):
        with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(io.StringIO()):
            return score_blind.main(["--rths", os.environ["BLIND_RTHS"], "--records", self.folder,
                                     "--require-reads"])

    def test_intact_record_reads_and_damaged_one_fails(self):
        self.assertEqual(self.score(), 0)
        record = os.path.join(self.folder, "tune_clean.rthsrec")
        with open(record, "r+b") as f:
            f.seek(os.path.getsize(record) // 2)
            f.write(b"XXXXXXXX")
        self.assertEqual(self.score(), 1)


if __name__ == "__main__":
    unittest.main()
