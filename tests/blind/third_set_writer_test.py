#!/usr/bin/python3
"""third_set_writer's cases do what their truth says (tests/blind/third_set_writer.cpp): the set
is written at 15 s, each record exported by `rths export --csv`, and each effect is found in the
recorded signals against the rig's own law (ks = 52.6 kN/m, the specimen a third of the paper's
frame): the clean rigs agree, the held sample holds 200 samples where its window says, the
crack and the bolt slip change force against displacement at their windows, the delay steps from
14 to 19 ms at its window, the dead band carries no force inside the play, the cross-talk is a
0.9 Hz force of 30 N, the valve's load-dependent speed and the sagging capacity bound the rod, the load cell's
lag grows and the damper's coefficient falls. truth.json: 13 cases, 2 clean, 4 windows.
Needs BLIND_RTHS, BLIND_THIRD_WRITER and BLIND_DATA (ctest sets them). Exit 0 when all hold."""
import csv
import json
import math
import os
import shutil
import subprocess
import tempfile
import unittest

KS = 1000.0 * (2.0 * math.pi / 0.5) ** 2 / 3.0  # N/m, the specimen of the paper's frame
DT = 0.001  # s


def lag_steps(lead, follow, start, end, shifts):
    """The shift s (steps) of `shifts` that best fits follow[k] ~ lead[k - s] over [start, end)."""
    return min(shifts, key=lambda s: sum((follow[k] - lead[k - s]) ** 2 for k in range(start, end)))


def fit_through_zero(x, y):
    return sum(a * b for a, b in zip(x, y)) / sum(a * a for a in x)


@unittest.skipUnless(os.environ.get("BLIND_RTHS") and os.environ.get("BLIND_THIRD_WRITER"),
                     "BLIND_RTHS and BLIND_THIRD_WRITER not set")
