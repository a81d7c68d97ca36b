#!/usr/bin/env python3
"""Real short runs analysed: test/scenes/paper_demo_60m.yaml (the paper's scene cut to 100 m: 60 m of
straight, then into the transition; 1.5 s) run by the vehicle node alone on the rigid track
(launch/vehicle_standalone.launch) and in co-simulation with the rigid FE and the flexible track
(launch/cosim.launch), each through `roslaunch --wait` against the rostest master; then the analysis of the
run directory: rigid_fe and standalone agree within the paper's deviations, the flexible run shows the
sleeper-passing frequency in the leading wheelset's vertical motion, and every figure and report.md are
written. The run directory is made as the runner makes it: <run>.bag (vehicle node), <run>.track.bag
(track node), <run>.scene.yaml (railsim_validate_scene's resolved print-out) and <run>.run.yaml."""
import glob
import os
import signal
import subprocess
import sys
import tempfile
import time
import unittest

import rospy
import rostest

HERE = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "src"))
from rail_analysis import analysis, report  # noqa: E402

WS = os.path.realpath(os.path.join(HERE, "..", "..", ".."))           # the catkin workspace
BASE_SCENE = os.path.join(WS, "test", "scenes", "paper_demo_60m.yaml")
CONFIG = os.path.join(WS, "config")
LAUNCH = os.path.join(WS, "launch")
END_TIME = 1.5          # [s], the scene's solver.end
RUN_TIMEOUT = 600.0     # [s] of wall time per run (about 10 s each on an idle 2-core machine)
DISCARD = 0.25
RUNS = (("standalone", "rigid", "vehicle_standalone.launch"), ("rigid_fe", "rigid_fe", "cosim.launch"),
        ("flexible", "flexible", "cosim.launch"))


def validate_scene_tool():
    """railsim_validate_scene of the workspace (devel), else wherever catkin_find finds it."""
    cand = os.path.join(WS, "devel", "lib", "rail_core", "railsim_validate_scene")
    if os.path.exists(cand):
        return cand
    out = subprocess.run(["catkin_find", "rail_core", "railsim_validate_scene"], stdout=subprocess.PIPE, text=True)
    paths = out.stdout.split()
    if not paths:
        raise RuntimeError("railsim_validate_scene not found in %s/devel nor by catkin_find" % WS)
    return paths[0]


def write_scene(directory, run, track_model):
    """The base scene for one run: its track model, bag <run>.bag, data paths absolute; the rigid tracks
    without rail_deflection (it needs the FE integration)."""
    with open(BASE_SCENE) as f:
        text = f.read()
    replacements = [("../../config/", CONFIG + "/"),
                    ("track_model: flexible ", "track_model: %s " % track_model),
                    ("bag: paper_demo_60m.bag", "bag: %s.bag" % run)]
    if track_model == "rigid":
        replacements += [("rail_deflection_output: true", "rail_deflection_output: false"),
                         ("contact_points, rail_deflection,", "contact_points,")]
    for old, new in replacements:
        assert old in text, "%s changed: %r not found" % (BASE_SCENE, old)
        text = text.replace(old, new)
    path = os.path.join(directory, run + ".input.yaml")
    with open(path, "w") as f:
        f.write(text)
    return path


def stop(proc, grace=30.0):
    """SIGINT (roslaunch and rosbag shut their children down on it), then SIGKILL after `grace` s."""
    if proc is None or proc.poll() is not None:
        return
    try:
        proc.send_signal(signal.SIGINT)
        proc.wait(timeout=grace)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.wait()


