#!/usr/bin/python3
"""Plots the CSV written by contact_geometry (rail_contact) to PNG.

Usage: /usr/bin/python3 plot_contact_geometry.py table.csv [conicity.csv] [--out prefix]
Writes <prefix>_geometry.png (rolling-radius difference, contact points, contact angles) and, with a
conicity file, <prefix>_conicity.png. Needs numpy and matplotlib (Debian's python3).
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def load(path):
    data = np.genfromtxt(path, delimiter=",", names=True, dtype=None, encoding="utf-8")
    return data


def main(argv):
    if any(a in ("-h", "--help") for a in argv[1:]):
        print(__doc__)
        return 0
    unknown = [a for a in argv[1:] if a.startswith("-") and a != "--out"]
    if unknown:
        print("plot_contact_geometry.py: unknown option %s (--help for usage)" % unknown[0], file=sys.stderr)
        return 2
    args = [a for a in argv[1:] if not a.startswith("--")]
    prefix = "contact_geometry"
    if "--out" in argv:
        prefix = argv[argv.index("--out") + 1]
        args = [a for a in args if a != prefix]
    if not args:
        print(__doc__)
        return 2
    t = load(args[0])
    y = t["y_m"] * 1e3
    fig, ax = plt.subplots(2, 2, figsize=(11, 8))
    ax[0, 0].plot(y, t["delta_r_m"] * 1e3)
    ax[0, 0].set_xlabel("lateral displacement y [mm]")
    ax[0, 0].set_ylabel("rolling-radius difference [mm]")
    for side in ("left", "right"):
        ax[0, 1].plot(y, t[side + "_y_wheel_m"] * 1e3, label=side + " wheel")
        ax[0, 1].plot(y, t[side + "_y_rail_m"] * 1e3, "--", label=side + " rail")
        ax[1, 0].plot(y, t[side + "_contact_angle_rad"], label=side)
        ax[1, 1].plot(y, t[side + "_rolling_radius_m"] * 1e3, label=side)
    ax[0, 1].set_ylabel("contact point, profile frame y [mm]")
    ax[1, 0].set_ylabel("contact angle [rad]")
    ax[1, 1].set_ylabel("rolling radius [mm]")
    for a in ax.flat:
        a.set_xlabel("lateral displacement y [mm]")
        a.grid(True)
    for a in (ax[0, 1], ax[1, 0], ax[1, 1]):
        a.legend()
    fig.tight_layout()
    fig.savefig(prefix + "_geometry.png", dpi=120)
    print("wrote", prefix + "_geometry.png")
    if len(args) > 1:
        c = load(args[1])
        fig, ax = plt.subplots(figsize=(6, 4))
        ax.plot(c["amplitude_m"] * 1e3, c["equivalent_conicity"], "o-")
        ax.set_xlabel("amplitude [mm]")
        ax.set_ylabel("equivalent conicity [-]")
        ax.grid(True)
        fig.tight_layout()
        fig.savefig(prefix + "_conicity.png", dpi=120)
        print("wrote", prefix + "_conicity.png")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
