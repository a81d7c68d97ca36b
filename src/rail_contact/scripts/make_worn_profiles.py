#!/usr/bin/python3
"""Makes worn example profiles from the standard shapes shipped in config/profiles/.

Usage: /usr/bin/python3 make_worn_profiles.py [--profiles DIR] [-h | --help]

Each worn shape is the standard one with a layer of material removed: every point moves along the
inward normal by a depth that varies smoothly along the profile (a cos^2 window), so the worn curve
stays smooth and joins the unworn part without a step. Writes, in DIR (default: config/profiles/ of
this workspace), plain 'y z' files in mm in the library's profile frames (doc/profiles.md):
  S1002_hollow_worn.txt      1.5 mm hollow on the tread, centred 8 mm field side of the taping line
  S1002_thin_flange.txt      flange face worn by 3 mm (flange thickness 32.5 -> about 29.5 mm)
  UIC60_1in20_side_worn.txt  gauge corner and face worn by 3 mm (rail inclined 1:20 built in)
Needs numpy (Debian's python3).
"""
import os
import sys

import numpy as np


def read_plain(path):
    rows = []
    with open(path) as f:
        for line in f:
            line = line.split("#", 1)[0].strip()
            if line:
                rows.append([float(v) for v in line.replace(",", " ").split()])
    return np.array(rows)


def read_miniprof(path):
    rows = []
    with open(path) as f:
        for line in f:
            t = line.strip()
            if not t or "=" in t or t.startswith('"'):
                continue
            x, y = (float(v) for v in t.split()[:2])
            rows.append([x, -y])  # MiniProf Y is positive down
    return np.array(rows)


def window(s, centre, half_width):
    """cos^2 bump: 1 at centre, 0 beyond half_width."""
    t = np.clip((s - centre) / half_width, -1.0, 1.0)
    return np.cos(0.5 * np.pi * t) ** 2


def wear(points, depth, solid_sign):
    """Moves points (y, z, mm, ordered along the curve, y increasing overall) by depth (mm, per point) into the solid.

    solid_sign: +1 when the solid lies to the left of the direction of increasing y (wheel), -1 when it
    lies to the right (rail).
    """
    d = np.gradient(points, axis=0)
    t = d / np.linalg.norm(d, axis=1)[:, None]
    inward = solid_sign * np.column_stack([-t[:, 1], t[:, 0]])
    return points + depth[:, None] * inward


def write_plain(path, points, comment):
    with open(path, "w") as f:
        f.write("# %s\n# units: mm\n# y z\n" % comment)
        for y, z in points:
            f.write("%+.15e %+.15e\n" % (y, z))
    print("wrote %s (%d points)" % (path, len(points)))


def main(argv):
    if "-h" in argv or "--help" in argv:
        print(__doc__)
        return 0
    here = os.path.dirname(os.path.abspath(__file__))
    out = os.path.normpath(os.path.join(here, "..", "..", "..", "config", "profiles"))
    args = argv[1:]
    if args[:1] == ["--profiles"] and len(args) == 2:
        out = args[1]
    elif args:
        print("make_worn_profiles.py: unknown arguments %s (--help lists them)" % " ".join(args), file=sys.stderr)
        return 2
    try:
        wheel = read_plain(os.path.join(out, "S1002.txt"))
        rail = read_miniprof(os.path.join(out, "UIC60_1in20.ban"))
    except (OSError, ValueError) as e:
        print("make_worn_profiles.py: %s (the standard shapes S1002.txt and UIC60_1in20.ban are read from "
              "--profiles DIR)" % e, file=sys.stderr)
        return 1
    # Keep the files' order along the curve (a vertical face has no order in y); only make y increase.
    if wheel[-1, 0] < wheel[0, 0]:
        wheel = wheel[::-1]
    if rail[-1, 0] < rail[0, 0]:
        rail = rail[::-1]
    y = wheel[:, 0]
    write_plain(os.path.join(out, "S1002_hollow_worn.txt"),
                wear(wheel, 1.5 * window(y, -8.0, 30.0), +1.0),
                "S1002 with a 1.5 mm hollow-worn tread (centred 8 mm field side of the taping line, 60 mm wide); "
                "made by make_worn_profiles.py from S1002.txt")
    # Flange face: from the flange root (y ~ 30 mm) over the tip (~ 49 mm), not the back.
    write_plain(os.path.join(out, "S1002_thin_flange.txt"),
                wear(wheel, 3.0 * window(y, 40.0, 12.0), +1.0),
                "S1002 with its flange face worn by 3 mm (thin flange); made by make_worn_profiles.py from S1002.txt")
    # Gauge corner of the inclined rail: the gauge side is +y; the corner lies about 30 mm from the axis.
    yr = rail[:, 0]
    write_plain(os.path.join(out, "UIC60_1in20_side_worn.txt"),
                wear(rail, 3.0 * window(yr, 34.0, 10.0), -1.0),
                "UIC60 inclined 1:20 with its gauge corner and face worn by 3 mm (side wear); made by "
                "make_worn_profiles.py from UIC60_1in20.ban")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
