"""Running safety, track loading and wear quantities of a run, with their limits (see doc/safety.md).

Frames and signs. /wheelset_kinematics gives, per wheel, the total force of the rail ON the wheel in the canted
track frame (x along, y left, z up). Per wheel:
  Q  = F.z                            vertical wheel force [N]
  Y  = -F_left.y  (left wheel)        lateral force pushing the wheel away from its rail toward the track
       +F_right.y (right wheel)       centre [N]: > 0 when the wheel flanges (flange-climb sense), so Y/Q > 0
  SumY = F_left.y + F_right.y         track-shift force of the wheelset [N] (the lateral force between the
                                      wheelset and the track, + to the left); judged by its magnitude.
Wheel ids as in rail_msgs/WheelState: wheel_id = 2 wheelset + side, side 0 left, 1 right; wheelset 0 leads.

Quantities and limits (formulas as the standards write them; sources beside the constants below):
  (Y/Q)_2m  <= (tan g - mu) / (1 + mu tan g)            Nadal, g = maximum flange angle, mu = friction
  dQ/Q0 = (Q0 - Q)/Q0 <= 0.6                            wheel unloading
  |SumY_2m| <= alpha (10 kN + P/3), P = 2 Q0            Prud'homme (EN 14363: alpha (10 + 2 Q0/3) kN)
  Q_max <= Q_lim(V), Q_qst <= 145 kN                    vertical wheel force, EN 14363 track loading
  Tgamma = sum over the wheel's contacts |Tx nu_x| + |Ty nu_y|   [N = J/m], informative (no limit)
  pad compression, ballast force, rail displacement    informative (flexible track)
  sleeper void (max open)                               informative (hanging sleepers)
_2m: sliding mean over 2 m of track (centred window over the wheel's arc length).
"""
import math
import os

import numpy as np

from . import comfort, loading
from .loading import AnalysisInputError, MissingTopicError


class AnalysisTooShortError(AnalysisInputError):
    """The run ends before the analysis has enough samples after its discard time (not a bad input)."""

G = 9.81  # [m/s^2], when a vehicle data file gives no gravity

# Maximum flange angle of the S1002 wheel profile (EN 13715): 70 deg; the flank of config/profiles/S1002.txt
# between z = -12.0 and -14.8 mm is at 70.0 deg.
S1002_FLANGE_ANGLE_DEG = 70.0
# Friction coefficient when neither the options nor the scene give one: rail_contact's WheelContactOptions
# default (0.3), which the vehicle and track nodes use (the scene has no friction key).
DEFAULT_FRICTION = 0.3
# Wheel unloading limit (dQ/Q0)_lim = 0.6: EN 14363 (safety against derailment on twisted track, wheel
# unloading criterion), as we read it; check against the edition you work to.
UNLOADING_LIMIT = 0.6
# Prud'homme's track-shift limit SumY_lim = alpha (10 kN + P/3): A. Prud'homme, "La resistance de la voie aux
# efforts transversaux exerces par le materiel roulant", Revue Generale des Chemins de fer, 1967; EN 14363
# writes (SumY_2m)_lim = alpha (10 + 2 Q0 / 3) kN with alpha = 1 for locomotives and passenger vehicles
# (0.85 for freight wagons).
PRUDHOMME_CONSTANT = 10e3   # [N]
PRUDHOMME_ALPHA = 1.0
# EN 14363 track loading, as we read EN 14363:2016: maximum vertical wheel force Q_lim by the vehicle's
# maximum speed [(V_max km/h, Q_lim N)], and the quasi-static vertical wheel force limit 145 kN.
Q_LIMITS_BY_SPEED = ((160.0, 200e3), (200.0, 190e3), (250.0, 180e3), (300.0, 170e3), (float("inf"), 160e3))
Q_QST_LIMIT = 145e3
# Filtering and windows (EN 14363: wheel forces low-passed at 20 Hz, Y/Q and SumY as 2 m sliding means).
Q_CUTOFF_HZ = 20.0
QST_CUTOFF_HZ = 2.0          # quasi-static part: low-pass cut-off (a choice; an option)
# Impacts (dipped joints, wheel flats): P1, the first peak, from the unfiltered force; P2, the wheel-on-track
# resonance that follows (30-90 Hz: Jenkins, Stephenson, Clayton, Morland and Lyon, "The effect of track and
# vehicle parameters on wheel/rail vertical dynamic forces", Railway Engineering Journal 3(1), 1974), from the
# force low-passed well above it and well below P1 (500-1000 Hz): 2nd order forward and backward at 150 Hz
# (gain 1 / (1 + (f/150)^4)) keeps 97.5 % of a steady 60 Hz sine and 0.2 % of a 700 Hz one.
P2_CUTOFF_HZ = 150.0
# An impact lasts about a millisecond: below this output rate P1 is under-sampled and says so.
P1_MIN_RATE_HZ = 5000.0
SLIDING_WINDOW_M = 2.0
# Tgamma bands of the Whole Life Rail Model damage function (Burstow, "A model to predict and understand
# rolling contact fatigue in wheels and rails", 2004): no damage below 15 J/m, the largest rolling contact
# fatigue damage at 65 J/m, wear dominating beyond 175 J/m. Informative.
TGAMMA_BANDS = (15.0, 65.0, 175.0)

PASS, FAIL, INFO, NOT_AVAILABLE = "pass", "fail", "informative", "not available"

