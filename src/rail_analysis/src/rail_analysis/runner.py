"""Running one scene as the user runs it, in isolation: roslaunch of the scene's launch plan on a master of
its own (a free port), each node under its guard, the run stopped whole (process group, and a master it left)
after a timeout or an interrupt, and its record: status, the nodes' exit codes, wall time, log tail, cost
profiles. The accuracy-cost map (costmap.py), the hard-case suite and the benchmarks run their scenes with
it; the analysis of what the runs leave is elsewhere.

A case directory receives scene.yaml (the resolved scene), run.log (the launch's console), run.bag,
run.track.bag (co-simulation), run.cost.yaml and run.track.cost.yaml.
"""
import glob
import os
import random
import re
import signal
import socket
import subprocess
import threading
import time

import yaml

DEFAULT_TIMEOUT = 900.0          # s of wall time per case
BAG = "run.bag"                  # the vehicle node's bag in a case directory
LOG_TAIL_LINES = 30              # lines of a failed case's log kept in its record
PORT_RANGE = (21000, 31000)      # masters' ports are drawn from here, below Linux's ephemeral range

_port_lock = threading.Lock()
_ports_given = set()


def _port_free(port):
    for family, addr in ((socket.AF_INET, ""), (socket.AF_INET, "127.0.0.1")):
        s = socket.socket(family, socket.SOCK_STREAM)
        try:
            s.bind((addr, port))
        except OSError:
            return False
        finally:
            s.close()
    return True


def free_port():
    """A TCP port nobody listens on, from PORT_RANGE, not handed out before by this process."""
    with _port_lock:
        for _ in range(1000):
            p = random.randrange(*PORT_RANGE)
            if p not in _ports_given and _port_free(p):
                _ports_given.add(p)
                return p
    raise RuntimeError("no free TCP port in %d..%d" % PORT_RANGE)


def _setup_script(workspace):
    for cand in (os.path.join(workspace, "devel", "setup.bash"), os.path.join(workspace, "install", "setup.bash"),
                 workspace):
        if os.path.isfile(cand):
            return cand
    return None


_running = {}   # pid -> Popen of the launches in progress (stopped when the tool is interrupted)
_running_lock = threading.Lock()


def _live_processes(pgid=None, cmdline_part=None):
    """Pids of this user's live (not zombie) processes in process group pgid, or whose command line holds
    cmdline_part, from /proc."""
    pids = []
    for entry in os.listdir("/proc"):
        if not entry.isdigit() or int(entry) == os.getpid():
            continue
        try:
            if os.stat("/proc/" + entry).st_uid != os.getuid():
                continue
            with open("/proc/%s/stat" % entry) as f:
                fields = f.read().rsplit(")", 1)[1].split()
            if fields[0] == "Z":
                continue
            if pgid is not None and int(fields[2]) == pgid:
                pids.append(int(entry))
            elif cmdline_part is not None:
                with open("/proc/%s/cmdline" % entry, "rb") as f:
                    if cmdline_part.encode() in f.read():
                        pids.append(int(entry))
        except (OSError, IndexError, ValueError):
            continue
    return pids


def _group_members(pgid):
    return _live_processes(pgid=pgid)


