#!/usr/bin/python3
"""fourth_set_writer's cases do what their truth says (tests/blind/fourth_set_writer.cpp): the
set is written at 15 s, each record exported by `rths export --csv`, and each effect is found in
the recorded signals against its own law on the rig (a bearing ks = 0.4 * 3000 kg (2 pi / 0.3 s)^2
= 526 kN/m, the declared 5 ms shift): the clean rigs agree and follow the bearing, the string pot
never rewinds faster than 0.09 m/s but extends faster, the Mullins bearing's force follows its
softening law, the load cell's zero shifts 45 N at its window, the delay saws between 5 and 6 ms,
the rod's lag grows from 0.5 to 3 ms, the load cell clips at 4 kN, impacts ring at 31 Hz every
2.5 s, the infill stiffens the bearing one way past 5 mm, the transducer's base slips 0.35 mm at
its window and its gain dips 4 %. truth.json: 12 cases, 2 clean, 3 windows, every seed its own.
Needs BLIND_RTHS, BLIND_FOURTH_WRITER and BLIND_DATA (ctest sets them). Exit 0 when all hold."""
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import third_set_writer_test as third  # noqa: E402  (a record's signals, a window's steps)

KS = 0.4 * 3000.0 * (2.0 * math.pi / 0.3) ** 2  # N/m, the bearing
DT = 0.001  # s
DELAY_STEPS = 5  # the declared 5 ms shift


fit_through_zero = third.fit_through_zero


def shifted(samples, k, shift):
    """samples at the fractional index k - shift, linear between samples, 0 before 0."""
    at = k - shift
    if at <= 0:
        return 0.0
    j = int(at)
    w = at - j
    return (1 - w) * samples[j] + w * samples[j + 1] if j + 1 <= k else samples[j]


def rms(values):
    values = list(values)
    return math.sqrt(sum(v * v for v in values) / len(values))


@unittest.skipUnless(os.environ.get("BLIND_RTHS") and os.environ.get("BLIND_FOURTH_WRITER"),
                     "BLIND_RTHS and BLIND_FOURTH_WRITER not set")