class AnalysisShort(unittest.TestCase):
    def run_one(self, work, run, track_model, launch):
        scene = write_scene(work, run, track_model)
        resolved = subprocess.run([validate_scene_tool(), scene], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                  text=True)
        self.assertEqual(resolved.returncode, 0, resolved.stderr)
        with open(os.path.join(work, run + ".scene.yaml"), "w") as f:
            f.write(resolved.stdout)
        log_path = os.path.join(work, run + ".log")
        t0 = time.time()
        proc = None
        try:
            with open(log_path, "w") as log:
                proc = subprocess.Popen(["roslaunch", "--wait", "--disable-title", os.path.join(LAUNCH, launch),
                                         "scene:=" + scene, "output_dir:=" + work],
                                        stdout=log, stderr=subprocess.STDOUT)
                proc.wait(timeout=RUN_TIMEOUT)
        finally:
            stop(proc)
            wall = time.time() - t0
        with open(log_path) as f:
            log_text = f.read()
        self.assertTrue(os.path.isfile(os.path.join(work, run + ".bag")), log_text[-3000:])
        self.assertIn("finished at t = 1", log_text, log_text[-3000:])
        if track_model != "rigid":
            self.assertTrue(os.path.isfile(os.path.join(work, run + ".track.bag")), log_text[-3000:])
        if not os.path.isfile(os.path.join(work, run + ".run.yaml")):
            with open(os.path.join(work, run + ".run.yaml"), "w") as f:
                f.write("{run: %s, scene: %s, track_model: %s, wall_time: %.3f, simulated_time: %g, exit_code: %d}\n"
                        % (run, scene, track_model, wall, END_TIME, proc.returncode))
        return wall

    def test_rigid_fe_and_standalone_agree_and_every_figure_is_written(self):
        work = tempfile.mkdtemp(prefix="rail_analysis_short_")
        shm_before = set(glob.glob("/dev/shm/*"))
        walls = {}
        for run, model, launch in RUNS:
            walls[run] = self.run_one(work, run, model, launch)
        print("wall times: %s" % walls)
        new_shm = set(glob.glob("/dev/shm/*")) - shm_before
        print("new /dev/shm entries after the runs (other runs on the machine may add some): %s" % sorted(new_shm))

        out = os.path.join(work, "analysis")
        path, runs, checks, figure_list = report.analyze(work, out, DISCARD, progress=print)
        self.assertEqual(sorted(runs), ["flexible", "rigid_fe", "standalone"])
        for run in ("standalone", "rigid_fe", "flexible"):
            k = runs[run].kinematics
            self.assertEqual(k["t"].size, 1501)  # 1 kHz over 1.5 s
            self.assertIsNotNone(runs[run].points)
        # The paper's largest deviations between its vehicle-alone and rigid-FE co-simulation runs (section
        # 6.2): the co-simulation on the rigid rails evaluates the same contact on the same rails, so the
        # two runs differ only by the coupling's wrench extrapolation and the integrator tolerances.
        dev = analysis.deviation_table(runs["standalone"], runs["rigid_fe"], DISCARD)
        print("rigid_fe - standalone, leading wheelset: %s" % dev)
        self.assertLess(dev["lateral"], analysis.PAPER_DEVIATION["lateral"])
        self.assertLess(dev["angle_of_attack_deg"], analysis.PAPER_DEVIATION["angle_of_attack_deg"])
        self.assertLess(dev["vertical"], analysis.PAPER_DEVIATION["vertical"])
        expected = ["fig16_lateral_displacement.png", "fig17_angle_of_attack.png", "fig18_vertical_displacement.png",
                    "fig19_flange_forces.png", "fig20_lateral_wheel_forces.png", "fig21_vertical_wheel_forces.png",
                    "rail_displacement_at_30m.png", "rail_displacement_at_45m.png",
                    "spectrum_vertical_first_straight.png"]
        self.assertEqual(sorted(n for _, n in figure_list), sorted(expected))
        for name in expected:
            self.assertGreater(os.path.getsize(os.path.join(out, name)), 10000, name)
        with open(path) as f:
            text = f.read()
        # The flexible track's sleepers (0.6 m) passed at 30.56 m/s: the largest line of the leading wheelset's
        # vertical motion above 10 Hz lies within max(one FFT bin, 5 %) of 50.9 Hz (analysis.check_...), and
        # the rigid runs have no such line.
        sleeper = [c for c in checks if "sleeper-passing" in c.title]
        self.assertEqual(len(sleeper), 1)
        self.assertEqual(sleeper[0].status, analysis.AGREES, sleeper[0].measured)
        self.assertIn("| lateral displacement [m] | %.3g | 2.5e-05 | yes |" % dev["lateral"], text)
        print("report: %s" % path)


if __name__ == "__main__":
    rospy.init_node("test_analysis_short", anonymous=True)
    rostest.rosrun("rail_analysis", "analysis_short", AnalysisShort)
