#!/usr/bin/python3
"""railsim_launch.py: runs one roslaunch of ./railsim run and tells the truth about it.

  railsim_launch.py --status-dir DIR [--log FILE] [--show REGEX] [--bag PATH ...] [--summary FILE]
                    -- roslaunch ARGS...

roslaunch exits 0 whatever its nodes do; this runner exits with the worst exit code of the nodes (README,
exit codes; a node ended by signal N counts as 128 + N), 0 only when every node exited 0. The nodes run
under scripts/railsim_node_guard, which writes each node's exit code to DIR/<node>.exit.
It also leaves nothing behind: it is the subreaper of the launch, so whatever roslaunch leaves when it dies
(master, rosout, nodes) becomes its child and is stopped (SIGINT, then SIGTERM, then SIGKILL); when this
runner's own parent dies, roslaunch gets SIGINT. A bag of --bag that was not closed (its node was killed)
is reindexed so that it opens, and said so; one that still does not open is removed, and said so. A log or
summary that cannot be written (disk full) is said in one line and makes the exit code 9. --summary writes what happened as YAML (nodes, exit_code,
reason, bags) for run.yaml.
"""
import argparse
import ctypes
import os
import re
import signal
import subprocess
import sys
import threading
import time

PR_SET_PDEATHSIG = 1
PR_SET_CHILD_SUBREAPER = 36
# What each exit code of a node means (README, exit codes).
MEANING = {
    0: "finished",
    2: "refused its scene or a data file",
    3: "the handshake was refused (the peer runs another scene)",
    4: "its peer never answered or stopped answering",
    5: "stopped by SIGINT/SIGTERM or by the ROS master going away",
    6: "internal error",
    7: "the vehicle derailed or reached the track's end",
    8: "the vehicle's integration failed",
    9: "could not write an output (disk full or unwritable)",
}
# Time the leftovers of a launch get after SIGINT (a node closes its bag), then after SIGTERM (s).
LEFTOVER_SIGINT_GRACE = 25.0
LEFTOVER_SIGTERM_GRACE = 5.0

_libc = ctypes.CDLL(None, use_errno=True)


def log(msg):
    print("[railsim] " + msg, file=sys.stderr, flush=True)


def meaning(code):
    if code < 0:
        try:
            return "killed by " + signal.Signals(-code).name
        except ValueError:
            return "killed by signal %d" % -code
    return MEANING.get(code, "exit code %d" % code)


def run_code(code):
    """A node's code as a process exit code (a signal N as 128 + N, as a shell reports it)."""
    return 128 - code if code < 0 else code


def children():
    """Pids of this process's live children (the orphans of the launch reparent here)."""
    me = str(os.getpid())
    out = []
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open("/proc/%s/stat" % d) as f:
                stat = f.read()
        except OSError:
            continue
        fields = stat[stat.rindex(")") + 2:].split()
        if fields[1] == me and fields[0] != "Z":
            out.append(int(d))
    return out


def comm(pid):
    try:
        with open("/proc/%d/cmdline" % pid, "rb") as f:
            return " ".join(a.decode(errors="replace") for a in f.read().split(b"\0")[:3] if a)
    except OSError:
        return "?"


# Exit codes of the nodes that became this runner's children (their guard died) and were reaped here.
orphan_codes = {}
orphan_names = {}


def full_cmdline(pid):
    try:
        with open("/proc/%d/cmdline" % pid, "rb") as f:
            return f.read().replace(b"\0", b" ").decode(errors="replace")
    except OSError:
        return ""


def reap():
    while True:
        try:
            pid, status = os.waitpid(-1, os.WNOHANG)
        except ChildProcessError:
            return
        if pid == 0:
            return
        if pid in orphan_names:
            orphan_codes[orphan_names[pid]] = os.waitstatus_to_exitcode(status)


def signal_tree(pid, sig):
    """Signals pid's process group when pid leads one (roslaunch starts each process in its own session),
    else pid alone."""
    try:
        if os.getpgid(pid) == pid:
            os.killpg(pid, sig)
        else:
            os.kill(pid, sig)
    except OSError:
        pass


