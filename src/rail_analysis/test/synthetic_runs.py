"""Writes a run directory of synthetic bags from an analytic motion, for the analysis tool's tests.

The three runs (standalone, rigid_fe, flexible) of a vehicle at constant speed on a track of a straight,
a left transition and a left circular curve; every quantity the tool reads is a closed-form function of
time whose analysed figures are known in advance (see the constants below).
"""
import math
import os

import numpy as np
import rosbag
import rospy
import yaml
from genpy.dynamic import generate_dynamic
from rail_msgs.msg import ContactPoint, ContactPoints, RailDeflection, WheelsetKinematics

# Track and vehicle.
SPEED = 30.5556                      # [m/s], 110 km/h
SLEEPER_SPACING = 0.6                # [m]; sleeper passing SPEED / SLEEPER_SPACING = 50.93 Hz
START_S = 25.0                       # leading wheelset at t = 0 [m]
WHEELSET_OFFSETS = (0.0, 2.7, 19.0, 21.7)  # behind the leading wheelset [m] (paper Table 3)
SEGMENTS = [{"type": "straight", "length": 60.0},
            {"type": "transition", "length": 40.0, "direction": "left", "radius_start": 0.0,
             "radius_end": 1250.0, "cant_start": 0.0, "cant_end": 0.064},
            {"type": "circular", "length": 60.0, "direction": "left", "radius": 1250.0, "cant": 0.064}]
SECTIONS = (40.0, 120.0)             # deflection sections: on the straight, in the circular curve [m]
T_END = 3.5                          # [s]: the leading wheelset ends at 131.9 m, in the circular curve
RATE = {"standalone": 500.0, "rigid_fe": 1000.0, "flexible": 1000.0}  # kinematics output rates [Hz]
POINT_RATE = 500.0                   # contact points and rail deflections [Hz]

# Leading wheelset motion common to the runs.
LAT_AMPLITUDE, LAT_FREQUENCY = 3e-3, 0.7      # lateral A sin(2 pi f t) [m, Hz]
AOA_AMPLITUDE = 1e-3                          # angle of attack B cos(2 pi f t) [rad]
VERT_AMPLITUDE, VERT_FREQUENCY = 1e-5, 2.0    # vertical C sin(2 pi f t) [m, Hz]
# rigid_fe = standalone + a ramp reaching these values at T_END (its largest deviation after the discard),
# plus a spike inside the discarded first 0.25 s that the table must ignore.
DEV_LATERAL = 2.0e-5          # [m]
DEV_AOA_DEG = 4.0e-4          # [deg]
DEV_VERTICAL = 6.0e-8         # [m]
SPIKE = 1.0e-3                # [m, rad] at t = 0.1 s
# Flexible run: vertical oscillation at this frequency added to the leading wheelset's motion.
FLEX_FREQUENCY, FLEX_AMPLITUDE = 51.0, 2e-5   # [Hz, m]
# Lateral wheel force on the straight [N] (left +, right -); the flexible run's is this ratio higher.
LATERAL_FORCE, FLEX_FORCE_RATIO = 2000.0, 1.10
# Outer (right) flange force in the curve [N]: plateau and a peak at each curved segment's entry; the
# flexible run's peaks are scaled by FLEX_PEAK_RATIO.
FLANGE_PLATEAU, FLANGE_PEAK, FLEX_PEAK_RATIO = 20e3, 15e3, 0.8
RAIL_VERTICAL, RAIL_LATERAL = 1.0e-3, 2.0e-4  # rail displacement amplitudes [m]


FORCE_LINES = "geometry_msgs/Vector3 left_force_in_track\ngeometry_msgs/Vector3 right_force_in_track\n"
VECTOR3 = "MSG: geometry_msgs/Vector3\nfloat64 x\nfloat64 y\nfloat64 z\n"


