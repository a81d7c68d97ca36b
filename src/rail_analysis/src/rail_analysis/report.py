"""railsim_analyze: reads a run directory (standalone, rigid_fe, flexible), writes the figures of the paper's
section 6 and report.md. Exit codes: 0 done, 2 an input refused (one line on stderr naming the file, and
for a bag the missing topic)."""
import argparse
import math
import os
import sys

from . import analysis, figures, loading

EXIT_OK = 0
EXIT_BAD_INPUT = 2
EXIT_TOO_SHORT = 3  # a run too short for the analysis (one line on stderr)
EXIT_WRITE_FAILED = loading.EXIT_WRITE_FAILED  # an output could not be written (one line on stderr)


def _fmt(x, spec="%.3g"):
    return spec % x if x is not None and isinstance(x, (int, float)) and math.isfinite(x) else "n/a"


def _num(info, key):
    try:
        v = float(info.get(key))
        return v if math.isfinite(v) else None
    except (TypeError, ValueError):
        return None


def load_runs(run_dir, names=loading.RUN_NAMES, progress=print):
    """{name: Run} of the runs present in run_dir, and the notes on those skipped."""
    runs, skipped = {}, []
    for name in names:
        if not loading.run_present(run_dir, name):
            skipped.append("%s: skipped, %s.bag not in %s" % (name, name, run_dir))
            progress("%s: not present, skipped" % name)
            continue
        progress("%s: loading %s" % (name, os.path.join(run_dir, name + ".bag")))
        runs[name] = loading.load_run(run_dir, name)
        k = runs[name].kinematics
        progress("%s: %d wheelset samples, t = %.3f..%.3f s" % (name, k["t"].size, k["t"][0], k["t"][-1]))
    return runs, skipped


def write_report(runs, skipped, run_dir, out_dir, t_discard, figure_list, checks, path):
    """Writes report.md: runs, deviation table, wall times, the paper's observations checked, figures."""
    scene = analysis._scene(runs)
    L = []
    L.append("# railsim run analysis: the paper's section 6 demonstration")
    L.append("")
    L.append("Run directory: `%s`. The first %.2f s of every run are discarded (transient start). The leading "
             "wheelset is wheelset 1 (index 0); left = wheel side 0; forces and displacements in the track frame "
             "(x along the track, y to the left, z up)." % (os.path.abspath(run_dir), t_discard))
    if scene is not None:
        segs = ", ".join("%s %.0f-%.0f m%s" % (k, a, b, (" " + d) if d else "") for k, a, b, d in scene.segments)
        L.append("")
        L.append("Track: %s. Speed %.2f m/s (%.1f km/h), sleepers every %.2f m: sleeper-passing frequency %.2f Hz."
                 % (segs, scene.speed, scene.speed * 3.6, scene.sleeper_spacing, scene.sleeper_frequency()))
    # A run that did not finish (the runner's run.yaml) is marked, not presented as whole.
    for name in loading.RUN_NAMES:
        r = runs.get(name)
        why = (r.info.get("incomplete") or ("" if r.info.get("exit_code") in (0, None) else
                                            "the run exited %s" % r.info.get("exit_code"))) if r else ""
        if why:
            L.append("")
            L.append("**%s: incomplete: %s**" % (name, why))
    L.append("")
    L.append("## Runs")
    L.append("")
    L.append("| run | track model | simulated time [s] | wall time [s] | wall / simulated | exit code |")
    L.append("|---|---|---|---|---|---|")
    for name in loading.RUN_NAMES:
        r = runs.get(name)
        if r is None:
            L.append("| %s | — | — | — | — | not present |" % name)
            continue
        # Simulated time: the runner's figure, else the last wheelset sample of the bag.
        sim, wall = _num(r.info, "simulated_time"), _num(r.info, "wall_time")
        if sim is None:
            sim = float(r.kinematics["t"][-1])
        model = r.info.get("track_model") or (r.scene.track_model if r.scene else "?")
        L.append("| %s | %s | %s | %s | %s | %s |" % (name, model, _fmt(sim, "%.3f"), _fmt(wall, "%.1f"),
                                                       _fmt(wall / sim if sim and wall else None, "%.1f"),
                                                       r.info.get("exit_code", "?")))
    for note in skipped:
        L.append("")
        L.append("- " + note)
    notes = [n for name in loading.RUN_NAMES if runs.get(name) for n in runs[name].notes]
    if notes:
        L.append("")
        L.append("Notes:")
        L.append("")
        for n in notes:
            L.append("- " + n)

    L.append("")
    L.append("## Co-simulation on the rigid FE track against the vehicle alone")
    L.append("")
    L.append("Largest absolute deviation of the leading wheelset between the runs `rigid_fe` and `standalone` "
             "after the discard, both interpolated linearly on a common time base.")
    L.append("")
    L.append("| quantity | this run | paper | within the paper's value |")
    L.append("|---|---|---|---|")
    if runs.get("standalone") and runs.get("rigid_fe"):
        dev = analysis.deviation_table(runs["standalone"], runs["rigid_fe"], t_discard)
    else:
        dev = None
    for key, label in (("lateral", "lateral displacement [m]"), ("angle_of_attack_deg", "angle of attack [deg]"),
                       ("vertical", "vertical displacement [m]")):
        paper = analysis.PAPER_DEVIATION[key]
        if dev is None:
            L.append("| %s | not available | %.2g | not available |" % (label, paper))
        else:
            L.append("| %s | %.3g | %.2g | %s |" % (label, dev[key], paper, "yes" if dev[key] <= paper else "no"))
    L.append("")
    ratios = analysis.wall_ratios(runs)
    L.append("| wall-time ratio | this run | paper |")
    L.append("|---|---|---|")
    for key in ("rigid_fe", "flexible"):
        L.append("| %s / standalone | %s | %.1f |" % (key, _fmt(ratios[key], "%.2f"), analysis.PAPER_WALL_RATIO[key]))

    L.append("")
    L.append("## The paper's observations, checked on these runs")
    L.append("")
    for i, c in enumerate(checks, 1):
        L.append("%d. **%s: %s.** Paper: %s Measured: %s." % (i, c.title, c.status, c.paper, c.measured))
    L.append("")
    counts = {s: sum(1 for c in checks if c.status == s) for s in (analysis.AGREES, analysis.DISAGREES,
                                                                   analysis.NOT_AVAILABLE)}
    L.append("Summary: %d agree, %d do not agree, %d not available." % (counts[analysis.AGREES],
                                                                      counts[analysis.DISAGREES],
                                                                      counts[analysis.NOT_AVAILABLE]))
    L.append("")
    # Running safety, track loading, wear and comfort of each run (safety_report; doc/safety.md).
    from . import safety_report
    L.extend(safety_report.section(runs, out_dir))
    L.append("## Figures")
    for caption, name in figure_list:
        L.append("")
        L.append("### " + caption)
        L.append("")
        L.append("![%s](%s)" % (caption, name))
    L.append("")
    with loading.writing(path), open(path, "w") as f:
        f.write("\n".join(L))
    return path


