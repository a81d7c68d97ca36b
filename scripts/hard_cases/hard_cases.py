"""The hard-case suite: scenes at the edges of what the simulator must survive (wheel lift-off, two-point
contact in a tight curve, standstill, hunting above the critical speed, the coarse corner of the
accuracy-cost map, poor track, a stiff pad on soft ballast, a wheel climbing the rail), each run on the
track models where it means something, checked for finite outputs, bounded contact forces, a bounded
energy balance and convergence of a named key figure, and written as a table into docs/hard_cases.md.

The runs use rail_analysis.runner.run_case (own ROS master on a free port per run, a wall-time limit,
the launch stopped cleanly on timeout); the bags are read with rail_analysis.loading. Scenes live in
config/scenes/hard/ (one per case, each with a header comment saying why its settings).

Units: SI throughout (m, s, N, J); the table writes forces in kN and displacements in mm.
"""
import concurrent.futures
import math
import os
import re
import sys
import time

import numpy as np
import yaml

HERE = os.path.dirname(os.path.realpath(__file__))
REPO = os.path.normpath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(REPO, "src", "rail_analysis", "src"))

from rail_analysis import costmap, loading, runner, safety  # noqa: E402  (after the path set-up above)

SCENES = os.path.join(REPO, "config", "scenes", "hard")
MODELS = ("rigid", "rigid_fe", "flexible")
DOCS_MARKER = "<!-- everything below this line is written by scripts/hard_cases/run_hard_cases.py -->"
# Solver defaults of the scene format (docs/scene.md, solver): used when a scene does not set them.
SOLVER_DEFAULTS = {"track_step": 2e-5, "vehicle_max_step": 2e-5, "vehicle_rtol": 1e-6, "vehicle_atol": 1e-8}
# The vehicle node's log line for a derailment (src/rail_vehicle_node/src/node/vehicle_node.cpp).
# roslaunch's line for the vehicle node's exit (its own code; roslaunch itself exits 0).
VEHICLE_EXIT = re.compile(r"process has died \[pid \d+, exit code (-?\d+), cmd \S*vehicle_node")
DERAIL_LOG = re.compile(r"run stopped \(derailed\)[^:]*: derailment: (.*?at s = ([-0-9.e+]+) m, t = ([-0-9.e+]+) s)")
# Contact force bound: Q < FORCE_FACTOR * Q0 + IMPACT_MARGIN * F_impact. A wheel load five times its static
# value Q0 is far beyond any measured running load (EN 14363's limit Q_lim is 145-200 kN, about 2-3 Q0 here)
# yet well below what a numerical blow-up produces. A wheel that lands on a rigid rail is another matter:
# Hertz's impact of a mass m at approach speed v on a contact N = K delta^1.5 peaks at
#   F_impact = (5/4 m v^2)^(3/5) K^(2/5)
# (energy 1/2 m v^2 = integral of K delta^1.5 = 2/5 K delta^2.5 at the deepest point), 2.9 MN for half a
# wheelset (900 kg) at 1.5 m/s with K ~ 1e11 N/m^1.5. For a landing the suite takes m = half the wheelset
# mass and v = the largest downward speed of a wheel in the run (wheelset vertical speed and roll rate times
# WHEEL_HALF_SPACING, from /wheelset_kinematics; an upper bound of the speed relative to the rail); for a
# flange strike the whole wheelset at its largest lateral speed, of whose normal force at most
# sqrt(1 + mu^2) shows as Q. K = the larger of the medians of N / delta^1.5 over the run's active tread
# and flange contacts (/contact_points): the run's own Hertz constant. IMPACT_MARGIN covers the primary
# suspension's push and the sampling of the peak.
FORCE_FACTOR = 5.0
IMPACT_MARGIN = 1.25
WHEEL_HALF_SPACING = 0.85   # [m] half the distance between the contact points (Iberian gauge 1.668 m)
# Energy balance (effects.energy_output): the coach coasts (no drive, no brake) and the rails are fixed or
# elastic, so nothing puts energy in: the vehicle's mechanical energy plus the flexible track's may never
# rise above its start value by more than
#   ENERGY_REL * kinetic energy at the start  (10x the vehicle's default rtol of 1e-6: the integrator's error
#                                             on the velocities, squared into the energy)
# + ENERGY_ABS                                (the Hertz contact springs, which neither topic counts: 8 wheels
#                                             x 2/5 Q delta is 23 J at the static load Q0 = 72.9 kN, delta
#                                             ~0.1 mm, and 74 J at 2 Q0 with delta ~ Q^(2/3); 100 J covers it).
ENERGY_REL = 1e-5
ENERGY_ABS = 100.0


class Case(object):
    """One hard case: key (also the scene's stem), title, what it checks, models it runs on (all subset)
    and in the CI subset (each with its refined run), its expectation ('run', 'derail', 'run_or_refuse'),
    the key figure (name, unit, function of the run's data, allowed relative change under refinement,
    why), and per-model extra overrides."""

    def __init__(self, key, title, checks, models, ci_models, key_figure, expect="run", extra=None, specific=None):
        self.key = key
        self.scene = os.path.join(SCENES, key + ".yaml")
        self.title = title
        self.checks = checks
        self.models = tuple(models)
        self.ci_models = tuple(ci_models)
        self.key_figure = key_figure          # (name, unit, scale for the table, function(data), rel tol, why)
        self.expect = expect
        self.extra = extra or {}              # {model: {key: value}}
        self.specific = specific              # function(data) -> (status, text): the case's own check


