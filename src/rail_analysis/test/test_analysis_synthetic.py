#!/usr/bin/env python3
"""The analysis tool on bags written by this test from an analytic motion (test/synthetic_runs.py): every
figure and report.md are written, the deviation table and wall-time ratios equal the differences put in,
the spectrum peak is at the frequency put in, each observation check agrees on data built to follow the
paper and disagrees on data built against it, and bad input is refused with its message.
Runs as a plain unittest (python3 test_analysis_synthetic.py --text) or through rosunit (JUnit XML)."""
import math
import os
import shutil
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.realpath(__file__))
PKG_SRC = os.path.join(os.path.dirname(HERE), "src")
SCRIPT = os.path.join(os.path.dirname(HERE), "scripts", "railsim_analyze")
sys.path.insert(0, PKG_SRC)
sys.path.insert(0, HERE)

import numpy as np  # noqa: E402
import rosbag  # noqa: E402
import rospy  # noqa: E402
from rail_msgs.msg import ContactPoints  # noqa: E402

import synthetic_runs as syn  # noqa: E402
from rail_analysis import analysis, loading, report  # noqa: E402

# The figure files the tool promises (one per paper figure, one per deflection section, the spectrum).
EXPECTED_FIGURES = ["fig16_lateral_displacement.png", "fig17_angle_of_attack.png", "fig18_vertical_displacement.png",
                    "fig19_flange_forces.png", "fig20_lateral_wheel_forces.png", "fig21_vertical_wheel_forces.png",
                    "rail_displacement_at_40m.png", "rail_displacement_at_120m.png",
                    "spectrum_vertical_first_straight.png"]
DISCARD = 0.25


def run_tool(args):
    env = dict(os.environ)
    env["PYTHONPATH"] = PKG_SRC + os.pathsep + env.get("PYTHONPATH", "")
    env["MPLBACKEND"] = "Agg"
    return subprocess.run([sys.executable, SCRIPT] + args, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                          text=True, env=env, timeout=300)


