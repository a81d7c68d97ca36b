"""Summary tables, CSV files, a Markdown section and figures of the safety, track-loading, wear and comfort
quantities (rail_analysis.safety) for one or several runs; the railsim_safety command line.

CSV columns (SI units): CSV_COLUMNS below; one row per quantity, values empty when not available.
"""
import argparse
import csv
import math
import os
import sys

import numpy as np
import yaml

from . import comfort, loading, safety

CSV_COLUMNS = ("run", "quantity", "unit", "maximum", "wheel_id", "wheelset", "side", "s_m", "t_s", "limit",
               "margin", "status", "note")
EXIT_OK = 0          # done (limits exceeded or not: see the status column)
EXIT_BAD_INPUT = 2   # an input refused (one line on stderr)
EXIT_TOO_SHORT = 3   # a run too short for the analysis (one line on stderr)
EXIT_WRITE_FAILED = loading.EXIT_WRITE_FAILED  # an output could not be written (one line on stderr)

SOURCES = [
    "Y/Q: Nadal's limit (tan g - mu)/(1 + mu tan g) (J. Nadal, Annales des Mines, 1896), g = the wheel "
    "profile's maximum flange angle (S1002, EN 13715: 70 deg), mu = friction coefficient; judged on the 2 m "
    "sliding mean as EN 14363 does.",
    "dQ/Q0: wheel unloading (Q0 - Q)/Q0 against 0.6 (EN 14363, twisted-track wheel-unloading criterion).",
    "SumY: track-shift force, 2 m sliding mean, against Prud'homme's alpha (10 kN + P/3) (Prud'homme, RGCF "
    "1967), written (SumY_2m)_lim = alpha (10 + 2 Q0/3) kN in EN 14363; alpha = 1 for passenger vehicles.",
    "Q: vertical wheel force low-passed at 20 Hz against EN 14363's Q_lim (200 kN up to 160 km/h); "
    "quasi-static Q (low-pass, cut-off an option) against Q_qst,lim = 145 kN.",
    "P1, P2: the impact forces of a dipped joint or a wheel flat (Jenkins, Stephenson, Clayton, Morland and "
    "Lyon, Railway Engineering Journal 3(1), 1974): P1 the unfiltered maximum of Q, P2 the maximum of Q "
    "low-passed at 150 Hz; informative.",
    "Tgamma: sum over the wheel's contacts of |Tx nu_x| + |Ty nu_y| [N = J/m] (spin term not included); "
    "informative; Whole Life Rail Model bands 15 / 65 / 175 J/m (Burstow 2004).",
    "N_MV: EN 12299 mean comfort 6 sqrt(a_XP95^2 + a_YP95^2 + a_ZP95^2), Wd (x, y) and Wb (z) weightings "
    "(ISO 2631-1 / ISO 2631-4 / EN 12299 parameters), 5 s r.m.s. windows, 95th percentile.",
]


def _f(x, spec="%.4g"):
    return spec % x if isinstance(x, (int, float, np.floating)) and math.isfinite(x) else ""


def _side(side):
    return {0: "left", 1: "right"}.get(side, "")


def csv_rows(run_name, rows):
    """The CSV records (dicts keyed by CSV_COLUMNS) of one run's rows."""
    out = []
    for r in rows:
        out.append({"run": run_name, "quantity": r.quantity, "unit": r.unit, "maximum": _f(r.value, "%.6g"),
                    "wheel_id": "" if r.wheel_id is None else str(r.wheel_id),
                    "wheelset": "" if r.wheelset is None else str(r.wheelset),
                    "side": _side(r.side), "s_m": _f(r.s, "%.3f"), "t_s": _f(r.t, "%.4f"),
                    "limit": _f(r.limit, "%.6g"), "margin": _f(r.margin, "%.6g"), "status": r.status,
                    "note": r.note})
    return out


def write_csv(path, run_name, rows):
    """Writes the rows of one run as CSV (CSV_COLUMNS). Returns the path."""
    with loading.writing(path), open(path, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=CSV_COLUMNS)
        w.writeheader()
        for rec in csv_rows(run_name, rows):
            w.writerow(rec)
    return path


def _where(r):
    parts = []
    if r.wheel_id is not None:
        parts.append(safety.wheel_label(r.wheel_id))
    elif r.wheelset is not None:
        parts.append("wheelset %d" % (r.wheelset + 1))
    if r.s is not None:
        parts.append("s = %.1f m" % r.s)
    if r.t is not None:
        parts.append("t = %.3f s" % r.t)
    return ", ".join(parts)