# ----------------------------------------------------------------------------------------- key figures

def _leading_q(d, side):
    k = d["kin"]
    f = k["right_force"] if side == "right" else k["left_force"]
    return k["t"], f[:, 0, 2]


def peak_q_leading_right(d):
    """Largest vertical contact force on the leading wheelset's right wheel [N] (the landing impact)."""
    return float(np.nanmax(_leading_q(d, "right")[1]))


def mean_y_leading_outer(d):
    """Mean lateral contact force on the leading wheelset's outer (right) wheel over the last 0.3 s [N]."""
    k = d["kin"]
    sel = k["t"] >= k["t"][-1] - 0.3
    return float(np.nanmean(k["right_force"][sel, 0, 1]))


def mean_q_all(d):
    """Mean vertical contact force over all wheels in the last 0.2 s [N]."""
    k = d["kin"]
    sel = k["t"] >= k["t"][-1] - 0.2
    return float(np.nanmean(np.concatenate([k["left_force"][sel, :, 2].ravel(), k["right_force"][sel, :, 2].ravel()])))


def lateral_amplitude_late(d):
    """Largest |lateral displacement| of the leading wheelset over the second half of the run [m]."""
    k = d["kin"]
    sel = k["t"] >= 0.5 * k["t"][-1]
    return float(np.nanmax(np.abs(k["lateral"][sel, 0])))


def q_rms_leading(d):
    """RMS of the leading wheelset's vertical contact forces (both wheels) after 0.1 s [N]."""
    k = d["kin"]
    sel = k["t"] >= 0.1
    q = np.concatenate([k["left_force"][sel, 0, 2], k["right_force"][sel, 0, 2]])
    return float(np.sqrt(np.nanmean(q * q)))


# The impact cases' defects come after this [s]: before it, the co-simulation's start (the vehicle, settled
# on rigid rails, meets the elastic track) loads a wheel up to 1.35 Q0 around t = 0.01 s.
IMPACT_FROM = 0.05


def p2_leading_left(d):
    """P2 of the leading wheelset's left wheel: the largest vertical force low-passed at 150 Hz [N]
    (rail_analysis.safety.p2_force) from IMPACT_FROM on."""
    t, q = _leading_q(d, "left")
    qp2 = safety.p2_force(t, q)
    return float(np.nanmax(qp2[t >= IMPACT_FROM])) if qp2 is not None else float("nan")


def derail_time(d):
    """Simulated time at which the derailment was detected [s] (from the vehicle node's log)."""
    m = DERAIL_LOG.search(d["log"])
    return float(m.group(3)) if m else float("nan")


# --------------------------------------------------------------------------------------- case checks

def check_lift_off(d):
    """The leading right wheel leaves the rail (Q < 1 N) and lands again (Q > 0.5 Q0 afterwards)."""
    t, q = _leading_q(d, "right")
    off = np.where(q < 1.0)[0]
    if off.size == 0:
        return "fail", "no lift-off: min Q = %.1f kN" % (np.nanmin(q) / 1e3)
    after = q[off[-1] + 1:]
    back = after.size and np.nanmax(after) > 0.5 * d["q0"]
    dur = off.size * (t[1] - t[0]) if len(t) > 1 else 0.0
    return ("pass" if back else "fail"), "airborne %.1f ms from t = %.3f s, %s" % (
        dur * 1e3, t[off[0]], "re-contact, peak Q %.0f kN" % (np.nanmax(after) / 1e3) if back else "no re-contact")


def check_two_point(d):
    """Tread and flange contact active at once on the leading outer (right) wheel (wheel_id 1)."""
    cp = d.get("points")
    if cp is None:
        return "n/a", "no /contact_points in the bags"
    wid = 1
    tread = (cp["active"] & (cp["kind"] == loading.KIND_TREAD) & (cp["wheel_id"] == wid)).any(axis=1)
    flange = (cp["active"] & (cp["kind"] == loading.KIND_FLANGE) & (cp["wheel_id"] == wid)).any(axis=1)
    both = tread & flange
    late = cp["t"] >= cp["t"][-1] - 0.3
    frac = float(both[late].mean()) if late.any() else 0.0
    fn = loading.flange_normal_force(cp, wid)
    return ("pass" if frac > 0.5 else "fail"), "two-point contact on %.0f %% of the last 0.3 s; flange N max %.1f kN" % (
        100 * frac, np.nanmax(fn) / 1e3)


def check_static(d):
    """Settled vertical wheel force equals the closed-form static wheel load Q0 = m g / 8 within 2 %."""
    q = mean_q_all(d)
    err = q / d["q0"] - 1.0
    # 2 %: the carbody's bounce on the secondary suspension (about 1 Hz) is not fully settled after 0.5 s;
    # the mean over 0.2 s keeps a fraction of its amplitude.
    return ("pass" if abs(err) < 0.02 else "fail"), "mean Q %.2f kN vs Q0 %.2f kN (%+.2f %%)" % (
        q / 1e3, d["q0"] / 1e3, 100 * err)