# What to set in the scene to record each topic.
TOPIC_HINTS = {
    "/wheelset_kinematics": "add wheelset_kinematics to output.topics",
    "/contact_points": "set effects.contact_point_output: true and add contact_points to output.topics",
    "/floor_accelerations": "set effects.floor_acceleration_output: true and add floor_accelerations to output.topics",
    "/pad_forces": ("set effects.pad_force_output: true and add pad_forces to output.topics "
                    "(flexible track only: effects.track_model: flexible)"),
}


def not_available_text(topic):
    """'needs <topic>: <what to set in the scene>'."""
    return "needs %s: %s" % (topic, TOPIC_HINTS.get(topic, "record it"))


class Settings(object):
    """Options of the evaluation (SI units, angles in degrees where the name says deg). None = from the run:
    friction (scene, else DEFAULT_FRICTION), q0 [N] static wheel load (vehicle data file, else estimated)."""

    def __init__(self, **kw):
        self.friction = None
        self.flange_angle_deg = S1002_FLANGE_ANGLE_DEG
        self.alpha = PRUDHOMME_ALPHA
        self.unloading_limit = UNLOADING_LIMIT
        self.q0 = None
        self.window = SLIDING_WINDOW_M         # [m] sliding mean of Y/Q and SumY
        self.q_cutoff_hz = Q_CUTOFF_HZ         # [Hz] low-pass of Q before its maximum
        self.qst_cutoff_hz = QST_CUTOFF_HZ     # [Hz] quasi-static Q
        self.p2_cutoff_hz = P2_CUTOFF_HZ       # [Hz] low-pass of Q before the P2 peak
        self.t_discard = 0.25                  # [s] start transient discarded
        self.comfort_window = comfort.WINDOW_S # [s]
        self.comfort_settle = 3.0              # [s] after t_discard, for the 0.4 Hz high-pass to settle
        self.q_limit = None                    # [N] None = EN 14363 by speed
        self.q_qst_limit = Q_QST_LIMIT         # [N]
        for k, v in kw.items():
            if not hasattr(self, k):
                raise ValueError("unknown setting %r" % k)
            setattr(self, k, v)


# ---------------------------------------------------------------------------------------------------------
# Formulas

def nadal_limit(flange_angle, friction):
    """Nadal's flange-climb limit (tan g - mu) / (1 + mu tan g) [-]; flange_angle g [rad], friction mu [-]."""
    tg = math.tan(flange_angle)
    return (tg - friction) / (1.0 + friction * tg)


def prudhomme_limit(axle_load, alpha=PRUDHOMME_ALPHA):
    """Prud'homme's track-shift force limit alpha (10 kN + P/3) [N]; axle_load P [N] (= 2 Q0)."""
    return alpha * (PRUDHOMME_CONSTANT + axle_load / 3.0)


def q_limit_for_speed(speed):
    """EN 14363 maximum vertical wheel force [N] for a vehicle speed [m/s] (Q_LIMITS_BY_SPEED)."""
    v_kmh = speed * 3.6
    for v_max, q in Q_LIMITS_BY_SPEED:
        if v_kmh <= v_max:
            return q
    return Q_LIMITS_BY_SPEED[-1][1]


def sliding_mean(s, y, window):
    """Centred sliding mean of y over window [m] of arc length s [m] (s non-decreasing): the mean of the
    piecewise-linear y over [s - w/2, s + w/2]; nan where the window is not covered by the record or y is nan."""
    s = np.asarray(s, dtype=float)
    y = np.asarray(y, dtype=float)
    out = np.full(s.shape, np.nan)
    ok = np.isfinite(s) & np.isfinite(y)
    if ok.sum() < 2:
        return out
    ss, yy = s[ok], y[ok]
    cum = np.concatenate([[0.0], np.cumsum(0.5 * (yy[1:] + yy[:-1]) * np.diff(ss))])
    h = 0.5 * window
    inside = (s - h >= ss[0]) & (s + h <= ss[-1]) & ok
    out[inside] = (np.interp(s[inside] + h, ss, cum) - np.interp(s[inside] - h, ss, cum)) / window
    return out


def exceeded_distance(s, y, limit):
    """Arc length [m] over which y > limit: each sample holds half of the spacing to each neighbour."""
    s = np.asarray(s, dtype=float)
    y = np.asarray(y, dtype=float)
    if s.size < 2:
        return 0.0
    ds = np.zeros(s.shape)
    d = np.abs(np.diff(s))
    ds[:-1] += 0.5 * d
    ds[1:] += 0.5 * d
    return float(np.sum(ds[np.nan_to_num(y, nan=-np.inf) > limit]))


def butter2_lowpass(fc, fs):
    """(b, a) of a second-order Butterworth low-pass at fc [Hz] for sampling frequency fs [Hz] (bilinear,
    pre-warped)."""
    w = 2 * math.pi * fc
    return comfort._bilinear_biquad((0.0, 0.0, w * w), (1.0, w * math.sqrt(2.0), w * w), fc, fs)


