#!/usr/bin/python3
"""The Manchester contact benchmark A-2.2: runs contact_geometry on the benchmark's own profiles and sets
the result beside the published reference results of the CONTACT code.

Usage: /usr/bin/python3 manchester_a22.py [--workspace WS] [--out DIR] [-h | --help]

Case A-2.2: S1002 wheel on UIC60 rail inclined 1:40 (config/profiles/manchester_a22/), gauge 1435 mm,
back-to-back 1360 mm, r0 460 mm, wheelset shift 0..10 mm toward the right rail in 0.5 mm steps with a
yaw of 2.4 mrad per mm, 10 kN vertical load per wheel, V 2 m/s, mu 0.3, G 82 GPa, nu 0.28; the
wheelset's height and roll carry the loads, its pitch rate lets it roll freely.

Writes to DIR (default output/manchester_a22): a22.csv (the tool's table), comparison.md (per shift and
wheel: this code beside CONTACT, and the worst difference per quantity) and contact_points.png (contact
points on the wheel and rail profiles, coloured by shift). The reference results are
docs/benchmarks/manchester_a22/contact_a22_{left,right}.csv (their source is in SOURCE.md there).
Exit 0 on success, 1 when the tool or a file fails, 2 on bad arguments. Needs numpy and matplotlib.
"""
import argparse
import csv
import os
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
WS_DEFAULT = os.path.normpath(os.path.join(HERE, "..", "..", ".."))

# Quantities compared: (key, label, unit, this code's value from a row, CONTACT's value from a row).
# CONTACT's frames (its user guide): profile y toward the field side, z down, forces on the rail; this
# code's: y toward the gauge side / flange, z up, forces on the wheel (doc/geometry.md). The signs below
# map CONTACT's values into this code's frame; creep forces and creepages are compared by magnitude
# (their tangent-plane axes differ in sign between the codes). CONTACT mirrors the left side: its lateral
# profile coordinates change sign between the wheels.


def side_sign(c):
    return -1.0 if c["side"] == "right" else 1.0


QUANTITIES = [
    ("y_rail", "contact on rail from top, gauge side +", "mm",
     lambda w: 1e3 * w["y_rail_from_top_m"], lambda c: side_sign(c) * c["ycp_r_mm"]),
    ("y_wheel", "contact on wheel from taping line, flange +", "mm",
     lambda w: 1e3 * w["y_wheel_m"], lambda c: side_sign(c) * c["ycp_w_mm"]),
    ("angle", "contact angle to the track plane", "rad", lambda w: w["contact_angle_track_rad"],
     lambda c: abs(c["deltcp_tr_rad"])),
    ("radius", "rolling radius", "mm", lambda w: 1e3 * w["rolling_radius_m"], lambda c: 460.0 + c["zcp_w_mm"]),
    ("N", "normal load", "N", lambda w: w["N_N"], lambda c: c["fn_N"]),
    ("nu_x", "|longitudinal creepage|", "-", lambda w: abs(w["nu_x"]), lambda c: abs(c["cksi"])),
    ("nu_y", "|lateral creepage|", "-", lambda w: abs(w["nu_y"]), lambda c: abs(c["ceta"])),
    ("phi", "|spin creepage|", "1/m", lambda w: abs(w["phi_1pm"]), lambda c: abs(1e3 * c["cphi_1pmm"])),
    ("F_x", "|longitudinal creep force|", "N", lambda w: abs(w["F_long_N"]), lambda c: abs(c["fx_N"])),
    ("F_y", "|lateral creep force|", "N", lambda w: abs(w["F_lat_N"]), lambda c: abs(c["fs_N"])),
]


def read_csv(path, numeric=True):
    with open(path) as f:
        rows = list(csv.DictReader(f))
    if numeric:
        for r in rows:
            for k, v in r.items():
                try:
                    r[k] = float(v)
                except ValueError:
                    pass
    return rows


def wheel_of(row, side):
    p = side + "_"
    return {k[len(p):]: v for k, v in row.items() if k.startswith(p)}


def run_tool(ws, table):
    prof = os.path.join(ws, "config", "profiles", "manchester_a22")
    tool = os.path.join(ws, "devel", "lib", "rail_contact", "contact_geometry")
    cmd = [tool, "--out", table, "--wheel", os.path.join(prof, "MBench_S1002_v3.prw"),
           "--rail", os.path.join(prof, "MBench_UIC60_v3.prr"), "--inclination", "0", "--gauge", "1.435",
           "--back-to-back", "1.360", "--radius", "0.46", "--y-min", "-0.010", "--y-max", "0", "--dy", "0.0005",
           "--yaw-per-shift", "2.4", "--load", "10000", "--speed", "2", "--friction", "0.3"]
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    sys.stderr.write(p.stderr)
    if p.returncode != 0:
        sys.stderr.write("manchester_a22.py: contact_geometry failed (exit %d): %s\n" % (p.returncode, " ".join(cmd)))
        return None
    return cmd


