"""Writes synthetic runs with known wheel forces, contact creepages, floor accelerations and pad forces, for the
tests of rail_analysis.safety (test_safety_synthetic.py). Every value the tests expect is a closed-form
consequence of the constants below.

Runs: standalone (vehicle bag: /wheelset_kinematics, /contact_points, /floor_accelerations), rigid_fe
(vehicle bag: /wheelset_kinematics; track bag: /contact_points) and flexible (the same plus /pad_forces in
the track bag); none but standalone records /floor_accelerations.
"""
import math
import os

import numpy as np
import rosbag
import rospy
import yaml
from geometry_msgs.msg import Point, Vector3
from rail_msgs.msg import (ContactPoint, ContactPoints, FloorAccelerations, RailPadForces, WheelsetKinematics,
                           WheelsetTrackState)

SPEED = 20.0                    # [m/s]
START_S = 10.0                  # leading wheelset at t = 0 [m]
OFFSETS = (0.0, 2.5, 17.0, 19.5)  # wheelsets behind the leading one [m]
T_END = 16.0                    # [s]; the leading wheelset ends at 330 m
RATE = 200.0                    # kinematics [Hz]; sample spacing V / RATE = 0.1 m
FLOOR_RATE = 250.0              # floor accelerations [Hz] (the weightings need > 200 Hz)
POINT_RATE = 50.0               # contact points [Hz]
PAD_RATE = 50.0                 # pad forces [Hz]
SEGMENTS = [{"type": "straight", "length": 100.0},
            {"type": "transition", "length": 60.0, "direction": "left", "radius_start": 0.0, "radius_end": 600.0,
             "cant_start": 0.0, "cant_end": 0.1},
            {"type": "circular", "length": 200.0, "direction": "left", "radius": 600.0, "cant": 0.1}]

# Vehicle data file: masses [kg] and gravity; Q0 = total mass g / (2 x 4 wheelsets).
MASSES = (40000.0, 3000.0, 3000.0, 1500.0, 1500.0, 1500.0, 1500.0)
GRAVITY = 9.81
Q0 = sum(MASSES) * GRAVITY / 8.0   # 63 765 N

# Wheel forces (rail on wheel, track frame). Every wheel carries Q0 and no lateral force except:
WS0_LEFT_FY, WS0_RIGHT_FY = 10e3, 30e3     # leading wheelset [N]: Y_left = -10 kN, Y_right = 30 kN
WS0_RIGHT_FY_AFTER = 50e3                  # right Fy from S_STEP on [N]
S_STEP = 150.0                             # [m]
WS0_LEFT_Q, WS0_RIGHT_Q = 60e3, 80e3       # [N]
WS1_CLIMB = (200.0, 203.0)                 # wheelset 2 (index 1), right wheel: Y/Q = 1.5 over these s [m]
WS1_RIGHT_Q, WS1_YQ = 60e3, 1.5
WS2_UNLOAD = (250.0, 252.0)                # wheelset 3 (index 2), left wheel: Q = 0.45 Q0 over these s [m]
WS2_UNLOAD_RATIO = 0.45

# Contact points: every wheel's tread (Tx, nu_x, Ty, nu_y) = TREAD_ALL; the leading right wheel (id 1) has
# TREAD_1 on its tread and FLANGE_1 on its active flange. Inactive flange slots carry INACTIVE values that
# must not count. Spin creepage SPIN on every point (not part of Tgamma).
TREAD_ALL = (1000.0, 0.001, 500.0, 0.002)          # Tgamma 2 N
TREAD_1 = (5000.0, 0.002, -4000.0, -0.003)         # 10 + 12 = 22 N
FLANGE_1 = (-2000.0, 0.01, 8000.0, 0.02)           # 20 + 160 = 180 N
INACTIVE = (1e4, 0.1, 1e4, 0.1)
SPIN = 0.5                                          # [1/m]
TGAMMA_ALL = 2.0
TGAMMA_1 = 202.0

# Floor accelerations: (name, position, (f_x, f_y, f_z) [Hz]); amplitude A on each axis, z offset +9.81.
FLOOR_POINTS = (("above_front_bogie", (21.0, 0.0, 1.2), (1.0, 2.0, 4.0)),
                ("centre", (11.5, 0.0, 1.2), (2.0, 4.0, 8.0)),
                ("above_rear_bogie", (2.0, 0.0, 1.2), (4.0, 1.0, 1.0)))
FLOOR_AMPLITUDE = 0.5           # [m/s^2]