class ThirdSet(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.folder = tempfile.mkdtemp(prefix="blind_third_")
        subprocess.run([os.environ["BLIND_THIRD_WRITER"], "--set", "third", "--out", cls.folder,
                        "--data", os.environ["BLIND_DATA"]], check=True, capture_output=True)
        with open(os.path.join(cls.folder, "truth.json")) as f:
            cls.truth = {c["name"]: c for c in json.load(f)["cases"]}

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.folder, ignore_errors=True)

    def signals(self, name):
        """{command, y, force, u} of the case's record, as `rths export --csv` reads it."""
        out = os.path.join(self.folder, name + ".csv")
        subprocess.run([os.environ["BLIND_RTHS"], "export",
                        os.path.join(self.folder, name + ".rthsrec"), "--csv", out],
                       check=True, capture_output=True)
        with open(out) as f:
            rows = list(csv.DictReader(f))
        return {key: [float(r[column]) for r in rows] for key, column in (
            ("command", "command_act1_m"), ("y", "measured_act1_m"), ("force", "force_act1_N"),
            ("u", "u_floor1_m"))}

    def window_steps(self, name):
        t0, t1 = self.truth[name]["truth"]["window_s"]
        return round(t0 / DT), round(t1 / DT)

    def residual(self, s):
        return [f - KS * y for f, y in zip(s["force"], s["y"])]

    def test_truth_lists_thirteen_cases_two_clean_four_windows(self):
        self.assertEqual(len(self.truth), 13)
        self.assertEqual(sum(1 for c in self.truth.values() if c["truth"]["part"] is None), 2)
        self.assertEqual(sum(1 for c in self.truth.values() if "window_s" in c["truth"]), 4)
        self.assertEqual(len({c["seed"] for c in self.truth.values()}), 13)

    def test_clean_rigs_agree_and_follow_the_specimen(self):
        a, b = self.signals("third_clean_a"), self.signals("third_clean_b")
        self.assertLess(max(abs(x - y) for x, y in zip(a["u"], b["u"])), 5e-5)
        self.assertLess(max(abs(r) for r in self.residual(a)[1:]), 5.0)

    def test_held_sample_repeats_one_reading_for_200_steps(self):
        s = self.signals("third_held_sample")
        k0, k1 = self.window_steps("third_held_sample")
        held = s["y"][k0 - 1]
        self.assertEqual(s["y"][k0:k1], [held] * (k1 - k0))
        self.assertNotEqual(s["y"][k1], held)
        self.assertEqual(k1 - k0, 200)

    def test_crack_loses_stiffness_at_its_window(self):
        s = self.signals("third_specimen_crack")
        k0, _ = self.window_steps("third_specimen_crack")
        before = fit_through_zero(s["y"][k0 - 2000:k0 - 1], s["force"][k0 - 2000:k0 - 1])
        after = fit_through_zero(s["y"][k0 + 1:k0 + 2000], s["force"][k0 + 1:k0 + 2000])
        self.assertAlmostEqual(before / KS, 1.0, delta=0.01)
        self.assertAlmostEqual(after / KS, 0.65, delta=0.01)

    def test_bolt_slip_offsets_the_force_after_its_window(self):
        s = self.signals("third_bolt_slip")
        k0, k1 = self.window_steps("third_bolt_slip")
        r = self.residual(s)
        self.assertLess(max(abs(x) for x in r[1:k0]), 5.0)
        offset = sum(r[k1 + 10:]) / len(r[k1 + 10:])
        self.assertAlmostEqual(abs(offset), KS * 0.8e-3, delta=3.0)

    def test_delay_steps_from_14_to_19_ms_at_its_window(self):
        s = self.signals("third_delay_jump")
        k0, _ = self.window_steps("third_delay_jump")
        shifts = range(10, 25)
        self.assertEqual(lag_steps(s["command"], s["y"], k0 - 1500, k0 - 1, shifts), 14)
        self.assertEqual(lag_steps(s["command"], s["y"], k0 + 50, k0 + 1500, shifts), 19)

    def test_dead_band_carries_no_force_inside_the_play(self):
        s = self.signals("third_pin_dead_band")
        inside = [f for f, y in zip(s["force"], s["y"]) if abs(y) < 0.5e-3]
        self.assertGreater(len(inside), 100)
        self.assertLess(max(abs(f) for f in inside), 3.0)

    def test_crosstalk_is_30_n_at_0_9_hz(self):
        r = self.residual(self.signals("third_crosstalk"))
        k = range(4500, 14500)  # 9 and 13 whole cycles of 0.9 and 1.3 Hz, after the fade-in
        for hz, expected in ((0.9, 30.0), (1.3, 0.0)):
            c = sum(r[i] * math.cos(2 * math.pi * hz * i * DT) for i in k) * 2 / len(k)
            q = sum(r[i] * math.sin(2 * math.pi * hz * i * DT) for i in k) * 2 / len(k)
            self.assertAlmostEqual(math.hypot(c, q), expected, delta=2.0)

    def test_valve_and_sagging_capacity_bound_the_rod(self):
        # |dy/dt| <= 0.16 m/s sqrt(max(0.05, 1 - sgn(dy/dt) f / 1500 N)), f = ks y; the reading's
        # noise and quantum give 15 mm/s of slack; pushing outward, the bound is reached.
        y = self.signals("third_valve_flow_limit")["y"]
        outward_at_bound = 0
        for k in range(1, len(y) - 1):
            speed = (y[k + 1] - y[k]) / DT
            sign = 1.0 if speed >= 0 else -1.0
            bound = 0.16 * math.sqrt(max(0.05, 1.0 - sign * KS * y[k] / 1500.0))
            self.assertLess(abs(speed), bound + 0.015)
            outward_at_bound += sign * y[k] > 0 and abs(speed) > bound - 0.015
        self.assertGreater(outward_at_bound, 10)
        y = self.signals("third_accumulator_sag")["y"]
        reach = [(1400.0 - 900.0 * k / len(y)) / KS for k in range(len(y))]
        self.assertTrue(all(abs(v) <= r + 1e-5 for v, r in zip(y, reach)))
        self.assertTrue(any(abs(v) > r - 1e-5 for v, r in zip(y, reach)))

    def test_load_cell_lag_grows_and_the_damper_cools_down(self):
        s = self.signals("third_cell_clock_drift")
        spring = [KS * y for y in s["y"]]
        early = lag_steps(spring, s["force"], 4000, 6000, range(0, 12))
        late = lag_steps(spring, s["force"], 12000, 14000, range(0, 12))
        self.assertLessEqual(early, 4)
        self.assertGreaterEqual(late, 7)
        s = self.signals("third_damper_warming")
        r = self.residual(s)
        v = [0.0] + [(s["y"][k + 1] - s["y"][k - 1]) / (2 * DT) for k in range(1, len(r) - 1)]
        c_early = fit_through_zero(v[4000:7000], r[4000:7000])
        c_late = fit_through_zero(v[11000:14999], r[11000:14999])
        self.assertAlmostEqual(c_early, 1200 * (0.4 + 0.6 * math.exp(-5.5 / 6)), delta=60)
        self.assertAlmostEqual(c_late, 1200 * (0.4 + 0.6 * math.exp(-13.0 / 6)), delta=60)


if __name__ == "__main__":
    unittest.main()
