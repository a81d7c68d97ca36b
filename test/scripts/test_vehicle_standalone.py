#!/usr/bin/env python3
"""The rail_vehicle node on the rigid track (test/scenes/vehicle_rigid_short.yaml, 0.5 s on a straight):
it publishes finite wheel states, contact wrenches, contact points and wheelset kinematics, the wheel loads
stay near W/8, it exits 0 and leaves a readable bag with the scene's topics."""
import math
import os
import subprocess
import tempfile
import threading
import unittest

import rosbag
import rospy
import rostest
from rail_msgs.msg import ContactPoints, ContactWrenches, WheelStates, WheelsetKinematics
from visualization_msgs.msg import MarkerArray

TEST_DIR = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))  # the railsim_tests package
SCENE = os.path.join(TEST_DIR, "scenes", "vehicle_rigid_short.yaml")
W8 = 59480.0 * 9.81 / 8.0  # Table 3 coach weight per wheel [N]


def finite(*values):
    return all(math.isfinite(v) for v in values)


class VehicleStandalone(unittest.TestCase):
    def test_rigid_track_run_publishes_and_records(self):
        with open(SCENE) as f:
            rospy.set_param("/vr/scene_yaml", f.read())
        rospy.set_param("/vr/scene_file", SCENE)
        received = {"wheel_states": [], "contact_wrenches": [], "contact_points": [], "kinematics": []}
        lock = threading.Lock()

        def keep(key):
            def cb(msg):
                with lock:
                    received[key].append(msg)
            return cb

        subs = [rospy.Subscriber("/wheel_states", WheelStates, keep("wheel_states")),
                rospy.Subscriber("/contact_wrenches", ContactWrenches, keep("contact_wrenches")),
                rospy.Subscriber("/contact_points", ContactPoints, keep("contact_points")),
                rospy.Subscriber("/wheelset_kinematics", WheelsetKinematics, keep("kinematics"))]
        out_dir = tempfile.mkdtemp(prefix="railsim_vehicle_")
        live = "[wheel_states, contact_wrenches, contact_points, wheelset_kinematics]"
        proc = subprocess.Popen(["rosrun", "rail_vehicle_node", "vehicle_node", "__name:=rail_vehicle",
                                 "_scene_ns:=/vr", "_output_dir:=" + out_dir, "_wait_for_subscribers:=" + live,
                                 "_subscriber_timeout:=60"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        out, _ = proc.communicate(timeout=240)
        rospy.sleep(0.5)
        for s in subs:
            s.unregister()
        self.assertEqual(proc.returncode, 0, out)
        self.assertIn("finished at t = 0.5", out)

        with lock:
            states, wrenches = received["wheel_states"], received["contact_wrenches"]
            points, kin = received["contact_points"], received["kinematics"]
        self.assertNotIn("no subscriber on", out)
        # The run publishes 51 of each (100 Hz over 0.5 s) and waited for these subscribers: each saw the
        # first output (t = 0) and most of the rest (the last few may still be in flight when the node exits).
        for name, msgs in (("wheel_states", states), ("contact_wrenches", wrenches),
                           ("contact_points", points), ("wheelset_kinematics", kin)):
            self.assertGreater(len(msgs), 40, name + ": " + out)
            self.assertLess(msgs[0].header.stamp.to_sec(), 1e-6, name + ": " + out)  # t = 0 (stamped 1 ns)
        for m in states:
            self.assertEqual(len(m.wheels), 8)
            for w in m.wheels:
                self.assertTrue(finite(w.arc_length, w.position.x, w.position.y, w.position.z,
                                       w.linear_velocity.x, w.angular_velocity.y))
                # Wheel centres at the nominal radius above the rail top (the vehicle settles ~0.1 mm).
                self.assertAlmostEqual(w.position.z, 0.445, delta=2e-3)
        for m in wrenches:
            self.assertEqual(len(m.wrenches), 8)
            for w in m.wrenches:
                self.assertTrue(finite(w.force.x, w.force.y, w.force.z, w.moment.x, w.moment.y, w.moment.z))
                # On straight track the vehicle starts in static equilibrium; the dynamic load stays within
                # 5 % of the static share W/8 (measured spread well below 1 %).
                self.assertAlmostEqual(w.force.z, W8, delta=0.05 * W8)
        for m in points:
            self.assertEqual(len(m.points), 32)  # four contact slots per wheel
            treads = m.points[0::4]  # each wheel's first slot: its tread contact
            self.assertTrue(all(p.active and p.kind == p.KIND_TREAD for p in treads))
            for p in m.points:
                self.assertTrue(finite(p.normal_force, p.penetration, p.creep_force_lateral))
        for m in kin:
            self.assertEqual(len(m.wheelsets), 4)
            for w in m.wheelsets:
                self.assertTrue(finite(w.lateral_displacement, w.angle_of_attack, w.spin_speed))
                self.assertLess(abs(w.lateral_displacement), 0.005)

        bag_path = os.path.join(out_dir, "vehicle_rigid_short.bag")
        self.assertTrue(os.path.exists(bag_path), out)
        with rosbag.Bag(bag_path) as bag:
            info = bag.get_type_and_topic_info().topics
            for topic in ("/wheel_states", "/contact_wrenches", "/contact_points", "/wheelset_kinematics",
                          "/tf", "/clock"):
                self.assertIn(topic, info)
                self.assertEqual(info[topic].message_count, 51, topic)
            last = None
            for _, msg, t in bag.read_messages(topics=["/wheel_states"]):
                last = (msg, t)
            self.assertAlmostEqual(last[1].to_sec(), 0.5, places=6)
            self.assertAlmostEqual(last[0].wheels[0].arc_length, 25.0 + 0.5 * 30.5556, delta=0.05)

    def test_waiting_for_a_topic_it_does_not_publish_is_refused(self):
        with open(SCENE) as f:
            rospy.set_param("/vw/scene_yaml", f.read())
        rospy.set_param("/vw/scene_file", SCENE)
        out_dir = tempfile.mkdtemp(prefix="railsim_vehicle_")
        proc = subprocess.Popen(["rosrun", "rail_vehicle_node", "vehicle_node", "__name:=rail_vehicle_w",
                                 "_scene_ns:=/vw", "_output_dir:=" + out_dir,
                                 "_wait_for_subscribers:=[wheel_states, rail_deflections]"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        out, _ = proc.communicate(timeout=240)
        self.assertEqual(proc.returncode, 2, out)  # bad input
        self.assertIn("~wait_for_subscribers names /rail_deflections, which this node does not publish", out)
        self.assertIn("/wheel_states", out)  # what it does publish
        self.assertEqual(os.listdir(out_dir), [], out)  # refused before its bag was opened

    def test_markers_draw_the_scenes_local_defects(self):
        # The coach over a dipped joint with a flat on both wheels of its leading wheelset: the markers draw
        # the joint on each rail with its label and the two flats on their rims.
        scene = """name: vehicle_defects_short
track:
  gauge: 1.668
  cant_reference_width: 1.733
  rail_inclination: 1/20
  segments:
    - {type: straight, length: 60.0}
  defects:
    - {type: dipped_joint, s: 40.0, length: 1.0, dip_angle: 0.01, rail: both}
vehicle:
  data: ../../config/vehicle/paper_coach.yaml
  start_arc_length: 25.0
  speed: 30.5556
  back_to_back: 1.592
  wheel_defects:
    - {type: flat, wheelset: 0, side: both, length: 0.05, shape: new, angle: -1.5708}
effects:
  track_model: rigid
  track_defects: true
  wheel_defects: true
  rviz_markers: true
solver:
  end: {time: 0.05}
output:
  rate: 100.0
"""
        rospy.set_param("/vd/scene_yaml", scene)
        rospy.set_param("/vd/scene_file", SCENE)  # relative data paths from test/scenes
        arrays = []
        lock = threading.Lock()

        def keep(msg):
            with lock:
                arrays.append(msg)

        sub = rospy.Subscriber("/vehicle_markers", MarkerArray, keep)
        out_dir = tempfile.mkdtemp(prefix="railsim_vehicle_")
        proc = subprocess.Popen(["rosrun", "rail_vehicle_node", "vehicle_node", "__name:=rail_vehicle_d",
                                 "_scene_ns:=/vd", "_output_dir:=" + out_dir,
                                 "_wait_for_subscribers:=vehicle_markers", "_subscriber_timeout:=60"],
                                stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        out, _ = proc.communicate(timeout=240)
        rospy.sleep(0.5)
        sub.unregister()
        self.assertEqual(proc.returncode, 0, out)
        with lock:
            self.assertGreater(len(arrays), 0, out)
            markers = arrays[0].markers
        by_ns = {}
        for m in markers:
            by_ns.setdefault(m.ns, []).append(m)
        self.assertEqual(len(by_ns.get("wheel_defects", [])), 2, sorted(by_ns))
        self.assertEqual(len(by_ns.get("rail_defects", [])), 2, sorted(by_ns))  # one line per rail
        labels = [m.text for m in by_ns.get("defect_labels", [])]
        self.assertEqual(labels, ["dipped joint 10.0 mrad"] * 2)
        for line in by_ns["rail_defects"]:
            xs = [p.x for p in line.points]
            # Along the joint's metre of rail (straight track from x = 0).
            self.assertAlmostEqual(min(xs), 39.5, delta=0.6)
            self.assertAlmostEqual(max(xs), 40.5, delta=0.6)


if __name__ == "__main__":
    rospy.init_node("test_vehicle_standalone")
    rostest.rosrun("railsim_tests", "vehicle_standalone", VehicleStandalone)