def kinematics_classes(with_forces):
    """(WheelsetKinematics, WheelsetTrackState) classes built from the message text, with or without the
    per-wheel track-frame forces (left/right_force_in_track), whichever the installed rail_msgs has: bags
    of both versions of the message."""
    text = WheelsetKinematics._full_text
    sections = text.split("=" * 80 + "\n")
    out = []
    for sec in sections:
        if sec.startswith("MSG: rail_msgs/WheelsetTrackState"):
            lines = [ln for ln in sec.splitlines(True) if "force_in_track" not in ln]
            if with_forces:
                lines.append(FORCE_LINES)
            sec = "".join(lines)
        if sec.startswith("MSG: geometry_msgs/Vector3"):
            continue
        out.append(sec)
    if with_forces:
        out.append(VECTOR3)
    text = ("=" * 80 + "\n").join(s if s.endswith("\n") else s + "\n" for s in out)
    types = generate_dynamic("rail_msgs/WheelsetKinematics", text)
    return types["rail_msgs/WheelsetKinematics"], types["rail_msgs/WheelsetTrackState"]


def scene_dict(track_model):
    return {"name": "synthetic", "track": {"gauge": 1.668, "sleeper_spacing": SLEEPER_SPACING,
                                           "start_arc_length": 0.0, "segments": SEGMENTS},
            "vehicle": {"start_arc_length": START_S, "speed": SPEED},
            "effects": {"track_model": track_model},
            "output": {"rate": 1000.0, "deflection_sections": list(SECTIONS)}}


def times(rate):
    n = int(round(T_END * rate)) + 1
    return np.arange(n) / rate


def arc_lengths(t):
    """(N, 4) wheelset arc lengths [m]."""
    return START_S + SPEED * np.asarray(t)[:, None] - np.array(WHEELSET_OFFSETS)[None, :]


def lateral(name, t):
    y = LAT_AMPLITUDE * np.sin(2 * math.pi * LAT_FREQUENCY * t)
    if name == "rigid_fe":
        y = y + DEV_LATERAL * t / T_END + SPIKE * np.exp(-((t - 0.1) / 0.01) ** 2)
    return y


def angle_of_attack(name, t):
    a = AOA_AMPLITUDE * np.cos(2 * math.pi * LAT_FREQUENCY * t)
    if name == "rigid_fe":
        a = a + math.radians(DEV_AOA_DEG) * t / T_END + SPIKE * np.exp(-((t - 0.1) / 0.01) ** 2)
    return a


def vertical(name, t):
    z = VERT_AMPLITUDE * np.sin(2 * math.pi * VERT_FREQUENCY * t)
    if name == "rigid_fe":
        z = z + DEV_VERTICAL * t / T_END + SPIKE * np.exp(-((t - 0.1) / 0.01) ** 2)
    if name == "flexible":
        z = z - 1e-4 + FLEX_AMPLITUDE * np.sin(2 * math.pi * FLEX_FREQUENCY * t)
    return z


def in_curve(s):
    return s >= SEGMENTS[0]["length"]


def flange_right(name, s):
    """Outer (right) flange normal force [N] of a wheel at arc length s: zero on the straight."""
    peak_scale = FLEX_PEAK_RATIO if name == "flexible" else 1.0
    entries = (60.0, 100.0)
    f = np.where(in_curve(s), FLANGE_PLATEAU, 0.0)
    for e in entries:
        f = f + np.where(s >= e, peak_scale * FLANGE_PEAK * np.exp(-((s - e - 2.0) / 1.0) ** 2), 0.0)
    return f


def lateral_force(name, s):
    """(left, right) lateral wheel force [N] in the track frame at arc length s."""
    k = FLEX_FORCE_RATIO if name == "flexible" else 1.0
    left = np.full(np.shape(s), k * LATERAL_FORCE)
    right = -left - np.where(in_curve(s), 0.5 * flange_right(name, s), 0.0)
    return left, right


def _stamp(t):
    return rospy.Time.from_sec(max(float(t), 1e-9))


def write_kinematics(bag, name, forces=True):
    cls, state_cls = kinematics_classes(forces)
    t = times(RATE[name])
    s = arc_lengths(t)
    y, a, z = lateral(name, t), angle_of_attack(name, t), vertical(name, t)
    fl, fr = lateral_force(name, s[:, 0])
    for i, ti in enumerate(t):
        m = cls()
        m.header.stamp = rospy.Time.from_sec(float(ti))
        for w in range(4):
            ws = state_cls()
            ws.wheelset = w
            ws.arc_length = s[i, w]
            ws.lateral_displacement = y[i] if w == 0 else 0.0
            ws.vertical_displacement = z[i] if w == 0 else 0.0
            ws.angle_of_attack = a[i] if w == 0 else 0.0
            ws.spin_speed = SPEED / 0.445
            if forces:
                ws.left_force_in_track.y = fl[i]
                ws.right_force_in_track.y = fr[i]
                ws.left_force_in_track.z = 70e3
                ws.right_force_in_track.z = 70e3 + (5e3 if in_curve(s[i, 0]) else 0.0)
            m.wheelsets.append(ws)
        bag.write("/wheelset_kinematics", m, _stamp(ti))


