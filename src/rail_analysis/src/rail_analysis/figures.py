"""PNG figures of the paper's section 6 from loaded runs (matplotlib, Agg backend).

Every function takes the runs ({name: Run}), the scene, the discard time [s] and the output directory,
writes one PNG and returns its file name. Plots show time after the discard on x (a second axis on top
gives the leading wheelset's arc length), millimetres, kilonewtons and degrees on y.
"""
import math
import os

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

from . import analysis, loading  # noqa: E402

STYLE = {  # label, colour, line style, width, drawing order
    "standalone": ("rigid track, vehicle alone", "black", "-", 1.6, 1),
    "rigid_fe": ("co-sim, rigid FE track", "tab:blue", "--", 1.2, 2),
    "flexible": ("co-sim, flexible track", "tab:red", "-", 0.9, 3),
}
ORDER = ("standalone", "rigid_fe", "flexible")


def _style(name):
    label, colour, ls, lw, z = STYLE[name]
    return dict(label=label, color=colour, linestyle=ls, linewidth=lw, zorder=z)


def _present(runs):
    return [n for n in ORDER if runs.get(n) is not None]


def _no_data(ax, text):
    ax.text(0.5, 0.5, text, transform=ax.transAxes, ha="center", va="center", fontsize=10, color="0.35",
            wrap=True)


def _shade_curves(ax, runs, scene):
    """Shades the time spans in which the leading wheelset is on a transition or the circular curve (the
    first run's timing), labelled once."""
    if scene is None:
        return
    name = _present(runs)[0]
    k = runs[name].kinematics
    s, t = k["arc_length"][:, 0], k["t"]
    labelled = set()
    for kind, lo, hi, _ in scene.curved_segments():
        m = (s >= lo) & (s < hi)
        if not m.any():
            continue
        colour = "0.93" if kind == "transition" else "0.85"
        lab = ("leading wheelset on a transition" if kind == "transition" else "leading wheelset in the curve")
        ax.axvspan(t[m][0], t[m][-1], color=colour, zorder=0, label=None if kind in labelled else lab)
        labelled.add(kind)


def _distance_axis(ax, runs):
    """A top x axis with the leading wheelset's arc length [m] (from the first run's timing)."""
    name = _present(runs)[0]
    k = runs[name].kinematics
    t, s = k["t"], k["arc_length"][:, 0]
    ok = np.isfinite(s)
    t, s = t[ok], s[ok]
    if t.size < 2 or np.any(np.diff(s) <= 0):
        return
    sec = ax.secondary_xaxis("top", functions=(lambda x: _interp_extrap(x, t, s), lambda y: _interp_extrap(y, s, t)))
    sec.set_xlabel("leading wheelset arc length s [m]")


def _interp_extrap(x, xp, fp):
    """Linear interpolation of fp(xp) at x, extended linearly beyond the ends (axis margins)."""
    x = np.asarray(x, float)
    y = np.interp(x, xp, fp)
    lo, hi = x < xp[0], x > xp[-1]
    y[lo] = fp[0] + (x[lo] - xp[0]) * (fp[1] - fp[0]) / (xp[1] - xp[0])
    y[hi] = fp[-1] + (x[hi] - xp[-1]) * (fp[-1] - fp[-2]) / (xp[-1] - xp[-2])
    return y


def _finish(fig, out_dir, name):
    loading.save_figure(fig, os.path.join(out_dir, name))
    return name


def _wheelset_plot(runs, scene, t_discard, out_dir, field, scale, ylabel, title, name):
    fig, ax = plt.subplots(figsize=(9, 4.6), constrained_layout=True)
    _shade_curves(ax, runs, scene)
    for n in _present(runs):
        k = runs[n].kinematics
        m = analysis.after(k["t"], t_discard)
        ax.plot(k["t"][m], k[field][m, 0] * scale, **_style(n))
    ax.set_xlabel("time t [s] (first %.2f s discarded)" % t_discard)
    ax.set_ylabel(ylabel)
    ax.set_title(title)
    ax.grid(True, alpha=0.3)
    ax.legend(loc="best", fontsize=8)
    _distance_axis(ax, runs)
    return _finish(fig, out_dir, name)


def fig_lateral(runs, scene, t_discard, out_dir):
    """Leading wheelset lateral displacement (paper Fig. 16)."""
    return _wheelset_plot(runs, scene, t_discard, out_dir, "lateral", 1e3,
                          "lateral displacement y [mm] (left > 0)",
                          "Leading wheelset: lateral displacement (paper Fig. 16)", "fig16_lateral_displacement.png")


def fig_angle_of_attack(runs, scene, t_discard, out_dir):
    """Leading wheelset angle of attack (paper Fig. 17)."""
    return _wheelset_plot(runs, scene, t_discard, out_dir, "angle_of_attack", 180.0 / math.pi,
                          "angle of attack [deg] (> 0 turning left)",
                          "Leading wheelset: angle of attack (paper Fig. 17)", "fig17_angle_of_attack.png")


