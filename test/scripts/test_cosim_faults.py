#!/usr/bin/env python3
"""The two co-simulation nodes over each transport (shm, service, topic): the same trajectories from each;
and each node killed mid-run (SIGKILL, no goodbye): the other one says which peer went away and at which
step, exits with the documented code within its exchange timeout, and leaves a readable bag and nothing in
/dev/shm. The scene is test/scenes/vehicle_rigid_short.yaml run with effects.track_model rigid_fe through the
scene overrides the launch files use."""
import glob
import os
import signal
import subprocess
import tempfile
import threading
import time
import unittest

import rosbag
import rospy
import rostest
from rosgraph_msgs.msg import Clock

TEST_DIR = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))  # the railsim_tests package
SCENE = os.path.join(TEST_DIR, "scenes", "vehicle_rigid_short.yaml")
TRACK_DATA = os.path.normpath(os.path.join(TEST_DIR, "..", "config", "track", "paper_track.yaml"))
EXCHANGE_TIMEOUT = 3.0  # s: a dead peer must be reported within this (plus start-up slack below)
EXIT_PEER_TIMEOUT = 4   # rail_core/exit_codes.hpp: the peer never answered or stopped answering
EXIT_CODES_OF_A_LOST_PEER = (3, 4)  # 3 (refused) also names a peer whose connection was dropped