class SyntheticRuns(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="rail_analysis_syn_")
        cls.runs_dir = os.path.join(cls.work, "runs")
        syn.write_all(cls.runs_dir)
        cls.out = os.path.join(cls.work, "out")
        cls.proc = run_tool([cls.runs_dir, "--out", cls.out])
        cls.runs, _ = report.load_runs(cls.runs_dir, progress=lambda s: None)
        cls.scene = analysis._scene(cls.runs)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    def test_every_figure_and_the_report_are_written(self):
        self.assertEqual(self.proc.returncode, 0, self.proc.stderr)
        for name in EXPECTED_FIGURES:
            path = os.path.join(self.out, name)
            self.assertTrue(os.path.isfile(path), name)
            with open(path, "rb") as f:
                self.assertEqual(f.read(8), b"\x89PNG\r\n\x1a\n", name)
            self.assertGreater(os.path.getsize(path), 10000, name)  # an empty 9 x 4.6 in canvas is smaller
        with open(os.path.join(self.out, "report.md")) as f:
            text = f.read()
        for name in EXPECTED_FIGURES:
            self.assertIn("(%s)" % name, text)
        # Progress per run, and the last line says where the report is.
        for name in loading.RUN_NAMES:
            self.assertIn("%s: loading" % name, self.proc.stdout)
        self.assertEqual(self.proc.stdout.strip().splitlines()[-1],
                         "report: " + os.path.abspath(os.path.join(self.out, "report.md")))

    def test_deviation_table_equals_the_difference_put_in(self):
        dev = analysis.deviation_table(self.runs["standalone"], self.runs["rigid_fe"], DISCARD)
        # rigid_fe = standalone + ramp reaching DEV_* at the end, so the largest deviation after the discard
        # is DEV_* (the spike inside the discarded 0.25 s must not count). The standalone run is sampled at
        # 500 Hz and interpolated linearly onto the 1 kHz base: the interpolation error of a sinusoid of
        # amplitude A and frequency f with step h is at most A (2 pi f h)^2 / 8, i.e. 2.9e-8 m lateral,
        # 5.5e-7 deg in angle of attack and 7.9e-10 m vertical here; the tolerances are these bounds plus
        # round-off.
        self.assertAlmostEqual(dev["lateral"], syn.DEV_LATERAL, delta=3e-8)
        self.assertAlmostEqual(dev["angle_of_attack_deg"], syn.DEV_AOA_DEG, delta=6e-7)
        self.assertAlmostEqual(dev["vertical"], syn.DEV_VERTICAL, delta=1e-9)
        with open(os.path.join(self.out, "report.md")) as f:
            text = f.read()
        self.assertIn("| lateral displacement [m] | %.3g | 2.5e-05 | yes |" % syn.DEV_LATERAL, text)
        self.assertIn("| angle of attack [deg] | %.3g | 0.00047 | yes |" % syn.DEV_AOA_DEG, text)
        self.assertIn("| vertical displacement [m] | %.3g | 8e-08 | yes |" % syn.DEV_VERTICAL, text)

    def test_deviation_without_the_discard_sees_the_spike(self):
        # The spike of 1e-3 at t = 0.1 s dominates when nothing is discarded (the function reads t_start).
        dev = analysis.deviation_table(self.runs["standalone"], self.runs["rigid_fe"], 0.0)
        self.assertGreater(dev["lateral"], 0.9 * syn.SPIKE)

    def test_wall_time_ratios(self):
        # Wall times written in the run.yaml files: 10, 79 and 573 s (ratios 7.9 and 57.3, exact decimals).
        r = analysis.wall_ratios(self.runs)
        self.assertAlmostEqual(r["rigid_fe"], 7.9, places=12)
        self.assertAlmostEqual(r["flexible"], 57.3, places=12)
        with open(os.path.join(self.out, "report.md")) as f:
            text = f.read()
        self.assertIn("| rigid_fe / standalone | 7.90 | 7.9 |", text)
        self.assertIn("| flexible / standalone | 57.30 | 57.3 |", text)

    def test_spectrum_peak_at_the_frequency_put_in(self):
        f, a, df = analysis.vertical_spectrum_first_straight(self.runs["flexible"], self.scene, DISCARD)
        fp, ap = analysis.peak_frequency(f, a, f_min=10.0)
        # The first straight after the discard lasts (60 - 25) / 30.5556 - 0.25 = 0.895 s: bin width 1.12 Hz.
        self.assertAlmostEqual(df, 1.0 / 0.895, delta=0.02)
        self.assertLessEqual(abs(fp - syn.FLEX_FREQUENCY), df)
        # Hann window: a line between bins loses at most 1 - sinc-shaped scalloping of 15 % (1.42 dB).
        self.assertGreater(ap, 0.85 * syn.FLEX_AMPLITUDE)
        self.assertLess(ap, 1.01 * syn.FLEX_AMPLITUDE)

    def test_amplitude_spectrum_of_a_sinusoid_on_a_bin(self):
        # 1 s at 1 kHz: bins every 1 Hz; a 40 Hz sinusoid of amplitude 3 sits on a bin, where the Hann
        # window's coherent gain is normalised away: peak 3 within the window's discretisation (0.1 %).
        t = np.arange(1000) / 1000.0
        f, a, df = analysis.amplitude_spectrum(t, 3.0 * np.sin(2 * math.pi * 40.0 * t) + 0.5 * t)
        k = int(np.argmax(a))
        self.assertAlmostEqual(f[k], 40.0, delta=df)
        self.assertAlmostEqual(a[k], 3.0, delta=3e-3)

    def test_passing_times(self):
        # Wheelset w reaches s at t = (s - 25 + offset_w) / speed; linear interpolation of a linear motion
        # is exact, but the header stamps hold whole nanoseconds: 1e-9 s at each of the two samples used,
        # hence the 3e-9 s tolerance.
        k = self.runs["flexible"].kinematics
        for s in syn.SECTIONS:
            got = analysis.passing_times(k, s)
            for w, off in enumerate(syn.WHEELSET_OFFSETS):
                expect = (s - syn.START_S + off) / syn.SPEED
                if expect <= syn.T_END:
                    self.assertAlmostEqual(got[w], expect, delta=3e-9)
                else:
                    self.assertIsNone(got[w])

    def test_checks_agree_on_data_built_like_the_paper(self):
        checks = analysis.all_checks(self.runs, DISCARD)
        self.assertEqual(len(checks), 6)
        for c in checks:
            self.assertEqual(c.status, analysis.AGREES, "%s: %s" % (c.title, c.measured))
        # The measured figures are printed: the flexible/rigid lateral force ratio put in, 1.10.
        self.assertIn("x%.3f" % syn.FLEX_FORCE_RATIO, checks[2].measured)
        with open(os.path.join(self.out, "report.md")) as f:
            text = f.read()
        self.assertIn("Summary: 6 agree, 0 do not agree, 0 not available.", text)

    def test_checks_disagree_when_the_tracks_are_swapped(self):
        swapped = dict(self.runs)
        swapped["standalone"], swapped["flexible"] = self.runs["flexible"], self.runs["standalone"]
        # The "flexible" run is now the rigid one: its flange peaks are higher, lateral forces lower and
        # it has no 51 Hz line.
        self.assertEqual(analysis.check_flange_peaks_lower_flexible(swapped, DISCARD).status, analysis.DISAGREES)
        self.assertEqual(analysis.check_lateral_force_straight(swapped, DISCARD).status, analysis.DISAGREES)
        self.assertEqual(analysis.check_sleeper_frequency(swapped, DISCARD).status, analysis.DISAGREES)

    def test_checks_disagree_on_contrary_rail_and_flange_data(self):
        flex = self.runs["flexible"]
        contrary = loading.Run("flexible")
        contrary.__dict__.update(flex.__dict__)
        # Rails moved inward in the curve (lateral signs flipped), and on the straight the largest
        # displacements put under a wheel (a larger peak at the instant wheelset 1 passes the section).
        contrary.deflection = {}
        for s, d in flex.deflection.items():
            e = {k: v.copy() for k, v in d.items()}
            tp = analysis.passing_times(flex.kinematics, s)[0]
            for side in ("left", "right"):
                if syn.in_curve(s):
                    e[side][:, 1] *= -1.0
                else:
                    e[side][np.argmin(np.abs(e["t"] - tp)), 1:] = (-5e-3, -5e-3)
            contrary.deflection[s] = e
        # Flange contact on the inner wheel too.
        pts = {k: v.copy() for k, v in flex.points.items()}
        sel = (pts["wheel_id"] == 0) & (pts["kind"] == loading.KIND_FLANGE)
        pts["active"][sel] = True
        pts["normal_force"][sel] = 10e3
        contrary.points = pts
        runs = dict(self.runs, flexible=contrary)
        self.assertEqual(analysis.check_rails_outward_in_curve(runs, DISCARD).status, analysis.DISAGREES)
        self.assertEqual(analysis.check_max_between_bogie_wheels(runs, DISCARD).status, analysis.DISAGREES)
        self.assertEqual(analysis.check_flange_outer_only(runs, DISCARD).status, analysis.DISAGREES)

    def test_rail_displacement_checks_not_available_without_the_flexible_run(self):
        runs = {k: v for k, v in self.runs.items() if k != "flexible"}
        for check in (analysis.check_rails_outward_in_curve, analysis.check_max_between_bogie_wheels):
            c = check(runs, DISCARD)
            self.assertEqual(c.status, analysis.NOT_AVAILABLE, check.__name__)
            self.assertEqual(c.measured, "needs the flexible run's rail displacements", check.__name__)


