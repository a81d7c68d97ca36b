#!/usr/bin/env python3
"""The nodes start, validate their scene, report what they will simulate and exit cleanly; a bad scene,
a missing parameter, a peer that runs another scene and a peer that never comes each give one clear
message and a documented exit code (see README, "Exit codes")."""
import os
import subprocess
import sys
import unittest

import rospy
import rostest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.realpath(__file__))))
SCENES = os.path.join(ROOT, "config", "scenes")
EXIT_OK, EXIT_BAD_INPUT, EXIT_PEER_REFUSED, EXIT_PEER_TIMEOUT = 0, 2, 3, 4


def put_scene(ns, path, text=None):
    """Hands a scene over the way the launch files do: its text and its path."""
    if text is None:
        with open(path) as f:
            text = f.read()
    rospy.set_param(ns + "/scene_yaml", text)
    rospy.set_param(ns + "/scene_file", path)


def start(pkg, exe, name, ns, *extra):
    args = ["rosrun", pkg, exe, "__name:=" + name, "_scene_ns:=" + ns] + list(extra)
    return subprocess.Popen(args, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)


def finish(proc, timeout=60):
    out, _ = proc.communicate(timeout=timeout)
    return proc.returncode, out


class NodeStartup(unittest.TestCase):
    def test_cosim_nodes_validate_handshake_and_exit_cleanly(self):
        put_scene("/ok", os.path.join(SCENES, "straight_short.yaml"))
        track = start("rail_track_node", "track_node", "rail_track", "/ok")
        vehicle = start("rail_vehicle_node", "vehicle_node", "rail_vehicle", "/ok")
        rc_v, out_v = finish(vehicle)
        rc_t, out_t = finish(track)
        self.assertEqual(rc_v, EXIT_OK, out_v)
        self.assertEqual(rc_t, EXIT_OK, out_t)
        self.assertIn("effects on: track_model=rigid_fe", out_v)
        self.assertIn("wheel-centre wrenches from the track node over service", out_v)
        self.assertIn("handshake with /rail_track complete", out_v)
        self.assertIn("rigid FE rails: contact on the undeformed rails, no FE integration", out_t)
        self.assertIn("handshake with /rail_vehicle complete", out_t)
        # Then they co-simulate the scene's 0.5 s in lockstep: 25001 exchanges at the 2e-5 s track step.
        self.assertIn("finished after 25001 steps (t = 0.5000 s), 0 Newmark steps", out_t)

    def test_validate_only_exits_after_the_summary(self):
        put_scene("/paper", os.path.join(SCENES, "paper_demo.yaml"))
        rc, out = finish(start("rail_vehicle_node", "vehicle_node", "rail_vehicle_v", "/paper", "_validate_only:=true"))
        self.assertEqual(rc, EXIT_OK, out)
        self.assertIn("scene 'paper_demo'", out)
        self.assertIn("effects on: track_model=flexible", out)

    def test_bad_scene_exits_non_zero_with_the_message(self):
        path = os.path.join(SCENES, "paper_demo.yaml")
        with open(path) as f:
            text = f.read().replace("radius: 500.0, cant: 0.160}", "radius: -500.0, cant: 0.160}")
        put_scene("/bad", path, text)
        for pkg, exe in (("rail_vehicle_node", "vehicle_node"), ("rail_track_node", "track_node")):
            rc, out = finish(start(pkg, exe, "bad_" + exe, "/bad"))
            self.assertEqual(rc, EXIT_BAD_INPUT, out)
            self.assertIn("scene refused: " + path + ": track.segments[2].radius: must be positive, got -500", out)

    def test_missing_scene_parameter_is_named(self):
        rc, out = finish(start("rail_vehicle_node", "vehicle_node", "lonely", "/nothing_here"))
        self.assertEqual(rc, EXIT_BAD_INPUT, out)
        self.assertIn("parameter /nothing_here/scene_yaml is not set", out)

    def test_peer_with_another_scene_is_refused_naming_what_differs(self):
        path = os.path.join(SCENES, "straight_short.yaml")
        with open(path) as f:
            text = f.read()
        put_scene("/a", path, text)
        put_scene("/b", path, text.replace("speed: 30.5556", "speed: 20.0"))
        track = start("rail_track_node", "track_node", "track_a", "/a")
        vehicle = start("rail_vehicle_node", "vehicle_node", "vehicle_b", "/b")
        rc_v, out_v = finish(vehicle)
        rc_t, out_t = finish(track)
        self.assertEqual(rc_v, EXIT_PEER_REFUSED, out_v)
        self.assertEqual(rc_t, EXIT_PEER_REFUSED, out_t)
        self.assertIn("/track_a refused the handshake: scene differs from /vehicle_b's: scene_hash", out_v)
        self.assertIn("handshake refused: scene differs from /vehicle_b's: scene_hash", out_t)

    def test_peer_that_never_comes_times_out_with_its_name(self):
        path = os.path.join(SCENES, "straight_short.yaml")
        with open(path) as f:
            text = f.read().replace("handshake_timeout: 20.0", "handshake_timeout: 1.0")
        put_scene("/alone", path, text)
        rc, out = finish(start("rail_vehicle_node", "vehicle_node", "vehicle_alone", "/alone"))
        self.assertEqual(rc, EXIT_PEER_TIMEOUT, out)
        self.assertIn("the track node did not offer /railsim/handshake within 1.0 s (solver.handshake_timeout)", out)
        rc, out = finish(start("rail_track_node", "track_node", "track_alone", "/alone"))
        self.assertEqual(rc, EXIT_PEER_TIMEOUT, out)
        self.assertIn("no vehicle node called /railsim/handshake within 1.0 s (solver.handshake_timeout)", out)


if __name__ == "__main__":
    rospy.init_node("test_node_startup")
    rostest.rosrun("railsim_tests", "node_startup", NodeStartup, sys.argv)