def compare(ours, ref):
    """Pairs of (shift_mm, side, ours wheel dict, reference row) for every shift of the reference."""
    by_shift = {round(-1e3 * r["y_m"], 3): r for r in ours}
    pairs = []
    for side in ("right", "left"):
        for c in ref[side]:
            s = round(c["y_ws_mm"], 3)
            if s not in by_shift:
                raise KeyError("shift %.1f mm: no row in this code's table" % s)
            w = wheel_of(by_shift[s], side)
            # The tool's angle is the normal's inclination to the axle; CONTACT's to the track plane.
            w["contact_angle_track_rad"] = w["contact_angle_rad"] + (1.0 if side == "left" else -1.0) * by_shift[s]["roll_rad"]
            pairs.append((s, side, w, c, by_shift[s]))
    return pairs


def markdown(pairs, cmd):
    out = ["<!-- written by src/rail_contact/scripts/manchester_a22.py; do not edit by hand -->", ""]
    out.append("Command: `%s`" % " ".join(os.path.relpath(a) if os.path.isabs(a) else a for a in cmd))
    out.append("")
    for side in ("right", "left"):
        out.append("### %s wheel" % side.capitalize())
        out.append("")
        out.append("| shift mm | yaw mrad | surface | rail pos mm (CONTACT) | wheel pos mm (CONTACT) | angle rad (CONTACT) | "
                   "radius mm (CONTACT) | N kN (CONTACT) | a x b mm | nu_x (CONTACT) | nu_y (CONTACT) | phi 1/m (CONTACT) | "
                   "F_x kN (CONTACT) | F_y kN (CONTACT) | pitch rate rad/s (CONTACT) |")
        out.append("|" + "---|" * 15)
        for s, sd, w, c, row in pairs:
            if sd != side:
                continue
            q = {k: (f(w), g(c)) for k, _, _, f, g in QUANTITIES}
            out.append("| %.1f | %.1f | %s | %.2f (%.2f) | %.2f (%.2f) | %.4f (%.4f) | %.3f (%.3f) | %.2f (%.2f) | "
                       "%.1f x %.1f | %.2e (%.2e) | %.2e (%.2e) | %.3f (%.3f) | %.2f (%.2f) | %.2f (%.2f) | %.4f (%.4f) |" % (
                           s, -1e3 * row["yaw_rad"], w["kind"], q["y_rail"][0], q["y_rail"][1], q["y_wheel"][0],
                           q["y_wheel"][1], q["angle"][0], q["angle"][1], q["radius"][0], q["radius"][1],
                           q["N"][0] / 1e3, q["N"][1] / 1e3, 1e3 * w["a_m"], 1e3 * w["b_m"], q["nu_x"][0], q["nu_x"][1],
                           q["nu_y"][0], q["nu_y"][1], q["phi"][0], q["phi"][1], q["F_x"][0] / 1e3, q["F_x"][1] / 1e3,
                           q["F_y"][0] / 1e3, q["F_y"][1] / 1e3, row["pitch_rate_rad_s"], -c["vpitch_rad_s"]))
        out.append("")
    out.append("### Worst difference per quantity (this code minus CONTACT)")
    out.append("")
    out.append("| quantity | unit | worst, tread (shift, wheel) | worst, flange (shift, wheel) |")
    out.append("|---|---|---|---|")
    for k, label, unit, f, g in QUANTITIES:
        cells = []
        for kind in ("tread", "flange"):
            worst = None
            for s, sd, w, c, row in pairs:
                if w["kind"] != kind:
                    continue
                d = f(w) - g(c)
                if worst is None or abs(d) > abs(worst[0]):
                    worst = (d, s, sd)
            cells.append("-" if worst is None else "%+.3g (%.1f mm, %s)" % worst)
        out.append("| %s | %s | %s | %s |" % (label, unit, cells[0], cells[1]))
    onset = [s for s, sd, w, c, row in pairs if sd == "right" and w["kind"] == "flange"]
    ref_onset = None
    prev = None
    for s, sd, w, c, row in sorted(pairs, key=lambda p: p[0]):
        if sd != "right":
            continue
        if prev is not None and c["roll_ws_rad"] - prev < -2e-3:
            ref_onset = s
            break
        prev = c["roll_ws_rad"]
    out.append("")
    out.append("Right wheel on its flange from shift %s mm (this code; CONTACT's roll angle jumps at %s mm)." % (
        "%.1f" % min(onset) if onset else "none", "%.1f" % ref_onset if ref_onset is not None else "none"))
    return "\n".join(out) + "\n"


def simpack_points(path, sign_y, sign_z):
    """The (y, z) rows of a SIMPACK profile's point table as written (mm), times sign_y and sign_z; the
    spline block's modifications are not applied (the benchmark's files need only their signs)."""
    pts, inside = [], False
    with open(path) as fh:
        for line in fh:
            t = line.split("!", 1)[0].strip()
            if t == "point.begin":
                inside = True
            elif t == "point.end":
                inside = False
            elif inside and t:
                y, z = (float(v) for v in t.split()[:2])
                pts.append((sign_y * y, sign_z * z))
    return pts


