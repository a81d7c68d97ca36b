"""Numerical analysis of loaded runs (numpy only): deviations on a common time base, amplitude spectra,
wheel passing instants, and the checks of the paper's section 6 observations.

Units: s, m, N, rad (degrees only where a name says deg). Frames: track frame (x along, y left, z up).
"""
import math

import numpy as np

from . import loading
from .loading import SIDE_LEFT, SIDE_RIGHT, flange_normal_force

# The paper's figures for its three runs (section 6.2): largest absolute deviations between the
# standalone run and the co-simulation on the rigid FE track, and wall-time ratios to the standalone run.
PAPER_DEVIATION = {"lateral": 2.5e-5, "angle_of_attack_deg": 4.7e-4, "vertical": 8e-8}  # m, deg, m
PAPER_WALL_RATIO = {"rigid_fe": 7.9, "flexible": 57.3}
# Paper section 6.2: lateral contact forces on the straight 10 % higher with the flexible track.
PAPER_LATERAL_FORCE_RATIO = 1.10
PAPER_SLEEPER_FREQUENCY_HZ = 51.0

AGREES = "agrees"
DISAGREES = "does not agree"
NOT_AVAILABLE = "not available"


def after(t, t_discard):
    """Boolean mask of the samples at or after t_discard [s]."""
    return np.asarray(t) >= t_discard


def common_time_base(t_a, t_b, t_start=0.0):
    """A uniform time base over the overlap of two sample sets from t_start on, with the finer of their
    median sample spacings; empty when they do not overlap."""
    t_a, t_b = np.asarray(t_a, float), np.asarray(t_b, float)
    lo = max(t_a.min(), t_b.min(), t_start)
    hi = min(t_a.max(), t_b.max())
    if hi <= lo:
        return np.zeros(0)
    dt = min(np.median(np.diff(t_a)), np.median(np.diff(t_b)))
    n = int(math.floor((hi - lo) / dt + 1e-9)) + 1
    return lo + dt * np.arange(n)


def max_abs_deviation(t_a, y_a, t_b, y_b, t_start=0.0):
    """max |y_a - y_b| over the common time base of the two series from t_start on (both interpolated
    linearly onto it); nan without overlap."""
    tc = common_time_base(t_a, t_b, t_start)
    if tc.size == 0:
        return float("nan")
    d = np.interp(tc, t_a, y_a) - np.interp(tc, t_b, y_b)
    return float(np.max(np.abs(d)))


