#!/usr/bin/python3
"""The wheel-flat map's figure and table: P1 and P2 of the strike against speed, one line per flat length,
from the map.csv that railsim_map writes for config/maps/wheel_flat.yaml.

  scripts/defects/plot_flat_map.py MAP.csv FIGURE.png
Prints the table (Markdown) on stdout. Exit 2 when the CSV has no case with a speed, a flat length and both
peaks (one line on stderr)."""
import csv
import re
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402


def cases(path):
    """{length_mm: [(speed_kmh, p1_kN, p2_kN)]} of the map's successful non-reference cases."""
    out = {}
    with open(path) as f:
        for row in csv.DictReader(f):
            if row.get("reference") == "True" or row.get("status") != "ok":
                continue
            v = re.search(r"vehicle\.speed=([0-9.eE+-]+)", row.get("settings", ""))
            L = re.search(r"length: ([0-9.eE+-]+)", row.get("settings", ""))
            if not (v and L and row.get("impact_p1") and row.get("impact_p2")):
                continue
            out.setdefault(round(float(L.group(1)) * 1e3), []).append(
                (float(v.group(1)) * 3.6, float(row["impact_p1"]) / 1e3, float(row["impact_p2"]) / 1e3))
    return {k: sorted(v) for k, v in out.items()}


def main(argv):
    if len(argv) != 3:
        print(__doc__.split("\n\n")[1].strip(), file=sys.stderr)
        return 2
    data = cases(argv[1])
    if not data:
        print("%s: no case with vehicle.speed, a flat length and impact_p1/impact_p2" % argv[1], file=sys.stderr)
        return 2
    fig, axes = plt.subplots(1, 2, figsize=(10, 4), sharey=True)
    for length, pts in sorted(data.items()):
        v = [p[0] for p in pts]
        axes[0].plot(v, [p[1] for p in pts], "o-", label="%d mm" % length)
        axes[1].plot(v, [p[2] for p in pts], "o-", label="%d mm" % length)
    for ax, what in zip(axes, ("P1: unfiltered peak", "P2: peak of the 150 Hz low-pass")):
        ax.set_xlabel("speed [km/h]")
        ax.set_title(what)
        ax.grid(True, alpha=0.3)
    axes[0].set_ylabel("vertical wheel-rail force [kN]")
    axes[1].legend(title="new flat", loc="best")
    fig.suptitle("New wheel flats on the paper's coach and flexible track (config/maps/wheel_flat.yaml)")
    fig.tight_layout()
    fig.savefig(argv[2], dpi=110)
    print("| speed [km/h] | " + " | ".join("P1 / P2, %d mm [kN]" % L for L in sorted(data)) + " |")
    print("|---|" + "---|" * len(data))
    speeds = sorted({p[0] for pts in data.values() for p in pts})
    for s in speeds:
        cells = []
        for L in sorted(data):
            hit = [p for p in data[L] if abs(p[0] - s) < 1e-6]
            cells.append("%.0f / %.0f" % (hit[0][1], hit[0][2]) if hit else "")
        print("| %.0f | %s |" % (s, " | ".join(cells)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
