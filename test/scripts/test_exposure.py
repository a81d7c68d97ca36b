#!/usr/bin/env python3
"""What a run exposes (doc/faults.md): the master of a run started as ./railsim starts it listens on the
loopback interface only; the shared-memory regions and the bags are readable by the user alone; a lockstep
frame from a node that did not complete the handshake, carrying another scene hash, is refused and reported,
never used.

The railsim-style run is launch/cosim.launch under `roslaunch -p PORT` with ROS_IP=127.0.0.1 (./railsim's
loopback_master and launch_scene); the lockstep cases start the two nodes themselves (test_faults.Run) on
the rostest master and publish or call from this test node, which did no handshake."""
import glob
import os
import re
import signal
import stat
import subprocess
import threading
import time
import unittest
import xmlrpc.client

import rospy
import rostest
from rail_msgs.msg import WheelState, WheelStates
from rail_msgs.srv import Lockstep, LockstepRequest

from test_faults import (EXIT_OK, EXIT_PEER_REFUSED, EXIT_PEER_TIMEOUT, EXIT_TIMEOUT, REPO, RUN_TIMEOUT, SCENE,
                         START_TIMEOUT, Run, RunTestCase, bag_series, bag_summary, descendants, free_port,
                         scene_overrides)

RAILSIM = os.path.join(REPO, "railsim")
COSIM_LAUNCH = os.path.join(REPO, "launch", "cosim.launch")
STATES_TOPIC = "/railsim/wheel_states_exchange"  # rail_ros/topic_transport.hpp, TopicTransportOptions
LOCKSTEP_SERVICE = "/railsim/lockstep"            # rail_ros/service_transport.hpp, ServiceTransportOptions
TRACK_STEP = 2.0e-5                               # s, solver.track_step of test/scenes/paper_demo_60m.yaml
FOREIGN_HASH = 0x0123456789ABCDEF                 # not the scene's hash (which the run prints)