def check_bounded_hunting(d):
    """Leading wheelset lateral motion bounded: |y| < 20 mm (inside the flangeway plus flange climb) and
    the amplitude of the last quarter not above 1.2 x that of the quarter before (no growth)."""
    k = d["kin"]
    y = k["lateral"][:, 0]
    t = k["t"]
    T = t[-1]
    q3 = np.nanmax(np.abs(y[(t >= 0.5 * T) & (t < 0.75 * T)]))
    q4 = np.nanmax(np.abs(y[t >= 0.75 * T]))
    ymax = np.nanmax(np.abs(y))
    ok = ymax < 0.020 and q4 <= 1.2 * q3 + 1e-4
    cyc = "limit cycle" if q4 > 1e-3 else "decays (below the critical speed?)"
    return ("pass" if ok else "fail"), "|y| max %.2f mm; amplitude %.2f -> %.2f mm over the last two quarters: %s" % (
        ymax * 1e3, q3 * 1e3, q4 * 1e3, cyc)


def check_derailed(d):
    """The log names the derailed wheel, s and t; exit code 7; bag readable with messages."""
    m = DERAIL_LOG.search(d["log"])
    if not m:
        return "fail", "no 'run stopped (derailed)' line in the log (exit %s)" % d["exit_code"]
    # 7: derailed (README's exit codes), the vehicle node's own code (in a co-simulation the track node then
    # stops with 4, its peer gone). The scene drives the outer (right) wheels up the rail: the message names
    # a right wheel lifted, or a wheelset off the centre line to the right (negative lateral offset), which
    # is what the flexible track shows first, its rail rolling out under the climbing flange.
    code = d["vehicle_exit_code"]
    outward = "right)" in m.group(1) or re.search(r"wheelset \d+ is -", m.group(1)) is not None
    ok = code == 7 and d["bag_messages"] > 0 and outward
    return ("pass" if ok else "fail"), "'%s', vehicle node exit %s, bag readable with %d messages" % (
        m.group(1), code, d["bag_messages"])


# British Rail's P2 formula (Jenkins, Stephenson, Clayton, Morland and Lyon, "The effect of track and vehicle
# parameters on wheel/rail vertical dynamic forces", Railway Engineering Journal 3(1), 1974; as restated by
# Mandal, Dhanasekar and Sun, Proc. IMechE Part F 230(1), 2016, doi 10.1177/0954409714537816):
#   P2 = P0 + 2 alpha V sqrt(Mu / (Mu + Mt)) (1 - Ct pi / (4 sqrt(Kt (Mu + Mt)))) sqrt(Kt Mu)
# with BR's constants for concrete-sleeper track, per rail: Kt = 150 MN/m, Mt = 245 kg, Ct = 55.7 kN s/m.
# This track's own static stiffness under one wheel is 141 MN/m (docs/receptance: 7.1e-9 m/N at 10 Hz), close
# to BR's Kt; its receptance has no single-mass shape to fit Mt and Ct to, so BR's are kept.
BR_KT, BR_MT, BR_CT = 150e6, 245.0, 55.7e3
# 15 %: the formula idealises wheel and track as two masses on springs, linear, with BR's empirical track
# mass and damping; the model's track is a beam on discrete supports with its own.
BR_P2_TOLERANCE = 0.15


def british_rail_p2(p0, dip_angle, speed, mu):
    """P2 [N] of a dipped joint of total angle dip_angle [rad] at speed [m/s], unsprung mass mu [kg] per wheel."""
    m = mu + BR_MT
    return p0 + dip_angle * speed * math.sqrt(mu / m) * (1.0 - BR_CT * math.pi / (4.0 * math.sqrt(BR_KT * m))) \
        * math.sqrt(BR_KT * mu)


def check_p2_british_rail(d):
    """The leading wheel's P2 within BR_P2_TOLERANCE of British Rail's formula (flexible track only)."""
    if d.get("model") != "flexible":
        return "n/a", "BR's formula needs the track's mass and stiffness: flexible track only"
    joint = d["scene"]["track"]["defects"][0]
    speed = float(d["scene"]["vehicle"]["speed"])
    mu = 0.5 * d["wheelset_mass"]
    expected = british_rail_p2(d["q0"], float(joint["dip_angle"]), speed, mu)
    got = p2_leading_left(d)
    err = got / expected - 1.0
    return ("pass" if abs(err) <= BR_P2_TOLERANCE else "fail"), (
        "P2 %.1f kN vs British Rail's %.1f kN (%+.1f %%, tolerance %.0f %%; Mu %.0f kg, P0 %.1f kN)"
        % (got / 1e3, expected / 1e3, 100 * err, 100 * BR_P2_TOLERANCE, mu, d["q0"] / 1e3))