def fig_vertical(runs, scene, t_discard, out_dir):
    """Leading wheelset vertical displacement (paper Fig. 18)."""
    return _wheelset_plot(runs, scene, t_discard, out_dir, "vertical", 1e3,
                          "vertical displacement z [mm] (up > 0)",
                          "Leading wheelset: vertical displacement (paper Fig. 18)", "fig18_vertical_displacement.png")


def _two_wheels(runs, scene, t_discard, out_dir, series, ylabel, title, name):
    """Left and right panels; series(run) -> (t, left, right) or None (with the reason in run.notes)."""
    fig, axes = plt.subplots(2, 1, figsize=(9, 6.8), sharex=True, constrained_layout=True)
    missing = []
    plotted = False
    for ax, side in zip(axes, ("left", "right")):
        _shade_curves(ax, runs, scene)
        for n in _present(runs):
            d = series(runs[n])
            if d is None:
                if side == "left":
                    missing.append(STYLE[n][0])
                continue
            t, left, right = d
            m = analysis.after(t, t_discard)
            ax.plot(t[m], (left if side == "left" else right)[m] / 1e3, **_style(n))
            plotted = True
        ax.set_ylabel("%s wheel: %s" % (side, ylabel))
        ax.grid(True, alpha=0.3)
    if missing:
        _no_data(axes[0], "not recorded: " + ", ".join(missing))
    if plotted:
        axes[0].legend(loc="best", fontsize=8)
    axes[1].set_xlabel("time t [s] (first %.2f s discarded)" % t_discard)
    axes[0].set_title(title)
    _distance_axis(axes[0], runs)
    return _finish(fig, out_dir, name)


def fig_flange_forces(runs, scene, t_discard, out_dir):
    """Flange contact normal forces on the leading wheelset's left and right wheels (paper Fig. 19)."""
    def series(r):
        return analysis.leading_flange_forces(r) if r.points is not None else None
    return _two_wheels(runs, scene, t_discard, out_dir, series, "flange normal force [kN]",
                       "Leading wheelset: flange contact normal force, contact angle > %.0f deg (paper Fig. 19)"
                       % np.degrees(loading.FLANGE_CONTACT_ANGLE), "fig19_flange_forces.png")


def _wheel_force(component):
    def series(r):
        k = r.kinematics
        if k["left_force"] is None:
            return None
        return k["t"], k["left_force"][:, 0, component], k["right_force"][:, 0, component]
    return series


def fig_lateral_forces(runs, scene, t_discard, out_dir):
    """Lateral (track y) contact forces on the leading left and right wheels (paper Fig. 20)."""
    return _two_wheels(runs, scene, t_discard, out_dir, _wheel_force(1), "lateral force F_y [kN] (left > 0)",
                       "Leading wheels: lateral contact force, track frame (paper Fig. 20)",
                       "fig20_lateral_wheel_forces.png")


def fig_vertical_forces(runs, scene, t_discard, out_dir):
    """Vertical (track z) contact forces on the leading left and right wheels (paper Fig. 21)."""
    return _two_wheels(runs, scene, t_discard, out_dir, _wheel_force(2), "vertical force F_z [kN] (up > 0)",
                       "Leading wheels: vertical contact force, track frame (paper Fig. 21)",
                       "fig21_vertical_wheel_forces.png")


def section_figure_name(s):
    """File name of the rail displacement figure of the section at arc length s [m]."""
    return "rail_displacement_at_%gm.png" % s


