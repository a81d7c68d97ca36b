#!/usr/bin/env python3
"""Faults at node level (doc/faults.md): a peer slower than the exchange timeout and one just inside it, the
shared-memory regions a crashed run leaves behind, SIGINT and SIGTERM to either node, and the ROS master
dying mid-run. For each: the message names what failed and where, the exit code is the documented one
(rail_core/exit_codes.hpp, README "Exit codes"), the bags are readable, nothing of the run is left in
/dev/shm and no process of it is left running.

The scene is test/scenes/paper_demo_60m.yaml as the rigid FE co-simulation (no rail deflections, which need
the FE integration) over the shm transport, with the overrides the launch files would pass. The test starts
the two nodes itself (rosrun, one process each, so that it can signal either one) under a scene namespace
of their own on the rostest master; the master case starts a roscore of its own. The Run class is shared
with test_exposure.py."""
import glob
import os
import re
import shutil
import signal
import socket
import stat
import subprocess
import tempfile
import threading
import time
import unittest
import xmlrpc.client

import rosbag
import rospy
import rostest
from rosgraph_msgs.msg import Clock

TEST_DIR = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))  # the railsim_tests package (test/)
REPO = os.path.normpath(os.path.join(TEST_DIR, ".."))
SCENE = os.path.join(TEST_DIR, "scenes", "paper_demo_60m.yaml")

# rail_core/exit_codes.hpp
EXIT_OK, EXIT_PEER_REFUSED, EXIT_PEER_TIMEOUT, EXIT_INTERRUPTED = 0, 3, 4, 5

RATE = 500.0            # Hz, output.rate: one recorded instant every 2 ms simulated
EXCHANGE_TIMEOUT = 5.0  # s, solver.exchange_timeout of the runs that are not about it
# Simulated seconds of a run that a fault ends early: long enough (30-60 s of wall time on 2 shared cores)
# that the fault lands mid-run on any machine; short enough that the vehicle stays on the scene's 100 m of
# track (leading wheelset from s = 25 m at 30.6 m/s: 86 m at 2 s). The run never gets that far.
LONG_END = 2.0
# Wall-time allowances. Generous (2 shared cores), never unbounded.
START_TIMEOUT = 180.0   # s: both nodes up, handshake done, vehicle settled, stepping
EXIT_TIMEOUT = 30.0     # s: a node's exit after what should end it (its own shutdown, bag closing)
RUN_TIMEOUT = 240.0     # s: a short run from start to finish


def scene_overrides(name, transport, end, exchange_timeout, rate=RATE):
    """The overrides (scene.launch's scene_overrides) of the test runs: rigid FE co-simulation of the
    shortened paper scene over `transport` to t = end [s]; the bag <name>.bag; contact points recorded by the
    track node (<name>.track.bag)."""
    return " ".join([
        "name=" + name, "effects.track_model=rigid_fe", "effects.rail_deflection_output=false",
        "effects.contact_point_output=true", "solver.transport=" + transport,
        "solver.exchange_timeout=%g" % exchange_timeout, "solver.handshake_timeout=120",
        "solver.end={time: %g}" % end, "output.bag=%s.bag" % name, "output.rate=%g" % rate,
        "output.topics=[wheel_states,contact_wrenches,contact_points,wheelset_kinematics,clock]"])