def analyze(run_dir, out_dir, t_discard=0.25, names=loading.RUN_NAMES, progress=print):
    """Loads the runs, writes the figures and report.md into out_dir. Returns (report path, runs, checks,
    figure list). Raises loading.AnalysisInputError on refused input."""
    if not os.path.isdir(run_dir):
        raise loading.AnalysisInputError("%s: no such run directory" % run_dir)
    runs, skipped = load_runs(run_dir, names, progress)
    if not runs:
        raise loading.AnalysisInputError("%s: none of the runs %s present (<run>.bag)" % (run_dir, ", ".join(names)))
    os.makedirs(out_dir, exist_ok=True)
    scene = analysis._scene(runs)
    progress("writing figures to %s" % out_dir)
    figure_list = figures.all_figures(runs, scene, t_discard, out_dir)
    checks = analysis.all_checks(runs, t_discard)
    for c in checks:
        progress("check: %s: %s (%s)" % (c.title, c.status, c.measured))
    path = write_report(runs, skipped, run_dir, out_dir, t_discard, figure_list, checks,
                        os.path.join(out_dir, "report.md"))
    return path, runs, checks, figure_list


def main(argv=None):
    p = argparse.ArgumentParser(prog="railsim_analyze", description=(
        "Figures and a Markdown report of the paper's three runs (standalone, rigid_fe, flexible) found in a "
        "run directory: <run>.bag, <run>.track.bag, <run>.run.yaml, <run>.scene.yaml."))
    p.add_argument("run_dir", help="directory holding the runs' files")
    p.add_argument("--out", required=True, help="directory for the PNG figures and report.md")
    p.add_argument("--discard", type=float, default=0.25, help="initial time discarded [s] (default 0.25)")
    p.add_argument("--runs", default=",".join(loading.RUN_NAMES),
                   help="comma-separated run names to look for (default: standalone,rigid_fe,flexible)")
    a = p.parse_args(argv)
    names = [n.strip() for n in a.runs.split(",") if n.strip()]
    bad = [n for n in names if n not in loading.RUN_NAMES]
    if bad or not (a.discard >= 0):
        msg = ("--runs: unknown run %r (known: %s)" % (bad[0], ", ".join(loading.RUN_NAMES)) if bad
               else "--discard: must be >= 0, got %r" % a.discard)
        sys.stderr.write("railsim_analyze: %s\n" % msg)
        return EXIT_BAD_INPUT
    try:
        path, _, _, _ = analyze(a.run_dir, a.out, a.discard, names, progress=lambda s: print(s, flush=True))
    except loading.AnalysisInputError as e:
        sys.stderr.write("railsim_analyze: %s\n" % str(e).replace("\n", " "))
        # A run too short for the analysis is not a bad input: the runner says so and keeps the run's code.
        return EXIT_TOO_SHORT if type(e).__name__ == "AnalysisTooShortError" else EXIT_BAD_INPUT
    except OSError as e:
        return loading.exit_write_failed("railsim_analyze", e, a.out or a.run_dir)
    print("report: %s" % os.path.abspath(path))
    return EXIT_OK
