"""The hard-case suite: scenes at the edges of what the simulator must survive (wheel lift-off, two-point
contact in a tight curve, standstill, hunting above the critical speed, the coarse corner of the
accuracy-cost map, poor track, a stiff pad on soft ballast, a wheel climbing the rail), each run on the
track models where it means something, checked for finite outputs, bounded contact forces, a bounded
energy proxy and convergence of a named key figure, and written as a table into docs/hard_cases.md.

The runs reuse rail_analysis.costmap.run_case (own ROS master on a free port per run, a wall-time limit,
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

from rail_analysis import costmap, loading, safety  # noqa: E402  (after the path set-up above)

SCENES = os.path.join(REPO, "config", "scenes", "hard")
MODELS = ("rigid", "rigid_fe", "flexible")
# Models that get a refined (convergence) run in most cases: a flexible refined run costs ~250 s of wall
# time per simulated second here, so it is kept for the cases where the flexible track is the point.
RIGID_MODELS = ("rigid", "rigid_fe")
DOCS_MARKER = "<!-- everything below this line is written by test/hard_cases/run_hard_cases.py -->"
# Solver defaults of the scene format (docs/scene.md, solver): used when a scene does not set them.
SOLVER_DEFAULTS = {"track_step": 2e-5, "vehicle_max_step": 2e-5, "vehicle_rtol": 1e-6, "vehicle_atol": 1e-8}
# The vehicle node's log line for a derailment (src/rail_vehicle_node/src/node/vehicle_node.cpp).
DERAIL_LOG = re.compile(r"run stopped \(derailed\)[^:]*: derailment: (.*?at s = ([-0-9.e+]+) m, t = ([-0-9.e+]+) s)")
# Contact force bound: Q < FORCE_FACTOR * Q0 (static wheel load) outside impacts. A wheel load five times
# its static value is far beyond any measured running load (EN 14363's limit Q_lim is 145-200 kN, about 2-3
# Q0 here) yet well below what a numerical blow-up produces; an impact case gets IMPACT_FORCE_FACTOR.
FORCE_FACTOR = 5.0
IMPACT_FORCE_FACTOR = 10.0
# Energy proxy: growth of the wheelsets' perturbation kinetic energy in the last quarter of the run over
# its maximum before, allowed factor and floor (J). See energy_proxy.
ENERGY_GROWTH = 2.0
ENERGY_FLOOR = 1.0


class Case(object):
    """One hard case: key (also the scene's stem), title, what it checks, models it runs on (all subset)
    and in the CI subset, its expectation ('run', 'derail', 'run_or_refuse'), the contact-force factor,
    the key figure (name, unit, function of the run's data, allowed relative change under refinement,
    why), and per-model extra overrides."""

    def __init__(self, key, title, checks, models, ci_models, key_figure, expect="run", force_factor=FORCE_FACTOR,
                 extra=None, converge_models=None, specific=None):
        self.key = key
        self.scene = os.path.join(SCENES, key + ".yaml")
        self.title = title
        self.checks = checks
        self.models = tuple(models)
        self.ci_models = tuple(ci_models)
        self.key_figure = key_figure          # (name, unit, scale for the table, function(data), rel tol, why)
        self.expect = expect
        self.force_factor = force_factor
        self.extra = extra or {}              # {model: {key: value}}
        self.converge_models = tuple(converge_models if converge_models is not None else models)
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


def peak_q_leading(d):
    """Largest vertical contact force on the leading wheelset's wheels after 0.1 s [N]."""
    k = d["kin"]
    sel = k["t"] >= 0.1
    return float(np.nanmax(np.concatenate([k["left_force"][sel, 0, 2], k["right_force"][sel, 0, 2]])))


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
    """The log names the derailed wheel, s and t; non-zero exit; bag readable with messages."""
    m = DERAIL_LOG.search(d["log"])
    if not m:
        return "fail", "no 'run stopped (derailed)' line in the log (exit %s)" % d["exit_code"]
    ok = d["exit_code"] not in (0, None) and d["bag_messages"] > 0
    return ("pass" if ok else "fail"), "'%s', exit %s, bag readable with %d messages" % (
        m.group(1), d["exit_code"], d["bag_messages"])


# Short names of the case checks in the table.
CHECK_NAMES = {"check_lift_off": "lift-off and re-contact", "check_two_point": "two-point contact",
               "check_static": "static load (Q0 within 2 %)", "check_bounded_hunting": "bounded lateral motion",
               "check_derailed": "derailment reported"}


# -------------------------------------------------------------------------------------------- the cases

CASES = [
    Case("lift_off_bump", "1. lift-off and re-contact over a 15 mm bump of one rail at 110 km/h",
         "the right wheel leaves the rail and lands again; impact bound %g Q0" % IMPACT_FORCE_FACTOR,
         MODELS, ("rigid",),
         ("peak Q leading right", "kN", 1e-3, peak_q_leading_right, 0.10,
          "the landing impact's peak: sensitive to the step, 10 %"),
         force_factor=IMPACT_FORCE_FACTOR, specific=check_lift_off),
    Case("tight_curve_flange_root", "2. two-point contact in R = 150 m, started inside the circle",
         "tread and flange root both in contact on the outer wheel", MODELS, ("rigid",),
         ("mean Y leading outer, last 0.3 s", "kN", 1e-3, mean_y_leading_outer, 0.05,
          "quasi-static curving force: 5 %"),
         specific=check_two_point, converge_models=RIGID_MODELS),
    Case("standstill", "3a. start from standstill (speed 0)",
         "settles to the closed-form static wheel load Q0 = m g / 8", MODELS, ("rigid",),
         ("mean Q, last 0.2 s", "kN", 1e-3, mean_q_all, 0.01, "a static load: 1 %"),
         specific=check_static, converge_models=RIGID_MODELS),
    Case("creep_speed", "3b. run at 0.1 m/s",
         "settles to Q0 at a tiny rolling speed (creepages divided by ~0.1 m/s)", MODELS, ("rigid",),
         ("mean Q, last 0.2 s", "kN", 1e-3, mean_q_all, 0.01, "a static load: 1 %"),
         specific=check_static, converge_models=RIGID_MODELS),
    Case("hunting_high_speed", "4. 450 km/h on straight track after a 4 mm alignment kink",
         "lateral motion bounded (limit cycle, no blow-up)", MODELS, (),
         ("lateral amplitude, 2nd half", "mm", 1e3, lateral_amplitude_late, 0.20,
          "a limit cycle's amplitude: 20 %"),
         specific=check_bounded_hunting, converge_models=RIGID_MODELS),
    Case("coarse_steps", "5. coarse corner of the accuracy-cost map: track step 8e-5 s, rtol 1e-5",
         "stable, or refused at start naming the limit", ("rigid_fe", "flexible"), (),
         ("RMS Q leading wheelset", "kN", 1e-3, q_rms_leading, 0.02,
          "against the refined run (4e-5 s, rtol 1e-6): 2 %"),
         expect="run_or_refuse"),
    Case("poor_track_psd", "6. FRA class 1 (the poorest) track irregularities at 50 km/h",
         "forces bounded and finite over large irregularities", MODELS, (),
         ("peak Q leading wheelset", "kN", 1e-3, peak_q_leading, 0.10, "a peak: 10 %"), converge_models=RIGID_MODELS),
    Case("stiff_pad_soft_ballast", "7. pad 10x stiffer, ballast 10x softer (paper_track_stiff_pad.yaml)",
         "stable co-simulation with a stiff pad on a soft foundation", ("flexible",), (),
         ("RMS Q leading wheelset", "kN", 1e-3, q_rms_leading, 0.02, "a mean level: 2 %")),
    Case("derailment_climb", "8. flange climb: R = 150 m at 90 km/h, 586 mm cant deficiency",
         "derailment detected and reported (wheel, s, t); clean stop, readable bag, no NaN", MODELS, ("rigid",),
         ("derailment time", "s", 1.0, derail_time, 0.05, "the detection instant: 5 %"),
         expect="derail", specific=check_derailed, converge_models=RIGID_MODELS),
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


def model_overrides(model):
    """Overrides that put a scene on one track model (the rigid track has no rails to deflect)."""
    ov = {"effects.track_model": model}
    if model == "rigid":
        ov["effects.rail_deflection_output"] = False
    return ov


def refined_overrides(scene_path):
    """Overrides of the convergence run: track step and vehicle max step halved, rtol and atol / 10."""
    s = (_load_yaml(scene_path).get("solver") or {})
    v = {k: float(s.get(k, d)) for k, d in SOLVER_DEFAULTS.items()}
    return {"solver.track_step": v["track_step"] / 2, "solver.vehicle_max_step": v["vehicle_max_step"] / 2,
            "solver.vehicle_rtol": v["vehicle_rtol"] / 10, "solver.vehicle_atol": v["vehicle_atol"] / 10}


class Run(object):
    """One launch: case, model, refined (bool), overrides, directory."""

    def __init__(self, case, model, refined, out_dir):
        self.case = case
        self.model = model
        self.refined = refined
        ov = model_overrides(model)
        ov.update(case.extra.get(model, {}))
        if refined:
            ov.update(refined_overrides(case.scene))
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
            if m in c.converge_models:
                runs.append(Run(c, m, True, out_dir))
    return runs


def execute(run, workspace, timeout):
    spec = {"case_dir": run.dir, "name": run.name, "case_id": run.name, "settings_hash": "",
            "scene": run.case.scene, "overrides": costmap.override_items(run.overrides),
            "workspace": workspace, "timeout": timeout}
    rec = costmap.run_case(spec)
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
    d["masses"] = _wheelset_inertia(vdata)
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
    d["kin"] = None
    d["points"] = None
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


def _wheelset_inertia(vehicle_path):
    """(mass [kg], roll inertia Jxx, yaw inertia Jzz [kg m^2]) of the first wheelset body (name ws*)."""
    data = _load_yaml(vehicle_path)
    for b in data.get("bodies", []):
        if str(b.get("name", "")).startswith("ws"):
            j = b.get("inertia", [0, 0, 0])
            return float(b["mass"]), float(j[0]), float(j[2])
    return 0.0, 0.0, 0.0


def energy_proxy(d):
    """Perturbation kinetic energy of the wheelsets relative to their nominal rolling motion [J], per sample:
    sum over wheelsets of m/2 (dy/dt^2 + dz/dt^2) + Jxx/2 (droll/dt)^2 + Jzz/2 (dyaw/dt)^2, with y, z, roll and
    the yaw (angle of attack) from /wheelset_kinematics, differentiated in time. The bags carry neither the
    carbody and bogie velocities nor the suspension deflections nor the work of the speed constraint, so a
    full energy balance is not available; this proxy covers the bodies in contact with the rails, where
    a numerical instability shows first."""
    k = d["kin"]
    m, jx, jz = d["masses"]
    t = k["t"]
    if len(t) < 3:
        return t, np.zeros_like(t)
    e = np.zeros(len(t))
    for key, inertia in (("lateral", m), ("vertical", m), ("roll", jx), ("angle_of_attack", jz)):
        v = np.gradient(k[key], t, axis=0)
        e += 0.5 * inertia * np.nansum(v * v, axis=1)
    return t, e


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
        lim = c.force_factor * d["q0"]
        checks.append(("Q < %g Q0" % c.force_factor, "pass" if qmax < lim else "fail",
                       "Q max %.1f kN, bound %.0f kN" % (qmax / 1e3, lim / 1e3)))
        t, e = energy_proxy(d)
        T = t[-1]
        late = t >= t[0] + 0.75 * (T - t[0])
        if late.any() and (~late).any():
            e_before = float(np.nanmax(e[~late]))
            e_late = float(np.nanmax(e[late]))
            ok = e_late <= ENERGY_GROWTH * e_before + ENERGY_FLOOR
            checks.append(("energy proxy bounded", "pass" if ok else "fail",
                           "wheelset perturbation KE max %.3g J before, %.3g J in the last quarter" % (e_before, e_late)))
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
            costmap.stop_all()
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
             "shared cores). Written by `test/hard_cases/run_hard_cases.py` on %s." % (
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
                     "vehicle max step halved, rtol and atol / 10) within %g %% (%s). Contact-force bound %g Q0%s."
                     % (c.title, c.key, c.checks, c.key_figure[0], 100 * c.key_figure[4], c.key_figure[5],
                        c.force_factor, " (an impact case)" if c.force_factor != FORCE_FACTOR else ""))
    return "\n".join(lines) + "\n"


def write_docs(path, rows, total_wall, subset, models, jobs):
    """Rewrites the part of the docs file below DOCS_MARKER, keeping the hand-written intro above it."""
    intro = "# Hard cases\n\n"
    if os.path.isfile(path):
        with open(path) as f:
            text = f.read()
        intro = text.split(DOCS_MARKER)[0]
    with open(path, "w") as f:
        f.write(intro.rstrip("\n") + "\n\n" + DOCS_MARKER + "\n\n" + markdown_table(rows, total_wall, subset, models, jobs))