def lowpass_zero_phase(t, y, fc):
    """y (N,) or (N, k) low-passed at fc [Hz] forward and backward (zero phase, fourth order in magnitude)
    on its uniform resampling, returned at the original instants; y unchanged when fc >= fs/2."""
    tu, yu, fs = comfort.uniform(t, y)
    if not (fc < 0.5 * fs) or tu.size < 8:
        return np.asarray(y, dtype=float)
    b, a = butter2_lowpass(fc, fs)
    y0 = yu[:1]
    f = comfort.biquad(b, a, yu - y0) + y0
    f = f[::-1]
    f0 = f[:1]
    f = comfort.biquad(b, a, f - f0) + f0
    f = f[::-1]
    if f.ndim == 1:
        return np.interp(t, tu, f)
    return np.stack([np.interp(t, tu, f[:, k]) for k in range(f.shape[1])], axis=1)


# ---------------------------------------------------------------------------------------------------------
# Loading

def p2_force(t, Q, cutoff_hz=P2_CUTOFF_HZ):
    """Q (N, ...) low-passed at cutoff_hz [Hz] (zero phase), whose maximum is the P2 force of an impact; None
    when the samples (t, uniform) are too sparse for the cut-off (rate at most twice it)."""
    rate = (len(t) - 1) / (t[-1] - t[0]) if len(t) > 1 and t[-1] > t[0] else 0.0
    if not rate > 2.0 * cutoff_hz:
        return None
    Q = np.asarray(Q, dtype=float)
    return lowpass_zero_phase(t, Q.reshape(len(t), -1), cutoff_hz).reshape(Q.shape)


def _find_topic(bags, topic):
    """The first of the bags (paths, None skipped) that records topic, or None."""
    for b in bags:
        if b and os.path.isfile(b) and topic in loading.bag_topics(b):
            return b
    return None


def load_floor(path):
    """/floor_accelerations: dict t [s] (N,), names [str] (M,), position [m] (M, 3) in the vehicle data frame,
    specific_force [m/s^2] (N, M, 3) in the carbody frame (x forward, y left, z up)."""
    msgs = loading._messages(path, "/floor_accelerations", "ride comfort")
    names = list(msgs[0].names)
    t = np.array([m.header.stamp.to_sec() for m in msgs])
    a = np.full((len(msgs), len(names), 3), np.nan)
    for i, m in enumerate(msgs):
        for j, v in enumerate(m.specific_force[:len(names)]):
            a[i, j] = (v.x, v.y, v.z)
    pos = np.array([[p.x, p.y, p.z] for p in msgs[0].position]) if msgs[0].position else np.zeros((0, 3))
    order = np.argsort(t, kind="stable")
    return {"t": t[order], "names": names, "position": pos, "specific_force": a[order]}


def load_pads(path):
    """/pad_forces: list per message of dict arc_length [m] (K,), left_pad, right_pad [N] (K, 3),
    left_disp, right_disp [m] (K, 3), ballast [N] (K, 3) (track frame), gap [m] (K,) (the hanging sleepers'
    open void; ballast and gap None in a bag recorded before the message had them), and t [s] (N,)."""
    msgs = loading._messages(path, "/pad_forces", "pad forces")
    frames = []
    vec = lambda vs: np.array([[v.x, v.y, v.z] for v in vs]).reshape(-1, 3)
    for m in msgs:
        frames.append({"arc_length": np.array(m.arc_length, dtype=float),
                       "left_pad": vec(m.left_pad_force), "right_pad": vec(m.right_pad_force),
                       "left_disp": vec(m.left_rail_displacement), "right_disp": vec(m.right_rail_displacement),
                       "ballast": (vec(m.ballast_force) if len(getattr(m, "ballast_force", ())) == len(m.arc_length)
                                   else None),
                       "gap": (np.array(m.ballast_gap, dtype=float)
                               if len(getattr(m, "ballast_gap", ())) == len(m.arc_length) else None)})
    t = np.array([m.header.stamp.to_sec() for m in msgs])
    order = np.argsort(t, kind="stable")
    return {"t": t[order], "frames": [frames[i] for i in order]}


def static_wheel_load_from_vehicle(path, wheelsets):
    """Static wheel load Q0 [N] = total mass |g| / (2 wheelsets) from a vehicle data file (bodies[].mass,
    gravity). Raises AnalysisInputError naming the file and field."""
    data = loading.load_yaml(path, required=("bodies",))
    bodies = data["bodies"]
    if not isinstance(bodies, list) or not bodies:
        raise AnalysisInputError("%s: bodies: expected a non-empty list" % path)
    total = 0.0
    for i, b in enumerate(bodies):
        try:
            m = float(b["mass"])
        except (TypeError, KeyError, ValueError):
            raise AnalysisInputError("%s: bodies[%d].mass: missing or not a number" % (path, i))
        if not (m > 0 and math.isfinite(m)):
            raise AnalysisInputError("%s: bodies[%d].mass: must be > 0, got %r" % (path, i, m))
        total += m
    g = G
    if "gravity" in data:
        try:
            g = float(np.linalg.norm(np.array(data["gravity"], dtype=float)))
        except (TypeError, ValueError):
            raise AnalysisInputError("%s: gravity: expected three numbers, got %r" % (path, data["gravity"]))
    if not (wheelsets > 0):
        raise AnalysisInputError("%s: wheelsets: must be > 0, got %r" % (path, wheelsets))
    return total * g / (2.0 * wheelsets)


