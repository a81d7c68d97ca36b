#!/usr/bin/env python3
"""Contact geometry of a scene's wheelset: runs contact_geometry with the wheelset and track a scene resolves
to (gauge, back-to-back distance, nominal rolling radius, rail inclination, wheel and rail profiles), and with
the scene's vehicle at rest on it: the static wheel load m g / (2 wheelsets) from the vehicle data file's
masses, the scene's speed and contact.friction. Then the plots (plot_contact_geometry.py).

  contact_geometry_for_scene.py SCENE.yaml --out-dir DIR [--set key=value ...] [--y-max M] [--dy M]
                                [--yaw RAD] [--no-load] [--workspace WS] [--no-plot]

Writes DIR/<scene>.csv, DIR/<scene>_conicity.csv and (unless --no-plot) the two PNGs, and prints the
contact_geometry command it ran. A scene the loader refuses is reported with the loader's message (exit 2).
Exit 0 on success, 2 on bad input, 1 when contact_geometry or the plot fails.
"""
import argparse
import os
import subprocess
import sys

import yaml

HERE = os.path.dirname(os.path.realpath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", "..", ".."))
G = 9.81  # [m/s^2], the vehicle data files' gravity


def resolved_scene(workspace, scene, overrides):
    """The scene as the loader resolves it (railsim_validate_scene), or exit 2 with its message."""
    tool = os.path.join(workspace, "devel", "lib", "rail_core", "railsim_validate_scene")
    cmd = [tool, scene] + sum((["--set", o] for o in overrides), [])
    p = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True)
    if p.returncode != 0:
        sys.stderr.write((p.stderr or p.stdout).strip() + "\n")
        sys.exit(2)
    return yaml.safe_load(p.stdout)


def static_wheel_load(vehicle_file, wheelsets):
    """m g / (2 wheelsets) from the masses of the vehicle data file's bodies [N]."""
    with open(vehicle_file) as f:
        data = yaml.safe_load(f)
    mass = sum(float(b["mass"]) for b in data.get("bodies", []))
    if mass <= 0.0:
        sys.stderr.write("%s: bodies: no masses to load the wheels with\n" % vehicle_file)
        sys.exit(2)
    return mass * G / (2.0 * wheelsets)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("scene")
    ap.add_argument("--out-dir", required=True)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE")
    ap.add_argument("--y-max", type=float, default=0.010)
    ap.add_argument("--dy", type=float, default=0.0001)
    ap.add_argument("--yaw", type=float, default=0.0)
    ap.add_argument("--no-load", action="store_true", help="geometry only (no loads, creepages, forces)")
    ap.add_argument("--no-plot", action="store_true")
    ap.add_argument("--workspace", default=REPO)
    a = ap.parse_args(argv)
    if not os.path.isfile(a.scene):
        sys.stderr.write("%s: cannot read the scene file\n" % a.scene)
        return 2
    s = resolved_scene(a.workspace, a.scene, a.set)
    if "vehicle" not in s:
        sys.stderr.write("%s: has no vehicle (a moving-load scene): no wheelset to tabulate\n" % a.scene)
        return 2
    here = os.path.dirname(os.path.abspath(a.scene))
    track, vehicle = s["track"], s["vehicle"]
    name = os.path.splitext(os.path.basename(a.scene))[0]
    os.makedirs(a.out_dir, exist_ok=True)
    table = os.path.join(a.out_dir, name + ".csv")
    conicity = os.path.join(a.out_dir, name + "_conicity.csv")
    cmd = [os.path.join(a.workspace, "devel", "lib", "rail_contact", "contact_geometry"), "--out", table,
           "--conicity", conicity, "--gauge", repr(float(track["gauge"])),
           "--back-to-back", repr(float(vehicle["back_to_back"])), "--radius", repr(float(vehicle["nominal_radius"])),
           "--inclination", repr(float(track["rail_inclination"])), "--y-max", repr(a.y_max), "--dy", repr(a.dy),
           "--yaw", repr(a.yaw)]
    for key, opt, builtin in (("rail_profile", "--rail", "uic60"), ("wheel_profile", "--wheel", "s1002")):
        where = track if key == "rail_profile" else vehicle
        value = str(where.get(key, builtin))
        if value != builtin:
            cmd += [opt, os.path.normpath(os.path.join(here, value))]
    if not a.no_load and not float(vehicle["speed"]) > 0.0:
        sys.stderr.write("%s: vehicle.speed is 0: the loaded columns (creepages, creep forces) need a rolling "
                         "speed; tabulating the geometry only\n" % a.scene)
        a.no_load = True
    if not a.no_load:
        q0 = static_wheel_load(os.path.normpath(os.path.join(here, vehicle["data"])), int(vehicle["wheelsets"]))
        cmd += ["--load", repr(q0), "--speed", repr(float(vehicle["speed"])),
                "--friction", repr(float((s.get("contact") or {}).get("friction", 0.3)))]
    print(" ".join(cmd), flush=True)
    if subprocess.run(cmd).returncode != 0:
        return 1
    if not a.no_plot:
        plot = [sys.executable, os.path.join(HERE, "plot_contact_geometry.py"), table, conicity, "--out",
                os.path.join(a.out_dir, name)]
        if subprocess.run(plot).returncode != 0:
            return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