def _value_text(v, unit):
    if v is None:
        return "—"
    if unit == "N":
        return "%.2f kN" % (v / 1e3) if abs(v) >= 1e3 else "%.3g N" % v
    if unit == "m" and abs(v) < 0.1:
        return "%.3f mm" % (v * 1e3)
    return "%.3g%s" % (v, (" " + unit) if unit not in ("-", "") else "")


def text_table(run_name, rows):
    """A plain-text summary table of one run (for the terminal)."""
    lines = ["%s:" % run_name]
    head = ("quantity", "maximum", "where", "limit", "margin", "status")
    body = []
    for r in rows:
        body.append((r.quantity, _value_text(r.value, r.unit), _where(r), _value_text(r.limit, r.unit),
                     _value_text(r.margin, r.unit), r.status if r.status != safety.NOT_AVAILABLE else
                     "not available: " + r.note))
    widths = [max(len(x[i]) for x in [head] + body) for i in range(5)]
    fmt = "  " + "  ".join("%%-%ds" % w for w in widths) + "  %s"
    lines.append(fmt % head)
    for b in body:
        lines.append(fmt % b)
    return "\n".join(lines)


def markdown_table(run_name, rows):
    L = ["| quantity | maximum | where | limit | margin | status | note |", "|---|---|---|---|---|---|---|"]
    for r in rows:
        L.append("| %s | %s | %s | %s | %s | %s | %s |" % (r.quantity, _value_text(r.value, r.unit), _where(r),
                                                          _value_text(r.limit, r.unit),
                                                          _value_text(r.margin, r.unit), r.status, r.note))
    return L


def comparison_table(evals, base="rigid_fe", other="flexible"):
    """Markdown lines comparing the maxima of two runs: quantity | base | other | change [%]."""
    if base not in evals or other not in evals:
        return []
    rb = {r.quantity: r for r in evals[base].rows}
    L = ["| quantity | %s | %s | change |" % (base, other), "|---|---|---|---|"]
    for r in evals[other].rows:
        b = rb.get(r.quantity)
        if b is None:
            continue
        if b.value is None or r.value is None:
            L.append("| %s | %s | %s | — |" % (r.quantity, _value_text(b.value, b.unit), _value_text(r.value, r.unit)))
            continue
        ch = "%+.1f %%" % (100.0 * (r.value - b.value) / abs(b.value)) if b.value else "—"
        L.append("| %s | %s | %s | %s |" % (r.quantity, _value_text(b.value, b.unit), _value_text(r.value, r.unit), ch))
    return L


# ---------------------------------------------------------------------------------------------------------
# Figures

def _plt():
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


STYLE = {"standalone": ("black", "-"), "rigid_fe": ("tab:blue", "--"), "flexible": ("tab:red", "-")}


def _style(name, k):
    colours = ("black", "tab:blue", "tab:red", "tab:green", "tab:orange")
    c, ls = STYLE.get(name, (colours[k % len(colours)], "-"))
    return dict(color=c, linestyle=ls, linewidth=1.0, label=name)


