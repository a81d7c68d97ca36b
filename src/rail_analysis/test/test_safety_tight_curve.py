#!/usr/bin/env python3
"""The tight curve (config/scenes/tight_curve.yaml: R = 150 m left, 50 km/h, 77 mm cant deficiency) run by the
vehicle node alone (launch/vehicle_standalone.launch) up to s = 180 m, 70 m into the circular curve, through
`roslaunch --wait` against the rostest master; then the running-safety analysis of its bag (safety.py): in a
left curve the leading wheelset is pushed to the outer (right) rail and flanges there, so the outer leading
wheel (wheel id 1: wheelset 0, right) carries the largest flange-climb ratio Y/Q, instantaneous and 2 m mean,
and dissipates the most energy in its contacts (T-gamma). The summary CSV is written beside the bag."""
import csv
import os
import signal
import subprocess
import sys
import tempfile
import unittest

import rospy
import rostest

HERE = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "src"))
from rail_analysis import safety, safety_report  # noqa: E402

WS = os.path.realpath(os.path.join(HERE, "..", "..", ".."))
SCENE = os.path.join(WS, "config", "scenes", "tight_curve.yaml")
LAUNCH = os.path.join(WS, "launch", "vehicle_standalone.launch")
VALIDATE = os.path.join(WS, "devel", "lib", "rail_core", "railsim_validate_scene")
OVERRIDES = ["solver.end={arc_length: 180.0}", "output.bag=tight_curve.bag",
             "output.topics=[wheel_states, contact_points, wheelset_kinematics]"]
RUN_TIMEOUT = 600.0  # [s] of wall time (about 1-2 min on an idle 2-core machine)


class SafetyTightCurve(unittest.TestCase):
    def test_outer_leading_wheel_has_the_largest_flange_climb_ratio_and_wear_number(self):
        work = tempfile.mkdtemp(prefix="rail_safety_tight_curve_")
        args = [VALIDATE, SCENE]
        for o in OVERRIDES:
            args += ["--set", o]
        resolved = subprocess.run(args, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.assertEqual(resolved.returncode, 0, resolved.stderr)
        scene_path = os.path.join(work, "tight_curve.scene.yaml")
        with open(scene_path, "w") as f:
            f.write(resolved.stdout)
        log_path = os.path.join(work, "run.log")
        proc = None
        try:
            with open(log_path, "w") as log:
                proc = subprocess.Popen(["roslaunch", "--wait", "--disable-title", LAUNCH, "scene:=" + SCENE,
                                         "output_dir:=" + work, "overrides:=" + " ".join(OVERRIDES)],
                                        stdout=log, stderr=subprocess.STDOUT)
                proc.wait(timeout=RUN_TIMEOUT)
        finally:
            if proc is not None and proc.poll() is None:
                proc.send_signal(signal.SIGINT)
                try:
                    proc.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    proc.kill()
        with open(log_path) as f:
            log_text = f.read()
        bag = os.path.join(work, "tight_curve.bag")
        self.assertTrue(os.path.isfile(bag), log_text[-3000:])
        self.assertIn("finished at t = ", log_text, log_text[-3000:])

        run = safety.load(bag, scene_path)
        ev = safety.evaluate(run, safety.Settings())
        for quantity in ("Y/Q", "Y/Q_2m", "Tgamma"):
            wheel, side, value = safety.largest(ev, quantity)
            print("largest %s: wheel %d (side %d) %.4g" % (quantity, wheel, side, value))
            self.assertEqual((wheel, side), (1, 1), "%s: largest on wheel %d, expected the outer leading wheel 1"
                             % (quantity, wheel))
            self.assertGreater(value, 0.0)
        # The CLI's summary table and CSV beside the bag.
        out = subprocess.run([os.path.join(os.path.dirname(HERE), "scripts", "railsim_safety"), bag, "--scene",
                              scene_path], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        self.assertEqual(out.returncode, 0, out.stderr)
        self.assertIn("Y/Q", out.stdout)
        csv_path = os.path.join(work, "tight_curve.safety.csv")
        with open(csv_path) as f:
            rows = list(csv.DictReader(f))
        self.assertGreater(len(rows), 0)
        self.assertEqual(list(rows[0].keys()), list(safety_report.CSV_COLUMNS))


if __name__ == "__main__":
    rospy.init_node("test_safety_tight_curve", anonymous=True)
    rostest.rosrun("rail_analysis", "safety_tight_curve", SafetyTightCurve)
