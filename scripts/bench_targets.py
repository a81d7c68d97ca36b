#!/usr/bin/env python3
"""Benchmark of the accuracy-cost issue's targets on this machine (prints its figures; not a test): the
paper's scene over the same simulated time run alone on the rigid track, co-simulated on the rigid FE track
and on the flexible track (the latter at the track steps the accuracy-cost map shows), the flexible run
on the 5 km version of the scene, and the vehicle alone over the whole scene (15.5 s; target: real-time
factor >= 1). Each case runs --repeat times, one at a time (run nothing else meanwhile); the figure is the
median of the slower node's loop wall time (set-up excluded, from the cost profiles), per simulated second,
and its ratio to the run alone; for the flexible runs also the track node's cost per track step by part
(median over the runs, from the track's cost profile). Then the vehicle alone's accuracy against a reference run of the whole
scene (Adams capped at 5e-6 s, 0.1 ms samples, cached in --out as accuracy_reference_0.1ms.csv; its first run
takes ~10 min; a cached one from another scene or an older build is refused, exit 2: delete it):
bench_vehicle_accuracy's table for the default run and for Adams at the former 2e-5 s cap.

  scripts/bench_targets.py [--repeat 3] [--end 1.5] [--out DIR] [--workspace WS] [--only TEXT ...]
                           [--no-accuracy]

--only keeps the cases whose name contains TEXT (the standalone run, the reference of the ratios, always
runs).
"""
import argparse
import os
import statistics
import subprocess
import sys

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "src", "rail_analysis", "src"))
from rail_analysis import costmap, runner  # noqa: E402

PAPER = os.path.join(REPO, "config", "scenes", "paper_demo.yaml")
PAPER_5KM = os.path.join(REPO, "test", "scenes", "paper_demo_5km.yaml")
PAPER_TRAIN = os.path.join(REPO, "config", "scenes", "paper_train.yaml")
TOPICS = ["wheelset_kinematics"]
CASES = [  # name, scene, overrides
    ("standalone", PAPER, {"effects.track_model": "rigid", "effects.rail_deflection_output": False}),
    ("rigid_fe", PAPER, {"effects.track_model": "rigid_fe"}),
    ("flexible, track step 2e-5 s", PAPER, {}),
    ("flexible, track step 4e-5 s", PAPER, {"solver.track_step": 4e-5, "solver.vehicle_max_step": 4e-5}),
    ("flexible, track step 8e-5 s", PAPER, {"solver.track_step": 8e-5, "solver.vehicle_max_step": 8e-5}),
    ("flexible, 5 km line, 2e-5 s", PAPER_5KM, {}),
    ("flexible, two-coach train, 2e-5 s", PAPER_TRAIN, {}),
    # The scene's own end (the leading wheelset at 499 m, 15.5 s): no solver.end override.
    ("standalone, whole scene", PAPER, {"effects.track_model": "rigid", "effects.rail_deflection_output": False,
                                        "solver.end": None}),
]


# The track node's cost per Newmark step: its components, then the finer parts of track_step
# (track_rhs and track_solve run beside the step on a second thread; track_solve_wait is what remains of them
# on the step).
STEP_PARTS = ["track_step", "transport_wait", "contact_detection", "contact_forces", "track_rhs", "track_solve",
              "track_solve_wait", "track_step_other"]