def figures(evals, out_dir, prefix="safety"):
    """Writes the figures of the evaluated runs ({name: Evaluation}) to out_dir; returns [(caption, file)]."""
    plt = _plt()
    out = []
    names = list(evals)
    # Y/Q of the leading wheels against s, with the limit.
    fig, axes = plt.subplots(2, 1, figsize=(9, 6), sharex=True)
    for k, n in enumerate(names):
        ev = evals[n]
        for side, ax in ((0, axes[0]), (1, axes[1])):
            st = _style(n, k)
            ax.plot(ev.s[:, 0], ev.yq[:, 0, side], alpha=0.35, **dict(st, label=None))
            ax.plot(ev.s[:, 0], ev.yq_2m[:, 0, side], **dict(st, label="%s, 2 m mean" % n))
    for side, ax in ((0, axes[0]), (1, axes[1])):
        lim = evals[names[0]].limits["yq"]
        ax.axhline(lim, color="k", linestyle=":", label="Nadal limit %.2f" % lim)
        ax.set_ylabel("Y/Q, %s wheel [-]" % _side(side))
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7)
    axes[1].set_xlabel("arc length of the leading wheelset s [m]")
    axes[0].set_title("Flange-climb ratio Y/Q, leading wheelset (faint: instantaneous)")
    out.append(("Y/Q of the leading wheels", _save(fig, out_dir, prefix + "_yq.png")))
    # SumY.
    fig, ax = plt.subplots(figsize=(9, 4))
    for k, n in enumerate(names):
        ev = evals[n]
        for w in range(ev.s.shape[1]):
            st = _style(n, k)
            ax.plot(ev.s[:, w], ev.sumy_2m[:, w] / 1e3, alpha=1.0 if w == 0 else 0.4,
                    **dict(st, label="%s ws%d" % (n, w + 1) if w == 0 else None))
    lim = evals[names[0]].limits["sumy"] / 1e3
    ax.axhline(lim, color="k", linestyle=":", label="Prud'homme limit ±%.1f kN" % lim)
    ax.axhline(-lim, color="k", linestyle=":")
    ax.set_xlabel("arc length of each wheelset s [m]")
    ax.set_ylabel("SumY, 2 m mean [kN]")
    ax.set_title("Track-shift force (leading wheelset solid, others faint)")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    out.append(("Track-shift force SumY", _save(fig, out_dir, prefix + "_sumy.png")))
    # Tgamma.
    fig, ax = plt.subplots(figsize=(9, 4))
    any_tg = False
    for k, n in enumerate(names):
        tg = evals[n].tgamma
        if tg is None:
            continue
        any_tg = True
        for wid, ls in ((0, ":"), (1, "-")):
            st = _style(n, k)
            st["linestyle"] = ls
            ax.plot(tg["s"][:, wid], tg["value"][:, wid], **dict(st, label="%s %s" % (n, safety.wheel_label(wid))))
    if not any_tg:
        ax.text(0.5, 0.5, safety.not_available_text("/contact_points"), transform=ax.transAxes, ha="center")
    for b in safety.TGAMMA_BANDS:
        ax.axhline(b, color="0.6", linestyle="--", linewidth=0.7)
    ax.set_xlabel("arc length s [m]")
    ax.set_ylabel("Tgamma [N = J/m]")
    ax.set_title("Wear index of the leading wheels (dashed: WLRM bands)")
    ax.grid(alpha=0.3)
    if any_tg:
        ax.legend(fontsize=7)
    out.append(("Wear index Tgamma", _save(fig, out_dir, prefix + "_tgamma.png")))
    # Comfort.
    fig, axes = plt.subplots(3, 1, figsize=(9, 7), sharex=True)
    any_c = False
    for k, n in enumerate(names):
        cm = evals[n].comfort
        if not cm:
            continue
        for pname, r in cm.items():
            if not r.aw:
                continue
            any_c = True
            for ax, axis in zip(axes, ("x", "y", "z")):
                ax.plot(r.t, r.aw[axis], linewidth=0.6, label="%s %s" % (n, pname))
    for ax, axis, wn in zip(axes, ("x", "y", "z"), ("Wd", "Wd", "Wb")):
        ax.set_ylabel("a_%s %s [m/s^2]" % (axis, wn))
        ax.grid(alpha=0.3)
    if any_c:
        axes[0].legend(fontsize=7)
    else:
        axes[1].text(0.5, 0.5, safety.not_available_text("/floor_accelerations"), transform=axes[1].transAxes,
                     ha="center", fontsize=8)
    axes[2].set_xlabel("t [s]")
    axes[0].set_title("Weighted carbody floor accelerations (EN 12299)")
    out.append(("Weighted floor accelerations", _save(fig, out_dir, prefix + "_comfort.png")))
    return out


def _save(fig, out_dir, name):
    fig.tight_layout()
    loading.save_figure(fig, os.path.join(out_dir, name))
    return name


# ---------------------------------------------------------------------------------------------------------
# Section and command line

def evaluate_runs(safety_runs, settings=None):
    """{name: Evaluation} of {name: SafetyRun}."""
    return {n: safety.evaluate(r, settings) for n, r in safety_runs.items()}


