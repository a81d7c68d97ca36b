#!/usr/bin/python3
"""The impact peaks P1 (unfiltered) and P2 (150 Hz low-pass) of the leading left wheel for the dipped-joint
and the wheel-flat hard cases on the flexible track, at several track steps and rail meshes: what step and
mesh an impact needs (docs/defects.md). Runs each case through ./railsim run, one at a time.

  scripts/defects/impact_steps.py [--out DIR] [--cases joint,flat]
"""
import argparse
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.realpath(__file__))
REPO = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(REPO, "src", "rail_analysis", "src"))

import numpy as np  # noqa: E402
import rosbag  # noqa: E402

from rail_analysis import safety  # noqa: E402

CASES = {"joint": "config/scenes/hard/dipped_joint_impact.yaml", "flat": "config/scenes/hard/wheel_flat_impact.yaml"}
# (track step [s], rail elements between sleepers); the first is the shipped scenes' setting.
SETTINGS = [("2e-5", 6), ("8e-5", 6), ("4e-5", 6), ("1e-5", 6), ("2e-5", 3), ("2e-5", 12)]
# The co-simulation's start (vehicle settled on rigid rails meeting the elastic track) is left out.
IMPACT_FROM = 0.05


def peaks(bag):
    """(P1, P2) [N] of the leading wheelset's left wheel from IMPACT_FROM on."""
    t, q = [], []
    with rosbag.Bag(bag) as b:
        for _, m, _ in b.read_messages(topics=["/wheelset_kinematics"]):
            t.append(m.header.stamp.to_sec())
            q.append(m.wheelsets[0].left_force_in_track.z)
    t, q = np.array(t), np.array(q)
    late = t >= IMPACT_FROM
    return float(q[late].max()), float(safety.p2_force(t, q)[late].max())


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default=os.path.join(REPO, "output", "impact_steps"))
    ap.add_argument("--cases", default="joint,flat")
    a = ap.parse_args()
    failed = 0
    for name in a.cases.split(","):
        for step, elements in SETTINGS:
            out = os.path.join(a.out, "%s_%s_%d" % (name, step, elements))
            os.makedirs(out, exist_ok=True)
            t0 = time.time()
            r = subprocess.run(["./railsim", "run", CASES[name], "--out", out,
                                "--set", "solver.track_step=%s" % step, "--set", "solver.vehicle_max_step=%s" % step,
                                "--set", "track.rail_elements_between_sleepers=%d" % elements,
                                "--set", "output.rate=%g" % min(10000.0, 1.0 / float(step))],
                               cwd=REPO, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
            wall = time.time() - t0
            bags = [os.path.join(out, f) for f in os.listdir(out) if f.endswith(".bag") and ".track." not in f]
            if r.returncode != 0 or not bags:
                print("%s step %s elements %d: run failed (exit %d; log in %s)" % (name, step, elements, r.returncode,
                                                                                  out), flush=True)
                failed += 1
                continue
            p1, p2 = peaks(bags[0])
            print("%s step %s elements %2d: P1 %6.1f kN  P2 %6.1f kN  (wall %.0f s)" % (
                name, step, elements, p1 / 1e3, p2 / 1e3, wall), flush=True)
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