class SafetyRun(object):
    """One run's inputs for the safety evaluation: name, scene (raw mapping) and scene_path, kinematics
    (loading.load_wheelset_kinematics), contacts (loading.load_contact_points) or None, floor (load_floor) or None, pads
    (load_pads) or None, missing {topic: bag searched}, notes [str], bags used."""

    def __init__(self, name):
        self.name = name
        self.scene = {}
        self.scene_path = None
        self.kinematics = None
        self.contacts = None
        self.floor = None
        self.pads = None
        self.missing = {}
        self.notes = []
        self.bag = None
        self.track_bag = None

    def hanging_sleepers(self):
        """True when the scene hangs sleepers over a void (a track.support zone with sleeper_gap, applied)."""
        if not (self.scene.get("effects") or {}).get("support_variation"):
            return False
        return any(isinstance(z, dict) and "sleeper_gap" in z for z in (self.scene.get("track") or {}).get("support") or ())

    def track_model(self):
        return str((self.scene.get("effects") or {}).get("track_model", ""))

    def speed(self):
        v = (self.scene.get("vehicle") or {}).get("speed")
        try:
            return float(v)
        except (TypeError, ValueError):
            return float("nan")


def load(bag, scene_path=None, track_bag=None, name=None):
    """Loads a run from its vehicle bag, the track bag (co-simulation, optional) and the resolved scene.
    /wheelset_kinematics is required (MissingTopicError); the other topics are optional and recorded in
    .missing when absent."""
    run = SafetyRun(name or os.path.basename(bag).split(".")[0])
    run.bag, run.track_bag = bag, track_bag
    if not os.path.isfile(bag):
        raise AnalysisInputError("%s: no such bag" % bag)
    if scene_path is not None:
        run.scene = loading.load_yaml(scene_path)
        run.scene_path = scene_path
    run.kinematics = loading.load_wheelset_kinematics(bag)
    if run.kinematics["left_force"] is None:
        raise AnalysisInputError("%s: /wheelset_kinematics lacks left_force_in_track / right_force_in_track "
                                 "(needed for Y and Q)" % bag)
    bags = [bag, track_bag]
    found = _find_topic([track_bag, bag], "/contact_points")
    if found:
        run.contacts = loading.load_contact_points(found, "Tgamma")
    else:
        run.missing["/contact_points"] = track_bag or bag
    found = _find_topic(bags, "/floor_accelerations")
    if found:
        run.floor = load_floor(found)
    else:
        run.missing["/floor_accelerations"] = bag
    found = _find_topic([track_bag, bag], "/pad_forces")
    if found:
        run.pads = load_pads(found)
    else:
        run.missing["/pad_forces"] = track_bag or bag
    return run


def load_run_dir(directory, name):
    """load() of <directory>/<name>.bag, <name>.track.bag (when present), <name>.scene.yaml (when present)."""
    bag = os.path.join(directory, name + ".bag")
    track = os.path.join(directory, name + ".track.bag")
    scene = os.path.join(directory, name + ".scene.yaml")
    run = load(bag, scene if os.path.isfile(scene) else None, track if os.path.isfile(track) else None, name)
    if run.scene_path is None:
        run.notes.append("%s.scene.yaml: missing; friction and static load from defaults and the bag" % name)
    return run


# ---------------------------------------------------------------------------------------------------------
# Evaluation

