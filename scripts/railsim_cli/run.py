"""./railsim run: one scene, or the paper's demonstration (three runs, the analysis and its report)."""
import datetime
import fcntl
import os
import socket
import subprocess
import sys
import time

import yaml

from .build import build
from .common import (EXIT_INTERRUPTED, EXIT_WRITE_FAILED, OUTPUT, ROOT, Parser, Refused, Stop, isolation_probe, log,
                     loopback_master, put, ros_env, user_path)
from .validate import check_data, validator

USAGE = """usage: ./railsim run [--full | --end SECONDS] [--runs 'standalone rigid_fe flexible'] [--scene S] [--out DIR]
       ./railsim run SCENE.yaml [--set key=value ...] [--out DIR] [--rviz]
  Without a scene: the paper's demonstration (three runs, bags, figures, report in DIR, default
  output/<scene>_<end>s). With a scene: one run of it (bags in DIR, default output/); --set overrides a
  key of the scene as `./railsim validate` does; --rviz shows the run in rviz as it goes (on $DISPLAY; the
  scene's rviz_markers turned on). Exit code: the worst of the nodes' (README, exit codes),
  0 only when every node finished its scene; 1 when the runner refused (bad option, output dir in use)."""

# Simulated seconds of the demonstration's default (short) run; --full runs the whole scene.
DEMO_SHORT_END = "1.5"
DEMO_RUNS = ("standalone", "rigid_fe", "flexible")
# Lines of a run's console output shown during the demonstration (all of it goes to <run>.log).
PROGRESS_LINES = "%|FATAL|ERROR|WARN|finished|stopped|bag closed|built"
# Per run of the demonstration: its track model, launch file and the effects its track model has. Every run
# records the floor accelerations (running-safety and comfort report); the topics are every one the run's
# resolved scene can record (railsim_validate_scene --topics).
DEMO_PLANS = {
    "standalone": ("rigid", "vehicle_standalone",
                   ["effects.rail_deflection_output=false", "effects.pad_force_output=false"]),
    "rigid_fe": ("rigid_fe", "cosim", ["effects.pad_force_output=false"]),
    "flexible": ("flexible", "cosim", ["effects.pad_force_output=true"]),
}

_lock_fd = None  # the output directory's lock, held until the process ends


def lock_out(directory):
    """Takes the lock of the output directory for the rest of this command: a second run into the same
    directory is refused naming the first one's pid. The lock goes with the process, whatever ends it."""
    global _lock_fd
    os.makedirs(directory, exist_ok=True)
    path = os.path.join(directory, ".railsim.lock")
    fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        with open(path, errors="replace") as f:
            holder = f.readline().strip() or "?"
        log("output directory %s is in use by another run: %s (lock %s); wait for it or give another --out"
            % (directory, holder, path))
        raise Stop(1)
    os.ftruncate(fd, 0)
    os.write(fd, ("pid %d: ./railsim %s (since %s)\n" % (os.getpid(), " ".join(sys.argv[1:]),
                                                        datetime.datetime.utcnow().strftime("%H:%M:%SZ"))).encode())
    _lock_fd = fd


def yaml_str(text):
    """text as a single-quoted YAML string."""
    return "'%s'" % text.replace("'", "''")


def status_lines(path, rc):
    """run.yaml lines of a launch's summary (nodes, exit code, why incomplete)."""
    if os.path.isfile(path):
        with open(path) as f:
            return "".join(line for line in f if not line.startswith("exit_code:"))
    return "incomplete: %s\n" % yaml_str("the launch's runner (scripts/railsim_launch.py) ended with exit %d without a "
                                         "summary" % rc)


def launch_scene(env, plan, scene, out, stem, show, bags, *launch_args):
    """One launch of a scene under scripts/railsim_launch.py (true exit codes, nothing left running, bags
    reindexed when a node was killed); its console in <stem>.log, its summary in <stem>.status.yaml."""
    cmd = [os.path.join(ROOT, "scripts", "railsim_isolate"), "/usr/bin/python3",
           os.path.join(ROOT, "scripts", "railsim_launch.py"), "--status-dir", stem + ".status", "--log", stem + ".log",
           "--summary", stem + ".status.yaml"]
    if show:
        cmd += ["--show", show]
    for b in bags:
        cmd += ["--bag", b]
    cmd += ["--", "roslaunch", "--disable-title", "-p", env["ROS_MASTER_URI"].rsplit(":", 1)[1],
            os.path.join(ROOT, "launch", plan + ".launch"), "scene:=" + os.path.realpath(scene), "output_dir:=" + out]
    return subprocess.run(cmd + list(launch_args), env=env).returncode


