"""Ride comfort from carbody floor accelerations: the frequency weightings Wb (vertical) and Wd (horizontal)
and the mean comfort index N_MV of EN 12299 (simplified / standard method).

Weighting filters. Each weighting is the analogue cascade H(s) = Hh(s) Hl(s) Ht(s) Hs(s) of ISO 2631-1:1997
Annex A (the form EN 12299 and ISO 2631-4 use), s = j 2 pi f:
  Hh  band-limiting high-pass  s^2 / (s^2 + w1 s / Q1 + w1^2)
  Hl  band-limiting low-pass   w2^2 / (s^2 + w2 s / Q2 + w2^2)
  Ht  acceleration-velocity transition  (1 + s / w3) / (1 + s / (Q4 w4) + s^2 / w4^2)
  Hs  upward step  (s^2 + w5 s / Q5 + w5^2) / (s^2 + w6 s / Q6 + w6^2)   (Wb only; 1 for Wd)
with w_i = 2 pi f_i, times a gain K. Q1 = Q2 = 1/sqrt(2).
Parameters (frequencies in Hz):
  Wd: f1 0.4, f2 100, f3 2, f4 2, Q4 0.63, K 1 -- ISO 2631-1:1997 Table A.1 / EN 12299:2009 (horizontal).
  Wb: f1 0.4, f2 100, f3 16, f4 16, Q4 0.55, f5 2.5, Q5 0.9, f6 4, Q6 0.95 -- ISO 2631-4:2001 Table A.1,
      EN 12299:2009 (vertical); values as ISO 8041:2005 Table 3 lists them (reproduced in the Larson Davis
      HVM200 Reference Manual, Table 3.1 "Parameters and transfer functions of the frequency weightings
      (source: ISO 8041)"). Check: |Wb| = 0.8126 and |Wd| = 0.1261 at 100 rad/s (15.915 Hz), the reference
      values that vibration-meter makers publish (ZETLAB, frequency weighting functions table). With the step Hs written as above (unity at high frequency) the gain is
      K = 1.024, as ISO 8041-1 Table 3 gives it; EN 12299 writes K = 0.4 with the step normalised to unity at
      low frequency: 0.4 (4 / 2.5)^2 = 1.024, the same filter.
The digital filters are second-order sections from the bilinear transform, each pre-warped at its own
corner frequency (f1, f2, f4, f6); Ht's first-order numerator is folded into its section.

Mean comfort, EN 12299:2009 (standard method, floor measurement):
  N_MV = 6 sqrt( (a_XP95^Wd)^2 + (a_YP95^Wd)^2 + (a_ZP95^Wb)^2 )
a_P95: the 95th percentile of the r.m.s. values of the weighted acceleration [m/s^2] over consecutive 5 s
windows, 60 windows (5 min) per evaluation. A run shorter than 5 min gives fewer windows: the percentile is
taken over the windows available and the result is flagged indicative; shorter than one window, the r.m.s. of
the whole record stands for the one window. Comfort scale (EN 12299): N < 1 very comfortable, 1-2
comfortable, 2-4 medium, 4-5 uncomfortable, >= 5 very uncomfortable.

Units: m/s^2, s, Hz. numpy only.
"""
import math

import numpy as np

# Weighting parameters (frequencies [Hz], quality factors [-], gain [-]); sources in the module docstring.
WEIGHTINGS = {
    # ISO 2631-1:1997 Table A.1 / EN 12299:2009: horizontal weighting Wd.
    "Wd": {"f1": 0.4, "f2": 100.0, "f3": 2.0, "f4": 2.0, "Q4": 0.63, "f5": None, "Q5": None, "f6": None,
           "Q6": None, "K": 1.0},
    # ISO 2631-4:2001 Table A.1 / EN 12299:2009: vertical weighting Wb; K = 1.024 with Hs unity at high
    # frequency (ISO 8041-1 Table 3), i.e. EN 12299's K = 0.4 with Hs unity at low frequency.
    "Wb": {"f1": 0.4, "f2": 100.0, "f3": 16.0, "f4": 16.0, "Q4": 0.55, "f5": 2.5, "Q5": 0.9, "f6": 4.0,
           "Q6": 0.95, "K": 1.024},
}
Q_BAND = 1.0 / math.sqrt(2.0)  # Q1 = Q2, band-limiting Butterworth sections

WINDOW_S = 5.0           # EN 12299: r.m.s. over 5 s
WINDOWS_PER_EVAL = 60    # EN 12299: 60 windows = 5 min
PERCENTILE = 95.0        # EN 12299: 95th percentile

COMFORT_SCALE = ((1.0, "very comfortable"), (2.0, "comfortable"), (4.0, "medium"), (5.0, "uncomfortable"),
                 (float("inf"), "very uncomfortable"))


