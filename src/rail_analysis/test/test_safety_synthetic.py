#!/usr/bin/env python3
"""The safety, track-loading, wear and comfort evaluation (rail_analysis.safety, comfort, safety_report) on
bags written by this test with known values (test/safety_synthetic_bags.py): Y/Q, SumY and their 2 m means,
Nadal's and Prud'homme's limits, wheel unloading, Tgamma, the EN 12299 weighted accelerations and N_MV
against the published weighting formula, pad forces, the "not available" texts, the CSV, the wheel with the
largest value, and refused input. Runs as a plain unittest (python3 test_safety_synthetic.py --text) or
through rosunit (JUnit XML; --gtest_output=xml:... is handled by rosunit)."""
import csv
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.realpath(__file__))
PKG_SRC = os.path.join(os.path.dirname(HERE), "src")
SCRIPT = os.path.join(os.path.dirname(HERE), "scripts", "railsim_safety")
sys.path.insert(0, PKG_SRC)
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
import yaml  # noqa: E402

import safety_synthetic_bags as syn  # noqa: E402
from rail_analysis import comfort, safety, safety_report  # noqa: E402

# Published weighting parameters, written out again here so that the expected gains do not come from the
# code under test: ISO 2631-1:1997 Table A.1 (Wd) and ISO 2631-4:2001 Table A.1 / EN 12299 (Wb), as ISO
# 8041:2005 Table 3 lists them (K = 1.024 with the step unity at high frequency; reproduced in the Larson Davis
# HVM200 Reference Manual, Table 3.1). f in Hz.
PUBLISHED = {"Wd": (0.4, 100.0, 2.0, 2.0, 0.63, None, None, None, None, 1.0),
             "Wb": (0.4, 100.0, 16.0, 16.0, 0.55, 2.5, 0.9, 4.0, 0.95, 1.024)}
# Weighting factors at the reference angular frequency 100 rad/s (15.915 Hz), four digits, as makers of
# vibration meters publish them (ZETLAB, frequency weighting functions: Wb 0.8126 (ISO 2631-4), Wd 0.1261
# (ISO 2631-1)).
REFERENCE_100_RAD_S = {"Wb": 0.8126, "Wd": 0.1261}
# ISO 2631-1:1997 Table 3: Wd weighting factors (x 1000 in the table) at 1, 2 and 4 Hz.
ISO2631_WD_TABLE = {1.0: 1.011, 2.0: 0.890, 4.0: 0.512}


def published_gain(name, f):
    """|H(j 2 pi f)| of ISO 2631-1 Annex A: |Hh Hl Ht Hs| K, Q1 = Q2 = 1/sqrt(2)."""
    f1, f2, f3, f4, q4, f5, q5, f6, q6, k = PUBLISHED[name]
    s = 2j * math.pi * f
    w = lambda x: 2 * math.pi * x
    q = 1 / math.sqrt(2)
    h = (s * s / (s * s + w(f1) / q * s + w(f1) ** 2)) * (w(f2) ** 2 / (s * s + w(f2) / q * s + w(f2) ** 2))
    h *= (1 + s / w(f3)) / (1 + s / (q4 * w(f4)) + (s / w(f4)) ** 2)
    if f5:
        h *= (s * s + w(f5) / q5 * s + w(f5) ** 2) / (s * s + w(f6) / q6 * s + w(f6) ** 2)
    return abs(k * h)


def run_tool(args):
    env = dict(os.environ)
    env["PYTHONPATH"] = PKG_SRC + os.pathsep + env.get("PYTHONPATH", "")
    env["MPLBACKEND"] = "Agg"
    return subprocess.run([sys.executable, SCRIPT] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, env=env, timeout=300)


def row(ev, prefix):
    rows = [r for r in ev.rows if r.quantity.startswith(prefix)]
    assert len(rows) == 1, (prefix, [r.quantity for r in ev.rows])
    return rows[0]