def markdown_section(safety_runs, evals, out_dir, figure_list=None):
    """Markdown lines of the section: sources and settings, a table per run, the rigid/flexible comparison,
    the Tgamma distribution over the curves, the figures."""
    L = ["## Running safety, track loading, wear and comfort", ""]
    any_ev = next(iter(evals.values()), None)
    if any_ev is not None:
        st = any_ev.settings
        L.append("Settings: the first %.2f s discarded; Y/Q and SumY as sliding means over %.1f m of track; Q "
                 "low-passed at %.0f Hz, quasi-static Q at %.1f Hz; comfort from %.1f s after the discard in %.0f s "
                 "windows. Y is the lateral force pushing each wheel away from its rail toward the track centre "
                 "(Y/Q > 0 when flanging); SumY = Y_left,track + Y_right,track (force of the rails on the wheelset, "
                 "+ left). Margin = limit - maximum."
                 % (st.t_discard, st.window, st.q_cutoff_hz, st.qst_cutoff_hz, st.comfort_settle, st.comfort_window))
        L.append("")
    L.append("Limits and sources:")
    L.append("")
    for s in SOURCES:
        L.append("- " + s)
    for n, ev in evals.items():
        r = safety_runs[n]
        L.append("")
        L.append("### %s" % n)
        L.append("")
        L.append("Static wheel load Q0 = %.2f kN (%s); friction mu = %.3g (%s); Nadal limit %.3f; Prud'homme "
                 "limit %.2f kN." % (ev.q0 / 1e3, ev.sources["q0"], ev.friction, ev.sources["friction"],
                                     ev.limits["yq"], ev.limits["sumy"] / 1e3))
        L.append("")
        L.extend(markdown_table(n, ev.rows))
        for note in r.notes:
            L.append("")
            L.append("- " + note)
        dist = safety.curve_distribution(ev, r.scene)
        if dist:
            L.append("")
            L.append("Tgamma over the curves (mean and maximum [N = J/m], energy dissipated [kJ]):")
            L.append("")
            L.append("| segment | wheel | mean | max | energy |")
            L.append("|---|---|---|---|---|")
            for label, k, mean, mx, e in dist:
                L.append("| %s | %s | %.1f | %.1f | %.2f |" % (label, safety.wheel_label(k), mean, mx, e / 1e3))
    comp = comparison_table(evals)
    if comp:
        L.append("")
        L.append("### Flexible against rigid FE track")
        L.append("")
        L.extend(comp)
    for caption, name in figure_list or []:
        L.append("")
        L.append("### " + caption)
        L.append("")
        L.append("![%s](%s)" % (caption, name))
    L.append("")
    return L


def section(runs, out_dir, settings=None, names=loading.RUN_NAMES):
    """For report.py: the Markdown lines of the section for the loaded runs ({name: loading.Run}, using
    their bag paths), with the figures written to out_dir. Inputs refused raise AnalysisInputError."""
    safety_runs, skipped = {}, []
    for n in names:
        r = runs.get(n)
        if r is None:
            continue
        scene = os.path.join(os.path.dirname(r.bag), n + ".scene.yaml")
        try:
            safety_runs[n] = safety.load(r.bag, scene if os.path.isfile(scene) else None, r.track_bag, n)
        except safety.AnalysisInputError as e:
            # The rest of the report stands; this run's safety quantities are listed as not evaluated.
            skipped.append("- %s: not evaluated: %s" % (n, e))
    lines = []
    if safety_runs:
        evals = evaluate_runs(safety_runs, settings)
        os.makedirs(out_dir, exist_ok=True)
        figs = figures(evals, out_dir)
        lines = markdown_section(safety_runs, evals, out_dir, figs)
    if skipped:
        if not lines:
            lines = ["## Running safety, track loading, wear and comfort", ""]
        lines += skipped + [""]
    return lines


def _settings_from_args(a):
    kw = {"flange_angle_deg": a.flange_angle, "alpha": a.alpha, "window": a.window, "t_discard": a.discard,
          "qst_cutoff_hz": a.qst_cutoff, "comfort_window": a.comfort_window, "unloading_limit": a.unloading_limit}
    if a.friction is not None:
        kw["friction"] = a.friction
    if a.q0 is not None:
        kw["q0"] = a.q0
    for k, v in kw.items():
        if not (isinstance(v, float) and math.isfinite(v) and (v >= 0 if k == "t_discard" else v > 0)):
            raise safety.AnalysisInputError("--%s: must be a positive number, got %r" % (k.replace("_", "-"), v))
    return safety.Settings(**kw)


def _incomplete(bag):
    """Why the run of bag did not finish, from the runner's <bag stem>.run.yaml beside it ('' when it did, or
    when there is no run.yaml)."""
    path = (bag[:-4] if bag.endswith(".bag") else bag) + ".run.yaml"
    try:
        with open(path) as f:
            info = yaml.safe_load(f) or {}
    except (OSError, yaml.YAMLError):
        return ""
    if info.get("incomplete"):
        return str(info["incomplete"])
    code = info.get("exit_code")
    return "" if code in (0, None) else "the run exited %s" % code