class FourthSet(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.folder = tempfile.mkdtemp(prefix="blind_fourth_")
        subprocess.run([os.environ["BLIND_FOURTH_WRITER"], "--set", "fourth", "--out",
                        cls.folder, "--data", os.environ["BLIND_DATA"]],
                       check=True, capture_output=True)
        with open(os.path.join(cls.folder, "truth.json")) as f:
            cls.truth = {c["name"]: c for c in json.load(f)["cases"]}

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.folder, ignore_errors=True)

    signals = third.ThirdSet.signals  # {command, y, force, u} as `rths export --csv` reads them
    window_steps = third.ThirdSet.window_steps  # the truth's window_s in steps of 1 ms

    def residual(self, s):
        return [f - KS * y for f, y in zip(s["force"], s["y"])]

    def test_truth_lists_twelve_cases_two_clean_three_windows(self):
        self.assertEqual(len(self.truth), 12)
        self.assertEqual(sum(1 for c in self.truth.values() if c["truth"]["part"] is None), 2)
        self.assertEqual(sum(1 for c in self.truth.values() if "window_s" in c["truth"]), 3)
        self.assertEqual(len({c["seed"] for c in self.truth.values()}), 12)

    def test_clean_rigs_agree_and_follow_the_bearing_5_ms_late(self):
        a, b = self.signals("fourth_clean_a"), self.signals("fourth_clean_b")
        self.assertLess(max(abs(x - y) for x, y in zip(a["u"], b["u"])), 5e-5)
        self.assertLess(max(abs(r) for r in self.residual(a)[1:]), 15.0)
        rod = [shifted(a["command"], k, DELAY_STEPS) for k in range(len(a["y"]))]
        self.assertLess(rms(y - x for y, x in zip(a["y"], rod)), 5e-6)

    def test_string_pot_rewinds_at_most_0_09_m_per_s(self):
        y = self.signals("fourth_string_pot_rewind")["y"]
        speeds = [(y[k + 1] - y[k]) / DT for k in range(len(y) - 1)]
        slack = 0.02  # m/s: two readings' noise (3 um, 4 sigma) and quantum (3 um) over 1 ms
        self.assertGreater(min(speeds), -0.09 - slack)
        self.assertGreater(sum(1 for v in speeds if v < -0.09 + slack), 50)
        self.assertGreater(max(speeds), 0.15)

    def test_mullins_bearing_follows_its_softening_law(self):
        s = self.signals("fourth_mullins_bearing")
        stretch, law = 0.0, []
        for y in s["y"]:
            stretch = max(stretch, abs(y))
            depth = 0.35 * (1 - math.exp(-stretch / 4e-3))
            law.append(KS * y * (1 - depth * (1 - (y / stretch) ** 2)) if stretch else 0.0)
        self.assertLess(rms(f - g for f, g in zip(s["force"], law)), 10.0)
        self.assertGreater(rms(self.residual(s)), 200.0)

    def test_load_cell_zero_shifts_45_n_at_its_window(self):
        s = self.signals("fourth_cell_overload")
        k0, _ = self.window_steps("fourth_cell_overload")
        r = self.residual(s)
        self.assertLess(abs(sum(r[1:k0]) / (k0 - 1)), 1.0)
        self.assertAlmostEqual(abs(sum(r[k0 + 1:]) / len(r[k0 + 1:])), 45.0, delta=1.0)
        self.assertGreater(abs(s["force"][k0]), 4500.0 - 10.0)
        self.assertLess(max(abs(f) for f in s["force"][:k0]), 4500.0 + 10.0)

    def test_delay_saws_between_5_and_6_ms_every_5_s(self):
        s = self.signals("fourth_clock_beat")
        for t0 in (3.6, 8.2, 8.6, 13.2):  # just after and before a slip (at 3.5, 8.5, 13.5 s)
            phase = (t0 + 0.1) / 5.0 + 0.3
            expected = 5.0 + (phase - math.floor(phase))  # ms
            ks = range(round(t0 / DT), round((t0 + 0.2) / DT))
            best = min((d / 10 for d in range(45, 66)), key=lambda d: sum(
                (s["y"][k] - shifted(s["command"], k, d)) ** 2 for k in ks))
            self.assertAlmostEqual(best, expected, delta=0.15)

    def test_rod_lag_grows_from_0_5_to_3_ms(self):
        s = self.signals("fourth_servo_gain_fade")

        def misfit(tau, start, end):
            x, total = 0.0, 0.0
            for k in range(start - 500, end):
                x += (shifted(s["command"], k, DELAY_STEPS) - x) * (1 - math.exp(-DT / tau))
                total += (s["y"][k] - x) ** 2 if k >= start else 0.0
            return total

        taus = [t / 10000 for t in range(2, 41, 2)]
        for start, tau in ((3000, 0.5e-3 + 2.5e-3 * 3.5 / 15), (12000, 0.5e-3 + 2.5e-3 * 12.5 / 15)):
            best = min(taus, key=lambda t: misfit(t, start, start + 1000))
            self.assertAlmostEqual(best, tau, delta=0.25e-3)

    def test_load_cell_clips_at_4_kn(self):
        s = self.signals("fourth_cell_clipping")
        self.assertLessEqual(max(abs(f) for f in s["force"]), 4000.0 + 1.6)
        clipped = [k for k, f in enumerate(s["force"]) if abs(f) > 4000.0 - 1.6]
        self.assertGreater(len(clipped), 100)
        self.assertTrue(all(KS * abs(s["y"][k]) > 4000.0 - 20.0 for k in clipped))
        below = [r for r, y in zip(self.residual(s), s["y"]) if KS * abs(y) < 3900.0]
        self.assertLess(max(abs(r) for r in below[1:]), 15.0)

    def test_impacts_ring_at_31_hz_every_2_5_s(self):
        r = self.residual(self.signals("fourth_floor_impact"))
        self.assertLess(max(abs(x) for x in r[1:1200]), 15.0)
        for t_i in (1.2, 3.7, 6.2, 8.7, 11.2, 13.7):
            k0 = round(t_i / DT)
            ks = range(k0, k0 + 120)
            c = sum(r[k] * math.cos(2 * math.pi * 31 * (k - k0) * DT) for k in ks)
            q = sum(r[k] * math.sin(2 * math.pi * 31 * (k - k0) * DT) for k in ks)
            envelope = sum(math.exp(-(k - k0) * DT / 0.06) for k in ks)
            self.assertAlmostEqual(math.hypot(c, q) * 2 / envelope, 80.0, delta=8.0)
            self.assertLess(rms(r[k0 - 400:k0 - 200]), 5.0)

    def test_infill_stiffens_the_bearing_one_way_past_5_mm(self):
        s = self.signals("fourth_infill_contact")
        r = self.residual(s)
        past = [max(0.0, y - 5e-3) for y in s["y"]]
        self.assertGreater(sum(1 for p in past if p > 1e-3), 50)
        self.assertAlmostEqual(fit_through_zero(past, r) / KS, 0.8, delta=0.02)
        self.assertLess(max(abs(x) for x, y in zip(r[1:], s["y"][1:]) if y < 4.9e-3), 15.0)
        self.assertLess(min(s["y"]), -5e-3)

    def test_transducer_base_slips_0_35_mm_at_its_window(self):
        s = self.signals("fourth_mount_slip")
        k0, k1 = self.window_steps("fourth_mount_slip")
        self.assertEqual(k1 - k0, 20)
        r = self.residual(s)
        self.assertLess(abs(sum(r[1:k0]) / (k0 - 1)), 1.0)
        self.assertAlmostEqual(sum(r[k1:]) / len(r[k1:]), -KS * 0.35e-3, delta=2.0)

    def test_transducer_gain_dips_4_pct_and_recovers(self):
        s = self.signals("fourth_excitation_sag")
        k0, k1 = self.window_steps("fourth_excitation_sag")
        self.assertEqual((k0, k1), (7500, 9000))
        rod = [f / KS for f in s["force"]]
        for start, gain in ((k0 - 1500, 1.0), (k0, 1 - 0.04 * math.exp(-0.1 / 1.5)),
                            (k0 + 4000, 1 - 0.04 * math.exp(-4.1 / 1.5))):
            ks = range(start, start + 200)
            fitted = fit_through_zero([rod[k] for k in ks], [s["y"][k] for k in ks])
            self.assertAlmostEqual(fitted, gain, delta=0.004)


if __name__ == "__main__":
    unittest.main()
