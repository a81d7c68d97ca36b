#!/usr/bin/python3
"""Plots a receptance CSV written by track_receptance: magnitude (log-log) and phase of the vertical and
lateral point receptances above a sleeper and at mid-span.

usage: plot_receptance.py receptance.csv receptance.png [--title TEXT] [--overlay other.csv LABEL]
"""
import argparse
import csv

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def read(path):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    return {k: [float(r[k]) for r in rows] for k in rows[0]}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("csv")
    ap.add_argument("png")
    ap.add_argument("--title", default="Point receptance of the track")
    ap.add_argument("--overlay", nargs=2, metavar=("CSV", "LABEL"),
                    help="a second receptance (e.g. other damping), drawn dashed")
    args = ap.parse_args()
    data = read(args.csv)
    other = read(args.overlay[0]) if args.overlay else None
    fig, ax = plt.subplots(2, 2, figsize=(11, 7), sharex=True, gridspec_kw={"height_ratios": [2, 1]})
    colours = {"sleeper": "tab:blue", "midspan": "tab:red"}
    for col, direction, name in ((0, "vert", "vertical"), (1, "lat", "lateral")):
        for place in ("sleeper", "midspan"):
            key = "%s_%s" % (direction, place)
            label = "above a sleeper" if place == "sleeper" else "mid-span"
            ax[0, col].loglog(data["f_Hz"], data[key + "_mag_m_per_N"], color=colours[place], label=label)
            ax[1, col].semilogx(data["f_Hz"], data[key + "_phase_deg"], color=colours[place])
            if other:
                ax[0, col].loglog(other["f_Hz"], other[key + "_mag_m_per_N"], "--", color=colours[place],
                                  label=label + ", " + args.overlay[1])
                ax[1, col].semilogx(other["f_Hz"], other[key + "_phase_deg"], "--", color=colours[place])
        ax[0, col].set_title(name)
        ax[0, col].set_ylabel("receptance [m/N]")
        ax[0, col].grid(True, which="both", alpha=0.3)
        ax[0, col].legend(fontsize=8)
        ax[1, col].set_ylabel("phase [deg]")
        ax[1, col].set_xlabel("frequency [Hz]")
        ax[1, col].set_ylim(-180, 10)
        ax[1, col].grid(True, which="both", alpha=0.3)
    fig.suptitle(args.title)
    fig.tight_layout()
    fig.savefig(args.png, dpi=110)


if __name__ == "__main__":
    main()