def check_flat_strike(d):
    """The flatted wheel leaves the rail (Q < 1 N) before the strike and strikes (Q > 2 Q0) within 3 ms of the
    instant its rolling angle brings the flat's centre to the rail."""
    v = d["scene"]["vehicle"]
    flat = v["wheel_defects"][0]
    r0 = float(v.get("nominal_radius", 0.445))
    angle = float(flat.get("angle", 0.0))
    hit = ((angle if angle > 0 else 2 * math.pi + angle) * r0) / float(v["speed"])
    t, q = _leading_q(d, "left")
    before = (t > hit - 0.01) & (t < hit)
    after = (t >= hit - 0.003) & (t < hit + 0.003)
    if not before.any() or not after.any():
        return "fail", "the run does not reach the strike at t = %.4f s" % hit
    least = float(np.nanmin(q[before]))
    i = int(np.nanargmax(np.where(after, q, -np.inf)))
    ok = least < 1.0 and q[i] > 2.0 * d["q0"]
    return ("pass" if ok else "fail"), "least Q before %.1f kN, strike %.0f kN (%.1f Q0) at %.4f s, predicted %.4f s" % (
        least / 1e3, q[i] / 1e3, q[i] / d["q0"], t[i], hit)


# Short names of the case checks in the table.
CHECK_NAMES = {"check_lift_off": "lift-off and re-contact", "check_two_point": "two-point contact",
               "check_static": "static load (Q0 within 2 %)", "check_bounded_hunting": "bounded lateral motion",
               "check_derailed": "derailment reported", "check_p2_british_rail": "P2 against British Rail's formula",
               "check_flat_strike": "flat: loss of contact and strike"}


# -------------------------------------------------------------------------------------------- the cases


CASES = [
    Case("lift_off_bump", "1. lift-off and re-contact over a 15 mm bump of one rail at 110 km/h",
         "the right wheel leaves the rail and lands again",
         MODELS, ("rigid",),
         ("peak Q leading right", "kN", 1e-3, peak_q_leading_right, 0.10,
          "the landing impact's peak: sensitive to the step, 10 %"),
         specific=check_lift_off),
    Case("tight_curve_flange_root", "2. two-point contact in R = 150 m, started inside the circle",
         "tread and flange root both in contact on the outer wheel", MODELS, ("rigid",),
         ("mean Y leading outer, last 0.3 s", "kN", 1e-3, mean_y_leading_outer, 0.05,
          "quasi-static curving force: 5 %"),
         specific=check_two_point),
    Case("standstill", "3a. start from standstill (speed 0)",
         "settles to the closed-form static wheel load Q0 = m g / 8", MODELS, ("rigid",),
         ("mean Q, last 0.2 s", "kN", 1e-3, mean_q_all, 0.01, "a static load: 1 %"),
         specific=check_static),
    Case("creep_speed", "3b. run at 0.1 m/s",
         "settles to Q0 at a tiny rolling speed (creepages divided by ~0.1 m/s)", MODELS, ("rigid",),
         ("mean Q, last 0.2 s", "kN", 1e-3, mean_q_all, 0.01, "a static load: 1 %"),
         specific=check_static),
    Case("hunting_high_speed", "4. 450 km/h on straight standard-gauge track (conicity 0.18) after a 4 mm alignment kink",
         "lateral motion bounded (limit cycle, no blow-up)", MODELS, (),
         ("lateral amplitude, 2nd half", "mm", 1e3, lateral_amplitude_late, 0.20,
          "a limit cycle's amplitude: 20 %"),
         specific=check_bounded_hunting),
    Case("coarse_steps",
         "5. coarse corner of the accuracy-cost map: track step 8e-5 s, rtol 1e-5, over german_high irregularities",
         "stable, or refused at start naming the limit", ("rigid_fe", "flexible"), (),
         ("RMS Q leading wheelset", "kN", 1e-3, q_rms_leading, 0.02,
          "against the refined run (4e-5 s, rtol 1e-6): 2 %"),
         expect="run_or_refuse"),
    Case("poor_track_psd", "6. FRA class 2 track irregularities (1-50 m) at 80 km/h",
         "forces bounded and finite over large irregularities", MODELS, (),
         ("RMS Q leading wheelset", "kN", 1e-3, q_rms_leading, 0.03,
          "an RMS over 1 s of irregular track: 3 %; the peak, an impact sampled at 1 kHz, moved by 18-22 % "
          "between base and refined runs and is no converging figure")),
    Case("stiff_pad_soft_ballast", "7. pad 10x stiffer, ballast 10x softer (paper_track_stiff_pad.yaml)",
         "stable co-simulation with a stiff pad on a soft foundation", ("flexible",), (),
         ("RMS Q leading wheelset", "kN", 1e-3, q_rms_leading, 0.02, "a mean level: 2 %")),
    Case("derailment_climb", "8. flange climb: R = 150 m at 108 km/h, very dry rail (mu 0.6)",
         "derailment detected and reported (wheel, s, t); clean stop, readable bag, no NaN", MODELS, ("rigid",),
         ("derailment time", "s", 1.0, derail_time, 0.05, "the detection instant: 5 %"),
         expect="derail", specific=check_derailed),
    Case("dipped_joint_impact", "9. dipped joint, 2 alpha = 10 mrad on both rails, at 110 km/h",
         "P1 and P2 resolved; P2 against British Rail's formula", ("flexible",), ("flexible",),
         ("P2 leading left (150 Hz low-pass)", "kN", 1e-3, p2_leading_left, 0.03,
          "the wheel-on-track bounce (~60 Hz) after the impact: 3 %"),
         specific=check_p2_british_rail),
    Case("wheel_flat_impact", "10. new 50 mm wheel flats on the leading wheelset at 70 km/h",
         "the wheel leaves the rail and strikes when the flat comes round", MODELS, ("rigid",),
         ("P2 leading left (150 Hz low-pass)", "kN", 1e-3, p2_leading_left, 0.05,
          "the strike's bounce, after a loss of contact: 5 %"),
         specific=check_flat_strike),
    Case("hanging_sleepers_closing", "11. three sleepers over a 1 mm void at 160 km/h",
         "a unilateral support that closes and opens under each wheel stays finite, bounded and convergent",
         ("flexible",), ("flexible",),
         ("P2 leading left (150 Hz low-pass)", "kN", 1e-3, p2_leading_left, 0.03,
          "the wheel force over the voids, low-passed: 3 %")),
]


