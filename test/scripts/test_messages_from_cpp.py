#!/usr/bin/env python3
"""A Python node reads what the C++ publisher wrote: rail_msgs is usable from both languages."""
import sys
import unittest

import rospy
import rostest
from rail_msgs.msg import ContactPoint, ContactPoints, ContactWrenches, RailDeflection, WheelState, WheelStates


class MessagesFromCpp(unittest.TestCase):
    def receive(self, topic, cls):
        return rospy.wait_for_message(topic, cls, timeout=20.0)

    def test_wheel_states(self):
        m = self.receive("wheel_states", WheelStates)
        self.assertEqual(m.step, 62500)
        self.assertEqual(m.scene_hash, 0xFEDCBA9876543210)
        self.assertAlmostEqual(m.header.stamp.to_sec(), 1.25)
        self.assertEqual(len(m.wheels), 8)
        self.assertEqual([w.wheel_id for w in m.wheels], list(range(8)))
        self.assertEqual(m.wheels[3].side, WheelState.SIDE_RIGHT)
        self.assertEqual(m.wheels[3].wheelset, 1)
        self.assertAlmostEqual(m.wheels[2].position.y, 0.8)
        self.assertAlmostEqual(m.wheels[0].angular_velocity.y, 30.5556 / 0.445)

    def test_contact_wrenches(self):
        m = self.receive("contact_wrenches", ContactWrenches)
        self.assertEqual(len(m.wrenches), 1)
        self.assertEqual(m.wrenches[0].wheel_id, 3)
        self.assertAlmostEqual(m.wrenches[0].force.z, 72900.0)
        self.assertAlmostEqual(m.wrenches[0].moment.x, -1234.5)

    def test_contact_points(self):
        m = self.receive("contact_points", ContactPoints)
        p = m.points[0]
        self.assertEqual(p.kind, ContactPoint.KIND_FLANGE)
        self.assertTrue(p.active)
        self.assertAlmostEqual(p.normal_force, 45000.0)
        self.assertAlmostEqual(p.semi_axis_a, 0.006)
        self.assertAlmostEqual(p.creepage_spin, 0.35)

    def test_rail_deflection(self):
        m = self.receive("rail_deflection", RailDeflection)
        self.assertAlmostEqual(m.arc_length, 66.0)
        self.assertAlmostEqual(m.left_displacement.z, -1.1e-3)
        self.assertAlmostEqual(m.right_rotation.x, 2e-4)


if __name__ == "__main__":
    rospy.init_node("test_messages_from_cpp")
    rostest.rosrun("railsim_tests", "messages_from_cpp", MessagesFromCpp, sys.argv)