def comfort_class(n_mv):
    """The EN 12299 comfort-scale wording of a mean comfort index N_MV [-]."""
    for upper, text in COMFORT_SCALE:
        if n_mv < upper:
            return text
    return "n/a"


def _param(name):
    if name not in WEIGHTINGS:
        raise ValueError("unknown weighting %r (known: %s)" % (name, ", ".join(sorted(WEIGHTINGS))))
    return WEIGHTINGS[name]


def analog_response(name, f):
    """Complex frequency response H(j 2 pi f) of weighting name ('Wb' or 'Wd') at f [Hz] (array-like)."""
    p = _param(name)
    s = 2j * np.pi * np.asarray(f, dtype=float)
    w1, w2, w3, w4 = (2 * np.pi * p[k] for k in ("f1", "f2", "f3", "f4"))
    h = s ** 2 / (s ** 2 + w1 / Q_BAND * s + w1 ** 2)
    h = h * w2 ** 2 / (s ** 2 + w2 / Q_BAND * s + w2 ** 2)
    h = h * (1 + s / w3) / (1 + s / (p["Q4"] * w4) + s ** 2 / w4 ** 2)
    if p["f5"] is not None:
        w5, w6 = 2 * np.pi * p["f5"], 2 * np.pi * p["f6"]
        h = h * (s ** 2 + w5 / p["Q5"] * s + w5 ** 2) / (s ** 2 + w6 / p["Q6"] * s + w6 ** 2)
    return p["K"] * h


def _bilinear_biquad(num, den, f_warp, fs):
    """Digital (b, a) of the analogue section num(s)/den(s) (coefficients of s^2, s, 1), by the bilinear
    transform pre-warped at f_warp [Hz]: s = c (1 - z^-1)/(1 + z^-1), c = 2 pi f_warp / tan(pi f_warp / fs)."""
    c = 2 * np.pi * f_warp / math.tan(np.pi * f_warp / fs)
    def z_poly(p):
        a2, a1, a0 = p
        # a2 c^2 (1 - z)^2 + a1 c (1 - z)(1 + z) + a0 (1 + z)^2 in powers of z^-1
        return np.array([a2 * c * c + a1 * c + a0, -2 * a2 * c * c + 2 * a0, a2 * c * c - a1 * c + a0])
    b, a = z_poly(num), z_poly(den)
    return b / a[0], a / a[0]


def digital_sections(name, fs):
    """Second-order sections [(b, a)] of weighting name at sampling frequency fs [Hz] (fs > 2 f2)."""
    p = _param(name)
    if not (fs > 2 * p["f2"]):
        raise ValueError("sampling frequency %g Hz too low for weighting %s (needs > %g Hz)" % (fs, name, 2 * p["f2"]))
    w1, w2, w3, w4 = (2 * np.pi * p[k] for k in ("f1", "f2", "f3", "f4"))
    secs = [
        _bilinear_biquad((1.0, 0.0, 0.0), (1.0, w1 / Q_BAND, w1 ** 2), p["f1"], fs),
        _bilinear_biquad((0.0, 0.0, w2 ** 2), (1.0, w2 / Q_BAND, w2 ** 2), p["f2"], fs),
        _bilinear_biquad((0.0, p["K"] / w3, p["K"]), (1.0 / w4 ** 2, 1.0 / (p["Q4"] * w4), 1.0), p["f4"], fs),
    ]
    if p["f5"] is not None:
        w5, w6 = 2 * np.pi * p["f5"], 2 * np.pi * p["f6"]
        secs.append(_bilinear_biquad((1.0, w5 / p["Q5"], w5 ** 2), (1.0, w6 / p["Q6"], w6 ** 2), p["f6"], fs))
    return secs


def biquad(b, a, x):
    """Direct-form II transposed second-order filter of x along axis 0, zero initial state."""
    x = np.asarray(x, dtype=float)
    y = np.empty_like(x)
    z1 = np.zeros(x.shape[1:])
    z2 = np.zeros(x.shape[1:])
    b0, b1, b2 = b
    _, a1, a2 = a
    for n in range(x.shape[0]):
        xn = x[n]
        yn = b0 * xn + z1
        z1 = b1 * xn - a1 * yn + z2
        z2 = b2 * xn - a2 * yn
        y[n] = yn
    return y


def sos_filter(sections, x):
    """x filtered by the cascade of second-order sections [(b, a)] along axis 0 (scipy when present)."""
    try:
        from scipy.signal import sosfilt
        sos = np.array([np.concatenate([b, a]) for b, a in sections])
        return sosfilt(sos, np.asarray(x, dtype=float), axis=0)
    except ImportError:
        y = np.asarray(x, dtype=float)
        for b, a in sections:
            y = biquad(b, a, y)
        return y