def case_by_key(key):
    for c in CASES:
        if c.key == key:
            return c
    raise KeyError(key)


# ------------------------------------------------------------------------------------------ the runs

def _load_yaml(path):
    with open(path) as f:
        return yaml.load(f, Loader=costmap._Loader)


def model_overrides(model, scene_path=None):
    """Overrides that put a scene on one track model (the rigid track has no rails to deflect) and record the
    energies the balance check needs (the scene's own topics kept)."""
    ov = {"effects.track_model": model, "effects.energy_output": True}
    if model == "rigid":
        ov["effects.rail_deflection_output"] = False
    topics = list(((_load_yaml(scene_path).get("output") or {}).get("topics") or [])) if scene_path else []
    if model == "rigid":
        topics = [t for t in topics if t not in ("rail_deflection", "pad_forces")]
    topics += ["vehicle_energy"] + (["track_energy"] if model == "flexible" else [])
    ov["output.topics"] = topics
    return ov


def refined_overrides(scene_path, extra=None):
    """Overrides of the convergence run: track step and vehicle max step (the co-simulation's cap) halved,
    rtol and atol / 10, from the scene's values with the case's extra overrides for the model applied. The
    vehicle alone has no cap (solver.standalone_max_step 0): its refinement is the tolerances."""
    s = (_load_yaml(scene_path).get("solver") or {})
    v = {k: float((extra or {}).get("solver." + k, s.get(k, d))) for k, d in SOLVER_DEFAULTS.items()}
    return {"solver.track_step": v["track_step"] / 2, "solver.vehicle_max_step": v["vehicle_max_step"] / 2,
            "solver.vehicle_rtol": v["vehicle_rtol"] / 10, "solver.vehicle_atol": v["vehicle_atol"] / 10}


class Run(object):
    """One launch: case, model, refined (bool), overrides, directory."""

    def __init__(self, case, model, refined, out_dir):
        self.case = case
        self.model = model
        self.refined = refined
        ov = model_overrides(model, case.scene)
        ov.update(case.extra.get(model, {}))
        if refined:
            ov.update(refined_overrides(case.scene, case.extra.get(model)))
        self.overrides = ov
        self.name = "%s-%s%s" % (case.key, model, "-refined" if refined else "")
        self.dir = os.path.join(out_dir, "runs", self.name)


def plan_runs(subset, models, out_dir):
    """The runs of a subset ('ci' or 'all') on the given models, longest-first is not known: in case order."""
    runs = []
    for c in CASES:
        ms = c.ci_models if subset == "ci" else c.models
        for m in ms:
            if m not in models:
                continue
            runs.append(Run(c, m, False, out_dir))
            runs.append(Run(c, m, True, out_dir))
    return runs


def execute(run, workspace, timeout):
    spec = {"case_dir": run.dir, "name": run.name, "case_id": run.name, "settings_hash": "",
            "scene": run.case.scene, "overrides": costmap.override_items(run.overrides),
            "workspace": workspace, "timeout": timeout}
    rec = runner.run_case(spec)
    with open(os.path.join(run.dir, "record.yaml"), "w") as f:
        yaml.safe_dump({"overrides": costmap.override_items(run.overrides), "record": rec}, f, sort_keys=False)
    return rec


# ------------------------------------------------------------------------------------------ evaluation

def _walk_numbers(msg, bad, path=""):
    """Counts the numeric fields of a message (recursively) that are not finite: bad = [count, first path]."""
    if isinstance(msg, float):
        if not math.isfinite(msg):
            bad[0] += 1
            if bad[1] is None:
                bad[1] = path
        return
    if isinstance(msg, (list, tuple)):
        for i, x in enumerate(msg):
            _walk_numbers(x, bad, "%s[%d]" % (path, i))
        return
    slots = getattr(msg, "__slots__", None)
    if slots:
        for s in slots:
            _walk_numbers(getattr(msg, s), bad, path + "." + s)


def scan_bag(path):
    """(messages, non-finite numeric fields, first offending topic.field) over every topic of a bag."""
    import rosbag
    n = 0
    bad = [0, None]
    with rosbag.Bag(path) as bag:
        for topic, msg, _ in bag.read_messages():
            n += 1
            _walk_numbers(msg, bad, topic)
    return n, bad[0], bad[1]


