#!/usr/bin/env python3
"""The rail_track and rail_vehicle nodes in co-simulation (effects.track_model rigid_fe, shared-memory
transport; the scene is test/scenes/vehicle_rigid_short.yaml cut to 0.2 s): both nodes exit 0, the vehicle's
bag holds the wheel states, and the leading wheelset's lateral and vertical displacements agree with the
vehicle node alone on the rigid track (track_model rigid, same scene otherwise). With rigid_fe the track
node evaluates the same contact on the same rigid rails, so the two runs differ only by the coupling's
wrench extrapolation and the integrator's tolerance."""
import glob
import os
import subprocess
import tempfile
import unittest

import rosbag
import rospy
import rostest

TEST_DIR = os.path.dirname(os.path.dirname(os.path.realpath(__file__)))  # the railsim_tests package
BASE_SCENE = os.path.join(TEST_DIR, "scenes", "vehicle_rigid_short.yaml")
END_TIME = 0.2
# The paper's largest deviations between its two rigid-track runs of the same case (section 7): lateral
# 2.5e-5 m, vertical 8e-8 m. The co-simulation on the rigid rails must stay within them.
TOL_LATERAL = 2.5e-5
TOL_VERTICAL = 8e-8


def write_scene(directory, name, track_model):
    """The base scene with another name, end time, track model, track data and (co-simulation) transport;
    the data paths absolute so the file may live elsewhere."""
    with open(BASE_SCENE) as f:
        text = f.read()
    config = os.path.normpath(os.path.join(os.path.dirname(BASE_SCENE), "../../config"))
    replacements = [
        ("name: vehicle_rigid_short", "name: " + name),
        ("data: ../../config/vehicle/paper_coach.yaml", "data: " + config + "/vehicle/paper_coach.yaml"),
        # The track's data (the FE track; read by both scenes so that they differ in the track model only).
        ("rail_inclination: 1/20\n", "rail_inclination: 1/20\n  data: " + config + "/track/paper_track.yaml\n"),
        ("track_model: rigid\n", "track_model: %s\n" % track_model),
        ("end: {time: 0.5}", "end: {time: %g}\n  transport: shm\n  exchange_timeout: 20.0\n"
                             "  handshake_timeout: 120.0" % END_TIME),
        ("bag: vehicle_rigid_short.bag", "bag: %s.bag" % name),
        ("rate: 100.0", "rate: 500.0"),
    ]
    for old, new in replacements:
        assert old in text, "base scene changed: %r not found" % old
        text = text.replace(old, new)
    path = os.path.join(directory, name + ".yaml")
    with open(path, "w") as f:
        f.write(text)
    return path


def set_scene(ns, path):
    with open(path) as f:
        rospy.set_param(ns + "/scene_yaml", f.read())
    rospy.set_param(ns + "/scene_file", path)


def leading_wheelset(bag_path):
    """{step: (lateral, vertical)} of the leading wheelset (index 0, front first) and the wheel-state count."""
    out = {}
    with rosbag.Bag(bag_path) as bag:
        n_states = bag.get_message_count(topic_filters=["/wheel_states"])
        for _, msg, t in bag.read_messages(topics=["/wheelset_kinematics"]):
            w = msg.wheelsets[0]
            out[round(t.to_sec() * 500.0)] = (w.lateral_displacement, w.vertical_displacement)
    return out, n_states


class CosimNodes(unittest.TestCase):
    def test_rigid_fe_cosimulation_matches_vehicle_alone(self):
        work = tempfile.mkdtemp(prefix="railsim_cosim_")
        alone_scene = write_scene(work, "alone", "rigid")
        cosim_scene = write_scene(work, "cosim", "rigid_fe")

        # The vehicle alone on the rigid track.
        set_scene("/alone", alone_scene)
        proc = subprocess.run(["rosrun", "rail_vehicle_node", "vehicle_node", "__name:=rail_vehicle_alone",
                               "_scene_ns:=/alone", "_output_dir:=" + work],
                              stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
        self.assertEqual(proc.returncode, 0, proc.stdout)

        # The co-simulation: track and vehicle nodes, shm regions named by this run's id.
        set_scene("/cosim", cosim_scene)
        run_id = "cosimtest%d" % os.getpid()
        track = subprocess.Popen(["rosrun", "rail_track_node", "track_node", "__name:=rail_track",
                                  "_scene_ns:=/cosim", "_run_id:=" + run_id],
                                 stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        vehicle = subprocess.Popen(["rosrun", "rail_vehicle_node", "vehicle_node", "__name:=rail_vehicle",
                                    "_scene_ns:=/cosim", "_run_id:=" + run_id, "_output_dir:=" + work],
                                   stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
        try:
            vehicle_out, _ = vehicle.communicate(timeout=300)
            track_out, _ = track.communicate(timeout=60)
        finally:
            for p in (vehicle, track):
                if p.poll() is None:
                    p.kill()
                    p.wait()
        self.assertEqual(vehicle.returncode, 0, vehicle_out + "\n----- track -----\n" + track_out)
        self.assertEqual(track.returncode, 0, track_out + "\n----- vehicle -----\n" + vehicle_out)
        self.assertIn("finished at t = 0.2", vehicle_out)
        # Both ends unlink their regions on close.
        self.assertEqual(glob.glob("/dev/shm/*" + run_id + "*"), [])

        alone, _ = leading_wheelset(os.path.join(work, "alone.bag"))
        cosim, n_states = leading_wheelset(os.path.join(work, "cosim.bag"))
        # 500 Hz over 0.2 s: outputs 0 .. 100.
        self.assertEqual(n_states, 101, vehicle_out)
        self.assertEqual(sorted(cosim.keys()), sorted(alone.keys()))
        d_lat = max(abs(cosim[k][0] - alone[k][0]) for k in alone)
        d_vert = max(abs(cosim[k][1] - alone[k][1]) for k in alone)
        print("leading wheelset, co-simulation - alone (max over %d samples): lateral %.3g m, vertical %.3g m"
              % (len(alone), d_lat, d_vert))
        self.assertLess(d_lat, TOL_LATERAL)
        self.assertLess(d_vert, TOL_VERTICAL)


if __name__ == "__main__":
    rospy.init_node("test_cosim_nodes")
    rostest.rosrun("railsim_tests", "cosim_nodes", CosimNodes)
