#!/usr/bin/env python3
"""Writes a train of N identical coaches as one vehicle data file: the coach's bodies, wheels, joints and
force elements N times, coach k shifted back by (k - 1) * --length along x, and one coupler between the
carbodies of neighbouring coaches. Prints the file to standard output (or --out FILE); exit 0 on success,
2 on a usage or input error (named file and field).

  scripts/make_train.py COACH.yaml N [--length 24.5] [--carbody carbody] [--coupler-height 1.06]
                        [--coupler-stiffness KX,KY,KZ] [--coupler-damping CX,CY,CZ] [--out FILE]

Names: wheelset bodies ws<j> and axleboxes ab<j>_... are renumbered along the train (coach 2 of a
4-wheelset coach has ws5..ws8), so that ws1 stays the leading wheelset; every other name of coach k > 1
gets the suffix _c<k>. The wheelsets are ordered by x in the simulator whatever their names.

The coupler is a bushing at x = the coaches' common end (half a --length behind the first carbody's
centre of mass), y = 0, z = --coupler-height. Its default values are illustrative, not a published vehicle's:
2 MN/m and 20 kN s/m along the train (draw gear and buffers of the order of a UIC screw coupling), 0.1 MN/m
and 5 kN s/m across it (a coupler bar carries little lateral or vertical load between two carbodies that
ride on their own bogies). Give a real vehicle's values with the options.
"""
import argparse
import copy
import re
import sys

import yaml


def fail(message):
    print("make_train.py: " + message, file=sys.stderr)
    sys.exit(2)


def triple(text, option):
    try:
        values = [float(v) for v in text.split(",")]
    except ValueError:
        values = []
    if len(values) != 3 or any(v < 0.0 for v in values):
        fail(f"{option}: three values >= 0 separated by commas, got '{text}'")
    return values


def rename(name, coach, wheelsets):
    """The name of body/element `name` of coach `coach` (1-based) in the train."""
    if coach == 1:
        return name
    shift = (coach - 1) * wheelsets

    def renumber(m):
        return m.group(1) + str(int(m.group(2)) + shift)

    # ws<j> and ab<j> wherever they stand in a name (bearing_ws1_left, primary_ws1_left, ab1_left).
    new = re.sub(r"((?:^|_)(?:ws|ab))(\d+)", renumber, name)
    if new == name:
        return f"{name}_c{coach}"
    return new


def shifted(point, dx):
    return [float(point[0]) + dx, float(point[1]), float(point[2])]


def main():
    ap = argparse.ArgumentParser(description="A train of N identical coaches as one vehicle data file.")
    ap.add_argument("coach")
    ap.add_argument("n", type=int)
    ap.add_argument("--length", type=float, default=24.5, help="coach length over the couplers [m]")
    ap.add_argument("--carbody", default="carbody", help="the coach's carbody body name")
    ap.add_argument("--coupler-height", type=float, default=1.06, help="coupler height above the rail top [m]")
    ap.add_argument("--coupler-stiffness", default="2.0e6,1.0e5,1.0e5", help="x,y,z [N/m]")
    ap.add_argument("--coupler-damping", default="20.0e3,5.0e3,5.0e3", help="x,y,z [N s/m]")
    ap.add_argument("--out", help="write here instead of standard output")
    a = ap.parse_args()
    if a.n < 1:
        fail(f"N: at least 1 coach, got {a.n}")
    if not a.length > 0.0:
        fail(f"--length: must be > 0 m, got {a.length}")
    stiffness = triple(a.coupler_stiffness, "--coupler-stiffness")
    damping = triple(a.coupler_damping, "--coupler-damping")
    try:
        with open(a.coach) as f:
            coach = yaml.safe_load(f)
    except OSError as e:
        fail(f"{a.coach}: {e.strerror}")
    except yaml.YAMLError as e:
        fail(f"{a.coach}: not YAML ({e})")
    if not isinstance(coach, dict) or not isinstance(coach.get("bodies"), list):
        fail(f"{a.coach}: bodies: a list of bodies is needed")
    bodies = {b.get("name") for b in coach["bodies"]}
    if a.carbody not in bodies:
        fail(f"{a.coach}: bodies: no body named '{a.carbody}' (--carbody)")
    carbody = next(b for b in coach["bodies"] if b["name"] == a.carbody)
    wheelsets = len({p["body"] for p in coach.get("load_points", [])})
    if wheelsets == 0:
        fail(f"{a.coach}: load_points: the coach has no wheels")

    train = {"name": f"{coach.get('name', 'coach')}_x{a.n}", "gravity": coach.get("gravity", [0.0, 0.0, -9.81])}
    for key in ("bodies", "measurement_points", "load_points", "joints", "forces"):
        train[key] = []
    for k in range(1, a.n + 1):
        dx = -(k - 1) * a.length
        for key in ("bodies", "measurement_points", "load_points", "joints", "forces"):
            for item in coach.get(key, []) or []:
                e = copy.deepcopy(item)
                e["name"] = rename(e["name"], k, wheelsets)
                for ref in ("body", "body_i", "body_j"):
                    if ref in e:
                        e[ref] = rename(e[ref], k, wheelsets)
                for pos in ("centre_of_mass", "position"):
                    if pos in e:
                        e[pos] = shifted(e[pos], dx)
                train[key].append(e)
    end_x = float(carbody["centre_of_mass"][0]) - 0.5 * a.length
    for k in range(1, a.n):
        train["forces"].append({
            "name": f"coupler_{k}_{k + 1}", "type": "bushing",
            "body_i": rename(a.carbody, k, wheelsets), "body_j": rename(a.carbody, k + 1, wheelsets),
            "position": [end_x - (k - 1) * a.length, 0.0, a.coupler_height],
            "stiffness": stiffness, "damping": damping})

    header = (f"# {a.n} coaches of {a.coach.split('/')[-1]} coupled, written by scripts/make_train.py "
              f"(--length {a.length}, coupler stiffness {a.coupler_stiffness} N/m, damping "
              f"{a.coupler_damping} N s/m at z = {a.coupler_height} m).\n"
              "# The coach data and their sources: the coach file. The coupler values are illustrative "
              "(scripts/make_train.py).\n")
    text = header + yaml.safe_dump(train, sort_keys=False, default_flow_style=None, width=120)
    if a.out:
        try:
            with open(a.out, "w") as f:
                f.write(text)
        except OSError as e:
            fail(f"{a.out}: {e.strerror}")
    else:
        sys.stdout.write(text)
    return 0


if __name__ == "__main__":
    sys.exit(main())