def load_data(run, rec):
    """What the checks need from a run: kinematics, contact points, log, Q0, bag scan."""
    d = {"exit_code": rec.get("exit_code"), "status": rec.get("status"), "wall_time": rec.get("wall_time")}
    try:
        with open(os.path.join(run.dir, "run.log"), errors="replace") as f:
            d["log"] = re.sub(r"\x1b\[[0-9;]*m", "", f.read())
    except OSError:
        d["log"] = ""
    scene = _load_yaml(run.case.scene)
    vdata = os.path.normpath(os.path.join(os.path.dirname(run.case.scene), scene["vehicle"]["data"]))
    d["q0"] = safety.static_wheel_load_from_vehicle(vdata, int(scene["vehicle"].get("wheelsets", 4)))
    d["wheelset_mass"] = _wheelset_mass(vdata)
    d["scene"] = scene
    d["model"] = run.model
    d["friction"] = float((scene.get("contact") or {}).get("friction", 0.3))  # scene, else the default
    bags = [p for p in (os.path.join(run.dir, "run.bag"), os.path.join(run.dir, "run.track.bag")) if os.path.isfile(p)]
    d["bags"] = bags
    d["bag_messages"], d["nonfinite"], d["nonfinite_at"] = 0, 0, None
    d["bag_error"] = None
    for b in bags:
        try:
            n, nb, where = scan_bag(b)
        except Exception as e:  # an unreadable bag is a finding, recorded as such
            d["bag_error"] = "%s: %s" % (os.path.basename(b), e)
            continue
        d["bag_messages"] += n
        d["nonfinite"] += nb
        d["nonfinite_at"] = d["nonfinite_at"] or where
    m = VEHICLE_EXIT.search(d["log"])
    d["vehicle_exit_code"] = int(m.group(1)) if m else d["exit_code"]
    d["kin"] = None
    d["points"] = None
    d["energy"] = None
    try:
        d["energy"] = load_energy(bags)
    except Exception as e:
        d["bag_error"] = d["bag_error"] or str(e)
    if bags:
        try:
            d["kin"] = loading.load_wheelset_kinematics(bags[0])
        except Exception as e:
            d["bag_error"] = d["bag_error"] or str(e)
        for b in bags:
            try:
                if "/contact_points" in loading.bag_topics(b):
                    d["points"] = loading.load_contact_points(b)
                    break
            except Exception:
                pass
    return d


def _wheelset_mass(vehicle_path):
    """Mass of the first wheelset body (name ws*) of a vehicle data file [kg]."""
    for b in _load_yaml(vehicle_path).get("bodies", []):
        if str(b.get("name", "")).startswith("ws"):
            return float(b["mass"])
    raise ValueError("%s: no wheelset body (name ws*)" % vehicle_path)


def load_energy(bags):
    """(t [s], total mechanical energy [J], kinetic energy at the start [J]) of a run: /vehicle_energy plus
    /track_energy (flexible) interpolated to the vehicle's instants; None when the vehicle's is missing."""
    series = {}
    for b in bags:
        topics = loading.bag_topics(b)
        for topic in ("/vehicle_energy", "/track_energy"):
            if topic in topics:
                import rosbag
                with rosbag.Bag(b) as bag:
                    rows = [(m.header.stamp.to_sec(), m.total, m.kinetic) for _, m, _ in bag.read_messages(topics=[topic])]
                series[topic] = np.array(rows)
    v = series.get("/vehicle_energy")
    if v is None or len(v) < 2:
        return None
    t, e = v[:, 0], v[:, 1].copy()
    kinetic0 = float(v[0, 2])
    tr = series.get("/track_energy")
    if tr is not None and len(tr):
        e += np.interp(t, tr[:, 0], tr[:, 1])
        kinetic0 += float(tr[0, 2])
    return t, e, kinetic0


def impact_force(d):
    """(F_impact [N] on the Q scale, v_vertical, v_lateral [m/s], K [N/m^1.5]) of the run (see FORCE_FACTOR);
    F = 0 without contact points."""
    k = d["kin"]
    t = k["t"]
    v_z = v_y = 0.0
    if len(t) > 2:
        for sign in (1.0, -1.0):  # left wheel z = vertical + b roll, right wheel z = vertical - b roll
            z = k["vertical"] + sign * WHEEL_HALF_SPACING * k["roll"]
            v_z = max(v_z, float(np.nanmax(-np.gradient(z, t, axis=0))))
        v_y = float(np.nanmax(np.abs(np.gradient(k["lateral"], t, axis=0))))
    cp = d.get("points")
    if cp is None:
        return 0.0, v_z, v_y, float("nan")
    pen = cp.get("penetration")
    K = 0.0
    for kind in (loading.KIND_TREAD, loading.KIND_FLANGE):  # the stiffer of the two surfaces' medians
        sel = cp["active"] & (cp["kind"] == kind) & (pen > 1e-7)
        if sel.any():
            K = max(K, float(np.median(cp["normal_force"][sel] / pen[sel] ** 1.5)))
    if K <= 0.0:
        return 0.0, v_z, v_y, float("nan")
    m = d["wheelset_mass"]
    hertz = lambda mass, v: (5.0 / 4.0 * mass * v * v) ** 0.6 * K ** 0.4
    # A wheel landing: half the wheelset at the vertical speed, the normal near vertical. A flange strike:
    # the whole wheelset at its lateral speed (an upper bound of the approach along the flange normal), of
    # whose normal force at most sqrt(1 + mu^2) appears as Q (normal and friction parts together).
    mu = d.get("friction", 0.3)
    return max(hertz(0.5 * m, v_z), math.sqrt(1.0 + mu * mu) * hertz(m, v_y)), v_z, v_y, K