def analysis_outcome(tool, code, run_rc):
    """An analysis' exit code folded into the run's: a run too short for the analysis (exit 3) is said and
    keeps the nodes' code; any other failure of the analysis makes a successful run 1."""
    if code == 3:
        log("%s: the run is too short for this analysis (see its message above): skipped" % tool)
    elif code != 0:
        log("%s failed (exit %d)" % (tool, code))
        return run_rc or 1
    return run_rc


def remove(*paths):
    for p in paths:
        try:
            os.remove(p)
        except FileNotFoundError:
            pass


def with_sets(overrides):
    args = []
    for o in overrides:
        args += ["--set", o]
    return args


def run_scene(argv):
    """One run of a scene."""
    parser = Parser("run", USAGE, unknown="unknown argument '%s' (one scene, then --set key=value, --out DIR or --rviz)",
                    needs={"--set": "needs key=value", "--out": "needs a directory"})
    parser.add_argument("scene")
    parser.add_argument("--set", action="append", default=[])
    parser.add_argument("--out", default=OUTPUT)
    parser.add_argument("--rviz", action="store_true")
    a = parser.parse(argv)
    scene, out, sets, rviz = user_path(a.scene), user_path(a.out), list(a.set), a.rviz
    if rviz:
        if not os.environ.get("DISPLAY"):
            raise Refused("run: --rviz needs a display (DISPLAY is not set)", USAGE)
        sets.append("effects.rviz_markers=true")
    build()
    env = loopback_master(ros_env())
    args = [scene] + with_sets(sets)
    plan = validator(args + ["--plan"]).strip()
    check_data(args)
    lock_out(out)
    isolation_probe(env)
    out = os.path.realpath(out)
    log("scene %s: %s" % (scene, plan))
    sys.stdout.write(validator(args + ["--summary"]))
    sys.stdout.flush()
    resolved = validator(args)
    overrides = " ".join(sets)
    bag = ((yaml.safe_load(resolved) or {}).get("output") or {}).get("bag") or ""
    bags = []
    if bag:
        if not bag.startswith("/"):
            bag = os.path.join(out, bag)
        stem = bag[:-4] if bag.endswith(".bag") else bag
        bags = [bag, stem + ".track.bag"]
        remove(*bags)
    else:
        stem = os.path.join(out, os.path.basename(scene)[:-5] if scene.endswith(".yaml") else os.path.basename(scene))
    remove(stem + ".status.yaml")
    rc = launch_scene(env, plan, scene, out, stem, "", bags, "overrides:=" + overrides,
                      "rviz:=" + ("true" if rviz else "false"))
    put(stem + ".run.yaml", "scene: %s\n" % yaml_str(scene) + ("overrides: %s\n" % yaml_str(overrides) if sets else "") +
        "exit_code: %d\n" % rc + status_lines(stem + ".status.yaml", rc))
    if rc == EXIT_WRITE_FAILED:  # its nodes said which file and why
        log("run of %s could not write its outputs (exit 9); see %s.run.yaml" % (scene, stem))
        return rc
    # The running-safety summary of the run (printed; CSV beside the bag), when it recorded a vehicle bag.
    if bag and plan != "track_standalone" and os.path.isfile(bag) and os.path.isfile(stem + ".status.yaml"):
        put(stem + ".scene.yaml", resolved)
        track_args = ["--track-bag", stem + ".track.bag"] if os.path.isfile(stem + ".track.bag") else []
        src = subprocess.run([os.path.join(ROOT, "src", "rail_analysis", "scripts", "railsim_safety"), bag, "--scene",
                              stem + ".scene.yaml"] + track_args, env=env).returncode
        rc = analysis_outcome("railsim_safety", src, rc)
    if rc != 0:
        with open(stem + ".run.yaml") as f:
            why = next((line[len("incomplete: "):].strip() for line in f if line.startswith("incomplete: ")), "")
        log("run of %s: exit %d (%s); see %s.log and %s.run.yaml" % (scene, rc, why, stem, stem))
    return rc