def write_points(bag, name):
    t = times(POINT_RATE)
    s = arc_lengths(t)
    for i, ti in enumerate(t):
        m = ContactPoints()
        m.header.stamp = rospy.Time.from_sec(float(ti))
        for w in range(4):
            for side in (0, 1):
                for kind in (ContactPoint.KIND_TREAD, ContactPoint.KIND_FLANGE):
                    p = ContactPoint()
                    p.wheel_id, p.side, p.kind = 2 * w + side, side, kind
                    p.arc_length = s[i, w]
                    # Contact angles as on S1002 / UIC60: tread a few hundredths of a radian, flange flank 70 deg.
                    p.contact_angle = 0.04 if kind == ContactPoint.KIND_TREAD else 1.2
                    if kind == ContactPoint.KIND_TREAD:
                        p.active, p.normal_force = True, 70e3
                    elif side == 1:
                        f = float(flange_right(name, s[i, w]))
                        p.active, p.normal_force = f > 0, f
                    m.points.append(p)
        bag.write("/contact_points", m, _stamp(ti))


def rail_shape(t, s_section):
    """Sum over the two bogies of a bump centred on the bogie centre passing the section (so the peaks
    fall between the wheels of a bogie)."""
    s = arc_lengths(t)
    out = np.zeros(len(t))
    for front, rear in ((0, 1), (2, 3)):
        mid = 0.5 * (s[:, front] + s[:, rear])
        out += np.exp(-((mid - s_section) / 1.2) ** 2)
    return out


def write_deflection(bag, name):
    t = times(POINT_RATE)
    for s_sec in SECTIONS:
        shape = rail_shape(t, s_sec) if name == "flexible" else np.zeros(len(t))
        curve = in_curve(s_sec)
        for i, ti in enumerate(t):
            m = RailDeflection()
            m.header.stamp = rospy.Time.from_sec(float(ti))
            m.arc_length = s_sec
            m.left_displacement.z = m.right_displacement.z = -RAIL_VERTICAL * shape[i]
            if curve:  # both rails toward the outside of the left curve (-y), the outer (right) more
                m.left_displacement.y = -0.3 * RAIL_LATERAL * shape[i]
                m.right_displacement.y = -RAIL_LATERAL * shape[i]
            else:      # both rails toward the track centre
                m.left_displacement.y = -RAIL_LATERAL * shape[i]
                m.right_displacement.y = RAIL_LATERAL * shape[i]
            bag.write("/rail_deflection", m, _stamp(ti))


def write_run(directory, name, forces=True, wall_time=None):
    """Writes <name>.bag (+ .track.bag for a co-simulation), .run.yaml and .scene.yaml."""
    model = {"standalone": "rigid", "rigid_fe": "rigid_fe", "flexible": "flexible"}[name]
    with rosbag.Bag(os.path.join(directory, name + ".bag"), "w") as bag:
        write_kinematics(bag, name, forces)
        if name == "standalone":
            write_points(bag, name)
    if name != "standalone":
        with rosbag.Bag(os.path.join(directory, name + ".track.bag"), "w") as bag:
            write_points(bag, name)
            write_deflection(bag, name)
    walls = {"standalone": 10.0, "rigid_fe": 79.0, "flexible": 573.0}
    with open(os.path.join(directory, name + ".run.yaml"), "w") as f:
        yaml.safe_dump({"run": name, "scene": "synthetic.yaml", "track_model": model,
                        "wall_time": walls[name] if wall_time is None else wall_time,
                        "simulated_time": T_END, "exit_code": 0}, f)
    with open(os.path.join(directory, name + ".scene.yaml"), "w") as f:
        yaml.safe_dump(scene_dict(model), f)


def write_all(directory, names=("standalone", "rigid_fe", "flexible")):
    os.makedirs(directory, exist_ok=True)
    for n in names:
        write_run(directory, n)