class Node(object):
    """One node process started with rosrun (which execs it: the pid is the node's), output collected."""

    def __init__(self, args, env):
        self.proc = subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, env=env,
                                     start_new_session=True)
        self.pid = self.proc.pid
        self._lines = []
        self._cond = threading.Condition()
        self._reader = threading.Thread(target=self._read, daemon=True)
        self._reader.start()

    def _read(self):
        for line in self.proc.stdout:
            with self._cond:
                self._lines.append(line)
                self._cond.notify_all()

    def text(self):
        with self._cond:
            return "".join(self._lines)

    def wait_for_line(self, pattern, timeout):
        """The first output line matching the regular expression, or None when the node ended or the
        timeout passed without one."""
        rx = re.compile(pattern)
        deadline = time.monotonic() + timeout
        seen = 0
        with self._cond:
            while True:
                for line in self._lines[seen:]:
                    if rx.search(line):
                        return line
                seen = len(self._lines)
                left = deadline - time.monotonic()
                if left <= 0 or (self.proc.poll() is not None and not self._reader.is_alive()):
                    return None
                self._cond.wait(min(left, 0.2))

    def lines(self, pattern):
        rx = re.compile(pattern)
        return [l for l in self.text().splitlines() if rx.search(l)]

    def wait(self, timeout):
        """(exit code, wall seconds waited); the code is None when it did not exit within the timeout."""
        t0 = time.monotonic()
        try:
            code = self.proc.wait(timeout=timeout)
        except subprocess.TimeoutExpired:
            code = None
        if code is not None:
            self._reader.join(10)
        return code, time.monotonic() - t0

    def signal(self, sig):
        if self.proc.poll() is None:
            os.kill(self.pid, sig)

    def kill(self):
        if self.proc.poll() is None:
            try:
                os.kill(self.pid, signal.SIGCONT)  # a stopped node would keep a SIGTERM pending
                os.kill(self.pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            self.proc.wait()
        self._reader.join(10)


def set_param(master_uri, key, value):
    code, msg, _ = xmlrpc.client.ServerProxy(master_uri).setParam("/railsim_faults_test", key, value)
    if code != 1:
        raise RuntimeError("setParam %s on %s: %s" % (key, master_uri, msg))


def node_env(master_uri=None):
    """The nodes' environment: this one, their master, and stdout line-buffered (rosconsole) so that their
    progress is seen as it happens, not when they exit."""
    env = dict(os.environ)
    env["ROSCONSOLE_STDOUT_LINE_BUFFERED"] = "1"
    if master_uri:
        env["ROS_MASTER_URI"] = master_uri
    return env


class Run(object):
    """Both nodes of one co-simulation under the scene namespace /<label>: node names track_<label> and
    vehicle_<label>, shm run id <run_id>, bags under <out_dir>."""

    def __init__(self, work, label, name=None, transport="shm", end=LONG_END, exchange_timeout=EXCHANGE_TIMEOUT,
                 master_uri=None, run_id=None, out_dir=None, start_vehicle=True):
        self.label = label
        self.name = name or label
        self.master_uri = master_uri or os.environ["ROS_MASTER_URI"]
        self.env = node_env(self.master_uri)
        self.run_id = run_id or "faults%d%s" % (os.getpid(), label)
        self.out_dir = out_dir or os.path.join(work, label)
        os.makedirs(self.out_dir, exist_ok=True)
        self.ns = "/" + label
        with open(SCENE) as f:
            set_param(self.master_uri, self.ns + "/scene_yaml", f.read())
        set_param(self.master_uri, self.ns + "/scene_file", SCENE)
        set_param(self.master_uri, self.ns + "/scene_overrides",
                  scene_overrides(self.name, transport, end, exchange_timeout))
        self.track_name = "/track_" + label
        self.vehicle_name = "/vehicle_" + label
        self.common = ["_scene_ns:=" + self.ns, "_run_id:=" + self.run_id, "_output_dir:=" + self.out_dir]
        self.track = Node(["rosrun", "rail_track_node", "track_node", "__name:=track_" + label] + self.common,
                          self.env)
        self.vehicle = None
        if start_vehicle:
            self.start_vehicle()

    def start_vehicle(self):
        self.vehicle = Node(["rosrun", "rail_vehicle_node", "vehicle_node", "__name:=vehicle_" + self.label]
                            + self.common, self.env)

    @property
    def bag(self):
        return os.path.join(self.out_dir, self.name + ".bag")

    @property
    def track_bag(self):
        return os.path.join(self.out_dir, self.name + ".track.bag")

    def node(self, which):
        return self.track if which == "track" else self.vehicle

    def wait_stepping(self, clock_source=None, min_clock=0.02, timeout=START_TIMEOUT):
        """Returns once the two nodes step in lockstep: the vehicle opened its bag (just before its first
        exchange), then the simulated clock passed min_clock [s] (clock_source: a callable giving the
        latest /clock), or 1.5 s of wall time passed when there is none. False if that never came."""
        if self.vehicle.wait_for_line(r"recording \[", timeout) is None:
            return False
        deadline = time.monotonic() + timeout
        if clock_source is None:
            time.sleep(1.5)
        else:
            while clock_source() < min_clock and time.monotonic() < deadline and self.vehicle.proc.poll() is None:
                time.sleep(0.02)
        return self.vehicle.proc.poll() is None and self.track.proc.poll() is None

    def close(self):
        for n in (self.vehicle, self.track):
            if n is not None:
                n.kill()

    def log(self):
        return "\n----- vehicle %s -----\n%s\n----- track %s -----\n%s" % (
            self.vehicle_name, self.vehicle.text() if self.vehicle else "", self.track_name, self.track.text())

    def shm_regions(self):
        return sorted(glob.glob("/dev/shm/*" + self.run_id + "*"))

    def processes(self):
        """Processes still running with this run's id on their command line."""
        return live_processes(self.run_id)


def live_processes(token):
    """(pid, command line) of the live processes (not zombies) whose command line contains token."""
    found = []
    for d in os.listdir("/proc"):
        if not d.isdigit() or int(d) == os.getpid():
            continue
        try:
            with open("/proc/%s/cmdline" % d, "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode("utf-8", "replace")
            with open("/proc/%s/stat" % d) as f:
                state = f.read().rsplit(")", 1)[1].split()[0]
        except (OSError, IndexError):
            continue
        if token in cmd and state not in ("Z", "X"):
            found.append((int(d), cmd.strip()))
    return found


def cmdline(pid):
    try:
        with open("/proc/%d/cmdline" % pid, "rb") as f:
            return f.read().replace(b"\0", b" ").decode("utf-8", "replace")
    except OSError:
        return ""


def descendants(pid):
    """pid and every process descended from it (parent pids from /proc/*/stat)."""
    parent = {}
    for d in os.listdir("/proc"):
        if d.isdigit():
            try:
                with open("/proc/%s/stat" % d) as f:
                    parent[int(d)] = int(f.read().rsplit(")", 1)[1].split()[1])
            except (OSError, IndexError, ValueError):
                pass
    tree, grew = {pid}, True
    while grew:
        grew = False
        for p, pp in parent.items():
            if pp in tree and p not in tree:
                tree.add(p)
                grew = True
    return tree


def bag_series(path, topic="/wheelset_kinematics"):
    """Every recorded instant of the wheelsets' track-relative state: {stamp ns: tuple per wheelset}."""
    out = {}
    with rosbag.Bag(path) as bag:
        for _, msg, t in bag.read_messages(topics=[topic]):
            out[t.to_nsec()] = tuple((w.wheelset, w.arc_length, w.lateral_displacement, w.vertical_displacement,
                                      w.angle_of_attack, w.roll, w.spin_speed) for w in msg.wheelsets)
    return out


def bag_summary(path):
    """(message count, last stamp [s]) of a bag; raises when it is not a closed, indexed bag."""
    with rosbag.Bag(path) as bag:
        return bag.get_message_count(), bag.get_end_time()


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


# "stopped at t = 0.0204 s" (vehicle), "stopped after 1022 steps (t = 0.0204 s)" (track)
STOP_TIME = re.compile(r"stopped (?:at |after \d+ steps \()t = ([0-9.]+) s")


class RunTestCase(unittest.TestCase):
    """Shared by the fault and exposure tests: a scratch directory per class and the latest /clock of the
    runs. Subclasses set WORK_PREFIX and their own _cache."""
    clock = 0.0
    WORK_PREFIX = "railsim_"

    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix=cls.WORK_PREFIX)
        rospy.Subscriber("/clock", Clock, cls._on_clock)

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.work, ignore_errors=True)

    @classmethod
    def _on_clock(cls, msg):
        cls.clock = msg.clock.to_sec()