class FlangeContactDefinition(unittest.TestCase):
    """Flange contact is counted by the contact angle, whichever wheel surface reported the point: a patch on
    the flange root that the tread surface reports (it continues past the split) is flange contact; the
    report says so."""

    def points(self, angles, kinds, forces):
        n = len(angles)
        return {"t": np.arange(n, dtype=float), "wheel_id": np.full((n, 1), 1), "side": np.ones((n, 1), dtype=int),
                "kind": np.array(kinds).reshape(n, 1), "active": np.ones((n, 1), dtype=bool),
                "normal_force": np.array(forces, dtype=float).reshape(n, 1),
                "contact_angle": np.array(angles, dtype=float).reshape(n, 1)}

    def test_a_flange_root_contact_reported_by_the_tread_is_flange_contact(self):
        # Flange flank (flange surface), flange root past the split (tread surface), tread, and the same
        # flange-root contact a sample later: the flange force stays continuous across the change of surface.
        # The low end of the flange root (0.29 rad in the paper's flexible run) is flange contact; the steepest
        # tread contact of a new S1002 (0.12 rad, Manchester benchmark) is not.
        p = self.points([1.15, 0.70, 0.05, 0.69, 0.29, 0.12],
                        [loading.KIND_FLANGE, loading.KIND_TREAD, loading.KIND_TREAD, loading.KIND_TREAD,
                         loading.KIND_TREAD, loading.KIND_TREAD], [95e3, 94e3, 70e3, 93e3, 80e3, 72e3])
        f = loading.flange_normal_force(p, 1)
        np.testing.assert_allclose(f, [95e3, 94e3, 0.0, 93e3, 80e3, 0.0])

    def test_bags_without_contact_angles_fall_back_on_the_reporting_surface(self):
        p = self.points([np.nan] * 2, [loading.KIND_FLANGE, loading.KIND_TREAD], [95e3, 94e3])
        np.testing.assert_allclose(loading.flange_normal_force(p, 1), [95e3, 0.0])

    def test_the_report_states_the_definition(self):
        work = tempfile.mkdtemp(prefix="rail_analysis_flange_")
        try:
            syn.write_all(work)
            out = os.path.join(work, "report")
            proc = run_tool([work, "--out", out])
            self.assertEqual(proc.returncode, 0, proc.stderr)
            with open(os.path.join(out, "report.md")) as f:
                text = f.read()
            self.assertIn("flange contact: a contact whose normal leans more than 0.20 rad (11 deg) toward the "
                          "track centre (flange root and flank)", text)
        finally:
            shutil.rmtree(work, ignore_errors=True)