def _stop(proc, grace=15.0):
    """SIGINT to the launch's process group (roslaunch shuts its nodes and master down), SIGKILL to what is
    left of the group after grace. Returns once no live process of the group is left: roslaunch can exit
    while the last of its nodes is still shutting down."""
    deadline = time.monotonic() + grace
    try:
        os.killpg(proc.pid, signal.SIGINT)
        proc.wait(timeout=grace)
    except (ProcessLookupError, subprocess.TimeoutExpired):
        pass
    while _group_members(proc.pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    if proc.poll() is None or _group_members(proc.pid):
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass
        proc.wait()
        end = time.monotonic() + 5.0
        while _group_members(proc.pid) and time.monotonic() < end:
            time.sleep(0.05)
    # A master that roslaunch started in its own session is outside the group; one that a launch stopped
    # during its start-up left behind still names the case directory (its log) on its command line.
    case_dir = getattr(proc, "case_dir", None)
    if case_dir:
        for sig, wait in ((signal.SIGINT, 5.0), (signal.SIGKILL, 5.0)):
            left = _live_processes(cmdline_part=case_dir)
            if not left:
                break
            for pid in left:
                try:
                    os.kill(pid, sig)
                except ProcessLookupError:
                    pass
            end = time.monotonic() + wait
            while _live_processes(cmdline_part=case_dir) and time.monotonic() < end:
                time.sleep(0.05)


def stop_all():
    """Stops every launch this process started that is still running."""
    with _running_lock:
        procs = list(_running.values())
    for p in procs:
        if p.poll() is None:
            _stop(p, grace=10.0)


def _node_exit_codes(log_text):
    """Exit codes roslaunch reports for nodes that died ("process has died [pid N, exit code C, ...")."""
    return [int(c) for c in re.findall(r"process has died \[pid \d+, exit code (-?\d+)", log_text)]


def _guard_exit_codes(status_dir):
    """{node: exit code} of the <node>.exit files the node guards wrote ({} without any)."""
    out = {}
    for f in sorted(glob.glob(os.path.join(status_dir, "*.exit"))):
        try:
            with open(f) as fh:
                out[os.path.basename(f)[:-5]] = int(fh.read().strip())
        except (OSError, ValueError):
            continue
    return out


def _tail(text, n=LOG_TAIL_LINES):
    text = re.sub(r"\x1b\[[0-9;]*m", "", text)
    return "\n".join(text.rstrip().splitlines()[-n:])


def run_case(spec):
    """Runs one case (a subprocess: roslaunch on its own master) and returns its run record (a dict).
    spec: case_dir, name, case_id, settings_hash, scene (abs path), overrides (["key=value"]), workspace,
    timeout [s]. Writes <case_dir>/scene.yaml (resolved), run.log, and the bags and cost profiles of the
    run. Never raises for a failing run: status 'ok', 'failed', 'timeout' or 'refused' (scene invalid)."""
    case_dir = spec["case_dir"]
    os.makedirs(case_dir, exist_ok=True)
    for f in glob.glob(os.path.join(case_dir, "run*.bag*")) + glob.glob(os.path.join(case_dir, "run*.cost.yaml")):
        os.remove(f)
    rec = {"status": "failed", "exit_code": None, "wall_time": None, "host": socket.gethostname(),
           "port": None, "log_tail": ""}
    setup = _setup_script(spec["workspace"])
    log_path = os.path.join(case_dir, "run.log")
    if setup is None:
        rec["log_tail"] = "workspace %s: no devel/setup.bash or install/setup.bash" % spec["workspace"]
        with open(log_path, "w") as f:
            f.write(rec["log_tail"] + "\n")
        return rec
    env = dict(os.environ)
    env["PATH"] = "/usr/bin:/bin:" + env.get("PATH", "")
    env["ROS_HOME"] = os.path.join(case_dir, "ros_home")
    env["ROS_IP"] = "127.0.0.1"
    env.pop("ROS_HOSTNAME", None)
    env["PYTHONUNBUFFERED"] = "1"
    # Each node's guard (scripts/railsim_node_guard) writes its exit code here, shutdown exits included.
    status_dir = os.path.join(case_dir, "node_exit")
    _rmtree(status_dir)
    env["RAILSIM_STATUS_DIR"] = status_dir
    wrap = ["bash", "-c", 'source "$0" >/dev/null || exit 97; exec "$@"', setup]
    sets = []
    for o in spec["overrides"]:
        sets += ["--set", o]
    # The resolved scene and the launch plan (vehicle_standalone or cosim), from the workspace's validator.
    val = wrap + ["rosrun", "rail_core", "railsim_validate_scene", spec["scene"]] + sets
    p = subprocess.run(val, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    with open(os.path.join(case_dir, "scene.yaml"), "w") as f:
        f.write(p.stdout)
    if p.returncode != 0:
        rec.update(status="refused", exit_code=p.returncode, log_tail=_tail(p.stdout))
        with open(log_path, "w") as f:
            f.write(p.stdout)
        return rec
    p = subprocess.run(val + ["--plan"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env)
    plan = p.stdout.strip()
    launch = os.path.join(spec["workspace"], "launch", plan + ".launch")
    if p.returncode != 0 or not os.path.isfile(launch):
        rec.update(status="refused", exit_code=p.returncode, log_tail=_tail(p.stdout))
        with open(log_path, "w") as f:
            f.write(p.stdout)
        return rec
    port = free_port()
    rec["port"] = port
    env["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
    # Whitespace inside {...}, [...] and quotes stays within one override (docs/scene.md, Overrides).
    overrides = " ".join(spec["overrides"] + ["output.bag=" + BAG])
    # In a network namespace with only loopback where the system allows it (scripts/railsim_isolate).
    isolate = os.path.join(spec["workspace"], "scripts", "railsim_isolate")
    prefix = [isolate] if os.access(isolate, os.X_OK) else []
    cmd = prefix + wrap + ["roslaunch", "--disable-title", "-p", str(port), launch, "scene:=" + spec["scene"],
                  "output_dir:=" + case_dir, "overrides:=" + overrides]
    rec["plan"] = plan
    t0 = time.monotonic()
    with open(log_path, "w") as log:
        log.write("# %s\n" % " ".join(cmd[len(prefix) + 4:]))
        log.flush()
        proc = subprocess.Popen(cmd, stdout=log, stderr=subprocess.STDOUT, env=env, start_new_session=True)
        proc.case_dir = case_dir  # what _stop clears up after the launch
        with _running_lock:
            _running[proc.pid] = proc
        try:
            rc = proc.wait(timeout=spec["timeout"])
            timed_out = False
        except subprocess.TimeoutExpired:
            _stop(proc)
            rc = proc.returncode
            timed_out = True
        finally:
            with _running_lock:
                _running.pop(proc.pid, None)
    rec["wall_time"] = round(time.monotonic() - t0, 3)
    if timed_out:
        # Shared-memory regions of a stopped co-simulation carry the launch's anonymous run id, which holds
        # the roslaunch pid (exec'd from the wrapper, so proc.pid).
        for f in glob.glob("/dev/shm/*_run_*_%d_*" % proc.pid):
            try:
                if os.stat(f).st_uid == os.getuid():
                    os.remove(f)
            except OSError:
                pass
    with open(log_path, errors="replace") as f:
        text = f.read()
    died = [c for c in _node_exit_codes(text) if c != 0]
    nodes = _guard_exit_codes(status_dir)
    if nodes:
        # The worst node code (a signal N as 128 + N); 0 only when every node finished.
        rec["nodes"] = nodes
        worst = max((128 - c if c < 0 else c) for c in nodes.values())
        rec["exit_code"] = worst if worst != 0 else rc
    else:
        rec["exit_code"] = rc if rc != 0 else (died[0] if died else 0)
    if timed_out:
        rec["status"] = "timeout"
        rec["log_tail"] = _tail(text) + "\n[railsim_map] stopped after the timeout of %g s" % spec["timeout"]
    elif rec["exit_code"] != 0 or not os.path.isfile(os.path.join(case_dir, BAG)):
        rec["status"] = "failed"
        rec["log_tail"] = _tail(text)
    else:
        rec["status"] = "ok"
        _rmtree(env["ROS_HOME"])
    return rec


def _rmtree(path):
    import shutil
    shutil.rmtree(path, ignore_errors=True)


def read_cost(case_dir):
    """{'vehicle': profile, 'track': profile} of the cost profiles beside the bag (missing ones left out):
    loop_wall_time, simulated_time, each component's seconds, count_<name>, finer_<part> seconds."""
    out = {}
    for who, fname in (("vehicle", "run.cost.yaml"), ("track", "run.track.cost.yaml")):
        try:
            with open(os.path.join(case_dir, fname)) as f:
                d = yaml.safe_load(f)
        except (OSError, yaml.YAMLError):
            continue
        if isinstance(d, dict):
            prof = {"loop_wall_time": d.get("loop_wall_time"), "simulated_time": d.get("simulated_time")}
            for comp, v in (d.get("components") or {}).items():
                prof[comp] = v.get("seconds") if isinstance(v, dict) else None
            for k, v in (d.get("counts") or {}).items():
                prof["count_" + k] = v
            for part, v in (d.get("finer") or {}).items():  # nested parts (e.g. track_solve in track_step)
                prof["finer_" + part] = v.get("seconds") if isinstance(v, dict) else None
            out[who] = prof
    return out