def weight(x, fs, name):
    """Weighted acceleration [m/s^2] of the uniformly sampled x [m/s^2] (axis 0 = time) at fs [Hz]. The first
    sample is subtracted first: the weightings block DC, so this starts the filter in the steady state of a
    constant input equal to x[0] (e.g. the 9.81 m/s^2 a vertical accelerometer reads at rest)."""
    x = np.asarray(x, dtype=float)
    return sos_filter(digital_sections(name, fs), x - x[:1])


def uniform(t, x):
    """(t_uniform, x_uniform, fs): x resampled linearly on a uniform base with the median sample spacing."""
    t = np.asarray(t, dtype=float)
    x = np.asarray(x, dtype=float)
    dt = float(np.median(np.diff(t)))
    n = int(math.floor((t[-1] - t[0]) / dt + 1e-9)) + 1
    tu = t[0] + dt * np.arange(n)
    if x.ndim == 1:
        xu = np.interp(tu, t, x)
    else:
        xu = np.stack([np.interp(tu, t, x[:, k]) for k in range(x.shape[1])], axis=1)
    return tu, xu, 1.0 / dt


def window_rms(y, fs, window=WINDOW_S):
    """r.m.s. of y over consecutive full windows of window [s] (array, one value per window); when y is
    shorter than one window, the r.m.s. of all of y (one value)."""
    y = np.asarray(y, dtype=float)
    n = int(round(window * fs))
    k = y.size // n if n > 0 else 0
    if k == 0:
        return np.array([math.sqrt(float(np.mean(y ** 2)))]) if y.size else np.zeros(0)
    return np.sqrt(np.mean(y[:k * n].reshape(k, n) ** 2, axis=1))


class ComfortResult(object):
    """Mean comfort at one floor point: n_mv [-], a_p95 {'x','y','z'} [m/s^2] (weighted, 95th percentile of
    the window r.m.s.), rms {'x','y','z'} [m/s^2] (weighted, over all the windows together), windows (count),
    window_rms {'x','y','z'} arrays, t_windows (window start times [s]), indicative (fewer than 60 windows),
    note (text), and the weighted series t, aw {'x','y','z'} for figures."""

    def __init__(self):
        self.n_mv = float("nan")
        self.a_p95 = {}
        self.rms = {}
        self.windows = 0
        self.window_rms = {}
        self.t_windows = np.zeros(0)
        self.indicative = True
        self.note = ""
        self.t = np.zeros(0)
        self.aw = {}


def mean_comfort(t, specific_force, t_start=0.0, window=WINDOW_S, percentile=PERCENTILE):
    """EN 12299 mean comfort N_MV at one floor point.

    t [s] (N,), specific_force [m/s^2] (N, 3) in the carbody frame (x forward, y left, z up). The record is
    weighted from its first sample (x, y with Wd, z with Wb), then the part from t_start [s] on (after the
    start transient of the vehicle and of the 0.4 Hz high-pass) is cut into windows of window [s].
    Returns a ComfortResult."""
    tu, a, fs = uniform(t, specific_force)
    r = ComfortResult()
    keep = tu >= t_start
    if keep.sum() < 2:
        r.note = "no samples after t = %.2f s" % t_start
        return r
    r.t = tu[keep]
    for k, axis, wname in ((0, "x", "Wd"), (1, "y", "Wd"), (2, "z", "Wb")):
        aw = weight(a[:, k], fs, wname)[keep]
        r.aw[axis] = aw
        r.window_rms[axis] = window_rms(aw, fs, window)
        r.a_p95[axis] = float(np.percentile(r.window_rms[axis], percentile))
        r.rms[axis] = math.sqrt(float(np.mean(r.window_rms[axis] ** 2)))
    r.windows = int(r.window_rms["z"].size)
    n_full = int((r.t.size) // int(round(window * fs)))
    r.t_windows = r.t[0] + window * np.arange(r.windows)
    r.n_mv = 6.0 * math.sqrt(r.a_p95["x"] ** 2 + r.a_p95["y"] ** 2 + r.a_p95["z"] ** 2)
    r.indicative = r.windows < WINDOWS_PER_EVAL
    if n_full == 0:
        r.note = ("indicative: %.1f s evaluated, shorter than one %.0f s window; the r.m.s. of the whole record "
                  "stands for it" % (r.t[-1] - r.t[0], window))
    elif r.indicative:
        r.note = ("indicative: %d window(s) of %.0f s (EN 12299 evaluates 60 windows = 5 min); %gth percentile "
                  "over the windows available" % (r.windows, window, percentile))
    return r
