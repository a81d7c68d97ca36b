#!/usr/bin/env python3
"""Runs the same scenes on the rigid track with two built workspaces (e.g. before and after a change of the
contact law) and prints a Markdown table of the contact-force figures that such a change moves: largest
wheel load Q, the leading outer wheel's mean lateral force Y over the run's last 0.3 s, single-sample load
dips (a sample below 30 % of both neighbours while they carry more than 20 kN), active contacts reported
with N = 0, and the derailment instant. Each run gets its own ROS master port and output directory.

  scripts/compare_contact_runs.py --before WS_A --after WS_B [--out DIR] [--scene "FILE[;key=value;...]" ...]

Without --scene the shipped comparison set runs: the tight curve (R 150 m) from s = 145 m for 1 s, the
paper's scene for 1.5 s, the lift-off bump and the flange-climb hard cases. Exit 0, or 2 on a usage error.
"""
import argparse
import os
import re
import subprocess
import sys

import numpy as np

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "src", "rail_analysis", "src"))
from rail_analysis import loading, runner  # noqa: E402

DEFAULT_SCENES = [
    ("config/scenes/tight_curve.yaml", ["vehicle.start_arc_length=145.0", "solver.end={time: 1.0}"]),
    ("config/scenes/paper_demo.yaml", ["solver.end={time: 1.5}", "effects.irregularities=false"]),
    ("config/scenes/hard/lift_off_bump.yaml", []),
    ("config/scenes/hard/hunting_high_speed.yaml", []),
]


def run(ws, scene, overrides, out_dir, port):
    os.makedirs(out_dir, exist_ok=True)
    env = dict(os.environ, PATH="/usr/bin:" + os.environ.get("PATH", ""), ROS_HOME=os.path.join(out_dir, "ros"))
    ov = " ".join(["effects.track_model=rigid", "output.bag=run.bag",
                   "output.topics=[wheel_states, contact_points, wheelset_kinematics]"] + overrides)
    cmd = ("source %s/devel/setup.bash && exec roslaunch -p %d %s/launch/vehicle_standalone.launch scene:=%s "
           "output_dir:=%s overrides:=\"%s\"" % (ws, port, ws, os.path.join(REPO, scene), out_dir, ov))
    with open(os.path.join(out_dir, "run.log"), "w") as log:
        subprocess.run(["bash", "-c", cmd], env=env, stdout=log, stderr=subprocess.STDOUT, timeout=1800)
    text = open(os.path.join(out_dir, "run.log"), errors="replace").read()
    return re.sub(r"\x1b\[[0-9;]*m", "", text)


def figures(out_dir, log):
    bag = os.path.join(out_dir, "run.bag")
    k = loading.load_wheelset_kinematics(bag)
    cp = loading.load_contact_points(bag)
    q = np.concatenate([k["left_force"][:, :, 2], k["right_force"][:, :, 2]], axis=1)
    dips = 0
    for j in range(q.shape[1]):
        x = q[:, j]
        mid, lo, hi = x[1:-1], x[:-2], x[2:]
        dips += int(np.sum((lo > 2e4) & (hi > 2e4) & (mid < 0.3 * lo) & (mid < 0.3 * hi)))
    sel = k["t"] >= k["t"][-1] - 0.3
    m = re.search(r"derailment: wheel (\d+).*? at s = ([-0-9.e+]+) m, t = ([-0-9.e+]+) s", log)
    wall = re.search(r"([0-9.]+) s wall", log)
    return {"Q max [kN]": np.nanmax(q) / 1e3,
            "Y lead outer, last 0.3 s [kN]": np.nanmean(k["right_force"][sel, 0, 1]) / 1e3,
            "dips": dips,
            "active with N = 0": int(np.sum(cp["active"] & (cp["normal_force"] <= 0.0))),
            "derailed": "wheel %s at %s s" % (m.group(1), m.group(3)) if m else "no",
            "wall [s]": float(wall.group(1)) if wall else float("nan")}


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--before", required=True)
    ap.add_argument("--after", required=True)
    ap.add_argument("--out", default="output/contact_compare")
    ap.add_argument("--scene", action="append", help="FILE[;key=value;...] (repeatable)")
    a = ap.parse_args(argv)
    scenes = DEFAULT_SCENES if not a.scene else [(s.split(";")[0], s.split(";")[1:]) for s in a.scene]
    rows = []
    for scene, ov in scenes:
        name = os.path.splitext(os.path.basename(scene))[0]
        res = {}
        for label, ws in (("before", a.before), ("after", a.after)):
            d = os.path.join(os.path.abspath(a.out), name, label)
            log = run(os.path.abspath(ws), scene, ov, d, runner.free_port())
            res[label] = figures(d, log)
            print("%s %s: %s" % (name, label, res[label]), flush=True)
        rows.append((name, res))
    keys = list(rows[0][1]["before"].keys())
    print("\n| scene | " + " | ".join("%s before / after" % k for k in keys) + " |")
    print("|---|" + "---|" * len(keys))
    for name, res in rows:
        cells = []
        for k in keys:
            b, f = res["before"][k], res["after"][k]
            cells.append("%.1f / %.1f" % (b, f) if isinstance(b, float) else "%s / %s" % (b, f))
        print("| %s | %s |" % (name, " | ".join(cells)))
    return 0


if __name__ == "__main__":
    sys.exit(main())