class Run(object):
    """Both nodes of one co-simulation, started with rosrun under their own scene namespace."""

    def __init__(self, work, name, transport, end, rate=500.0):
        self.work, self.name = work, name
        ns = "/" + name
        with open(SCENE) as f:
            rospy.set_param(ns + "/scene_yaml", f.read())
        rospy.set_param(ns + "/scene_file", SCENE)
        rospy.set_param(ns + "/scene_overrides", " ".join([
            "name=" + name, "effects.track_model=rigid_fe", "track.data=" + TRACK_DATA,
            "solver.transport=" + transport, "solver.exchange_timeout=%g" % EXCHANGE_TIMEOUT,
            "solver.handshake_timeout=120", "solver.end={time: %g}" % end, "output.bag=%s.bag" % name,
            "output.rate=%g" % rate, "effects.contact_point_output=true",
            "output.topics=[wheel_states,contact_wrenches,contact_points,wheelset_kinematics,clock]"]))
        self.run_id = "faults%d%s" % (os.getpid(), name)
        common = ["_scene_ns:=" + ns, "_run_id:=" + self.run_id, "_output_dir:=" + work]
        self.track = subprocess.Popen(["rosrun", "rail_track_node", "track_node", "__name:=track_" + name] + common,
                                      stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.vehicle = subprocess.Popen(["rosrun", "rail_vehicle_node", "vehicle_node", "__name:=vehicle_" + name]
                                        + common, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        self.out = {}
        self.readers = [threading.Thread(target=self._read, args=(k, p))
                        for k, p in (("track", self.track), ("vehicle", self.vehicle))]
        for r in self.readers:
            r.start()

    def _read(self, key, proc):
        self.out[key] = proc.stdout.read()

    def wait(self, proc, timeout):
        """Exit code and the wall time it took, or None after killing it."""
        t0 = time.monotonic()
        try:
            return proc.wait(timeout=timeout), time.monotonic() - t0
        except subprocess.TimeoutExpired:
            return None, time.monotonic() - t0

    def close(self):
        for p in (self.vehicle, self.track):
            if p.poll() is None:
                p.kill()
                p.wait()
        for r in self.readers:
            r.join(10)

    def log(self):
        return "\n----- vehicle -----\n%s\n----- track -----\n%s" % (self.out.get("vehicle", ""),
                                                                     self.out.get("track", ""))


def leading_wheelset(bag_path):
    out = {}
    with rosbag.Bag(bag_path) as bag:
        for _, msg, t in bag.read_messages(topics=["/wheelset_kinematics"]):
            w = msg.wheelsets[0]
            out[round(t.to_sec() * 500.0)] = (w.lateral_displacement, w.vertical_displacement, w.angle_of_attack)
    return out


class CosimFaults(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="railsim_faults_")
        cls.clock = 0.0
        rospy.Subscriber("/clock", Clock, cls._on_clock)

    @classmethod
    def _on_clock(cls, msg):
        cls.clock = msg.clock.to_sec()

    def test_the_three_transports_give_the_same_trajectories(self):
        # The frames carry the same doubles over every transport (shm copies them, ROS serialises float64
        # exactly) and both nodes are deterministic, so the trajectories must be identical, not just close.
        runs = {}
        for transport in ("shm", "service", "topic"):
            run = Run(self.work, "same_" + transport, transport, end=0.1)
            try:
                code, _ = run.wait(run.vehicle, 300)
                track_code, _ = run.wait(run.track, 60)
            finally:
                run.close()
            self.assertEqual(code, 0, run.log())
            self.assertEqual(track_code, 0, run.log())
            runs[transport] = leading_wheelset(os.path.join(self.work, "same_%s.bag" % transport))
        self.assertEqual(len(runs["shm"]), 51)
        for transport in ("service", "topic"):
            self.assertEqual(runs[transport], runs["shm"], transport)

    def kill_mid_run(self, transport, victim):
        name = "kill_%s_%s" % (victim, transport)
        # Long enough (5 s simulated) that the kill lands mid-run whatever the machine's speed.
        run = Run(self.work, name, transport, end=5.0)
        try:
            # Mid-run: once the simulated clock has passed 20 ms (both nodes stepping in lockstep).
            deadline = time.monotonic() + 240.0
            type(self).clock = 0.0
            while type(self).clock < 0.02 and time.monotonic() < deadline and run.vehicle.poll() is None:
                time.sleep(0.05)
            self.assertGreaterEqual(type(self).clock, 0.02, "the run never started" + run.log())
            dead, survivor = (run.track, run.vehicle) if victim == "track" else (run.vehicle, run.track)
            dead.send_signal(signal.SIGKILL)
            dead.wait()
            # The survivor notices within its exchange timeout (+ slack for the node's own shutdown).
            code, took = run.wait(survivor, EXCHANGE_TIMEOUT + 10.0)
        finally:
            run.close()
        log = run.log()
        self.assertIsNotNone(code, "the survivor did not exit" + log)
        self.assertIn(code, EXIT_CODES_OF_A_LOST_PEER, log)
        self.assertLess(took, EXCHANGE_TIMEOUT + 10.0, log)
        survivor_out = run.out["vehicle" if victim == "track" else "track"]
        peer_name = "/%s_%s" % (victim, name)
        self.assertIn(peer_name, survivor_out, "the message names the peer" + log)
        self.assertIn("step", survivor_out, "the message names the step" + log)
        # The survivor's bag is closed and readable.
        bag = os.path.join(self.work, name + (".bag" if victim == "track" else ".track.bag"))
        with rosbag.Bag(bag) as b:
            self.assertGreater(b.get_message_count(), 0, bag)
        # No shared-memory region of this run is left behind.
        self.assertEqual(glob.glob("/dev/shm/*" + run.run_id + "*"), [], log)

    def test_track_killed_over_shm(self):
        self.kill_mid_run("shm", "track")

    def test_vehicle_killed_over_shm(self):
        self.kill_mid_run("shm", "vehicle")

    def test_track_killed_over_service(self):
        self.kill_mid_run("service", "track")

    def test_vehicle_killed_over_service(self):
        self.kill_mid_run("service", "vehicle")

    def test_track_killed_over_topic(self):
        self.kill_mid_run("topic", "track")

    def test_vehicle_killed_over_topic(self):
        self.kill_mid_run("topic", "vehicle")


if __name__ == "__main__":
    rospy.init_node("test_cosim_faults")
    rostest.rosrun("railsim_tests", "cosim_faults", CosimFaults)