class Faults(RunTestCase):
    WORK_PREFIX = "railsim_node_faults_"
    _cache = {}

    def latest_clock(self):
        return type(self).clock

    def start_mid_run(self, run):
        """Waits until `run` steps mid-run (fails the test if it never does)."""
        type(self).clock = 0.0
        ok = run.wait_stepping(self.latest_clock if run.master_uri == os.environ["ROS_MASTER_URI"] else None)
        self.assertTrue(ok, "the run never got to stepping" + run.log())

    def assert_clean(self, run):
        """Nothing of the run left in /dev/shm, no process of it left running."""
        self.assertEqual(run.shm_regions(), [], "shared-memory regions left behind" + run.log())
        self.assertEqual(run.processes(), [], "processes left behind")

    def assert_bag_readable(self, path, log, at_least_until=None):
        """The bag is closed (indexed) and holds messages; its last stamp is >= at_least_until [s]."""
        self.assertTrue(os.path.isfile(path), "no bag %s%s" % (path, log))
        try:
            count, end = bag_summary(path)
        except Exception as e:  # rosbag's own exceptions: unindexed, truncated
            self.fail("bag %s is not readable: %s%s" % (path, e, log))
        self.assertGreater(count, 0, path)
        if at_least_until is not None:
            self.assertGreaterEqual(end, at_least_until, path)
        return count, end

    def run_to_end(self, label, **kw):
        """A run that is left alone: both nodes' exit codes, the run."""
        run = Run(self.work, label, **kw)
        try:
            code, _ = run.vehicle.wait(RUN_TIMEOUT)
            track_code, _ = run.track.wait(EXIT_TIMEOUT)
        finally:
            run.close()
        self.assertEqual((code, track_code), (EXIT_OK, EXIT_OK), run.log())
        return run

    # --- 1. a peer slower than the exchange timeout ------------------------------------------------------
    EXCHANGE_TIMEOUT_1 = 2.0  # s: the timeout these cases set (solver.exchange_timeout)

    def stopped_past_timeout(self):
        """The track node stopped (SIGSTOP) mid-run for longer than the exchange timeout; continued
        (SIGCONT) once the vehicle has given up. Run once, shared by the tests that look at it."""
        if "past" in self._cache:
            return self._cache["past"]
        run = Run(self.work, "stop_past", exchange_timeout=self.EXCHANGE_TIMEOUT_1)
        try:
            self.start_mid_run(run)
            run.track.signal(signal.SIGSTOP)
            t0 = time.monotonic()
            code, _ = run.vehicle.wait(self.EXCHANGE_TIMEOUT_1 + EXIT_TIMEOUT)
            took = time.monotonic() - t0
            run.track.signal(signal.SIGCONT)
            track_code, _ = run.track.wait(EXIT_TIMEOUT)
        finally:
            run.close()
        self._cache["past"] = (run, code, took, track_code)
        return self._cache["past"]

    def test_1_peer_stopped_past_the_exchange_timeout(self):
        run, code, took, track_code = self.stopped_past_timeout()
        log = run.log()
        # The vehicle gives up after the exchange timeout, not before (its wait began at most one exchange,
        # well under 0.1 s, before the stop) and not much after (a slice of 50 ms + its own shutdown).
        self.assertEqual(code, EXIT_PEER_TIMEOUT, log)
        self.assertGreaterEqual(took, self.EXCHANGE_TIMEOUT_1 - 0.1, log)
        self.assertLess(took, self.EXCHANGE_TIMEOUT_1 + 15.0, log)
        fatal = run.vehicle.lines(r"exchange with the track node failed")
        self.assertEqual(len(fatal), 1, log)
        self.assertRegex(fatal[0], r"at step \d+ \(t = [0-9.]+ s\)")
        self.assertIn("did not answer within 2 s (solver.exchange_timeout)", fatal[0])
        # Its bag is closed and holds the run up to the stop (at least to the 20 ms it was stopped after).
        self.assert_bag_readable(run.bag, log, at_least_until=0.02)
        # The track, continued after the vehicle left, sees the vehicle's end and reports it.
        self.assertEqual(track_code, EXIT_PEER_TIMEOUT, log)
        self.assertTrue(run.track.lines(r"vehicle node %s went away after step \d+|sending the wrenches of step \d+ "
                                        r"to the vehicle node %s failed" % (run.vehicle_name, run.vehicle_name)), log)
        self.assert_bag_readable(run.track_bag, log)
        self.assert_clean(run)

    def test_1_timeout_message_names_the_peer(self):
        run, code, _, _ = self.stopped_past_timeout()
        fatal = run.vehicle.lines(r"exchange with the track node")
        self.assertTrue(fatal and run.track_name in fatal[0], run.log())

    def test_1_peer_stopped_within_the_exchange_timeout(self):
        # Stopped for half the timeout: the vehicle waits it out and the run ends as an undisturbed one. Both
        # nodes are deterministic and the exchange carries the same doubles whenever it happens, so the
        # recorded trajectories must be identical, not just close.
        end = 0.3
        base = self.run_to_end("stop_base", end=end, exchange_timeout=self.EXCHANGE_TIMEOUT_1)
        run = Run(self.work, "stop_within", end=end, exchange_timeout=self.EXCHANGE_TIMEOUT_1)
        try:
            self.start_mid_run(run)
            run.track.signal(signal.SIGSTOP)
            time.sleep(0.5 * self.EXCHANGE_TIMEOUT_1)
            run.track.signal(signal.SIGCONT)
            code, _ = run.vehicle.wait(RUN_TIMEOUT)
            track_code, _ = run.track.wait(EXIT_TIMEOUT)
        finally:
            run.close()
        log = run.log()
        self.assertEqual((code, track_code), (EXIT_OK, EXIT_OK), log)
        self.assertIn("finished at t = 0.3000 s", run.vehicle.text())
        got, want = bag_series(run.bag), bag_series(base.bag)
        self.assertEqual(len(want), int(round(end * RATE)) + 1)
        self.assertEqual(got, want)
        self.assert_clean(run)
        self.assert_clean(base)

    # --- 2. stale shared-memory regions of a crashed run -----------------------------------------------
    def stale_regions(self):
        if "stale" in self._cache:
            return self._cache["stale"]
        # Same scene (name, end, every override) and run id in both runs: the same region names.
        run_id = "faults%dstale" % os.getpid()
        crashed = Run(self.work, "stale", end=0.3, run_id=run_id, out_dir=os.path.join(self.work, "stale_crashed"))
        try:
            self.start_mid_run(crashed)
            # Both frozen first, so that neither sees the other die and cleans up, then killed (no goodbye).
            crashed.vehicle.signal(signal.SIGSTOP)
            crashed.track.signal(signal.SIGSTOP)
            crashed.vehicle.signal(signal.SIGKILL)
            crashed.track.signal(signal.SIGKILL)
            crashed.vehicle.wait(EXIT_TIMEOUT)
            crashed.track.wait(EXIT_TIMEOUT)
            left = {p: stat.S_IMODE(os.stat(p).st_mode) for p in crashed.shm_regions()}
        finally:
            crashed.close()
        run = Run(self.work, "stale", end=0.3, run_id=run_id, out_dir=os.path.join(self.work, "stale_next"))
        try:
            code, _ = run.vehicle.wait(RUN_TIMEOUT)
            track_code, _ = run.track.wait(EXIT_TIMEOUT)
        finally:
            run.close()
        self._cache["stale"] = (crashed, left, run, code, track_code)
        return self._cache["stale"]

    def test_2_stale_shm_regions_are_replaced(self):
        crashed, left, run, code, track_code = self.stale_regions()
        log = crashed.log() + run.log()
        # The crash left both regions (vehicle -> track and track -> vehicle), private to the user.
        self.assertEqual(sorted(os.path.basename(p)[-3:] for p in left), ["t2v", "v2t"], log)
        self.assertEqual(set(left.values()), {0o600}, left)
        # The next run of the same scene and run id finds them, takes them for stale (their creators are
        # dead) and replaces them: it runs to the end as any run does.
        self.assertEqual((code, track_code), (EXIT_OK, EXIT_OK), log)
        self.assertIn("finished at t = 0.3000 s", run.vehicle.text(), log)
        self.assertNotIn("is in use by", log)
        self.assert_bag_readable(run.bag, log, at_least_until=0.3 - 1e-9)
        self.assert_clean(run)

    def test_2_replaced_region_is_reported(self):
        crashed, left, run, _, _ = self.stale_regions()
        replaced = run.vehicle.lines(r"stale") + run.track.lines(r"stale")
        for region in left:
            self.assertTrue(any(os.path.basename(region) in l for l in replaced), run.log())

    # --- 3. SIGINT and SIGTERM to either node --------------------------------------------------------
    def signalled(self, victim, sig):
        key = (victim, sig)
        if key in self._cache:
            return self._cache[key]
        label = "%s_%s" % (signal.Signals(sig).name.lower(), victim)
        run = Run(self.work, label)
        try:
            self.start_mid_run(run)
            target, survivor = run.node(victim), run.node("vehicle" if victim == "track" else "track")
            target.signal(sig)
            code, _ = target.wait(EXIT_TIMEOUT)
            survivor_code, _ = survivor.wait(EXCHANGE_TIMEOUT + EXIT_TIMEOUT)
        finally:
            run.close()
        self._cache[key] = (run, code, survivor_code)
        return self._cache[key]

    def check_signalled(self, victim, sig):
        run, code, survivor_code = self.signalled(victim, sig)
        log = run.log()
        target = run.node(victim)
        other = "vehicle" if victim == "track" else "track"
        # The signalled node stops at the next step, says when, closes its bag and exits 5.
        self.assertEqual(code, EXIT_INTERRUPTED, log)
        stops = [m.group(1) for m in map(STOP_TIME.search, target.text().splitlines()) if m]
        self.assertTrue(stops, "no 'stopped at t = ...' line" + log)
        t_stop = float(stops[0])
        self.assertGreater(t_stop, 0.0, log)
        bag = run.bag if victim == "vehicle" else run.track_bag
        _, end = self.assert_bag_readable(bag, log)
        # Messages up to the stop: the last recorded instant is the last output instant (every 2 ms) before
        # it. Stamps are the simulated times (the printed stop time is rounded to 0.1 ms).
        self.assertLessEqual(end, t_stop + 1e-4, bag)
        self.assertGreaterEqual(end, t_stop - 1.0 / RATE - 1e-4, bag)
        # Why it stopped: a signal seen between two steps, or one that ended the wait for the peer's frame.
        why = (r"stopped at t = [0-9.]+ s \((SIGINT|SIGTERM|ROS shutdown)\); closing the bag" if victim == "vehicle"
               else r"stopped at t = [0-9.]+ s\b") + r"|failed at step \d+.*: interrupted"
        self.assertTrue(target.lines(why), log)
        # The peer reports the other side's going away, naming it and the step, and exits 4 (the peer stopped
        # answering); its own bag is closed too.
        self.assertEqual(survivor_code, EXIT_PEER_TIMEOUT, log)
        survivor = run.node(other)
        if other == "track":
            self.assertTrue(survivor.lines(r"the vehicle node %s went away after step \d+" % run.vehicle_name), log)
        else:
            self.assertTrue(survivor.lines(r"exchange with the track node failed at step \d+ .*the track closed the "
                                           r"connection"), log)
        self.assert_bag_readable(run.track_bag if victim == "vehicle" else run.bag, log)
        self.assert_clean(run)

    def test_3_sigint_to_vehicle(self):
        self.check_signalled("vehicle", signal.SIGINT)

    def test_3_sigterm_to_vehicle(self):
        self.check_signalled("vehicle", signal.SIGTERM)

    def test_3_sigint_to_track(self):
        self.check_signalled("track", signal.SIGINT)

    def test_3_sigterm_to_track(self):
        self.check_signalled("track", signal.SIGTERM)

    def test_3_stop_message_names_the_signal(self):
        for victim in ("vehicle", "track"):
            for sig in (signal.SIGINT, signal.SIGTERM):
                run, _, _ = self.signalled(victim, sig)
                self.assertTrue(run.node(victim).lines(r"stopped at t = .*%s" % signal.Signals(sig).name), run.log())

    # --- 4. the ROS master dying mid-run -------------------------------------------------------------
    def master_died(self):
        if "master" in self._cache:
            return self._cache["master"]
        port = free_port()
        uri = "http://127.0.0.1:%d" % port
        env = node_env(uri)
        env["ROS_IP"] = "127.0.0.1"
        env.pop("ROS_HOSTNAME", None)
        env["ROS_HOME"] = os.path.join(self.work, "master_ros_home")
        core = subprocess.Popen(["roscore", "-p", str(port)], stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT,
                                env=env, start_new_session=True)
        run = None
        try:
            deadline = time.monotonic() + 60.0
            while time.monotonic() < deadline:
                try:
                    xmlrpc.client.ServerProxy(uri).getPid("/railsim_faults_test")
                    break
                except OSError:
                    time.sleep(0.2)
            run = Run(self.work, "master_dies", end=1.0, master_uri=uri)
            self.start_mid_run(run)
            # rosmaster first (the master dying, no goodbye), then roscore's roslaunch and rosout.
            tree = descendants(core.pid)
            for pid in sorted(tree, key=lambda p: 0 if "rosmaster" in cmdline(p) else 1):
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            core.wait()
            t_kill = time.monotonic()
            code, _ = run.vehicle.wait(RUN_TIMEOUT)
            track_code, _ = run.track.wait(EXIT_TIMEOUT)
            took = time.monotonic() - t_kill
        finally:
            for pid in descendants(core.pid) if core.poll() is None else ():
                try:
                    os.kill(pid, signal.SIGKILL)
                except ProcessLookupError:
                    pass
            core.wait()
            if run is not None:
                run.close()
        self._cache["master"] = (run, code, track_code, took, port)
        return self._cache["master"]

    def test_4_master_dies_mid_run(self):
        # Both nodes end (each on the lost master, or on its peer going away after the peer noticed it
        # first), close their bags and leave no process or region behind.
        run, code, track_code, took, port = self.master_died()
        log = run.log()
        self.assertIn(code, (EXIT_OK, EXIT_INTERRUPTED, EXIT_PEER_TIMEOUT), log)
        self.assertIn(track_code, (EXIT_OK, EXIT_INTERRUPTED, EXIT_PEER_TIMEOUT), log)
        self.assert_bag_readable(run.bag, log)
        self.assert_bag_readable(run.track_bag, log)
        self.assert_clean(run)
        self.assertEqual(live_processes("-p %d" % port), [], "roscore processes left behind")

    def test_4_master_loss_stops_both_nodes_with_exit_5(self):
        run, code, track_code, took, port = self.master_died()
        log = run.log()
        uri = re.escape("http://127.0.0.1:%d" % port)
        # Whichever node notices the lost master first exits 5 naming it; the other may instead see that node
        # go (exit 4) before its own master check: both orders happen, depending on the machine's load.
        self.assertIn(EXIT_INTERRUPTED, (code, track_code), log)
        self.assertIn(code, (EXIT_INTERRUPTED, EXIT_PEER_TIMEOUT), log)
        self.assertIn(track_code, (EXIT_INTERRUPTED, EXIT_PEER_TIMEOUT), log)
        self.assertLess(took, 15.0, log)
        # The node that exited 5 says that the master (its URI) went away and when (the simulated time).
        if code == EXIT_INTERRUPTED:
            self.assertTrue(run.vehicle.lines(r"master %s.*t = [0-9.]+ s" % uri), log)
        if track_code == EXIT_INTERRUPTED:
            self.assertTrue(run.track.lines(r"master %s|vehicle node %s went away" % (uri, run.vehicle_name)), log)
        self.assert_bag_readable(run.bag, log)
        self.assert_clean(run)


if __name__ == "__main__":
    rospy.init_node("test_faults")
    rostest.rosrun("railsim_tests", "faults", Faults)