def plot(pairs, ws, path):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    prof = os.path.join(ws, "config", "profiles", "manchester_a22")
    # Library frames: rail y toward the gauge side, z up; wheel y toward the flange, z up (radius r0 - z).
    rail = list(zip(*simpack_points(os.path.join(prof, "MBench_UIC60_v3.prr"), -1.0, -1.0)))
    wheel = list(zip(*simpack_points(os.path.join(prof, "MBench_S1002_v3.prw"), 1.0, -1.0)))  # mirrors y itself
    fig, ax = plt.subplots(2, 1, figsize=(10, 9))
    fig.subplots_adjust(hspace=0.35)
    cmap = plt.get_cmap("viridis")
    for side, marker in (("right", "o"), ("left", "s")):
        sel = [p for p in pairs if p[1] == side]
        shifts = [p[0] for p in sel]
        col = [cmap(s / 10.0) for s in shifts]
        ax[0].scatter([1e3 * p[2]["y_rail_m"] for p in sel], [1e3 * p[2]["z_rail_m"] for p in sel], c=col, marker=marker,
                      label="%s wheel, this code" % side, zorder=3)
        ax[0].scatter([side_sign(p[3]) * p[3]["ycp_r_mm"] for p in sel], [-p[3]["zcp_r_mm"] for p in sel], facecolors="none",
                      edgecolors=col, marker=marker, s=90, label="%s wheel, CONTACT" % side, zorder=3)
        ax[1].scatter([1e3 * p[2]["y_wheel_m"] for p in sel], [1e3 * p[2]["z_wheel_m"] for p in sel], c=col, marker=marker,
                      label="%s wheel, this code" % side, zorder=3)
        ax[1].scatter([side_sign(p[3]) * p[3]["ycp_w_mm"] for p in sel], [-p[3]["zcp_w_mm"] for p in sel], facecolors="none",
                      edgecolors=col, marker=marker, s=90, label="%s wheel, CONTACT" % side, zorder=3)
    panels = ((rail, (-35, 45), (-20, 2), "Contact points on the rail (UIC60 1:40, origin at its highest point)",
               "y toward the gauge side [mm]", "z [mm]"),
              (wheel, (-40, 50), (-30, 3), "Contact points on the wheel (S1002, origin on the taping line)",
               "y toward the flange [mm]", "z toward the axle [mm]"))
    for a, (curve, xlim, ylim, title, xlabel, ylabel) in zip(ax, panels):
        a.plot(curve[0], curve[1], "k-", lw=1)
        a.set_xlim(*xlim)
        a.set_ylim(*ylim)
        a.set_title(title)
        a.set_xlabel(xlabel)
        a.set_ylabel(ylabel)
        a.grid(True, alpha=0.3)
        a.legend(fontsize=8, loc="lower left")
    sm = plt.cm.ScalarMappable(cmap=cmap, norm=plt.Normalize(0, 10))
    fig.colorbar(sm, ax=ax, label="wheelset shift toward the right rail [mm]")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0],
                                 formatter_class=argparse.RawDescriptionHelpFormatter, epilog=__doc__)
    ap.add_argument("--workspace", default=WS_DEFAULT, help="catkin workspace (default: this one)")
    ap.add_argument("--out", default=None, help="output directory (default WS/output/manchester_a22)")
    a = ap.parse_args(argv)
    out = a.out or os.path.join(a.workspace, "output", "manchester_a22")
    tool = os.path.join(a.workspace, "devel", "lib", "rail_contact", "contact_geometry")
    if not os.access(tool, os.X_OK):
        sys.stderr.write("manchester_a22.py: %s: not built (run ./railsim setup in %s)\n" % (tool, a.workspace))
        return 1
    os.makedirs(out, exist_ok=True)
    table = os.path.join(out, "a22.csv")
    cmd = run_tool(a.workspace, table)
    if cmd is None:
        return 1
    refdir = os.path.join(a.workspace, "docs", "benchmarks", "manchester_a22")
    try:
        ours = read_csv(table)
        ref = {s: read_csv(os.path.join(refdir, "contact_a22_%s.csv" % s)) for s in ("right", "left")}
        for s_, rows_ in ref.items():
            for r_ in rows_:
                r_["side"] = s_
        pairs = compare(ours, ref)
    except (OSError, KeyError) as e:
        sys.stderr.write("manchester_a22.py: %s\n" % e)
        return 1
    md = markdown(pairs, cmd)
    with open(os.path.join(out, "comparison.md"), "w") as f:
        f.write(md)
    plot(pairs, a.workspace, os.path.join(out, "contact_points.png"))
    print("wrote %s, %s and %s" % (table, os.path.join(out, "comparison.md"), os.path.join(out, "contact_points.png")))
    return 0


if __name__ == "__main__":
    sys.exit(main())
