"""./railsim two-hosts: the README's two-machine recipe across two network namespaces."""
import glob
import os
import re
import shutil
import signal
import subprocess
import time

from .build import build
from .common import OUTPUT, ROOT, Parser, Stop, log, user_path

USAGE = """usage: ./railsim two-hosts [--out DIR]
  The README's two-machine recipe across two network namespaces joined by a veth pair, each with its own
  host name and ROS_IP: host A (10.218.0.1) runs the master, scene.launch and the track node, host B
  (10.218.0.2) the vehicle node. Over service and topic both nodes must finish (exit 0); over shm the
  vehicle must be refused with the message naming both hosts. Needs root. Exit 0 when all three hold.
  Logs in DIR (default output/two_hosts)."""

PORT = 11311
SCENE = os.path.join(ROOT, "test", "scenes", "paper_demo_60m.yaml")
# Each side: its own UTS namespace (host name) inside its network namespace, the workspace sourced.
SIDE = 'hostname "$0"; source "$1/devel/setup.bash"; shift; exec "$@"'


def side(ns, host, ip, ros_home):
    return ["ip", "netns", "exec", ns, "unshare", "--uts", "bash", "-c", SIDE, host, ROOT, "env", "ROS_IP=" + ip,
            "ROS_MASTER_URI=http://10.218.0.1:%d" % PORT, "ROS_HOME=" + ros_home]


def run_once(transport, ns_a, ns_b, directory):
    """One run of the recipe over `transport`; (track exit code, vehicle exit code)."""
    overrides = ("solver.transport=%s effects.track_model=rigid_fe effects.rail_deflection_output=false "
                 "solver.end={time: 0.05} solver.handshake_timeout=10 solver.exchange_timeout=10 "
                 "output.bag=two_hosts_%s.bag output.topics=[wheel_states,wheelset_kinematics,clock]"
                 % (transport, transport))
    os.makedirs(directory, exist_ok=True)
    a = side(ns_a, "railsim-a", "10.218.0.1", os.path.join(directory, "ros_home_a"))
    b = side(ns_b, "railsim-b", "10.218.0.2", os.path.join(directory, "ros_home_b"))

    def logged(name):
        return open(os.path.join(directory, name), "w")

    core = subprocess.Popen(a + ["roscore", "-p", str(PORT)], stdout=logged("roscore.log"), stderr=subprocess.STDOUT,
                            start_new_session=True)
    try:
        for _ in range(100):
            if subprocess.run(a + ["rosparam", "list"], stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL).returncode == 0:
                break
            time.sleep(0.2)
        subprocess.run(a + ["timeout", "60", "roslaunch", os.path.join(ROOT, "launch", "scene.launch"),
                            "scene:=" + SCENE, "overrides:=" + overrides], stdout=logged("scene.log"),
                       stderr=subprocess.STDOUT)
        track = subprocess.Popen(a + ["timeout", "120", "rosrun", "rail_track_node", "track_node",
                                      "_output_dir:=" + directory], stdout=logged("track.log"),
                                 stderr=subprocess.STDOUT, start_new_session=True)
        vrc = subprocess.run(b + ["timeout", "120", "rosrun", "rail_vehicle_node", "vehicle_node",
                                  "_output_dir:=" + directory], stdout=logged("vehicle.log"),
                             stderr=subprocess.STDOUT).returncode
        trc = track.wait()
    finally:
        try:
            os.killpg(core.pid, signal.SIGINT)
        except OSError:
            pass
        core.wait()
    return trc, vrc


def cleanup(namespaces):
    for sig in (signal.SIGTERM, signal.SIGKILL):
        for ns in namespaces:
            pids = subprocess.run(["ip", "netns", "pids", ns], capture_output=True, text=True).stdout.split()
            for p in pids:
                try:
                    os.kill(int(p), sig)
                except (OSError, ValueError):
                    pass
        time.sleep(0.5 if sig == signal.SIGTERM else 0.0)
    for ns in namespaces:
        subprocess.run(["ip", "netns", "del", ns], stderr=subprocess.DEVNULL)


def main(argv):
    parser = Parser("two-hosts", USAGE, needs={"--out": "needs a directory"})
    parser.add_argument("--out", default=os.path.join(OUTPUT, "two_hosts"))
    out = user_path(parser.parse(argv).out)
    if os.geteuid() != 0:
        log("two-hosts: needs root (ip netns, veth)")
        raise Stop(1)
    build()
    ns_a, ns_b = "railsim_a_%d" % os.getpid(), "railsim_b_%d" % os.getpid()
    va, vb = "rsa%d" % os.getpid(), "rsb%d" % os.getpid()
    try:
        steps = [["ip", "netns", "add", ns_a], ["ip", "netns", "add", ns_b],
                 ["ip", "link", "add", va, "type", "veth", "peer", "name", vb],
                 ["ip", "link", "set", va, "netns", ns_a], ["ip", "link", "set", vb, "netns", ns_b],
                 ["ip", "-n", ns_a, "addr", "add", "10.218.0.1/24", "dev", va],
                 ["ip", "-n", ns_b, "addr", "add", "10.218.0.2/24", "dev", vb],
                 ["ip", "-n", ns_a, "link", "set", "lo", "up"], ["ip", "-n", ns_b, "link", "set", "lo", "up"],
                 ["ip", "-n", ns_a, "link", "set", va, "up"], ["ip", "-n", ns_b, "link", "set", vb, "up"]]
        for s in steps:
            if subprocess.run(s).returncode != 0:
                log("two-hosts: cannot set up the network namespaces")
                raise Stop(1)
        shutil.rmtree(out, ignore_errors=True)
        os.makedirs(out)
        failed = False
        for transport in ("service", "topic", "shm"):
            t0 = time.monotonic()
            trc, vrc = run_once(transport, ns_a, ns_b, os.path.join(out, transport))
            r, wall = "track=%d vehicle=%d" % (trc, vrc), time.monotonic() - t0
            logs = ""
            for path in sorted(glob.glob(os.path.join(out, transport, "*.log"))):
                with open(path, errors="replace") as f:
                    logs += f.read()
            if transport == "shm":
                m = re.search(r"region \S* refused: created on host '[^']*', this is host '[^']*'", logs)
                if "the shm transport needs both nodes on one host" in logs:
                    log("two-hosts: shm refused across the hosts (%s, %.1f s): %s" % (r, wall, m.group(0) if m else ""))
                else:
                    log("two-hosts: shm FAILED: not refused with its message (%s); logs in %s/shm" % (r, out))
                    failed = True
            elif (trc, vrc) == (0, 0):
                log("two-hosts: %s: both nodes finished across the hosts (%.1f s)" % (transport, wall))
            else:
                log("two-hosts: %s FAILED (%s); logs in %s/%s" % (transport, r, out, transport))
                failed = True
        log("two-hosts: failed" if failed else "two-hosts: passed")
        return 1 if failed else 0
    finally:
        cleanup((ns_a, ns_b))