def fig_rail_section(runs, scene, t_discard, out_dir, s_section, paper_fig=""):
    """Lateral and vertical displacement of the left and right rails at one section, with the instants at
    which each wheelset passes (paper Figs. 22 and 23)."""
    fig, axes = plt.subplots(2, 2, figsize=(11, 6.8), sharex=True, constrained_layout=True)
    have = [n for n in _present(runs) if runs[n].deflection and _match_section(runs[n].deflection, s_section)]
    for n in have:
        d = runs[n].deflection[_match_section(runs[n].deflection, s_section)]
        m = analysis.after(d["t"], t_discard)
        for col, side in enumerate(("left", "right")):
            axes[0, col].plot(d["t"][m], d[side][m, 1] * 1e3, **_style(n))
            axes[1, col].plot(d["t"][m], d[side][m, 2] * 1e3, **_style(n))
    ref = runs.get("flexible") or runs[_present(runs)[0]]
    passes = analysis.passing_times(ref.kinematics, s_section)
    for ax in axes.flat:
        for w, tp in enumerate(passes):
            if tp is not None and tp >= t_discard:
                ax.axvline(tp, color="0.3", linewidth=0.8, linestyle=":")
        ax.grid(True, alpha=0.3)
    for w, tp in enumerate(passes):
        if tp is not None and tp >= t_discard:
            for ax in axes[0]:  # staggered so that the labels of a bogie's two wheelsets do not overlap
                ax.annotate("ws %d" % (w + 1), xy=(tp, 1.0), xycoords=("data", "axes fraction"),
                            xytext=(2, -10 - 9 * (w % 2)), textcoords="offset points", fontsize=7, color="0.3")
    axes[0, 0].set_ylabel("lateral y [mm] (left > 0)")
    axes[1, 0].set_ylabel("vertical z [mm] (up > 0)")
    axes[0, 0].set_title("left rail")
    axes[0, 1].set_title("right rail")
    for ax in axes[1]:
        ax.set_xlabel("time t [s] (first %.2f s discarded)" % t_discard)
    kind = analysis._section_kind(scene, s_section) if scene is not None else None
    fig.suptitle("Rail displacement at s = %g m (%s)%s; dotted: wheelsets 1-4 passing"
                 % (s_section, kind or "section", (" (paper %s)" % paper_fig) if paper_fig else ""))
    if have:
        axes[0, 0].legend(loc="best", fontsize=8)
    else:
        for ax in axes.flat:
            _no_data(ax, "no run recorded rail displacements here")
    return _finish(fig, out_dir, section_figure_name(s_section))


def _match_section(deflection, s, tol=1e-3):
    for key in deflection:
        if abs(key - s) <= tol:
            return key
    return None


def fig_spectrum(runs, scene, t_discard, out_dir):
    """Amplitude spectrum of the leading wheelset's vertical displacement on the first straight after the
    discard, with the sleeper-passing frequency marked."""
    fig, ax = plt.subplots(figsize=(9, 4.6), constrained_layout=True)
    fs = scene.sleeper_frequency() if scene is not None and np.isfinite(scene.speed) else float("nan")
    f_hi, a_hi = 0.0, 0.0
    plotted = False
    for n in _present(runs):
        spec = analysis.vertical_spectrum_first_straight(runs[n], scene, t_discard)
        if spec is None:
            continue
        f, a, df = spec
        ax.semilogy(f[1:], a[1:] * 1e3, **_style(n))
        f_hi = max(f_hi, f[-1])
        a_hi = max(a_hi, float(np.max(a[1:])) * 1e3)
        plotted = True
    if np.isfinite(fs):
        ax.axvline(fs, color="tab:green", linewidth=1.2, linestyle="-.",
                   label="sleeper passing %.1f Hz (%.2f m/s / %.2f m)" % (fs, scene.speed, scene.sleeper_spacing))
    if plotted:
        ax.set_xlim(0, min(f_hi, 4 * fs if np.isfinite(fs) else f_hi))
        if a_hi > 0:  # eight decades below the largest line: a rigid run's round-off floor stays out of view
            ax.set_ylim(a_hi * 1e-8, a_hi * 3)
        ax.legend(loc="best", fontsize=8)
    else:
        _no_data(ax, "no samples on the first straight after the discard")
    ax.set_xlabel("frequency [Hz]")
    ax.set_ylabel("amplitude of z [mm]")
    ax.set_title("Leading wheelset vertical displacement on the first straight: amplitude spectrum (Hann)")
    ax.grid(True, which="both", alpha=0.3)
    return _finish(fig, out_dir, "spectrum_vertical_first_straight.png")


def all_figures(runs, scene, t_discard, out_dir):
    """Writes every figure; returns [(caption, file name)] in the report's order."""
    out = [("Leading wheelset lateral displacement", fig_lateral(runs, scene, t_discard, out_dir)),
           ("Leading wheelset angle of attack", fig_angle_of_attack(runs, scene, t_discard, out_dir)),
           ("Leading wheelset vertical displacement", fig_vertical(runs, scene, t_discard, out_dir)),
           ("Flange contact normal forces, leading wheelset (%s)" % loading.FLANGE_CONTACT_DEFINITION,
            fig_flange_forces(runs, scene, t_discard, out_dir)),
           ("Lateral contact forces, leading wheels", fig_lateral_forces(runs, scene, t_discard, out_dir)),
           ("Vertical contact forces, leading wheels", fig_vertical_forces(runs, scene, t_discard, out_dir))]
    sections = scene.deflection_sections if scene is not None else []
    for s in sections:
        kind = analysis._section_kind(scene, s)
        paper_fig = "Fig. 22" if kind == "straight" else ("Fig. 23" if kind in ("circular", "transition") else "")
        out.append(("Rail displacements at s = %g m (%s)" % (s, kind or "?"),
                    fig_rail_section(runs, scene, t_discard, out_dir, s, paper_fig)))
    out.append(("Spectrum of the leading wheelset's vertical motion on the first straight",
                fig_spectrum(runs, scene, t_discard, out_dir)))
    return out