def step_parts(track):
    """{part: us per Newmark step} of a track cost profile (runner.read_cost)."""
    n = float(track["count_newmark_steps"])
    out = {}
    for k in STEP_PARTS:
        v = track.get(k, track.get("finer_" + k))
        out[k] = 1e6 * (v or 0.0) / n
    return out


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--end", type=float, default=1.5, help="simulated seconds of every run")
    ap.add_argument("--out", default=os.path.join(REPO, "output", "bench_targets"))
    ap.add_argument("--workspace", default=REPO)
    ap.add_argument("--only", action="append", default=[], metavar="TEXT")
    ap.add_argument("--no-accuracy", action="store_true", help="skip the accuracy comparison")
    a = ap.parse_args(argv)
    rows, steps = [], []
    for name, scene, ov in CASES:
        if a.only and name != "standalone" and not any(t in name for t in a.only):
            continue
        overrides = {"solver.end": {"time": a.end}}
        overrides.update(ov)
        if overrides["solver.end"] is None:
            del overrides["solver.end"]
        # A flexible run records one track topic too: the track node writes its bag, and its cost profile
        # beside it (the per-step table below); two deflection sections at the output rate cost ~0.01 %.
        topics = TOPICS + (["rail_deflection"] if name.startswith("flexible") else [])
        overrides.update({"output.topics": topics, "output.bag": "run.bag"})
        loops, walls, simulated, per_step = [], [], [], []
        for i in range(a.repeat):
            case_dir = os.path.join(a.out, name.replace(" ", "_").replace(",", ""), str(i))
            spec = {"case_dir": case_dir, "name": name, "case_id": name, "settings_hash": "", "scene": scene,
                    "overrides": costmap.override_items(overrides), "workspace": a.workspace, "timeout": 1800.0}
            rec = runner.run_case(spec)
            if rec.get("status") != "ok":
                print("%s: run %d %s (exit %s): %s" % (name, i, rec.get("status"), rec.get("exit_code"),
                                                       (rec.get("log_tail") or "").strip()[-300:]))
                return 1
            cost = runner.read_cost(case_dir)
            loops.append(max(p["loop_wall_time"] for p in cost.values()))
            simulated.append(min(p["simulated_time"] for p in cost.values()))
            walls.append(rec["wall_time"])
            if "track" in cost and cost["track"].get("count_newmark_steps"):
                per_step.append(step_parts(cost["track"]))
            print("%-30s run %d: loop %.2f s, launch to exit %.2f s" % (name, i, loops[-1], walls[-1]), flush=True)
        rows.append((name, statistics.median(loops), statistics.median(walls), statistics.median(simulated)))
        if per_step:
            steps.append((name, {k: statistics.median(r[k] for r in per_step) for k in per_step[0]}))
    base = rows[0][1] / rows[0][3]
    print("\n| run (%.2f s simulated unless said, median of %d) | simulated [s] | loop wall [s] | per simulated s | "
          "real-time factor | x standalone | launch to exit [s] |" % (a.end, a.repeat))
    print("|---|---|---|---|---|---|---|")
    for name, loop, wall, sim in rows:
        print("| %s | %.2f | %.2f | %.3f | %.2f | %.2f | %.1f |" % (name, sim, loop, loop / sim, sim / loop,
                                                              loop / sim / base, wall))
    if steps:
        print("\n| track node, us per track step (median of %d) | %s |" % (a.repeat, " | ".join(STEP_PARTS)))
        print("|---|%s" % ("---|" * len(STEP_PARTS)))
        for name, parts in steps:
            print("| %s | %s |" % (name, " | ".join("%.0f" % parts[k] for k in STEP_PARTS)))
    flex = [r for r in rows if r[0] == "flexible, track step 2e-5 s"]
    five = [r for r in rows if r[0].startswith("flexible, 5 km")]
    if flex and five:
        print("\n5 km against 500 m (flexible, 2e-5 s): loop %+.1f %%, launch to exit %+.1f %%" % (
            100 * (five[0][1] / flex[0][1] - 1), 100 * (five[0][2] / flex[0][2] - 1)))
    if not a.no_accuracy:
        return accuracy(a)
    return 0


def accuracy(a):
    """The vehicle alone against the reference run (bench_vehicle_accuracy; its table printed as is)."""
    exe = os.path.join(a.workspace, "devel", "lib", "rail_vehicle_node", "bench_vehicle_accuracy")
    os.makedirs(a.out, exist_ok=True)
    # Sampled every 0.1 ms: a flange impact lasts about a millisecond, so 1 ms samples catch its peak by chance.
    reference = os.path.join(a.out, "accuracy_reference_0.1ms.csv")
    print("\nAccuracy of the vehicle alone, whole scene, against Adams capped at 5e-6 s, 0.1 ms samples (%s):"
          % reference, flush=True)
    p = subprocess.run([exe, "--sample", "1e-4", PAPER, reference, "auto", "0", "0", "0", "adams", "2e-5", "0", "0"],
                       check=False)
    if p.returncode != 0:
        print("bench_targets: bench_vehicle_accuracy exited %d (a run stopped early, or bad input such as a stale %s)"
              % (p.returncode, reference),
              file=sys.stderr)
    return p.returncode


if __name__ == "__main__":
    sys.exit(main())