def stop_leftovers(launch_pid):
    left = [p for p in children() if p != launch_pid]
    if not left:
        return []
    names = [comm(p) for p in left]
    for p in left:
        m = re.search(r"__name:=(\S+)", full_cmdline(p))
        if m and m.group(1) != "rosout":
            orphan_names[p] = m.group(1)
    log("roslaunch left %d process(es) running: %s; stopping them" % (len(left), "; ".join(names)))
    for sig, grace in ((signal.SIGINT, LEFTOVER_SIGINT_GRACE), (signal.SIGTERM, LEFTOVER_SIGTERM_GRACE),
                       (signal.SIGKILL, 5.0)):
        for p in left:
            signal_tree(p, sig)
        deadline = time.monotonic() + grace
        while time.monotonic() < deadline:
            reap()
            left = children()
            if not left:
                return names
            time.sleep(0.1)
    reap()
    return names


def close_quietly(f):
    try:
        f.close()
    except OSError:
        pass


def remove_quietly(path):
    try:
        os.remove(path)
    except OSError:
        pass


def check_bag(path, killed):
    """'ok', 'reindexed' or 'unreadable: <why>' for a bag that exists."""
    import rosbag
    try:
        rosbag.Bag(path).close()
        return "ok"
    except rosbag.ROSBagUnindexedException:
        pass
    except Exception as e:  # noqa: BLE001 - any other failure to open is reported as such
        return "unreadable: %s" % e
    try:
        b = rosbag.Bag(path, "a", allow_unindexed=True)
        for _ in b.reindex():
            pass
        b.close()
        n = rosbag.Bag(path).get_message_count()
    except Exception as e:  # noqa: BLE001
        return "unreadable: reindexing failed: %s" % (e.strerror if isinstance(e, OSError) and e.strerror else e)
    log("%s was left unindexed (%s); reindexed: it opens now (%d messages)" % (path, killed or "not closed", n))
    return "reindexed"


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--status-dir", required=True)
    ap.add_argument("--log")
    ap.add_argument("--show", help="console shows only the lines matching this regex (the log has all)")
    ap.add_argument("--bag", action="append", default=[])
    ap.add_argument("--summary")
    ap.add_argument("cmd", nargs=argparse.REMAINDER)
    a = ap.parse_args()
    cmd = a.cmd[1:] if a.cmd[:1] == ["--"] else a.cmd
    if not cmd:
        ap.error("no roslaunch command after --")
    _libc.prctl(PR_SET_CHILD_SUBREAPER, 1, 0, 0, 0)
    parent = os.getppid()
    _libc.prctl(PR_SET_PDEATHSIG, signal.SIGTERM, 0, 0, 0)
    os.makedirs(a.status_dir, exist_ok=True)
    for f in os.listdir(a.status_dir):
        if f.endswith(".exit"):
            os.remove(os.path.join(a.status_dir, f))
    env = dict(os.environ, RAILSIM_STATUS_DIR=os.path.abspath(a.status_dir))
    env.setdefault("ROSCONSOLE_STDOUT_LINE_BUFFERED", "1")  # console lines as they are written

    def launch_child():
        # roslaunch stops its nodes and master when this runner dies (SIGKILL included).
        _libc.prctl(PR_SET_PDEATHSIG, signal.SIGINT, 0, 0, 0)

    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, env=env,
                            preexec_fn=launch_child)
    interrupted = []

    def on_signal(sig, _frame):
        interrupted.append(signal.Signals(sig).name)
        try:
            proc.send_signal(signal.SIGINT)
        except OSError:
            pass

    signal.signal(signal.SIGINT, on_signal)
    signal.signal(signal.SIGTERM, on_signal)
    show = re.compile(a.show) if a.show else None
    write_errors = []  # "cannot write <file>: <reason>" of the runner's own files
    logf = None
    if a.log:
        try:
            logf = open(a.log, "w")
        except OSError as e:
            write_errors.append("cannot write %s: %s" % (a.log, e.strerror))
    text = []

    def pump():
        nonlocal logf
        for raw in iter(proc.stdout.readline, b""):
            line = raw.decode(errors="replace")
            text.append(line)
            if logf:
                try:
                    logf.write(line)
                    logf.flush()
                except OSError as e:
                    write_errors.append("cannot write %s: %s" % (a.log, e.strerror))
                    close_quietly(logf)
                    logf = None
            if show is None or show.search(line):
                sys.stdout.write(line)
                sys.stdout.flush()

    reader = threading.Thread(target=pump, daemon=True)
    reader.start()
    while True:
        try:
            rc = proc.wait(timeout=0.5)
            break
        except subprocess.TimeoutExpired:
            if os.getppid() != parent and not interrupted:
                interrupted.append("the runner went away")
                proc.send_signal(signal.SIGINT)
    left = stop_leftovers(proc.pid)
    reader.join(timeout=5.0)
    if logf:
        close_quietly(logf)
    full = "".join(text)

    # Each node's exit code: the guard's record, else what roslaunch reported.
    nodes = {}
    for f in sorted(os.listdir(a.status_dir)):
        if f.endswith(".exit"):
            with open(os.path.join(a.status_dir, f)) as fh:
                nodes[f[:-5]] = int(fh.read().strip() or 6)
    for name, code in orphan_codes.items():
        if name not in nodes:
            nodes[name] = code
            log("%s outlived its guard; stopped and reaped by the runner (exit %d)" % (name, code))
    for name in re.findall(r"process\[(rail_\w+?)-\d+\]: started with pid", full):
        if name not in nodes:
            m = re.search(r"\[%s-\d+\] process has died \[pid \d+, exit code (-?\d+)" % name, full)
            nodes[name] = int(m.group(1)) if m else 6
            if not m:
                log("%s left no exit code (its guard was killed?): counted as 6" % name)
    worst = max([run_code(c) for c in nodes.values()] or [0])
    reasons = ["%s exited %d (%s)" % (n, c, meaning(c)) for n, c in nodes.items() if c != 0]
    if not nodes:
        worst = rc if rc > 0 else 1
        reasons.append("roslaunch started no node (exit %d); see %s" % (rc, a.log or "its output"))
    elif rc < 0:
        reasons.append("roslaunch was %s" % meaning(rc))
        worst = max(worst, run_code(rc))
    if interrupted:
        reasons.append("stopped by " + interrupted[0])
        worst = worst or 5
    if left:
        reasons.append("roslaunch left %d process(es) that the runner stopped" % len(left))
    killed = ", ".join("%s %s" % (n, meaning(c)) for n, c in nodes.items() if c < 0)
    bags = {}
    for b in a.bag:
        if os.path.isfile(b):
            bags[b] = check_bag(b, killed)
            if bags[b].startswith("unreadable"):
                try:
                    os.remove(b)
                    bags[b] += "; removed"
                except OSError as e:
                    bags[b] += "; cannot remove it: %s" % e.strerror
                log("%s is %s" % (b, bags[b]))
                reasons.append("%s is %s" % (os.path.basename(b), bags[b]))
                worst = worst or 6
    for n, c in nodes.items():
        (log if c != 0 else lambda m: None)("%s exited %d: %s" % (n, c, meaning(c)))
    for e in write_errors[:1]:
        log(e)
        reasons.append(e)
        worst = worst or 9
    if a.summary:
        import yaml
        try:
            with open(a.summary, "w") as f:
                yaml.safe_dump({"exit_code": worst, "nodes": nodes, "incomplete": "; ".join(reasons) or None,
                                "bags": bags or None}, f, sort_keys=False, width=10000)
        except OSError as e:
            log("cannot write %s: %s" % (a.summary, e.strerror))
            remove_quietly(a.summary)
            worst = worst or 9
    return min(worst, 255)


if __name__ == "__main__":
    sys.exit(main())