# Pad forces (flexible run): sleepers every 0.6 m from s_rear - 3 m to s_front + 3 m; every pad pressed by
# PAD_BASE; at t = PAD_PEAK_T the right pad of the sleeper nearest PAD_PEAK_S pressed by PAD_PEAK and the
# right rail there displaced by RAIL_PEAK (z down, y out). Each sleeper presses the ballast with both pads'
# compression and SLEEPER_WEIGHT (ballast=False: no ballast forces, as a bag of an older build).
PAD_BASE, PAD_PEAK = 30e3, 55e3   # [N] compression (pad force z = -compression)
PAD_PEAK_T, PAD_PEAK_S = 8.0, 170.0
SLEEPER_WEIGHT = 2.9e3           # [N] added to both pads' compression in each sleeper's ballast force
BALLAST_PEAK = PAD_BASE + PAD_PEAK + SLEEPER_WEIGHT
VOID_S, VOID_OPEN, VOID_PEAK, VOID_PEAK_T = 283 * 0.6, 0.4e-3, 1.1e-3, 8.0  # a hanging sleeper's void [m, m, m, s]
RAIL_BASE = 0.5e-3
RAIL_PEAK = (0.0, -0.3e-3, -1.2e-3)   # [m]; magnitude 1.2369 mm


def arc_lengths(t):
    return START_S + SPEED * np.asarray(t)[:, None] - np.array(OFFSETS)[None, :]


def wheel_forces(s):
    """(left, right) (N, 4, 3) rail-on-wheel forces in the track frame at the wheelset arc lengths s (N, 4)."""
    n = s.shape[0]
    left = np.zeros((n, 4, 3))
    right = np.zeros((n, 4, 3))
    left[:, :, 2] = Q0
    right[:, :, 2] = Q0
    left[:, 0, 1], left[:, 0, 2] = WS0_LEFT_FY, WS0_LEFT_Q
    right[:, 0, 1] = np.where(s[:, 0] < S_STEP, WS0_RIGHT_FY, WS0_RIGHT_FY_AFTER)
    right[:, 0, 2] = WS0_RIGHT_Q
    climb = (s[:, 1] >= WS1_CLIMB[0]) & (s[:, 1] < WS1_CLIMB[1])
    right[:, 1, 2] = WS1_RIGHT_Q
    right[:, 1, 1] = np.where(climb, WS1_YQ * WS1_RIGHT_Q, 0.0)
    unload = (s[:, 2] >= WS2_UNLOAD[0]) & (s[:, 2] < WS2_UNLOAD[1])
    left[:, 2, 2] = np.where(unload, WS2_UNLOAD_RATIO * Q0, Q0)
    return left, right


def _times(rate):
    return np.arange(int(round(T_END * rate)) + 1) / rate


def _stamp(t):
    return rospy.Time.from_sec(max(float(t), 1e-9))


def write_kinematics(bag):
    t = _times(RATE)
    s = arc_lengths(t)
    left, right = wheel_forces(s)
    for i, ti in enumerate(t):
        m = WheelsetKinematics()
        m.header.stamp = rospy.Time.from_sec(float(ti))
        for w in range(4):
            ws = WheelsetTrackState()
            ws.wheelset, ws.arc_length, ws.spin_speed = w, s[i, w], SPEED / 0.445
            ws.left_force_in_track = Vector3(*left[i, w])
            ws.right_force_in_track = Vector3(*right[i, w])
            m.wheelsets.append(ws)
        bag.write("/wheelset_kinematics", m, _stamp(ti))


def _point(wheel_id, kind, active, values, s):
    p = ContactPoint()
    p.wheel_id, p.side, p.kind, p.active = wheel_id, wheel_id % 2, kind, active
    p.contact_angle = 0.04 if kind == ContactPoint.KIND_TREAD else 1.2  # tread; flange flank (70 deg)
    p.arc_length = s
    p.normal_force = 50e3 if active else 0.0
    p.creep_force_longitudinal, p.creepage_longitudinal, p.creep_force_lateral, p.creepage_lateral = values
    p.creepage_spin = SPIN
    return p