def amplitude_spectrum(t, y):
    """One-sided amplitude spectrum of y(t): resampled on a uniform base (the median spacing), linear trend
    removed, Hann window; scaled so that a sinusoid of amplitude A shows a peak of about A.
    Returns (f [Hz], amplitude [units of y], bin width df [Hz])."""
    t, y = np.asarray(t, float), np.asarray(y, float)
    if t.size < 8:
        return np.zeros(0), np.zeros(0), float("nan")
    dt = float(np.median(np.diff(t)))
    n = int(math.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    tu = t[0] + dt * np.arange(n)
    yu = np.interp(tu, t, y)
    yu = yu - np.polyval(np.polyfit(tu - tu[0], yu, 1), tu - tu[0])
    w = np.hanning(n)
    spec = np.abs(np.fft.rfft(yu * w)) * 2.0 / w.sum()
    f = np.fft.rfftfreq(n, dt)
    return f, spec, 1.0 / (n * dt)


def peak_frequency(f, amplitude, f_min=0.0, f_max=float("inf")):
    """(frequency [Hz], amplitude) of the largest spectral line in [f_min, f_max], refined by a parabola
    through the log amplitudes of the peak bin and its neighbours; (nan, nan) if the band is empty."""
    f, a = np.asarray(f), np.asarray(amplitude)
    band = np.where((f >= f_min) & (f <= f_max))[0]
    if band.size == 0:
        return float("nan"), float("nan")
    k = band[np.argmax(a[band])]
    if 0 < k < len(a) - 1 and min(a[k - 1], a[k], a[k + 1]) > 0:
        la, lb, lc = np.log(a[k - 1]), np.log(a[k]), np.log(a[k + 1])
        den = la - 2 * lb + lc
        p = 0.5 * (la - lc) / den if den != 0 else 0.0
        if abs(p) <= 1:
            return float(f[k] + p * (f[1] - f[0])), float(a[k])
    return float(f[k]), float(a[k])


def passing_times(kin, s_section):
    """Instants [s] at which each wheelset's centre reaches arc length s_section [m] (linear interpolation
    of its recorded arc length): a list, index = wheelset, None when it does not reach the section."""
    out = []
    for w in range(kin["arc_length"].shape[1]):
        s = kin["arc_length"][:, w]
        ok = np.isfinite(s)
        s, t = s[ok], kin["t"][ok]
        if s.size < 2 or not (s[0] <= s_section <= s[-1]):
            out.append(None)
            continue
        k = int(np.searchsorted(s, s_section))
        k = min(max(k, 1), len(s) - 1)
        s0, s1 = s[k - 1], s[k]
        out.append(float(t[k - 1] + (t[k] - t[k - 1]) * ((s_section - s0) / (s1 - s0) if s1 != s0 else 0.0)))
    return out


def region_mask(kin, s_ranges, wheelset=0):
    """Samples whose wheelset arc length lies in any of the (s_start, s_end) ranges [m]."""
    s = kin["arc_length"][:, wheelset]
    m = np.zeros(s.shape, bool)
    for lo, hi in s_ranges:
        m |= (s >= lo) & (s < hi)
    return m


def leading_wheel_ids(kin=None):
    """(left, right) wheel ids of the leading wheelset: wheel_id = 2 * wheelset + side."""
    return 2 * 0 + SIDE_LEFT, 2 * 0 + SIDE_RIGHT


def leading_flange_forces(run):
    """(t [s], left [N], right [N]): flange normal forces on the leading wheelset's wheels."""
    left_id, right_id = leading_wheel_ids()
    p = run.points
    return p["t"], flange_normal_force(p, left_id), flange_normal_force(p, right_id)


def deviation_table(standalone, rigid_fe, t_discard):
    """Largest absolute deviations of the leading wheelset between the co-simulation on the rigid FE track
    and the standalone run after t_discard: {'lateral': m, 'angle_of_attack_deg': deg, 'vertical': m}."""
    a, b = standalone.kinematics, rigid_fe.kinematics
    out = {}
    for key, field, scale in (("lateral", "lateral", 1.0), ("angle_of_attack_deg", "angle_of_attack", 180 / math.pi),
                              ("vertical", "vertical", 1.0)):
        out[key] = max_abs_deviation(a["t"], a[field][:, 0] * scale, b["t"], b[field][:, 0] * scale, t_discard)
    return out


def wall_ratios(runs):
    """{'rigid_fe': ratio, 'flexible': ratio} of wall times to the standalone run's (nan when unknown)."""
    def wall(name):
        r = runs.get(name)
        try:
            return float(r.info.get("wall_time")) if r is not None else float("nan")
        except (TypeError, ValueError):
            return float("nan")
    base = wall("standalone")
    return {k: (wall(k) / base if base > 0 else float("nan")) for k in ("rigid_fe", "flexible")}


class Check(object):
    """One observation of the paper checked on the data: title, the paper's statement, the measured
    figures (text) and the status (AGREES, DISAGREES or NOT_AVAILABLE)."""

    def __init__(self, title, paper, measured, status):
        self.title, self.paper, self.measured, self.status = title, paper, measured, status

    def __repr__(self):
        return "Check(%r, %r, %r)" % (self.title, self.status, self.measured)


def _scene(runs):
    for name in ("flexible", "rigid_fe", "standalone"):
        r = runs.get(name)
        if r is not None and r.scene is not None:
            return r.scene
    return None


def _flexible_deflections(runs, title, paper):
    """(the flexible run, the runs' scene, None) when that run recorded rail displacements, else
    (None, scene, the check titled `title` marked not available)."""
    flex = runs.get("flexible")
    if flex is not None and flex.deflection:
        return flex, _scene(runs), None
    return None, _scene(runs), Check(title, paper, "needs the flexible run's rail displacements", NOT_AVAILABLE)


def _outer_inner(scene):
    """(outer, inner) side names of the scene's curve: a left curve has its outer rail on the right."""
    d = scene.curve_direction() if scene is not None else None
    if d is None:
        return None
    return ("right", "left") if d == "left" else ("left", "right")


def _curve_ranges(scene):
    return [(s0, s1) for _, s0, s1, _ in scene.curved_segments()]


def check_flange_outer_only(runs, t_discard):
    """Flange contact only on the outer wheel of the leading wheelset in the curve, for every run with
    contact points that reaches a curved segment."""
    title = "Flange contact only on the outer wheel in the curve"
    paper = "Flange contact only occurs in the outer wheel during curve negotiation (Fig. 19)."
    scene = _scene(runs)
    sides = _outer_inner(scene)
    if sides is None:
        return Check(title, paper, "the scene has no curve", NOT_AVAILABLE)
    outer, inner = sides
    parts, ok_all, any_run = [], True, False
    for name in ("standalone", "rigid_fe", "flexible"):
        r = runs.get(name)
        if r is None or r.points is None:
            continue
        t, left, right = leading_flange_forces(r)
        s = np.interp(t, r.kinematics["t"], r.kinematics["arc_length"][:, 0])
        m = after(t, t_discard) & np.zeros_like(t, dtype=bool)
        for lo, hi in _curve_ranges(scene):
            m |= (s >= lo) & (s < hi) & after(t, t_discard)
        if not m.any():
            continue
        any_run = True
        f = {"left": left[m], "right": right[m]}
        peak_out, peak_in = float(f[outer].max()), float(f[inner].max())
        share_out = float(np.mean(f[outer] > 0))
        # Only the outer wheel: flange contact on the outer wheel, none on the inner (a contact force below
        # 1 % of the outer peak counts as none: numerical grazing of the flange root).
        ok = peak_out > 0 and peak_in <= 0.01 * peak_out
        ok_all &= ok
        parts.append("%s: peak outer (%s) %.1f kN, in flange contact %.0f %% of the curve samples; peak inner "
                     "(%s) %.2f kN" % (name, outer, peak_out / 1e3, 100 * share_out, inner, peak_in / 1e3))
    if not any_run:
        return Check(title, paper, "no run reaches the curve (after the discard)", NOT_AVAILABLE)
    return Check(title, paper, "; ".join(parts) + " (%s)" % loading.FLANGE_CONTACT_DEFINITION,
                 AGREES if ok_all else DISAGREES)


def check_flange_peaks_lower_flexible(runs, t_discard):
    """Peaks of the outer flange force lower with the flexible track than on the rigid track (standalone),
    at the entry of each curved segment the leading wheelset reaches."""
    title = "Lower flange-force peaks with the flexible track"
    paper = ("The flange force peaks when the wheels enter the transition and the curve are smaller when track "
             "flexibility is considered (Fig. 19).")
    scene = _scene(runs)
    sides = _outer_inner(scene)
    rigid, flex = runs.get("standalone"), runs.get("flexible")
    if sides is None:
        return Check(title, paper, "the scene has no curve", NOT_AVAILABLE)
    if rigid is None or flex is None:
        return Check(title, paper, "needs the standalone and flexible runs", NOT_AVAILABLE)
    outer = sides[0]
    parts, ok_all, n = [], True, 0
    for kind, lo, hi, _ in scene.curved_segments():
        peaks = []
        for r in (rigid, flex):
            t, left, right = leading_flange_forces(r)
            s = np.interp(t, r.kinematics["t"], r.kinematics["arc_length"][:, 0])
            m = (s >= lo) & (s < hi) & after(t, t_discard)
            peaks.append(float((left if outer == "left" else right)[m].max()) if m.any() else None)
        if None in peaks or max(peaks) <= 0:
            continue
        n += 1
        ok = peaks[1] < peaks[0]
        ok_all &= ok
        parts.append("%s %.0f-%.0f m: rigid %.1f kN, flexible %.1f kN (%+.0f %%)"
                     % (kind, lo, hi, peaks[0] / 1e3, peaks[1] / 1e3, 100 * (peaks[1] / peaks[0] - 1)))
    if n == 0:
        return Check(title, paper, "no flange contact in a curved segment both runs reach", NOT_AVAILABLE)
    return Check(title, paper, "peak outer flange force per segment: " + "; ".join(parts),
                 AGREES if ok_all else DISAGREES)


def check_lateral_force_straight(runs, t_discard):
    """Mean absolute lateral (y) contact force on the leading wheels on the first straight: flexible track
    against the rigid track (standalone); the paper finds it 10 % higher."""
    title = "Lateral wheel forces on the straight higher with the flexible track"
    paper = "On the straight the lateral contact forces with the flexible track are 10 % higher (Fig. 20)."
    rigid, flex = runs.get("standalone"), runs.get("flexible")
    scene = _scene(runs)
    if rigid is None or flex is None:
        return Check(title, paper, "needs the standalone and flexible runs", NOT_AVAILABLE)
    if rigid.kinematics["left_force"] is None or flex.kinematics["left_force"] is None:
        return Check(title, paper, "wheel forces in the track frame not recorded", NOT_AVAILABLE)
    straight = scene.first_straight() if scene is not None else None
    if straight is None:
        return Check(title, paper, "the track does not start with a straight", NOT_AVAILABLE)
    means = []
    for r in (rigid, flex):
        k = r.kinematics
        m = region_mask(k, [straight]) & after(k["t"], t_discard)
        if not m.any():
            return Check(title, paper, "no samples on the first straight after the discard", NOT_AVAILABLE)
        means.append((float(np.mean(np.abs(k["left_force"][m, 0, 1]))),
                      float(np.mean(np.abs(k["right_force"][m, 0, 1])))))
    ratios = [means[1][i] / means[0][i] if means[0][i] > 0 else float("nan") for i in (0, 1)]
    ok = all(np.isfinite(x) and x > 1.0 for x in ratios)
    text = ("mean |F_y| on the first straight, rigid -> flexible: left %.2f -> %.2f kN (x%.3f), right %.2f -> "
            "%.2f kN (x%.3f); paper x%.2f" % (means[0][0] / 1e3, means[1][0] / 1e3, ratios[0],
                                             means[0][1] / 1e3, means[1][1] / 1e3, ratios[1],
                                             PAPER_LATERAL_FORCE_RATIO))
    return Check(title, paper, text, AGREES if ok else DISAGREES)


def _section_kind(scene, s):
    seg = scene.segment_at(s) if scene is not None else None
    return seg[0] if seg is not None else None


def _peak_signed(y):
    """The value of largest magnitude of y (keeps its sign)."""
    return float(y[np.argmax(np.abs(y))])


def check_rails_outward_in_curve(runs, t_discard):
    """Lateral displacement of both rails at a section in a curved segment (the flexible run): both pushed
    toward the outside of the curve."""
    title = "Rails pushed outward in the curve"
    paper = ("On the curved segment both rails are displaced to the outer side of the curve, the outer rail more "
             "(Fig. 23).")
    flex, scene, missing = _flexible_deflections(runs, title, paper)
    if missing is not None:
        return missing
    sides = _outer_inner(scene)
    if sides is None:
        return Check(title, paper, "the scene has no curve", NOT_AVAILABLE)
    outward = -1.0 if scene.curve_direction() == "left" else 1.0  # sign of y toward the outside
    parts, ok_all, n = [], True, 0
    for s, d in flex.deflection.items():
        if _section_kind(scene, s) not in ("circular", "transition"):
            continue
        # The vehicle's effect: from just before the first wheelset reaches the section to just after the
        # last one leaves it, relative to the rails before it came (on a canted curve the track's own
        # weight already shifts both rails toward the inside).
        passing = [p for p in passing_times(flex.kinematics, s) if p is not None]
        if not passing:
            continue
        t = d["t"]
        m = after(t, t_discard) & (t >= min(passing) - 0.1) & (t <= max(passing) + 0.1)
        if not m.any():
            continue
        before = int(np.argmax(t >= max(t_discard, min(passing) - 0.1)))
        n += 1
        yl = _peak_signed(d["left"][m, 1] - d["left"][before, 1])
        yr = _peak_signed(d["right"][m, 1] - d["right"][before, 1])
        ok = yl * outward > 0 and yr * outward > 0
        ok_all &= ok
        outer_more = abs(yr if sides[0] == "right" else yl) > abs(yl if sides[0] == "right" else yr)
        parts.append("at %.0f m peak lateral displacement under the vehicle left %+.3f mm, right %+.3f mm (outside = %s y); the "
                     "outer rail moves %s" % (s, yl * 1e3, yr * 1e3, "-" if outward < 0 else "+",
                                              "more" if outer_more else "less"))
    if n == 0:
        return Check(title, paper, "no deflection section in a curved segment that the vehicle passes", NOT_AVAILABLE)
    return Check(title, paper, "; ".join(parts), AGREES if ok_all else DISAGREES)


def wheel_location(kin, t, s_section, bogies=((0, 1), (2, 3)), under=None):
    """Where the wheels are when the rail at s_section peaks at time t: ('under', wheelset) when a wheelset
    is within `under` m (default half a metre) of the section, ('between', bogie index) when the section lies
    between the wheelsets of a bogie, else ('outside', None)."""
    under = 0.5 if under is None else under
    s = np.array([np.interp(t, kin["t"], kin["arc_length"][:, w]) for w in range(kin["arc_length"].shape[1])])
    d = s - s_section
    w = int(np.argmin(np.abs(d)))
    if abs(d[w]) <= under:
        return ("under", w)
    for b, (front, rear) in enumerate(bogies):
        if rear < len(s) and s[rear] < s_section < s[front]:
            return ("between", b)
    return ("outside", None)


def check_max_between_bogie_wheels(runs, t_discard, under=None):
    """At a section on a straight (flexible run), the instant of the largest absolute lateral and vertical
    displacement of each rail falls between the wheels of a bogie (not under a wheel)."""
    title = "Largest rail displacement between the wheels of a bogie on the straight"
    paper = ("The absolute maximum displacement peaks are observed in-between the front and rear wheel passage of "
             "each bogie (Fig. 22).")
    flex, scene, missing = _flexible_deflections(runs, title, paper)
    if missing is not None:
        return missing
    parts, ok_all, n = [], True, 0
    for s, d in flex.deflection.items():
        if _section_kind(scene, s) != "straight":
            continue
        m = after(d["t"], t_discard)
        if not m.any():
            continue
        n += 1
        t = d["t"][m]
        for side in ("left", "right"):
            for comp, label in ((1, "lateral"), (2, "vertical")):
                y = d[side][m, comp]
                k = int(np.argmax(np.abs(y)))
                where, idx = wheel_location(flex.kinematics, t[k], s, under=under)
                ok = where == "between"
                ok_all &= ok
                desc = {"under": "under wheelset %s" % (idx + 1 if idx is not None else "?"),
                        "between": "between the wheels of bogie %s" % (idx + 1 if idx is not None else "?"),
                        "outside": "outside the bogies"}[where]
                parts.append("%s %s %+.3f mm at %.3f s, %s" % (side, label, y[k] * 1e3, t[k], desc))
        parts[-4] = ("at %.0f m: " % s) + parts[-4]
    if n == 0:
        return Check(title, paper, "no deflection section on a straight", NOT_AVAILABLE)
    return Check(title, paper, "; ".join(parts), AGREES if ok_all else DISAGREES)


def vertical_spectrum_first_straight(run, scene, t_discard):
    """Amplitude spectrum of the leading wheelset's vertical displacement while it is on the first straight
    after the discard: (f [Hz], amplitude [m], df [Hz]) or None without samples there."""
    straight = scene.first_straight() if scene is not None else None
    if straight is None:
        return None
    k = run.kinematics
    m = region_mask(k, [straight]) & after(k["t"], t_discard)
    if m.sum() < 8:
        return None
    return amplitude_spectrum(k["t"][m], k["vertical"][m, 0])


def check_sleeper_frequency(runs, t_discard, f_min=10.0):
    """The flexible run's leading wheelset vertical motion on the first straight has its largest spectral
    line above f_min at the sleeper-passing frequency (speed / sleeper spacing), within the larger of one
    bin width and 5 %."""
    title = "Vertical oscillation at the sleeper-passing frequency (~51 Hz)"
    paper = ("With track flexibility the wheelset oscillates vertically at about 51 Hz, the sleeper-passing "
             "frequency for sleepers every 0.6 m at 110 km/h (Fig. 18).")
    flex = runs.get("flexible")
    scene = _scene(runs)
    if flex is None:
        return Check(title, paper, "needs the flexible run", NOT_AVAILABLE)
    if scene is None or not np.isfinite(scene.speed):
        return Check(title, paper, "needs the scene's speed and sleeper spacing", NOT_AVAILABLE)
    spec = vertical_spectrum_first_straight(flex, scene, t_discard)
    if spec is None:
        return Check(title, paper, "no samples on the first straight after the discard", NOT_AVAILABLE)
    f, a, df = spec
    fs = scene.sleeper_frequency()
    fp, ap = peak_frequency(f, a, f_min=f_min)
    tol = max(df, 0.05 * fs)
    ok = abs(fp - fs) <= tol
    text = ("largest line above %.0f Hz at %.1f Hz (amplitude %.3g mm, bin width %.2f Hz); sleeper passing "
            "%.2f Hz (%.3f m/s / %.2f m); tolerance %.1f Hz" % (f_min, fp, ap * 1e3, df, fs, scene.speed,
                                                               scene.sleeper_spacing, tol))
    rigid = runs.get("standalone") or runs.get("rigid_fe")
    if rigid is not None:
        sr = vertical_spectrum_first_straight(rigid, scene, t_discard)
        if sr is not None and sr[0].size:
            ar = float(np.interp(fp, sr[0], sr[1]))
            text += "; %s at that frequency %.3g mm" % (rigid.name, ar * 1e3)
    return Check(title, paper, text, AGREES if ok else DISAGREES)


def all_checks(runs, t_discard):
    """The six checks of the paper's observations, in the report's order."""
    return [check_flange_outer_only(runs, t_discard),
            check_flange_peaks_lower_flexible(runs, t_discard),
            check_lateral_force_straight(runs, t_discard),
            check_rails_outward_in_curve(runs, t_discard),
            check_max_between_bogie_wheels(runs, t_discard),
            check_sleeper_frequency(runs, t_discard)]