class Row(object):
    """One summary-table row: quantity, unit, value (the maximum), wheel_id / wheelset / side (or None),
    s [m], t [s] where it occurs, limit (or None), margin = limit - value (same unit), status
    (pass/fail/informative/not available), note (source, settings, or what is missing)."""

    FIELDS = ("quantity", "unit", "value", "wheel_id", "wheelset", "side", "s", "t", "limit", "margin", "status",
              "note")

    def __init__(self, quantity, unit, value=None, wheel_id=None, s=None, t=None, limit=None, status=INFO,
                 note="", wheelset=None, side=None):
        self.quantity, self.unit, self.value = quantity, unit, value
        self.wheel_id = wheel_id
        self.wheelset = wheelset if wheelset is not None else (wheel_id // 2 if wheel_id is not None else None)
        self.side = side if side is not None else (wheel_id % 2 if wheel_id is not None else None)
        self.s, self.t, self.limit = s, t, limit
        self.margin = (limit - value) if (limit is not None and value is not None) else None
        self.status, self.note = status, note


def _status(value, limit):
    return PASS if value <= limit else FAIL


def _resolve_friction(run, settings):
    if settings.friction is not None:
        return float(settings.friction), "option"
    for where in (("contact", "friction"), ("effects", "friction"), ("track", "friction")):
        d = run.scene.get(where[0])
        if isinstance(d, dict) and where[1] in d:
            try:
                mu = float(d[where[1]])
            except (TypeError, ValueError):
                raise AnalysisInputError("%s: %s.%s: not a number (%r)" % (run.scene_path, where[0], where[1],
                                                                          d[where[1]]))
            if not (0 < mu < 5):
                raise AnalysisInputError("%s: %s.%s: must be in (0, 5), got %g" % (run.scene_path, where[0],
                                                                                   where[1], mu))
            return mu, "scene %s.%s" % where
    return DEFAULT_FRICTION, "default of the contact model (the scene has no friction key)"


def _resolve_q0(run, settings, kin, mask):
    """(Q0 [N], source): the option, else the vehicle data file's masses, else the mean Q of all wheels after
    the discard."""
    if settings.q0 is not None:
        return float(settings.q0), "option"
    veh = run.scene.get("vehicle") or {}
    path = veh.get("data")
    wheelsets = veh.get("wheelsets", kin["arc_length"].shape[1])
    if path:
        if not os.path.isabs(path):
            # Relative to the scene file the run was made from: the resolved scene's directory, else the
            # original scene named by the runner's <run>.run.yaml beside the bag.
            candidates = [os.path.dirname(run.scene_path)] if run.scene_path else []
            run_yaml = os.path.join(os.path.dirname(run.bag or ""), run.name + ".run.yaml")
            if os.path.isfile(run_yaml):
                try:
                    original = (loading.load_yaml(run_yaml) or {}).get("scene")
                except AnalysisInputError:
                    original = None
                if original:
                    candidates.append(os.path.dirname(str(original)))
            found = [os.path.join(d, path) for d in candidates if os.path.isfile(os.path.join(d, path))]
            path = found[0] if found else os.path.join(candidates[0] if candidates else "", path)
        if os.path.isfile(path):
            try:
                return static_wheel_load_from_vehicle(path, int(wheelsets)), \
                    "vehicle data file masses (%s)" % os.path.basename(path)
            except (TypeError, ValueError):
                raise AnalysisInputError("%s: vehicle.wheelsets: not an integer (%r)" % (run.scene_path, wheelsets))
        run.notes.append("vehicle data file %s not found: static wheel load estimated from the bag" % path)
    q = np.concatenate([kin["left_force"][mask, :, 2].ravel(), kin["right_force"][mask, :, 2].ravel()])
    q = q[np.isfinite(q)]
    return float(np.mean(q)), "estimated: mean Q of all wheels after the discard"


class Evaluation(object):
    """The evaluated quantities of one run: rows [Row], and the series for figures:
    t (N,), s (N, W) wheelset arc lengths, yq, yq_2m (N, W, 2), Y, Q, Q_f, Q_qst (N, W, 2) [N],
    sumy, sumy_2m (N, W) [N], limits {name: value}, tgamma {t, s (N, 2W), value (N, 2W)} or None,
    comfort {point name: ComfortResult} or None, pads {t, s_max..} or None, q0, friction, sources."""


def wheel_label(wheel_id):
    return "wheelset %d %s" % (wheel_id // 2 + 1, "left" if wheel_id % 2 == 0 else "right")


def _argmax_nan(a):
    a = np.where(np.isfinite(a), a, -np.inf)
    return np.unravel_index(int(np.argmax(a)), a.shape)


def evaluate(run, settings=None):
    """Evaluates every quantity of the run (SafetyRun) into an Evaluation."""
    st = settings or Settings()
    ev = Evaluation()
    ev.settings = st
    kin = run.kinematics
    mask = kin["t"] >= st.t_discard
    if mask.sum() < 2:
        raise AnalysisTooShortError("%s: fewer than 2 /wheelset_kinematics samples after t = %.3f s: the run "
                                    "is too short for this analysis" % (run.bag, st.t_discard))
    t = kin["t"][mask]
    s = kin["arc_length"][mask]
    fl, fr = kin["left_force"][mask], kin["right_force"][mask]
    W = s.shape[1]
    Y = np.stack([-fl[:, :, 1], fr[:, :, 1]], axis=2)          # toward the track centre, > 0 flanging
    Q = np.stack([fl[:, :, 2], fr[:, :, 2]], axis=2)
    with np.errstate(divide="ignore", invalid="ignore"):
        yq = np.where(Q > 0, Y / Q, np.nan)
    sumy = fl[:, :, 1] + fr[:, :, 1]
    yq_2m = np.full(yq.shape, np.nan)
    sumy_2m = np.full(sumy.shape, np.nan)
    for w in range(W):
        for side in (0, 1):
            yq_2m[:, w, side] = sliding_mean(s[:, w], yq[:, w, side], st.window)
        sumy_2m[:, w] = sliding_mean(s[:, w], sumy[:, w], st.window)
    Qf = lowpass_zero_phase(t, Q.reshape(len(t), -1), st.q_cutoff_hz).reshape(Q.shape)
    Qqst = lowpass_zero_phase(t, Q.reshape(len(t), -1), st.qst_cutoff_hz).reshape(Q.shape)
    mu, mu_src = _resolve_friction(run, st)
    q0, q0_src = _resolve_q0(run, st, kin, mask)
    if not (q0 > 0):
        raise AnalysisInputError("%s: static wheel load not positive (%g N)" % (run.bag, q0))
    gamma = math.radians(st.flange_angle_deg)
    lim_yq = nadal_limit(gamma, mu)
    lim_sumy = prudhomme_limit(2 * q0, st.alpha)
    speed = run.speed()
    lim_q = st.q_limit if st.q_limit is not None else (q_limit_for_speed(speed) if math.isfinite(speed) else None)
    ev.t, ev.s, ev.Y, ev.Q, ev.yq, ev.yq_2m, ev.sumy, ev.sumy_2m = t, s, Y, Q, yq, yq_2m, sumy, sumy_2m
    ev.Q_f, ev.Q_qst, ev.q0, ev.friction = Qf, Qqst, q0, mu
    ev.limits = {"yq": lim_yq, "sumy": lim_sumy, "unloading": st.unloading_limit, "q": lim_q,
                 "q_qst": st.q_qst_limit}
    ev.sources = {"friction": mu_src, "q0": q0_src}
    rows = []

    def wheel_row(quantity, unit, a, limit, note, status_fn=_status, scale=1.0):
        i, w, side = _argmax_nan(a)
        v = float(a[i, w, side])
        if not math.isfinite(v):
            rows.append(Row(quantity, unit, status=NOT_AVAILABLE, note="no finite value after the discard"))
            return
        lim = None if limit is None else limit * scale
        rows.append(Row(quantity, unit, v * scale, 2 * w + side, float(s[i, w]), float(t[i]), lim,
                        status_fn(v * scale, lim) if lim is not None else INFO, note))

    nadal_note = ("Nadal (tan g - mu)/(1 + mu tan g), g = %.1f deg, mu = %.3g (%s)"
                  % (st.flange_angle_deg, mu, mu_src))
    # Y/Q: judged on the 2 m sliding mean; the raw maximum and the distance over the limit reported too.
    wheel_row("Y/Q (%.0f m mean)" % st.window, "-", yq_2m, lim_yq, nadal_note + "; sliding mean over %.1f m" % st.window)
    raw = yq
    i, w, side = _argmax_nan(raw)
    dist = exceeded_distance(s[:, w], raw[:, w, side], lim_yq)
    worst = max(range(2 * W), key=lambda k: exceeded_distance(s[:, k // 2], raw[:, k // 2, k % 2], lim_yq))
    worst_d = exceeded_distance(s[:, worst // 2], raw[:, worst // 2, worst % 2], lim_yq)
    rows.append(Row("Y/Q (instantaneous)", "-", float(raw[i, w, side]), 2 * w + side, float(s[i, w]), float(t[i]),
                    lim_yq, INFO, "not judged (EN 14363 judges the 2 m mean); over the limit along %.2f m "
                    "(most: %s, %.2f m)" % (dist, wheel_label(worst), worst_d)))
    ev.yq_exceeded = {k: exceeded_distance(s[:, k // 2], raw[:, k // 2, k % 2], lim_yq) for k in range(2 * W)}
    rows.append(Row("Y/Q over the limit (distance)", "m", worst_d, worst, None, None, None, INFO,
                    "arc length along which the instantaneous Y/Q exceeds Nadal's limit, largest wheel"))
    unload = (q0 - Q) / q0
    wheel_row("wheel unloading dQ/Q0", "-", unload, st.unloading_limit, "Q0 = %.1f kN (%s)" % (q0 / 1e3, q0_src))
    # SumY: magnitude of the 2 m mean.
    a = np.abs(sumy_2m)
    a2 = np.where(np.isfinite(a), a, -np.inf)
    i, w = np.unravel_index(int(np.argmax(a2)), a2.shape)
    if math.isfinite(a[i, w]):
        v = float(a[i, w])
        rows.append(Row("track-shift force SumY (%.0f m mean, magnitude)" % st.window, "N", v, None, float(s[i, w]),
                        float(t[i]), lim_sumy, _status(v, lim_sumy),
                        "Prud'homme alpha (10 kN + P/3), alpha = %.2f, P = 2 Q0 = %.1f kN; sliding mean over %.1f m"
                        % (st.alpha, 2 * q0 / 1e3, st.window), wheelset=int(w), side=None))
    else:
        rows.append(Row("track-shift force SumY (%.0f m mean, magnitude)" % st.window, "N", status=NOT_AVAILABLE,
                        note="record shorter than the %.1f m window" % st.window))
    wheel_row("vertical wheel force Q (%.0f Hz low-pass)" % st.q_cutoff_hz, "N", Qf, lim_q,
              "EN 14363 Q_lim for V = %.0f km/h" % (speed * 3.6) if st.q_limit is None else "option")
    wheel_row("quasi-static Q (%.1f Hz low-pass)" % st.qst_cutoff_hz, "N", Qqst, st.q_qst_limit,
              "EN 14363 Q_qst,lim; low-pass cut-off %.1f Hz" % st.qst_cutoff_hz)
    # Impact peaks: informative (no limit of their own; EN 14363's Q_lim above judges the 20 Hz force).
    rate = (len(t) - 1) / (t[-1] - t[0]) if t[-1] > t[0] else 0.0
    p1_note = "unfiltered, at the output rate %.0f Hz" % rate
    if rate < P1_MIN_RATE_HZ:
        p1_note += " (under-sampled: an impact lasts about 1 ms; output.rate >= %.0f Hz resolves it)" % P1_MIN_RATE_HZ
    wheel_row("impact force P1 (unfiltered Q)", "N", Q, None, p1_note)
    Qp2 = p2_force(t, Q, st.p2_cutoff_hz)
    ev.Q_p2 = Qp2
    if Qp2 is not None:
        wheel_row("impact force P2 (%.0f Hz low-pass)" % st.p2_cutoff_hz, "N", Qp2, None,
                  "the wheel-on-track resonance after an impact (30-90 Hz)")
    else:
        rows.append(Row("impact force P2 (%.0f Hz low-pass)" % st.p2_cutoff_hz, "N", status=NOT_AVAILABLE,
                        note="needs output.rate above %.0f Hz" % (2.0 * st.p2_cutoff_hz)))

    # Tgamma.
    ev.tgamma = None
    if run.contacts is None:
        rows.append(Row("wear index Tgamma", "N", status=NOT_AVAILABLE, note=not_available_text("/contact_points")))
    else:
        ev.tgamma = tgamma_series(run.contacts, kin, W, st.t_discard)
        tg = ev.tgamma["value"]
        if tg.size and np.isfinite(tg).any():
            i, k = np.unravel_index(int(np.nanargmax(tg)), tg.shape)
            rows.append(Row("wear index Tgamma", "N", float(tg[i, k]), int(k), float(ev.tgamma["s"][i, k]),
                            float(ev.tgamma["t"][i]), None, INFO,
                            "sum over tread and flange of |Tx nu_x| + |Ty nu_y| (spin term not included); "
                            "WLRM bands %g / %g / %g J/m" % TGAMMA_BANDS))
        else:
            rows.append(Row("wear index Tgamma", "N", status=NOT_AVAILABLE, note="no contact samples after the discard"))

    # Comfort.
    ev.comfort = None
    if run.floor is None:
        rows.append(Row("mean comfort N_MV", "-", status=NOT_AVAILABLE, note=not_available_text("/floor_accelerations")))
    else:
        ev.comfort = {}
        fl_ = run.floor
        for j, pname in enumerate(fl_["names"]):
            r = comfort.mean_comfort(fl_["t"], fl_["specific_force"][:, j, :], st.t_discard + st.comfort_settle,
                                     st.comfort_window)
            ev.comfort[pname] = r
            rows.append(Row("mean comfort N_MV at %s" % pname, "-", r.n_mv if math.isfinite(r.n_mv) else None,
                            None, None, None, None, INFO if math.isfinite(r.n_mv) else NOT_AVAILABLE,
                            "EN 12299: %s; a_P95 x/y/z = %.3f/%.3f/%.3f m/s^2%s" % (
                                comfort.comfort_class(r.n_mv) if math.isfinite(r.n_mv) else "n/a",
                                r.a_p95.get("x", float("nan")), r.a_p95.get("y", float("nan")),
                                r.a_p95.get("z", float("nan")), ("; " + r.note) if r.note else "")))

    # Pads and rail displacement (flexible track).
    ev.pads = None
    if run.pads is None:
        if run.track_model() and run.track_model() != "flexible":
            note = "not applicable: track_model %s (pad forces exist on the flexible track only)" % run.track_model()
        else:
            note = not_available_text("/pad_forces")
        for q, u in (("pad compression (max)", "N"), ("ballast force (max)", "N"), ("rail displacement (max)", "m"),
                     ("sleeper void (max open)", "m")):
            rows.append(Row(q, u, status=NOT_AVAILABLE, note=note))
    else:
        ev.pads = pad_extremes(run.pads, st.t_discard)
        p = ev.pads
        rows.append(Row("pad compression (max)", "N", p["compression"], None, p["compression_s"], p["compression_t"],
                        None, INFO, "-z of the rail-on-sleeper pad force, %s rail" % p["compression_rail"],
                        side=p["compression_side"]))
        if p["ballast"] is None:
            rows.append(Row("ballast force (max)", "N", status=NOT_AVAILABLE,
                            note="the bag's /pad_forces has no ballast forces (recorded by an older build)"))
        else:
            rows.append(Row("ballast force (max)", "N", p["ballast"], None, p["ballast_s"], p["ballast_t"], None,
                            INFO, "-z of the sleeper-on-ballast force, summed over the sleeper"))
        rows.append(Row("rail displacement (max)", "m", p["displacement"], None, p["displacement_s"],
                        p["displacement_t"], None, INFO, "magnitude of the rail centre displacement, %s rail"
                        % p["displacement_rail"], side=p["displacement_side"]))
        if not run.hanging_sleepers():
            rows.append(Row("sleeper void (max open)", "m", status=NOT_AVAILABLE,
                            note="no hanging sleepers in the scene (track.support sleeper_gap)"))
        elif p["gap"] is None:
            rows.append(Row("sleeper void (max open)", "m", status=NOT_AVAILABLE,
                            note="the bag's /pad_forces has no sleeper voids (recorded by an older build)"))
        else:
            rows.append(Row("sleeper void (max open)", "m", p["gap"], None, p["gap_s"], p["gap_t"], None, INFO,
                            "open void between a hanging sleeper and the ballast, mean over its ballast elements"))
    ev.rows = rows
    return ev


def tgamma_series(contacts, kin, wheelsets, t_discard=0.0):
    """Tgamma per wheel [N] (sum over its active contacts of |Tx nu_x| + |Ty nu_y|): dict t (N,), value (N, 2W),
    s (N, 2W) the wheel's wheelset arc length at t (from the kinematics), and per-kind sums tread, flange."""
    keep = contacts["t"] >= t_discard
    c = {k: v[keep] for k, v in contacts.items()}
    per_point = np.where(c["active"], np.abs(c["creep_force_longitudinal"] * c["creepage_longitudinal"]) +
                         np.abs(c["creep_force_lateral"] * c["creepage_lateral"]), 0.0)
    n = c["t"].size
    val = np.zeros((n, 2 * wheelsets))
    tread = np.zeros((n, 2 * wheelsets))
    flange = np.zeros((n, 2 * wheelsets))
    s = np.full((n, 2 * wheelsets), np.nan)
    for k in range(2 * wheelsets):
        sel = c["wheel_id"] == k
        val[:, k] = np.where(sel, per_point, 0.0).sum(axis=1)
        on_flange = loading.flange_contact_mask(c)
        tread[:, k] = np.where(sel & ~on_flange, per_point, 0.0).sum(axis=1)
        flange[:, k] = np.where(sel & on_flange, per_point, 0.0).sum(axis=1)
        sw = kin["arc_length"][:, k // 2]
        ok = np.isfinite(sw)
        if ok.sum() >= 2:
            s[:, k] = np.interp(c["t"], kin["t"][ok], sw[ok])
    return {"t": c["t"], "value": val, "tread": tread, "flange": flange, "s": s}


def pad_extremes(pads, t_discard=0.0):
    """Largest pad compression (-z of the pad force) [N], largest ballast force (-z of the sleeper-on-ballast
    force) [N], largest rail displacement magnitude [m] and largest open sleeper void [m] over the sleepers
    and instants from t_discard on, with where (arc length, time, rail); ballast and gap None when the frames
    have no ballast forces or voids."""
    best = {"compression": -np.inf, "displacement": -np.inf, "ballast": -np.inf}
    out = {}
    ballast = None
    gap = None
    for t, fr in zip(pads["t"], pads["frames"]):
        if t < t_discard or fr["arc_length"].size == 0:
            continue
        if fr.get("gap") is not None:
            j = int(np.argmax(fr["gap"]))
            if gap is None or fr["gap"][j] > gap["gap"]:
                gap = {"gap": float(fr["gap"][j]), "gap_s": float(fr["arc_length"][j]), "gap_t": float(t)}
        if fr.get("ballast") is not None:
            comp = -fr["ballast"][:, 2]
            j = int(np.argmax(comp))
            if comp[j] > best["ballast"]:
                best["ballast"] = comp[j]
                ballast = {"ballast": float(comp[j]), "ballast_s": float(fr["arc_length"][j]), "ballast_t": float(t)}
        for side, rail in ((0, "left"), (1, "right")):
            comp = -fr[rail + "_pad"][:, 2]
            j = int(np.argmax(comp))
            if comp[j] > best["compression"]:
                best["compression"] = comp[j]
                out.update(compression=float(comp[j]), compression_s=float(fr["arc_length"][j]),
                           compression_t=float(t), compression_rail=rail, compression_side=side)
            d = np.linalg.norm(fr[rail + "_disp"], axis=1)
            j = int(np.argmax(d))
            if d[j] > best["displacement"]:
                best["displacement"] = d[j]
                out.update(displacement=float(d[j]), displacement_s=float(fr["arc_length"][j]),
                           displacement_t=float(t), displacement_rail=rail, displacement_side=side)
    if not out:
        out = {"compression": None, "compression_s": None, "compression_t": None, "compression_rail": "-",
               "compression_side": None, "displacement": None, "displacement_s": None, "displacement_t": None,
               "displacement_rail": "-", "displacement_side": None}
    out.update(ballast or {"ballast": None, "ballast_s": None, "ballast_t": None})
    out.update(gap or {"gap": None, "gap_s": None, "gap_t": None})
    return out


QUANTITIES = ("Y/Q", "Y/Q_2m", "Tgamma", "Q", "dQ/Q0")


def largest(run, quantity, settings=None):
    """(wheel_id, side, value) of the wheel with the largest value of quantity over the run after the
    discard: 'Y/Q' (instantaneous), 'Y/Q_2m' (2 m mean), 'Tgamma' [N], 'Q' [N] (raw), 'dQ/Q0' [-].
    run: a SafetyRun or an Evaluation. Raises AnalysisInputError when the quantity's topic is missing."""
    if quantity not in QUANTITIES:
        raise ValueError("unknown quantity %r (known: %s)" % (quantity, ", ".join(QUANTITIES)))
    ev = run if isinstance(run, Evaluation) else evaluate(run, settings)
    if quantity == "Tgamma":
        if ev.tgamma is None:
            raise AnalysisInputError("Tgamma " + not_available_text("/contact_points"))
        a = ev.tgamma["value"]
        i, k = np.unravel_index(int(np.nanargmax(a)), a.shape)
        return int(k), int(k % 2), float(a[i, k])
    a = {"Y/Q": ev.yq, "Y/Q_2m": ev.yq_2m, "Q": ev.Q, "dQ/Q0": (ev.q0 - ev.Q) / ev.q0}[quantity]
    i, w, side = _argmax_nan(a)
    return int(2 * w + side), int(side), float(a[i, w, side])


def curve_distribution(ev, scene_data):
    """Tgamma over the curved segments of the scene: [(segment label, wheel_id, mean [N], max [N],
    energy [J] = integral of Tgamma ds over the part of the segment the wheel covered)]."""
    out = []
    if ev.tgamma is None or not scene_data:
        return out
    try:
        sc = loading.Scene(scene_data)
    except AnalysisInputError:
        return out
    tg = ev.tgamma
    for kind, lo, hi, direction in sc.segments:
        if kind not in ("transition", "circular"):
            continue
        label = "%s %s %.0f-%.0f m" % (kind, direction, lo, hi)
        for k in range(tg["value"].shape[1]):
            sk, vk = tg["s"][:, k], tg["value"][:, k]
            m = (sk >= lo) & (sk < hi) & np.isfinite(sk)
            if m.sum() < 2:
                continue
            energy = float(np.trapz(vk[m], sk[m]))
            out.append((label, k, float(np.mean(vk[m])), float(np.max(vk[m])), energy))
    return out