class Refusals(unittest.TestCase):
    def setUp(self):
        self.work = tempfile.mkdtemp(prefix="rail_analysis_bad_")

    def tearDown(self):
        shutil.rmtree(self.work, ignore_errors=True)

    def test_bag_without_wheelset_kinematics_is_refused(self):
        bag_path = os.path.join(self.work, "standalone.bag")
        with rosbag.Bag(bag_path, "w") as bag:
            m = ContactPoints()
            m.header.stamp = rospy.Time.from_sec(0.001)
            bag.write("/contact_points", m, m.header.stamp)
        proc = run_tool([self.work, "--out", os.path.join(self.work, "out")])
        self.assertEqual(proc.returncode, 2, proc.stdout + proc.stderr)
        self.assertEqual(proc.stderr, "railsim_analyze: %s: topic /wheelset_kinematics not in the bag "
                                      "(needed for the wheelset motion)\n" % bag_path)

    def test_flexible_track_bag_without_rail_deflection_is_refused(self):
        syn.write_run(self.work, "flexible")
        track = os.path.join(self.work, "flexible.track.bag")
        with rosbag.Bag(track, "w") as bag:
            m = ContactPoints()
            m.header.stamp = rospy.Time.from_sec(0.001)
            bag.write("/contact_points", m, m.header.stamp)
        proc = run_tool([self.work, "--out", os.path.join(self.work, "out")])
        self.assertEqual(proc.returncode, 2, proc.stdout + proc.stderr)
        self.assertEqual(proc.stderr, "railsim_analyze: %s: topic /rail_deflection not in the bag "
                                      "(needed for the rail displacements)\n" % track)

    def test_missing_run_is_skipped_with_a_note(self):
        syn.write_run(self.work, "standalone", forces=False)
        syn.write_run(self.work, "rigid_fe", forces=False)
        out = os.path.join(self.work, "out")
        proc = run_tool([self.work, "--out", out])
        self.assertEqual(proc.returncode, 0, proc.stderr)
        with open(os.path.join(out, "report.md")) as f:
            text = f.read()
        self.assertIn("flexible: skipped, flexible.bag not in %s" % self.work, text)
        self.assertIn("are not recorded in /wheelset_kinematics", text)
        # Without the flexible run: the checks that compare with it are not available.
        self.assertIn("Summary: 1 agree, 0 do not agree, 5 not available.", text)
        for name in EXPECTED_FIGURES:
            self.assertTrue(os.path.isfile(os.path.join(out, name)), name)

    def test_malformed_run_yaml_is_refused(self):
        syn.write_run(self.work, "standalone")
        path = os.path.join(self.work, "standalone.run.yaml")
        with open(path, "w") as f:
            f.write("run: standalone\nwall_time: [1.0\n")
        proc = run_tool([self.work, "--out", os.path.join(self.work, "out")])
        self.assertEqual(proc.returncode, 2)
        self.assertTrue(proc.stderr.startswith("railsim_analyze: %s:" % path), proc.stderr)
        self.assertEqual(len(proc.stderr.strip().splitlines()), 1, proc.stderr)


if __name__ == "__main__":
    import rosunit
    # Both test cases of this module (rosunit loads them by the module's name; --text prints instead of XML).
    rosunit.unitrun("rail_analysis", "test_analysis_synthetic", "test_analysis_synthetic")