def write_points(bag):
    t = _times(POINT_RATE)
    s = arc_lengths(t)
    for i, ti in enumerate(t):
        m = ContactPoints()
        m.header.stamp = rospy.Time.from_sec(float(ti))
        for wid in range(8):
            sw = float(s[i, wid // 2])
            if wid == 1:
                m.points.append(_point(wid, ContactPoint.KIND_TREAD, True, TREAD_1, sw))
                m.points.append(_point(wid, ContactPoint.KIND_FLANGE, True, FLANGE_1, sw))
            else:
                m.points.append(_point(wid, ContactPoint.KIND_TREAD, True, TREAD_ALL, sw))
                m.points.append(_point(wid, ContactPoint.KIND_FLANGE, False, INACTIVE, sw))
        bag.write("/contact_points", m, _stamp(ti))


def floor_signal(t, f):
    return FLOOR_AMPLITUDE * np.sin(2 * math.pi * f * np.asarray(t))


def write_floor(bag):
    t = _times(FLOOR_RATE)
    sig = {(j, k): floor_signal(t, p[2][k]) for j, p in enumerate(FLOOR_POINTS) for k in range(3)}
    for i, ti in enumerate(t):
        m = FloorAccelerations()
        m.header.stamp = rospy.Time.from_sec(float(ti))
        for j, (name, pos, _) in enumerate(FLOOR_POINTS):
            m.names.append(name)
            m.position.append(Point(*pos))
            m.specific_force.append(Vector3(sig[j, 0][i], sig[j, 1][i], 9.81 + sig[j, 2][i]))
        bag.write("/floor_accelerations", m, _stamp(ti))


def write_pads(bag, ballast=True):
    t = _times(PAD_RATE)
    s = arc_lengths(t)
    for i, ti in enumerate(t):
        lo, hi = s[i, 3] - 3.0, s[i, 0] + 3.0
        sl = np.arange(math.ceil(lo / 0.6), math.floor(hi / 0.6) + 1) * 0.6
        m = RailPadForces()
        m.header.stamp = rospy.Time.from_sec(float(ti))
        m.arc_length = [float(x) for x in sl]
        k_peak = int(np.argmin(np.abs(sl - PAD_PEAK_S))) if abs(ti - PAD_PEAK_T) < 1e-9 else -1
        for k in range(len(sl)):
            m.left_pad_force.append(Vector3(0.0, 0.0, -PAD_BASE))
            m.right_pad_force.append(Vector3(0.0, 0.0, -(PAD_PEAK if k == k_peak else PAD_BASE)))
            m.left_rail_displacement.append(Vector3(0.0, 0.0, -RAIL_BASE))
            m.right_rail_displacement.append(Vector3(*RAIL_PEAK) if k == k_peak else Vector3(0.0, 0.0, -RAIL_BASE))
            if ballast:
                pads = PAD_BASE + (PAD_PEAK if k == k_peak else PAD_BASE)
                m.ballast_force.append(Vector3(0.0, 0.0, -(pads + SLEEPER_WEIGHT)))
                # The hanging sleeper's void: open by VOID_OPEN, widest at VOID_PEAK_T.
                open_gap = VOID_PEAK if abs(ti - VOID_PEAK_T) < 1e-9 else VOID_OPEN
                m.ballast_gap.append(open_gap if abs(sl[k] - VOID_S) < 1e-9 else 0.0)
        bag.write("/pad_forces", m, _stamp(ti))


def scene_dict(track_model, vehicle_file="vehicle.yaml"):
    return {"name": "safety_synthetic",
            "track": {"gauge": 1.435, "sleeper_spacing": 0.6, "start_arc_length": 0.0, "segments": SEGMENTS},
            "vehicle": {"data": vehicle_file, "start_arc_length": START_S, "speed": SPEED, "wheelsets": 4},
            "effects": {"track_model": track_model},
            "output": {"rate": RATE, "topics": ["wheelset_kinematics", "contact_points"]}}


def write_vehicle(directory):
    bodies = [{"name": "b%d" % i, "mass": m, "centre_of_mass": [0.0, 0.0, 1.0], "inertia": [1.0, 1.0, 1.0]}
              for i, m in enumerate(MASSES)]
    with open(os.path.join(directory, "vehicle.yaml"), "w") as f:
        yaml.safe_dump({"name": "synthetic", "gravity": [0.0, 0.0, -GRAVITY], "bodies": bodies}, f)


def write_run(directory, name, floor=None, pads=None, ballast=True):
    """Writes <name>.bag (+ .track.bag for rigid_fe/flexible) and <name>.scene.yaml; floor (default: only for
    standalone) adds /floor_accelerations, pads (default: only for flexible) adds /pad_forces (ballast: with the
    sleepers' ballast forces)."""
    os.makedirs(directory, exist_ok=True)
    write_vehicle(directory)
    model = {"standalone": "rigid", "rigid_fe": "rigid_fe", "flexible": "flexible"}.get(name, "rigid")
    floor = (name == "standalone") if floor is None else floor
    pads = (name == "flexible") if pads is None else pads
    cosim = model != "rigid"
    with rosbag.Bag(os.path.join(directory, name + ".bag"), "w") as bag:
        write_kinematics(bag)
        if not cosim:
            write_points(bag)
        if floor:
            write_floor(bag)
    if cosim:
        with rosbag.Bag(os.path.join(directory, name + ".track.bag"), "w") as bag:
            write_points(bag)
            if pads:
                write_pads(bag, ballast)
    with open(os.path.join(directory, name + ".scene.yaml"), "w") as f:
        yaml.safe_dump(scene_dict(model), f)


def write_all(directory):
    for n in ("standalone", "rigid_fe", "flexible"):
        write_run(directory, n)