class SafetySynthetic(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="rail_safety_syn_")
        cls.dir = os.path.join(cls.work, "runs")
        syn.write_all(cls.dir)
        # Comfort windows start 5 s after the discard: the 0.4 Hz band-limiting high-pass (time constant
        # 1/(2 pi 0.4 / sqrt 2) = 0.56 s) has then decayed the sine-onset transient by exp(-9) ~ 1e-4.
        cls.settings = safety.Settings(comfort_settle=5.0)
        cls.runs = {n: safety.load_run_dir(cls.dir, n) for n in ("standalone", "rigid_fe", "flexible")}
        cls.evals = {n: safety.evaluate(r, cls.settings) for n, r in cls.runs.items()}
        cls.ev = cls.evals["standalone"]

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    # --- forces ----------------------------------------------------------------------------------------
    def test_static_wheel_load_from_the_vehicle_masses(self):
        # Q0 = 52 000 kg x 9.81 / 8 wheels; only rounding (1e-9 relative).
        self.assertAlmostEqual(self.ev.q0, sum(syn.MASSES) * 9.81 / 8, delta=1e-9 * syn.Q0)
        self.assertIn("vehicle data file", self.ev.sources["q0"])

    def test_constant_y_and_q_give_y_over_q_and_sumy(self):
        ev = self.ev
        # Before the step: right wheel Y = +30 kN, Q = 80 kN; left wheel Y = -10 kN (pushed away from the
        # centre), Q = 60 kN; SumY = 10 + 30 kN. Exact (1e-12) since the values are constant.
        before = ev.s[:, 0] < syn.S_STEP - 2.0
        np.testing.assert_allclose(ev.yq[before, 0, 1], 30e3 / 80e3, rtol=1e-12)
        np.testing.assert_allclose(ev.yq[before, 0, 0], -10e3 / 60e3, rtol=1e-12)
        np.testing.assert_allclose(ev.sumy[before, 0], 40e3, rtol=1e-12)
        # The 2 m mean of a constant is the constant, where the window is covered.
        m = before & np.isfinite(ev.sumy_2m[:, 0])
        self.assertGreater(m.sum(), 100)
        np.testing.assert_allclose(ev.sumy_2m[m, 0], 40e3, rtol=1e-12)
        np.testing.assert_allclose(ev.yq_2m[m, 0, 1], 0.375, rtol=1e-12)

    def test_two_metre_mean_across_a_step(self):
        # Right Fy steps 30 -> 50 kN at S_STEP. A centred 2 m window around s holds a = S_STEP - (s - 1) m at
        # 30 kN and 2 - a at 50 kN; SumY adds the left wheel's 10 kN. The samples are ds = V / rate = 0.1 m
        # apart and the record's linear interpolation spreads the step over one spacing, which moves the
        # mean by at most ds/2 x 20 kN / 2 m = 0.5 kN: tolerance 0.6 kN.
        ev = self.ev
        s0 = ev.s[:, 0]
        k = int(np.argmin(np.abs(s0 - (syn.S_STEP + 0.5))))
        a = syn.S_STEP - (s0[k] - 1.0)
        expected = syn.WS0_LEFT_FY + (a * syn.WS0_RIGHT_FY + (2.0 - a) * syn.WS0_RIGHT_FY_AFTER) / 2.0
        self.assertAlmostEqual(ev.sumy_2m[k, 0], expected, delta=600.0)
        # Fully past the step: 60 kN (exact).
        k = int(np.argmin(np.abs(s0 - (syn.S_STEP + 5.0))))
        self.assertAlmostEqual(ev.sumy_2m[k, 0], 60e3, delta=1e-6)

    def test_nadal_and_prudhomme_limits(self):
        # Nadal at 70 deg, mu = 0.3 (no friction in the scene: the contact model's default):
        # tan 70 deg = 2.74748; (2.74748 - 0.3)/(1 + 0.3 x 2.74748) = 2.44748 / 1.82424 = 1.34164 (hand value).
        self.assertAlmostEqual(self.ev.friction, 0.3)
        self.assertAlmostEqual(self.ev.limits["yq"], 1.34164, delta=1e-5)
        # Prud'homme: 10 kN + 2 Q0 / 3 with alpha = 1 (rounding only).
        self.assertAlmostEqual(self.ev.limits["sumy"], 10e3 + 2 * syn.Q0 / 3, delta=1e-6)
        # A friction in the scene or the options is used instead.
        ev = safety.evaluate(self.runs["standalone"], safety.Settings(friction=0.5, comfort_settle=5.0))
        t = math.tan(math.radians(70))
        self.assertAlmostEqual(ev.limits["yq"], (t - 0.5) / (1 + 0.5 * t), delta=1e-12)

    def test_flange_climb_row_fails_and_distance_is_measured(self):
        r = row(self.ev, "Y/Q (2 m mean)")
        # Wheelset 2 right: Y/Q = 1.5 over 3 m; the 2 m mean reaches 1.5 (window inside the plateau).
        self.assertEqual((r.wheel_id, r.wheelset, r.side), (3, 1, 1))
        self.assertAlmostEqual(r.value, 1.5, delta=1e-9)
        self.assertEqual(r.status, safety.FAIL)
        self.assertAlmostEqual(r.margin, self.ev.limits["yq"] - 1.5, delta=1e-9)
        # Distance over the limit: 3 m to one sample spacing (0.1 m).
        d = row(self.ev, "Y/Q over the limit")
        self.assertEqual(d.wheel_id, 3)
        self.assertAlmostEqual(d.value, 3.0, delta=0.1 + 1e-9)
        # SumY of that wheelset: 1.5 x 60 kN = 90 kN over 3 m > Prud'homme's 52.5 kN.
        r = row(self.ev, "track-shift force")
        self.assertEqual(r.wheelset, 1)
        self.assertAlmostEqual(r.value, 90e3, delta=1e-6)
        self.assertEqual(r.status, safety.FAIL)

    def test_wheel_unloading(self):
        r = row(self.ev, "wheel unloading")
        # Wheelset 3 left at 0.45 Q0: dQ/Q0 = 0.55 < 0.6 (exact up to rounding).
        self.assertEqual(r.wheel_id, 4)
        self.assertAlmostEqual(r.value, 1 - syn.WS2_UNLOAD_RATIO, delta=1e-12)
        self.assertEqual(r.status, safety.PASS)
        self.assertAlmostEqual(r.limit, 0.6)

    def test_vertical_force_and_quasi_static_part(self):
        # The largest Q is the constant 80 kN of the leading right wheel; a low-pass keeps a constant
        # (1e-6 relative: the filters' rounding). Limits: 200 kN (EN 14363, V <= 160 km/h) and 145 kN.
        for prefix, lim in (("vertical wheel force", 200e3), ("quasi-static Q", 145e3)):
            r = row(self.ev, prefix)
            self.assertEqual(r.wheel_id, 1, prefix)
            self.assertAlmostEqual(r.value, syn.WS0_RIGHT_Q, delta=1e-6 * syn.WS0_RIGHT_Q)
            self.assertEqual(r.limit, lim)
            self.assertEqual(r.status, safety.PASS)

    def test_impact_peaks_p1_and_p2(self):
        # An impact's force, sampled at 10 kHz: Q0 plus a 700 Hz burst (P1, decaying in ~1 ms) and a 60 Hz
        # response (P2, decaying in ~20 ms), the two frequencies of Jenkins et al. (1974). P1 is the raw
        # maximum; the 150 Hz low-pass (2nd order, forward and backward: gain 1 / (1 + (f/150)^4)) keeps
        # 97.5 % of a steady 60 Hz sine and 0.2 % of the 700 Hz burst; the response's onset and decay spread
        # its spectrum and cost about 2 % more: P2 within 6 % of the 60 Hz part's own peak.
        t = np.arange(0.0, 0.2, 1e-4)
        q0, t0 = 73e3, 0.05
        tau = np.clip(t - t0, 0.0, None)
        p2_part = 60e3 * np.exp(-tau / 0.02) * np.sin(2 * np.pi * 60.0 * tau)
        p1_part = 90e3 * np.exp(-tau / 1e-3) * np.sin(2 * np.pi * 700.0 * tau)
        q = q0 + p2_part + p1_part
        qp2 = safety.p2_force(t, q)
        self.assertAlmostEqual(float(np.max(qp2)), q0 + float(np.max(p2_part)), delta=0.06 * float(np.max(p2_part)))
        self.assertGreater(float(np.max(q)), float(np.max(qp2)) + 20e3)  # P1 (the raw peak, 144 kN) above P2
        # Too sparse for the cut-off: none, and the report says what rate it needs.
        self.assertIsNone(safety.p2_force(t[::40], q[::40]))
        r = row(self.ev, "impact force P1")
        self.assertEqual(r.status, safety.INFO)
        self.assertIn("under-sampled", r.note)

    def test_sliding_mean_of_a_ramp(self):
        # The centred mean of a linear function is its value at the centre (exact for the trapezoid rule).
        s = np.linspace(0.0, 10.0, 1001)
        m = safety.sliding_mean(s, 3.0 * s + 1.0, 2.0)
        ok = np.isfinite(m)
        self.assertEqual(int(ok.sum()), 801)  # windows inside [0, 10]: centres 1..9 m
        np.testing.assert_allclose(m[ok], 3.0 * s[ok] + 1.0, rtol=1e-12)

    # --- wear ------------------------------------------------------------------------------------------
    def test_tgamma_from_known_creepages_and_forces(self):
        tg = self.ev.tgamma
        # Leading right wheel: tread 5000 x 0.002 + 4000 x 0.003 = 22 N, flange 2000 x 0.01 + 8000 x 0.02 =
        # 180 N; others 1000 x 0.001 + 500 x 0.002 = 2 N; inactive slots and spin do not count. Exact values
        # (1e-9 relative).
        np.testing.assert_allclose(tg["value"][:, 1], syn.TGAMMA_1, rtol=1e-9)
        np.testing.assert_allclose(tg["tread"][:, 1], 22.0, rtol=1e-9)
        np.testing.assert_allclose(tg["flange"][:, 1], 180.0, rtol=1e-9)
        for k in (0, 2, 3, 4, 5, 6, 7):
            np.testing.assert_allclose(tg["value"][:, k], syn.TGAMMA_ALL, rtol=1e-9)
        r = row(self.ev, "wear index Tgamma")
        self.assertEqual((r.wheel_id, r.value), (1, syn.TGAMMA_1))
        # Distribution over the circular curve (the part the wheel covered): mean 202 N for wheel 1.
        dist = [d for d in safety.curve_distribution(self.ev, self.runs["standalone"].scene)
                if d[1] == 1 and d[0].startswith("circular")]
        self.assertEqual(len(dist), 1)
        self.assertAlmostEqual(dist[0][2], 202.0, delta=1e-9)

    def test_largest(self):
        run = self.runs["standalone"]
        self.assertEqual(safety.largest(self.ev, "Tgamma"), (1, 1, syn.TGAMMA_1))
        wid, side, v = safety.largest(self.ev, "Y/Q")
        self.assertEqual((wid, side), (3, 1))
        self.assertAlmostEqual(v, 1.5, delta=1e-12)
        wid, side, v = safety.largest(run, "dQ/Q0", self.settings)
        self.assertEqual((wid, side), (4, 0))
        self.assertAlmostEqual(v, 0.55, delta=1e-12)
        with self.assertRaises(ValueError):
            safety.largest(self.ev, "speed")

    # --- comfort ---------------------------------------------------------------------------------------
    def test_weighting_matches_the_published_formula_and_table(self):
        for name in ("Wb", "Wd"):
            for f in (0.5, 1.0, 2.0, 4.0, 8.0, 16.0, 31.5):
                self.assertAlmostEqual(abs(complex(comfort.analog_response(name, f))), published_gain(name, f),
                                       delta=1e-12)
        # ISO 2631-1 Table 3 gives three digits: tolerance half a unit of the last digit.
        for f, g in ISO2631_WD_TABLE.items():
            self.assertAlmostEqual(abs(complex(comfort.analog_response("Wd", f))), g, delta=0.0005)
        # The published values at 100 rad/s (four digits: half a unit of the last digit).
        for name, g in REFERENCE_100_RAD_S.items():
            self.assertAlmostEqual(abs(complex(comfort.analog_response(name, 100.0 / (2.0 * math.pi)))), g,
                                   delta=0.00005, msg=name)

    def test_weighted_rms_of_sinusoids(self):
        # a = A sin(2 pi f t): the weighted r.m.s. is A/sqrt(2) |H(f)|. The 5 s windows hold whole periods;
        # the bilinear filters at 250 Hz differ from the analogue gain by < 0.2 % up to 8 Hz (pre-warped
        # corners; the 100 Hz low-pass section is the one that moves): tolerance 0.3 %.
        cm = self.ev.comfort
        self.assertEqual(sorted(cm), sorted(p[0] for p in syn.FLOOR_POINTS))
        for name, _, freqs in syn.FLOOR_POINTS:
            r = cm[name]
            expected = {}
            for axis, f, w in zip("xyz", freqs, ("Wd", "Wd", "Wb")):
                expected[axis] = syn.FLOOR_AMPLITUDE / math.sqrt(2) * published_gain(w, f)
                self.assertAlmostEqual(r.a_p95[axis], expected[axis], delta=3e-3 * expected[axis], msg=(name, axis))
                self.assertAlmostEqual(r.rms[axis], expected[axis], delta=3e-3 * expected[axis], msg=(name, axis))
            n_mv = 6 * math.sqrt(sum(v * v for v in expected.values()))
            self.assertAlmostEqual(r.n_mv, n_mv, delta=3e-3 * n_mv)
            # 16 s record, 0.25 s discard + 5 s settling: two full 5 s windows, fewer than EN 12299's 60.
            self.assertEqual(r.windows, 2)
            self.assertTrue(r.indicative)
            self.assertIn("indicative", r.note)
        r = row(self.ev, "mean comfort N_MV at centre")
        self.assertAlmostEqual(r.value, cm["centre"].n_mv)

    def test_comfort_scale(self):
        self.assertEqual(comfort.comfort_class(0.9), "very comfortable")
        self.assertEqual(comfort.comfort_class(1.5), "comfortable")
        self.assertEqual(comfort.comfort_class(4.5), "uncomfortable")

    # --- flexible track, missing topics, CSV, command line ----------------------------------------------
    def test_pad_forces_and_rail_displacement(self):
        ev = self.evals["flexible"]
        r = row(ev, "pad compression")
        self.assertAlmostEqual(r.value, syn.PAD_PEAK, delta=1e-6)
        self.assertAlmostEqual(r.t, syn.PAD_PEAK_T, delta=1e-6)
        self.assertLess(abs(r.s - syn.PAD_PEAK_S), 0.3 + 1e-9)  # nearest sleeper, 0.6 m spacing
        r = row(ev, "rail displacement")
        self.assertAlmostEqual(r.value, float(np.linalg.norm(syn.RAIL_PEAK)), delta=1e-12)
        r = row(ev, "ballast force")
        self.assertAlmostEqual(r.value, syn.BALLAST_PEAK, delta=1e-6)
        self.assertAlmostEqual(r.t, syn.PAD_PEAK_T, delta=1e-6)
        self.assertLess(abs(r.s - syn.PAD_PEAK_S), 0.3 + 1e-9)
        self.assertEqual(r.status, safety.INFO)
        # A bag recorded before /pad_forces carried the ballast says so; the pad rows stay.
        d = os.path.join(self.work, "noballast")
        syn.write_run(d, "flexible", ballast=False)
        ev = safety.evaluate(safety.load_run_dir(d, "flexible"), self.settings)
        self.assertEqual(row(ev, "ballast force").status, safety.NOT_AVAILABLE)
        self.assertEqual(row(ev, "ballast force").note,
                         "the bag's /pad_forces has no ballast forces (recorded by an older build)")
        self.assertAlmostEqual(row(ev, "pad compression").value, syn.PAD_PEAK, delta=1e-6)

    def test_sleeper_void_row(self):
        # No hanging sleepers in the scene: not applicable, even though the bag has the field.
        r = row(self.evals["flexible"], "sleeper void")
        self.assertEqual(r.status, safety.NOT_AVAILABLE)
        self.assertEqual(r.note, "no hanging sleepers in the scene (track.support sleeper_gap)")
        # A scene that hangs sleepers: the widest open void, where and when.
        d = os.path.join(self.work, "hanging")
        syn.write_run(d, "flexible")
        path = os.path.join(d, "flexible.scene.yaml")
        with open(path) as f:
            scene = yaml.safe_load(f)
        scene["effects"]["support_variation"] = True
        scene["track"]["support"] = [{"s_from": 169.7, "s_to": 169.9, "sleeper_gap": 0.0015}]
        with open(path, "w") as f:
            yaml.safe_dump(scene, f)
        ev = safety.evaluate(safety.load_run_dir(d, "flexible"), self.settings)
        r = row(ev, "sleeper void")
        self.assertEqual(r.status, safety.INFO)
        self.assertAlmostEqual(r.value, syn.VOID_PEAK, delta=1e-15)
        self.assertAlmostEqual(r.s, syn.VOID_S, delta=1e-9)
        self.assertAlmostEqual(r.t, syn.VOID_PEAK_T, delta=1e-6)
        # The same scene with a bag recorded before the message had the voids.
        d = os.path.join(self.work, "hanging_old")
        syn.write_run(d, "flexible", ballast=False)
        path = os.path.join(d, "flexible.scene.yaml")
        with open(path, "w") as f:
            yaml.safe_dump(scene, f)
        r = row(safety.evaluate(safety.load_run_dir(d, "flexible"), self.settings), "sleeper void")
        self.assertEqual(r.status, safety.NOT_AVAILABLE)
        self.assertEqual(r.note, "the bag's /pad_forces has no sleeper voids (recorded by an older build)")

    def test_missing_topics_are_not_available_with_the_setting(self):
        text = ("needs /floor_accelerations: set effects.floor_acceleration_output: true and add "
                "floor_accelerations to output.topics")
        for n in ("rigid_fe", "flexible"):
            r = row(self.evals[n], "mean comfort N_MV")
            self.assertEqual(r.status, safety.NOT_AVAILABLE)
            self.assertEqual(r.note, text)
        r = row(self.evals["rigid_fe"], "pad compression")
        self.assertEqual(r.status, safety.NOT_AVAILABLE)
        self.assertIn("flexible track only", r.note)
        # A flexible run without /pad_forces names the topic and the setting.
        d = os.path.join(self.work, "nopads")
        syn.write_run(d, "flexible", pads=False)
        ev = safety.evaluate(safety.load_run_dir(d, "flexible"), self.settings)
        self.assertEqual(row(ev, "pad compression").note, "needs /pad_forces: set effects.pad_force_output: true and "
                         "add pad_forces to output.topics (flexible track only: effects.track_model: flexible)")

    @unittest.skipUnless(os.geteuid() == 0, "needs root (mount a small tmpfs), as CI has")
    def test_full_output_disk_is_one_line_and_exit_9(self):
        # --out on a 16 kB tmpfs: the first figure does not fit. One line naming the file and the system's
        # reason, exit 9, no traceback, and the file that failed is not left half-written.
        mnt = tempfile.mkdtemp(prefix="rail_safety_full_")
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=16k", "tmpfs", mnt], check=True)
        try:
            proc = run_tool([self.dir, "--out", os.path.join(mnt, "report")])
            self.assertEqual(proc.returncode, 9, proc.stderr)
            self.assertNotIn("Traceback", proc.stderr)
            lines = proc.stderr.strip().splitlines()
            self.assertEqual(len(lines), 1, proc.stderr)
            self.assertRegex(lines[0], r"^railsim_safety: cannot write %s/report/\S+\.png( \(partial file removed\))?: "
                                       r"No space left on device$" % re.escape(mnt))
            failed = re.search(r"cannot write (\S+)", lines[0]).group(1)
            self.assertFalse(os.path.exists(failed))
        finally:
            subprocess.run(["umount", "-l", mnt])
            os.rmdir(mnt)

    def test_command_line_prints_and_writes_the_csv(self):
        out = os.path.join(self.work, "report")
        proc = run_tool([self.dir, "--out", out])
        self.assertEqual(proc.returncode, 0, proc.stderr)
        for n in ("standalone", "rigid_fe", "flexible"):
            self.assertIn("%s:" % n, proc.stdout)
            path = os.path.join(self.dir, n + ".safety.csv")
            with open(path) as f:
                rd = csv.DictReader(f)
                self.assertEqual(tuple(rd.fieldnames), safety_report.CSV_COLUMNS)
                recs = {r["quantity"]: r for r in rd}
            r = recs["Y/Q (2 m mean)"]
            self.assertEqual((r["run"], r["wheel_id"], r["wheelset"], r["side"], r["status"]),
                             (n, "3", "1", "right", "fail"))
            self.assertAlmostEqual(float(r["maximum"]), 1.5, delta=1e-5)
            self.assertAlmostEqual(float(r["limit"]), 1.34164, delta=1e-5)
            self.assertAlmostEqual(float(r["margin"]), 1.34164 - 1.5, delta=1e-5)
            r = recs["wear index Tgamma"]
            self.assertEqual((r["wheel_id"], r["maximum"], r["status"]), ("1", "202", "informative"))
        with open(os.path.join(out, "safety.md")) as f:
            md = f.read()
        for fig in ("safety_yq.png", "safety_sumy.png", "safety_tgamma.png", "safety_comfort.png"):
            self.assertIn("(%s)" % fig, md)
            self.assertGreater(os.path.getsize(os.path.join(out, fig)), 10000)
        self.assertIn("### Flexible against rigid FE track", md)
        self.assertIn("Nadal", md)

    def test_single_bag_with_scene(self):
        bag = os.path.join(self.dir, "standalone.bag")
        proc = run_tool([bag, "--scene", os.path.join(self.dir, "standalone.scene.yaml"), "--friction", "0.4"])
        self.assertEqual(proc.returncode, 0, proc.stderr)
        t = math.tan(math.radians(70))
        self.assertIn("%.3g" % ((t - 0.4) / (1 + 0.4 * t)), proc.stdout)

    def test_bad_input_is_refused_with_one_line(self):
        proc = run_tool([os.path.join(self.dir, "standalone.bag")])
        self.assertEqual(proc.returncode, 2)
        self.assertEqual(proc.stderr.strip(), "railsim_safety: %s: a bag needs --scene SCENE.yaml"
                         % os.path.join(self.dir, "standalone.bag"))
        d = os.path.join(self.work, "badveh")
        syn.write_run(d, "standalone", floor=False)
        with open(os.path.join(d, "vehicle.yaml"), "w") as f:
            f.write("bodies:\n  - {name: a, mass: -5}\n")
        proc = run_tool([d, "--runs", "standalone"])
        self.assertEqual(proc.returncode, 2)
        self.assertEqual(proc.stderr.strip(), "railsim_safety: %s: bodies[0].mass: must be > 0, got -5.0"
                         % os.path.join(d, "vehicle.yaml"))


if __name__ == "__main__":
    import rosunit
    rosunit.unitrun("rail_analysis", "test_safety_synthetic", SafetySynthetic)