def check_energy(d):
    """Energy never above its start value by more than ENERGY_REL * kinetic0 + ENERGY_ABS (see above)."""
    en = d.get("energy")
    if en is None:
        return "fail", "no /vehicle_energy in the bag"
    t, e, kinetic0 = en
    rise = e - e[0]
    i = int(np.nanargmax(rise))
    margin = ENERGY_REL * kinetic0 + ENERGY_ABS
    ok = bool(np.all(np.isfinite(e))) and rise[i] <= margin
    return ("pass" if ok else "fail"), "E0 %.4g J; largest rise %+.1f J at t = %.3f s (margin %.0f J); change at the end %+.4g J" % (
        e[0], rise[i], t[i], margin, rise[-1])


def evaluate(run, rec, fine=None):
    """{checks: [(name, status, text)], key: value or None, converge: (status, text), data}: the checks of
    one base run, with the refined run's data for the convergence check."""
    d = load_data(run, rec)
    c = run.case
    checks = []
    refused = rec.get("status") == "refused" or (rec.get("exit_code") == 2 and not d["bags"])
    if c.expect == "run_or_refuse" and refused:
        tail = rec.get("log_tail", "")
        states_limit = bool(re.search(r"(must|limit|<=|>=|at most|at least)", tail))
        checks.append(("refused at start", "pass" if states_limit else "fail", tail.strip().splitlines()[-1][:200]
                       if tail.strip() else "no message"))
        return {"checks": checks, "key": None, "converge": ("n/a", "refused"), "data": d}
    if c.expect == "derail":
        pass
    elif rec.get("status") != "ok":
        checks.append(("run completes", "fail", "status %s, exit %s: %s" % (
            rec.get("status"), rec.get("exit_code"), (rec.get("log_tail") or "").strip().splitlines()[-1:]) ))
    else:
        checks.append(("run completes", "pass", "exit 0"))
    # Finite numbers in every bag.
    if not d["bags"]:
        checks.append(("finite outputs", "fail", "no bag written"))
    elif d["bag_error"]:
        checks.append(("finite outputs", "fail", "bag unreadable: %s" % d["bag_error"]))
    else:
        checks.append(("finite outputs", "pass" if d["nonfinite"] == 0 else "fail",
                       "%d messages, %d non-finite fields%s" % (d["bag_messages"], d["nonfinite"],
                                                                 " (first: %s)" % d["nonfinite_at"] if d["nonfinite"] else "")))
    k = d["kin"]
    if k is not None and k["left_force"] is not None and len(k["t"]):
        q = np.concatenate([k["left_force"][:, :, 2].ravel(), k["right_force"][:, :, 2].ravel()])
        qmax = float(np.nanmax(q))
        f_imp, v_z, v_y, K = impact_force(d)
        lim = FORCE_FACTOR * d["q0"] + IMPACT_MARGIN * f_imp
        checks.append(("Q < %g Q0 + %g F_impact" % (FORCE_FACTOR, IMPACT_MARGIN), "pass" if qmax < lim else "fail",
                       "Q max %.1f kN, bound %.0f kN (F_impact %.0f kN: v down %.2f m/s, v lateral %.2f m/s, "
                       "K = %.3g N/m^1.5)" % (qmax / 1e3, lim / 1e3, f_imp / 1e3, v_z, v_y, K)))
    if d["bags"]:
        st, txt = check_energy(d)
        checks.append(("energy never above its start + margin", st, txt))
    elif c.expect != "derail":
        checks.append(("Q bound", "fail", "no wheelset kinematics in the bag"))
    if c.specific is not None and (k is not None or c.expect == "derail"):
        try:
            st, txt = c.specific(d)
        except Exception as e:  # a check that cannot be evaluated is a failure with its reason
            st, txt = "fail", "cannot evaluate: %s" % e
        checks.append((CHECK_NAMES.get(c.specific.__name__, c.specific.__name__), st, txt))
    key = None
    if k is not None or c.expect == "derail":
        try:
            key = c.key_figure[3](d)
        except Exception:
            key = None
    conv = ("n/a", "no refined run")
    if fine is not None:
        fd = load_data(fine[0], fine[1])
        fkey = None
        if fd["kin"] is not None or c.expect == "derail":
            try:
                fkey = c.key_figure[3](fd)
            except Exception:
                fkey = None
        if key is None or fkey is None or not (math.isfinite(key) and math.isfinite(fkey)):
            conv = ("fail", "key figure not available (base %s, refined %s, refined status %s)" % (
                key, fkey, fine[1].get("status")))
        else:
            rel = abs(key - fkey) / max(abs(fkey), 1e-12)
            conv = ("pass" if rel < c.key_figure[4] else "fail", "%s -> %s (%.2f %%, limit %g %%)" % (
                _fmt(key, c), _fmt(fkey, c), 100 * rel, 100 * c.key_figure[4]))
    return {"checks": checks, "key": key, "converge": conv, "data": d}


def _fmt(v, case):
    if v is None or not math.isfinite(v):
        return "n/a"
    return "%.4g %s" % (v * case.key_figure[2], case.key_figure[1])