def demo(argv):
    """The paper's demonstration (section 6): the scene run three times, vehicle alone on the rigid track,
    co-simulation with the rigid FE track, co-simulation with the flexible track; each run's bag, resolved
    scene and wall time go to one directory, then the analysis writes the figures and report.md there."""
    parser = Parser("run", USAGE)
    parser.add_argument("--full", action="store_true")
    parser.add_argument("--end")
    parser.add_argument("--scene", default=os.path.join(ROOT, "config", "scenes", "paper_demo.yaml"))
    parser.add_argument("--runs", default=" ".join(DEMO_RUNS))
    parser.add_argument("--out", default="")
    a = parser.parse(argv)
    end = a.end if a.end is not None else ("" if a.full else DEMO_SHORT_END)
    scene, out, runs = user_path(a.scene), user_path(a.out) if a.out else "", a.runs.split()
    for r in runs:
        if r not in DEMO_PLANS:
            raise Refused("run: unknown run '%s' (standalone, rigid_fe, flexible)" % r, USAGE)
    stem = os.path.basename(scene)[:-5] if scene.endswith(".yaml") else os.path.basename(scene)
    out = out or os.path.join(OUTPUT, stem + ("_%ss" % end if end else ""))
    build()
    env = loopback_master(ros_env())
    lock_out(out)
    isolation_probe(env)
    out = os.path.realpath(out)
    log("demonstration of %s%s -> %s" % (scene, " (first %s s; --full for the whole scene)" % end if end else "", out))
    worst = 0
    for k, run in enumerate(runs, 1):
        model, plan, effects = DEMO_PLANS[run]
        more = ["output.bag=%s.bag" % run] + (["solver.end={time: %s}" % end] if end else []) + \
            ["effects.floor_acceleration_output=true"] + effects
        base = [scene, "--set", "effects.track_model=" + model] + with_sets(more)
        topics = validator(base + ["--set", "output.topics=[]", "--topics"]).strip()
        more.append("output.topics=[%s]" % topics)
        args = [scene, "--set", "effects.track_model=" + model] + with_sets(more)
        put(os.path.join(out, run + ".scene.yaml"), validator(args))
        log("run %d/%d: %s (%s)" % (k, len(runs), run, validator(args + ["--summary"]).splitlines()[0]))
        prefix = os.path.join(out, run)
        remove(prefix + ".bag", prefix + ".track.bag", prefix + ".status.yaml")
        t0 = time.monotonic()
        rc = launch_scene(env, plan, scene, out, prefix, PROGRESS_LINES, [prefix + ".bag", prefix + ".track.bag"],
                          "overrides:=" + " ".join(more), "track_model:=" + model)
        wall = time.monotonic() - t0
        put(prefix + ".run.yaml",
            "# written by ./railsim run: how this run was made, what it cost and how it ended\n"
            "run: %s\nscene: %s\ntrack_model: %s\nend_time: %s\n"
            "wall_time: %.2f   # s, roslaunch start to exit (node start-up and settling included)\n"
            "exit_code: %d\ndate: %s\nhost: %s\n"
            % (run, yaml_str(scene), model, end or "null", wall, rc,
               datetime.datetime.utcnow().strftime("%Y-%m-%dT%H:%M:%SZ"), socket.gethostname()) +
            status_lines(prefix + ".status.yaml", rc))
        worst = max(worst, rc)
        if rc == EXIT_INTERRUPTED:  # Ctrl-C, SIGTERM, the master gone: the demonstration stops with it
            log("run %s stopped (exit 5): demonstration stopped; its log: %s.log" % (run, prefix))
            raise Stop(EXIT_INTERRUPTED)
        if rc == EXIT_WRITE_FAILED:  # a full disk: the next runs would fail alike
            log("run %s could not write its outputs (exit 9): demonstration stopped; see %s.run.yaml" % (run, prefix))
            raise Stop(EXIT_WRITE_FAILED)
        if not os.path.isfile(prefix + ".bag"):
            log("run %s wrote no bag (exit %d); its log: %s.log" % (run, rc, prefix))
            raise Stop(worst)
        log("run %d/%d: %s done in %.2f s wall (exit %d)" % (k, len(runs), run, wall, rc))
    analyze = os.path.join(ROOT, "src", "rail_analysis", "scripts", "railsim_analyze")
    if os.access(analyze, os.X_OK):
        log("analysis")
        arc = subprocess.run([analyze, out, "--out", os.path.join(out, "report")], env=env).returncode
        worst = analysis_outcome("railsim_analyze", arc, worst)
        log("running safety, track loading, wear and comfort (CSV beside each bag)")
        arc = subprocess.run([os.path.join(ROOT, "src", "rail_analysis", "scripts", "railsim_safety"), out, "--runs",
                              ",".join(runs)], env=env).returncode
        worst = analysis_outcome("railsim_safety", arc, worst)
        if os.path.isfile(os.path.join(out, "report", "report.md")):
            log("report: %s" % os.path.join(out, "report", "report.md"))
    else:
        log("bags in %s" % out)
    if worst != 0:
        log("demonstration: exit %d (see the messages above and each %s/<run>.run.yaml)" % (worst, out))
    return worst


def main(argv):
    if not argv or argv[0].startswith("--"):
        return demo(argv)
    if argv[0] == "-h":
        print(USAGE)
        return 0
    if argv[0].startswith("-"):
        raise Refused("run: unknown option '%s'" % argv[0], USAGE)
    return run_scene(argv)