def main(argv=None):
    p = argparse.ArgumentParser(prog="railsim_safety", description=(
        "Running-safety, track-loading, wear and comfort quantities of railsim runs. "
        "railsim_safety RUN_DIR [--runs names] [--out DIR]  or  railsim_safety BAG --scene SCENE.yaml. "
        "Prints the summary table and writes <run>.safety.csv beside each bag."))
    p.add_argument("input", help="a run directory, or a vehicle bag")
    p.add_argument("--scene", help="resolved scene of the bag (with a bag)")
    p.add_argument("--track-bag", help="the track node's bag of a co-simulation (with a bag)")
    p.add_argument("--runs", default=",".join(loading.RUN_NAMES), help="run names in RUN_DIR (comma-separated)")
    p.add_argument("--out", help="directory for safety.md and the figures")
    p.add_argument("--discard", type=float, default=0.25, help="initial time discarded [s] (0.25)")
    p.add_argument("--friction", type=float, help="friction coefficient (default: scene, else 0.3)")
    p.add_argument("--flange-angle", type=float, default=safety.S1002_FLANGE_ANGLE_DEG,
                   help="maximum flange angle [deg] (S1002: 70)")
    p.add_argument("--alpha", type=float, default=safety.PRUDHOMME_ALPHA, help="Prud'homme alpha (1.0)")
    p.add_argument("--q0", type=float, help="static wheel load [N] (default: vehicle data file masses)")
    p.add_argument("--window", type=float, default=safety.SLIDING_WINDOW_M, help="sliding-mean length [m] (2)")
    p.add_argument("--qst-cutoff", type=float, default=safety.QST_CUTOFF_HZ, help="quasi-static Q cut-off [Hz] (2)")
    p.add_argument("--comfort-window", type=float, default=comfort.WINDOW_S, help="comfort r.m.s. window [s] (5)")
    p.add_argument("--unloading-limit", type=float, default=safety.UNLOADING_LIMIT, help="dQ/Q0 limit (0.6)")
    a = p.parse_args(argv)
    try:
        settings = _settings_from_args(a)
        runs = {}
        if os.path.isdir(a.input):
            names = [n.strip() for n in a.runs.split(",") if n.strip()]
            for n in names:
                if os.path.isfile(os.path.join(a.input, n + ".bag")):
                    runs[n] = safety.load_run_dir(a.input, n)
            if not runs:
                raise safety.AnalysisInputError("%s: none of the runs %s present (<run>.bag)"
                                                % (a.input, ", ".join(names)))
        else:
            if a.scene is None:
                raise safety.AnalysisInputError("%s: a bag needs --scene SCENE.yaml" % a.input)
            run = safety.load(a.input, a.scene, a.track_bag)
            runs[run.name] = run
        evals = evaluate_runs(runs, settings)
    except safety.AnalysisInputError as e:
        sys.stderr.write("railsim_safety: %s\n" % str(e).replace("\n", " "))
        return EXIT_TOO_SHORT if isinstance(e, safety.AnalysisTooShortError) else EXIT_BAD_INPUT
    try:
        return _write_outputs(a, runs, evals)
    except OSError as e:
        return loading.exit_write_failed("railsim_safety", e, a.out or a.input)


def _write_outputs(a, runs, evals):
    """The summary tables, the CSV beside each bag and (with --out) safety.md and its figures."""
    incomplete = {n: _incomplete(r.bag) for n, r in runs.items()}
    for n, ev in evals.items():
        if incomplete[n]:
            print("%s: incomplete: %s" % (n, incomplete[n]))
        print(text_table(n, ev.rows))
        print("")
        bag = runs[n].bag
        base = bag[:-4] if bag.endswith(".bag") else bag
        path = write_csv(base + ".safety.csv", n, ev.rows)
        print("csv: %s" % os.path.abspath(path))
    if a.out:
        os.makedirs(a.out, exist_ok=True)
        figs = figures(evals, a.out)
        lines = markdown_section(runs, evals, a.out, figs)
        marks = ["**%s: incomplete: %s**" % (n, why) for n, why in incomplete.items() if why]
        if marks:
            lines[1:1] = [""] + marks
        path = os.path.join(a.out, "safety.md")
        with loading.writing(path), open(path, "w") as f:
            f.write("\n".join(lines))
        print("report: %s" % os.path.abspath(path))
    return EXIT_OK