# ------------------------------------------------------------------------------------------ the suite

def _read_record(run):
    try:
        with open(os.path.join(run.dir, "record.yaml")) as f:
            return (yaml.safe_load(f) or {}).get("record")
    except (OSError, yaml.YAMLError):
        return None


def run_suite(subset="all", models=MODELS, jobs=2, out_dir="output/hard_cases", workspace=REPO, timeout=900.0,
              progress=print, only=None):
    """Runs the subset and evaluates it; only: case keys to (re)run, the other runs of the subset are
    evaluated from their earlier results in out_dir when present. Returns (rows in case order, wall s)."""
    out_dir = os.path.abspath(out_dir)
    planned = plan_runs(subset, models, out_dir)
    recs = {}
    runs = []
    for r in planned:
        old = _read_record(r) if only and r.case.key not in only else None
        if old is not None:
            recs[r.name] = (r, old)
        elif not only or r.case.key in only:
            runs.append(r)
    progress("hard cases: %d run(s) (%s subset, models %s) on %d job(s) -> %s" % (
        len(runs), subset, ",".join(models), jobs, out_dir))
    t0 = time.monotonic()
    with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
        futs = {pool.submit(execute, r, workspace, timeout): r for r in runs}
        try:
            for fut in concurrent.futures.as_completed(futs):
                r = futs[fut]
                try:
                    rec = fut.result()
                except Exception as e:  # an error outside the run: recorded, the suite goes on
                    rec = {"status": "failed", "exit_code": None, "wall_time": None, "log_tail": repr(e)}
                recs[r.name] = (r, rec)
                progress("  %s: %s (exit %s, %s s wall)" % (r.name, rec.get("status"), rec.get("exit_code"),
                                                            rec.get("wall_time")))
        except BaseException:
            for f in futs:
                f.cancel()
            runner.stop_all()
            raise
    total = time.monotonic() - t0
    rows = []
    for r in planned:
        if r.refined or r.name not in recs:
            continue
        base = recs[r.name]
        fine = recs.get(r.name + "-refined")
        ev = evaluate(base[0], base[1], fine)
        rows.append({"case": r.case, "model": r.model, "run": r.name, "record": base[1],
                     "fine_record": fine[1] if fine else None, "eval": ev})
    return rows, total


def row_passed(row):
    ev = row["eval"]
    return all(st != "fail" for _, st, _ in ev["checks"]) and ev["converge"][0] != "fail"


def markdown_table(rows, total_wall, subset, models, jobs):
    lines = ["## Results", "",
             "Subset `%s`, models %s, %d job(s); suite wall time %.0f s (runs and evaluation on this machine's 2 "
             "shared cores). Written by `scripts/hard_cases/run_hard_cases.py` on %s." % (
                 subset, ", ".join(models), jobs, total_wall, time.strftime("%Y-%m-%d %H:%M UTC", time.gmtime())), "",
             "| case | model | result | checks | key figure (base -> refined) | wall [s] base / refined |",
             "|---|---|---|---|---|---|"]
    for row in rows:
        ev = row["eval"]
        c = row["case"]
        checks = "<br>".join("%s %s: %s" % ("ok" if st == "pass" else ("n/a" if st == "n/a" else "**FAIL**"), n,
                                             txt.replace("|", "/")) for n, st, txt in ev["checks"])
        kf = "%s: %s" % (c.key_figure[0], ev["converge"][1] if ev["converge"][0] != "n/a" else
                         ("%s (%s)" % (_fmt(ev["key"], c), ev["converge"][1])))
        if ev["converge"][0] == "fail":
            kf = "**FAIL** " + kf
        wb = row["record"].get("wall_time")
        wf = row["fine_record"].get("wall_time") if row["fine_record"] else None
        lines.append("| %s | %s | %s | %s | %s | %s / %s |" % (
            c.title, row["model"], "pass" if row_passed(row) else "**FAIL**", checks, kf,
            "-" if wb is None else "%.0f" % wb, "-" if wf is None else "%.0f" % wf))
    lines += ["", "### What each case checks and why its margins", ""]
    for c in CASES:
        lines.append("- **%s** (`config/scenes/hard/%s.yaml`): %s. Key figure: %s, refined run (track step and "
                     "vehicle max step halved, rtol and atol / 10) within %g %% (%s). Contact-force bound %g Q0 + %g F_impact."
                     % (c.title, c.key, c.checks, c.key_figure[0], 100 * c.key_figure[4], c.key_figure[5],
                        FORCE_FACTOR, IMPACT_MARGIN))
    return "\n".join(lines) + "\n"


def write_docs(path, rows, total_wall, subset, models, jobs):
    """Rewrites the part of the docs file below DOCS_MARKER, keeping the hand-written intro above it."""
    intro = "# Hard cases\n\n"
    source = path if os.path.isfile(path) else os.path.join(REPO, "docs", "hard_cases.md")
    if os.path.isfile(source):
        with open(source) as f:
            text = f.read()
        intro = text.split(DOCS_MARKER)[0]
    with open(path, "w") as f:
        f.write(intro.rstrip("\n") + "\n\n" + DOCS_MARKER + "\n\n" + markdown_table(rows, total_wall, subset, models, jobs))