def listening(pids):
    """[(process name, pid, local address, port)] of the TCP sockets the given processes listen on."""
    out = subprocess.run(["ss", "-ltnpH"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True,
                         timeout=30).stdout
    found = []
    for line in out.splitlines():
        cols = line.split()
        if len(cols) < 6:
            continue
        addr, port = cols[3].rsplit(":", 1)
        for name, pid in re.findall(r'\("([^"]+)",pid=(\d+)', line):
            if int(pid) in pids:
                found.append((name, int(pid), addr.strip("[]"), int(port)))
    return found


def process_alive(pid):
    """True while pid runs (a zombie, ended but not reaped, does not count)."""
    try:
        with open("/proc/%d/stat" % pid) as f:
            return f.read().rsplit(")", 1)[1].split()[0] not in ("Z", "X")
    except (OSError, IndexError):
        return False


def cmdline(pid):
    try:
        with open("/proc/%d/cmdline" % pid, "rb") as f:
            return [a.decode(errors="replace") for a in f.read().split(b"\0") if a]
    except OSError:
        return []


def loopback(addr):
    return addr.startswith("127.") or addr == "::1"


def launched_run_id(master_uri):
    """/railsim/run_id as cosim.launch set it ($(anon run)), or None while it is not set."""
    try:
        code, _, value = xmlrpc.client.ServerProxy(master_uri).getParam("/railsim_exposure_test", "/railsim/run_id")
    except OSError:
        return None
    return value if code == 1 else None


def shm_modes(run_id):
    """{name: permission bits} of the /dev/shm regions of a run id."""
    if not run_id:
        return {}
    modes = {}
    for p in glob.glob("/dev/shm/*_" + run_id + "_*"):
        try:
            modes[os.path.basename(p)] = stat.S_IMODE(os.stat(p).st_mode)
        except OSError:
            pass
    return modes


def wait_master(uri, timeout=60.0):
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            xmlrpc.client.ServerProxy(uri).getPid("/railsim_exposure_test")
            return True
        except OSError:
            time.sleep(0.2)
    return False


def railsim_env(port, ros_home):
    """./railsim's environment for a run: loopback_master() (ROS_IP=127.0.0.1, no ROS_HOSTNAME, its own
    master URI on 127.0.0.1)."""
    env = dict(os.environ)
    env["ROS_IP"] = "127.0.0.1"
    env.pop("ROS_HOSTNAME", None)
    env["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
    env["ROS_HOME"] = ros_home
    return env


def foreign_frame(step):
    """A well-formed wheel-states frame of the scene's 8 wheels for `step`, stamped step x track_step (so
    only its sender and its scene hash are wrong)."""
    m = WheelStates()
    m.header.frame_id = "world"
    m.header.stamp = rospy.Time.from_sec(step * TRACK_STEP)
    m.step = step
    m.scene_hash = FOREIGN_HASH
    for i in range(8):
        w = WheelState(wheel_id=i, wheelset=i // 2, side=i % 2, arc_length=25.0)
        w.orientation.w = 1.0
        m.wheels.append(w)
    return m


class Exposure(RunTestCase):
    WORK_PREFIX = "railsim_exposure_"
    _cache = {}

    # --- 5 and 6: a run started as ./railsim starts it ---------------------------------------------------
    def railsim_run(self):
        """cosim.launch under roslaunch -p PORT in ./railsim's environment (umask 022, the usual default),
        looked at while it runs: every listening socket of its processes and the modes of its /dev/shm
        regions; then left to finish (0.3 s simulated)."""
        if "railsim" in self._cache:
            return self._cache["railsim"]
        port = free_port()
        out_dir = os.path.join(self.work, "railsim_run")
        env = railsim_env(port, os.path.join(self.work, "ros_home"))
        name = "exposure_railsim"
        overrides = scene_overrides(name, "shm", 0.3, 10.0)
        # ./railsim's launch_scene: roslaunch --disable-title -p <port> launch/<plan>.launch scene:= output_dir:=
        umask = os.umask(0o022)  # inherited by the launch (set here: no preexec_fn in a threaded process)
        try:
            launch = subprocess.Popen(
                ["roslaunch", "--disable-title", "-p", str(port), COSIM_LAUNCH, "scene:=" + SCENE,
                 "output_dir:=" + out_dir, "overrides:=" + overrides],
                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env, start_new_session=True)
        finally:
            os.umask(umask)
        lines = []
        reader = threading.Thread(target=lambda: lines.extend(launch.stdout), daemon=True)
        reader.start()
        sockets, regions, run_id, pids = [], {}, None, set()
        try:
            # While it runs: both nodes up and the shm regions (named after the run id cosim.launch sets) open.
            deadline = time.monotonic() + START_TIMEOUT
            while time.monotonic() < deadline and launch.poll() is None:
                if run_id is None:
                    run_id = launched_run_id(env["ROS_MASTER_URI"])
                tree = descendants(launch.pid)
                names = {n for n, _, _, _ in listening(tree)}
                regions = shm_modes(run_id)
                if {"rosmaster", "track_node", "vehicle_node"} <= names and len(regions) == 2:
                    sockets, pids = listening(tree), tree
                    break
                time.sleep(0.1)
            code = launch.wait(timeout=RUN_TIMEOUT)
        finally:
            if launch.poll() is None:
                os.killpg(launch.pid, signal.SIGINT)
                try:
                    launch.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    os.killpg(launch.pid, signal.SIGKILL)
                    launch.wait()
            reader.join(10)
        bags = {p: stat.S_IMODE(os.stat(os.path.join(out_dir, p)).st_mode)
                for p in os.listdir(out_dir)} if os.path.isdir(out_dir) else {}
        result = dict(port=port, code=code, log="".join(lines), sockets=sockets, regions=regions, files=bags,
                      out_dir=out_dir, name=name, run_id=run_id, left=shm_modes(run_id), pids=pids)
        self._cache["railsim"] = result
        return result

    def test_5_railsim_keeps_its_master_on_loopback(self):
        # ./railsim itself: loopback_master() sets ROS_IP=127.0.0.1 and drops ROS_HOSTNAME, and launch_scene
        # has roslaunch start the master on that URI's port (what this test reproduces below).
        cli = os.path.join(os.path.dirname(RAILSIM), "scripts", "railsim_cli")
        with open(os.path.join(cli, "common.py")) as f:
            text = f.read()
        self.assertIn('env["ROS_IP"] = "127.0.0.1"', text)
        self.assertIn('env.pop("ROS_HOSTNAME", None)', text)
        self.assertIn('env["ROS_MASTER_URI"] = "http://127.0.0.1:%s" % port', text)
        with open(os.path.join(cli, "run.py")) as f:
            self.assertIn('"roslaunch", "--disable-title", "-p", env["ROS_MASTER_URI"].rsplit(":", 1)[1]', f.read())
        r = self.railsim_run()
        log = r["log"]
        self.assertTrue(r["sockets"], "the run's sockets were never seen" + log)
        master = [s for s in r["sockets"] if s[0] == "rosmaster"]
        self.assertEqual([(a, p) for _, _, a, p in master], [("127.0.0.1", r["port"])], r["sockets"])
        # roslaunch's own XML-RPC server (Python, rosgraph's bind address) follows ROS_IP as well.
        python_side = [s for s in r["sockets"] if s[0] in ("roslaunch", "rosmaster")]
        self.assertEqual(sorted({s[0] for s in python_side}), ["roslaunch", "rosmaster"], r["sockets"])
        self.assertEqual([s for s in python_side if not loopback(s[2])], [], r["sockets"])
        # (roslaunch exits 0 whatever its nodes do; both nodes' own lines say how they ended.)
        self.assertEqual(r["code"], EXIT_OK, log)
        self.assertIn("finished at t = 0.3000 s", log)
        self.assertRegex(log, r"finished after \d+ steps \(t = 0.3000 s\)")
        self.assertEqual([p for p in r["pids"] if process_alive(p)], [], "processes of the run left behind")

    def test_5_node_sockets_on_loopback(self):
        # roscpp's XML-RPC server listens on 0.0.0.0 whatever ROS_IP says (xmlrpcpp XmlRpcSocket::bind), so
        # ./railsim runs each launch in a network namespace with only loopback (scripts/railsim_isolate): the
        # nodes' ports are then reachable from that loopback alone. Where the system cannot isolate, the
        # run says so and this test is skipped with that reason.
        probe = subprocess.run([os.path.join(REPO, "scripts", "railsim_isolate"), "--probe"],
                               capture_output=True, text=True)
        if probe.returncode != 0:
            self.skipTest(probe.stderr.strip())
        port = free_port()
        out_dir = os.path.join(self.work, "isolated_run")
        env = dict(railsim_env(port, os.path.join(self.work, "ros_home_isolated")), RAILSIM_NO_BUILD="1",
                   RAILSIM_MASTER_PORT=str(port))
        sets = []
        for o in ("solver.end={time: 0.3}", "effects.track_model=rigid_fe", "effects.rail_deflection_output=false",
                  "solver.transport=topic", "output.bag=isolated.bag",
                  "output.topics=[wheel_states,contact_wrenches,wheelset_kinematics,clock]"):
            sets += ["--set", o]
        run = subprocess.Popen([RAILSIM, "run", SCENE, "--out", out_dir] + sets,
                               stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                               start_new_session=True)
        lines = []
        reader = threading.Thread(target=lambda: lines.extend(run.stdout), daemon=True)
        reader.start()
        host_ns = os.readlink("/proc/self/ns/net")
        seen = None
        try:
            deadline = time.monotonic() + START_TIMEOUT
            while time.monotonic() < deadline and run.poll() is None and seen is None:
                # Each command line read once: a process can end between two reads.
                names = {p: os.path.basename((cmdline(p) or [""])[0]) for p in descendants(run.pid)}
                nodes = {n: p for p, name in names.items() for n in ("track_node", "vehicle_node")
                         if name == n and process_alive(p)}
                if len(nodes) == 2:
                    ns = {n: os.readlink("/proc/%d/ns/net" % p) for n, p in nodes.items()}
                    inside = ["nsenter", "--net=/proc/%d/ns/net" % nodes["vehicle_node"]]
                    links = subprocess.run(inside + ["ip", "-o", "link", "show"], capture_output=True,
                                           text=True).stdout
                    socks = subprocess.run(inside + ["ss", "-ltnpH"], capture_output=True, text=True).stdout
                    if all(("pid=%d," % p) in socks for p in nodes.values()):
                        seen = (ns, links, socks)
                        break
                time.sleep(0.1)
            code = run.wait(timeout=RUN_TIMEOUT)
        finally:
            if run.poll() is None:
                os.killpg(run.pid, signal.SIGINT)
                run.wait(timeout=60)
            reader.join(10)
        log = "".join(lines)
        self.assertEqual(code, EXIT_OK, log[-3000:])
        self.assertIsNotNone(seen, "the nodes' sockets were never seen\n" + log[-3000:])
        ns, links, socks = seen
        self.assertEqual(len(set(ns.values())), 1, ns)
        self.assertNotEqual(ns["vehicle_node"], host_ns, "the run shares the host's network namespace")
        self.assertEqual([l.split(":")[1].strip() for l in links.splitlines()], ["lo"], links)

    def test_5_master_bind_address_follows_ros_ip(self):
        # The launch files cannot choose the master's address: rosgraph binds it to 127.0.0.1 when ROS_IP is
        # a 127/8 address or ROS_HOSTNAME is localhost, and to every interface otherwise. So a bare
        # `roslaunch launch/cosim.launch` in a shell without either exposes the master (README: export
        # ROS_IP=127.0.0.1 first, as ./railsim does).
        for setting, expected in ((("ROS_IP", "127.0.0.1"),), "127.0.0.1"), \
                                 ((("ROS_HOSTNAME", "localhost"),), "127.0.0.1"), \
                                 ((), "0.0.0.0"):
            port = free_port()
            env = dict(os.environ)
            env.pop("ROS_IP", None)
            env.pop("ROS_HOSTNAME", None)
            env.update(dict(setting))
            env["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % port
            env["ROS_HOME"] = os.path.join(self.work, "ros_home_bind")
            core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL,
                                    stderr=subprocess.STDOUT, env=env, start_new_session=True)
            try:
                self.assertTrue(wait_master(env["ROS_MASTER_URI"]), setting)
                master = [s for s in listening(descendants(core.pid)) if s[0] == "rosmaster"]
            finally:
                os.killpg(core.pid, signal.SIGINT)
                try:
                    core.wait(timeout=30)
                except subprocess.TimeoutExpired:
                    os.killpg(core.pid, signal.SIGKILL)
                    core.wait()
            self.assertEqual([(a, p) for _, _, a, p in master], [(expected, port)], setting)

    def test_6_shm_regions_are_private_to_the_user(self):
        r = self.railsim_run()
        self.assertEqual(len(r["regions"]), 2, "the run's regions were never seen" + r["log"])
        self.assertEqual(set(r["regions"].values()), {0o600}, r["regions"])
        self.assertEqual(r["left"], {}, "regions left after the run")

    def test_6_bags_are_private_to_the_user(self):
        r = self.railsim_run()
        bags = {p: m for p, m in r["files"].items() if p.endswith(".bag")}
        self.assertEqual(sorted(bags), sorted([r["name"] + ".bag", r["name"] + ".track.bag"]), r["files"])
        self.assertEqual({p: m & 0o077 for p, m in r["files"].items()}, {p: 0 for p in r["files"]}, r["files"])

    def test_6_bags_exist_and_are_readable(self):
        r = self.railsim_run()
        for bag in (r["name"] + ".bag", r["name"] + ".track.bag"):
            count, _ = bag_summary(os.path.join(r["out_dir"], bag))
            self.assertGreater(count, 0, bag)

    # --- 7. a lockstep frame from a node that did no handshake, with another scene hash -------------------
    def baseline(self, transport):
        key = ("baseline", transport)
        if key not in self._cache:
            run = Run(self.work, "exp_base_" + transport, transport=transport, end=0.1, exchange_timeout=10.0)
            try:
                codes = (run.vehicle.wait(RUN_TIMEOUT)[0], run.track.wait(EXIT_TIMEOUT)[0])
            finally:
                run.close()
            self.assertEqual(codes, (EXIT_OK, EXIT_OK), run.log())
            self._cache[key] = bag_series(run.bag)
        return self._cache[key]

    def injected(self, transport):
        """A run over `transport` into which this node (no handshake) sends foreign frames mid-run."""
        key = ("injected", transport)
        if key in self._cache:
            return self._cache[key]
        run = Run(self.work, "exp_inject_" + transport, transport=transport, end=0.1, exchange_timeout=10.0)
        answers = []
        try:
            type(self).clock = 0.0
            self.assertTrue(run.wait_stepping(lambda: type(self).clock, min_clock=0.01), run.log())
            if transport == "topic":
                pub = rospy.Publisher(STATES_TOPIC, WheelStates, queue_size=10)
                deadline = time.monotonic() + 30.0
                while pub.get_num_connections() == 0 and time.monotonic() < deadline:
                    time.sleep(0.01)
                for k in range(5):
                    step = int(round(type(self).clock / TRACK_STEP)) + 1
                    pub.publish(foreign_frame(step))
                    time.sleep(0.05)
                pub.unregister()
            else:
                proxy = rospy.ServiceProxy(LOCKSTEP_SERVICE, Lockstep)

                def call():
                    try:
                        res = proxy(LockstepRequest(states=foreign_frame(int(round(type(self).clock / TRACK_STEP)) + 1)))
                        answers.append((res.ok, res.error))
                    except (rospy.ServiceException, OSError) as e:
                        answers.append((False, "call failed: %s" % e))

                caller = threading.Thread(target=call, daemon=True)
                caller.start()
                caller.join(30.0)
            codes = (run.vehicle.wait(RUN_TIMEOUT)[0], run.track.wait(EXIT_TIMEOUT)[0])
        finally:
            run.close()
        self._cache[key] = (run, codes, answers)
        return self._cache[key]

    def check_refused(self, transport):
        # What holds today and after the change below: the foreign frame is never used. Either the track
        # refuses it and stops the run (exit 3, the frame's step or hash named), or it ignores it and the run
        # ends exactly as the undisturbed one.
        run, codes, answers = self.injected(transport)
        log = run.log()
        me = rospy.get_name()
        refusal = run.track.lines(r"refused")
        if codes[1] == EXIT_OK:
            self.assertEqual(codes[0], EXIT_OK, log)
            self.assertEqual(bag_series(run.bag), self.baseline(transport))
            self.assertTrue(run.track.lines(re.escape(me)), "the track does not report the foreign frame" + log)
        else:
            self.assertEqual(codes[1], EXIT_PEER_REFUSED, log)
            self.assertTrue(refusal, log)
            self.assertRegex(refusal[0], r"scene hash 0123456789abcdef received|step \d+ received")
            self.assertIn(codes[0], (EXIT_PEER_TIMEOUT, EXIT_PEER_REFUSED), log)
            count, _ = bag_summary(run.bag)
            self.assertGreater(count, 0)
        self.assertEqual(run.shm_regions(), [])
        self.assertEqual(run.processes(), [])

    def test_7_foreign_topic_frame_is_refused(self):
        self.check_refused("topic")

    def test_7_foreign_service_call_is_refused(self):
        self.check_refused("service")

    def check_ignored(self, transport):
        run, codes, answers = self.injected(transport)
        log = run.log()
        self.assertEqual(codes, (EXIT_OK, EXIT_OK), log)
        self.assertEqual(bag_series(run.bag), self.baseline(transport))
        self.assertTrue(run.track.lines(re.escape(rospy.get_name())), log)
        if transport == "service":
            self.assertTrue(answers and not answers[0][0] and run.vehicle_name in answers[0][1], answers)

    def test_7_foreign_topic_frame_leaves_the_run_unchanged(self):
        self.check_ignored("topic")

    def test_7_foreign_service_call_leaves_the_run_unchanged(self):
        self.check_ignored("service")


if __name__ == "__main__":
    rospy.init_node("test_exposure")
    rostest.rosrun("railsim_tests", "exposure", Exposure)
