#!/usr/bin/env python3
"""Compares two runs of the same scene (e.g. the same flexible run from two builds) by the figures a change
that should leave the results alone must keep: on the straights and in the steady curves the wheel forces
pointwise within --force-tol of the static wheel load; the rail displacements at the deflection sections
pointwise within --deflection-tol of their peak; in the transitions, where the flange contact bounces
chaotically, the flange-force bursts' count, largest force and mean within --burst-tol. Prints a Markdown
table; exit 0 when every figure is within its tolerance, 1 when one is not, 2 on a usage or input error.

  scripts/compare_flexible_runs.py BEFORE_DIR AFTER_DIR [--run flexible] [--force-tol 0.01]
                                   [--deflection-tol 0.01] [--burst-tol 0.05]

BEFORE_DIR and AFTER_DIR are run directories of ./railsim run (<run>.bag, <run>.track.bag,
<run>.scene.yaml). A window is straight or steady curve when every wheelset is on one straight or circular
segment, transition otherwise. Bursts: runs of samples with flange contact on the leading wheelset's wheel
that carries the more flange force in the window (the definition of bench_vehicle_accuracy).
"""
import argparse
import os
import sys

import numpy as np

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), ".."))
sys.path.insert(0, os.path.join(REPO, "src", "rail_analysis", "src"))
from rail_analysis import loading  # noqa: E402


def windows(scene, arc_length):
    """Per sample: 'straight', 'curve' or 'transition' by where the wheelsets are (arc_length (N, W))."""
    kinds = []
    for row in arc_length:
        segs = {scene.segment_at(s) for s in row if np.isfinite(s)}
        if len(segs) == 1 and None not in segs:
            kind = next(iter(segs))[0]
            kinds.append("straight" if kind == "straight" else "curve" if kind == "circular" else "transition")
        else:
            kinds.append("transition")
    return np.array(kinds)


def bursts(t, flange_left, flange_right, sel):
    """count, largest [N] and mean over the samples in contact [N] of the flange-force bursts in sel."""
    f = flange_left if flange_left[sel].sum() > flange_right[sel].sum() else flange_right
    x = f[sel]
    on = x > 0.0
    count = int(np.sum(on[1:] & ~on[:-1]) + (1 if on.size and on[0] else 0))
    return count, (float(x.max()) if on.any() else 0.0), (float(x[on].mean()) if on.any() else 0.0)


def common(ta, tb):
    """Indices of the samples present in both runs (times equal to 1 us)."""
    ka, kb = np.round(ta * 1e6).astype(np.int64), np.round(tb * 1e6).astype(np.int64)
    _, ia, ib = np.intersect1d(ka, kb, return_indices=True)
    return ia, ib


def relative(d, ref):
    return d / ref if ref > 0 else float("inf")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("before")
    ap.add_argument("after")
    ap.add_argument("--run", default="flexible")
    ap.add_argument("--force-tol", type=float, default=0.01)
    ap.add_argument("--deflection-tol", type=float, default=0.01)
    ap.add_argument("--burst-tol", type=float, default=0.05)
    a = ap.parse_args(argv)
    try:
        A = loading.load_run(a.before, a.run)
        B = loading.load_run(a.after, a.run)
    except (loading.AnalysisInputError, OSError) as e:
        print("compare_flexible_runs: %s" % e, file=sys.stderr)
        return 2
    if A.scene is None or A.kinematics["left_force"] is None or B.kinematics["left_force"] is None:
        print("compare_flexible_runs: %s: needs <run>.scene.yaml and the wheel forces in /wheelset_kinematics"
              % a.before, file=sys.stderr)
        return 2
    ka, kb = A.kinematics, B.kinematics
    ia, ib = common(ka["t"], kb["t"])
    if ia.size < 10:
        print("compare_flexible_runs: the runs share %d samples" % ia.size, file=sys.stderr)
        return 2
    kind = windows(A.scene, ka["arc_length"][ia])
    fa = np.concatenate([ka["left_force"][ia], ka["right_force"][ia]], axis=1)  # (N, 2W, 3)
    fb = np.concatenate([kb["left_force"][ib], kb["right_force"][ib]], axis=1)
    straight = kind == "straight"
    q0 = float(np.nanmean(fa[straight, :, 2])) if straight.any() else float(np.nanmean(fa[:, :, 2]))
    rows, ok = [], True
    for name in ("straight", "curve"):
        sel = kind == name
        if not sel.any():
            rows.append((name + ": wheel forces", "no samples", "", ""))
            continue
        d = np.nanmax(np.abs(fa[sel][:, :, 1:] - fb[sel][:, :, 1:]))
        good = relative(d, q0) <= a.force_tol
        ok = ok and good
        rows.append((name + ": wheel forces (lateral, vertical), largest difference",
                     "%.1f N = %.3f %% of Q0 = %.1f kN (%d samples)" % (d, 100 * relative(d, q0), q0 / 1e3, sel.sum()),
                     "%.1f %%" % (100 * a.force_tol), "yes" if good else "NO"))
    for s, da in sorted((A.deflection or {}).items()):
        db = (B.deflection or {}).get(s)
        if db is None:
            rows.append(("rail at %.0f m" % s, "missing in %s" % a.after, "", "NO"))
            ok = False
            continue
        ja, jb = common(da["t"], db["t"])
        xa = np.concatenate([da["left"][ja], da["right"][ja]], axis=1)
        xb = np.concatenate([db["left"][jb], db["right"][jb]], axis=1)
        peak = float(np.max(np.abs(xa)))
        d = float(np.max(np.abs(xa - xb)))
        good = relative(d, peak) <= a.deflection_tol
        ok = ok and good
        rows.append(("rail displacement at %.0f m, largest difference" % s,
                     "%.3g m = %.3f %% of its peak %.3g m" % (d, 100 * relative(d, peak), peak),
                     "%.1f %%" % (100 * a.deflection_tol), "yes" if good else "NO"))
    # Transitions: the leading wheelset's flange bursts, window by window (contiguous transition samples).
    pa, pb = A.points, B.points
    trans = kind == "transition"
    if pa is not None and pb is not None and trans.any():
        ja, jb = common(pa["t"], pb["t"])
        t_common = pa["t"][ja]
        in_trans = np.interp(t_common, ka["t"][ia], trans.astype(float)) > 0.5
        edges = np.flatnonzero(np.diff(np.concatenate([[0], in_trans.astype(int), [0]])))
        for w0, w1 in zip(edges[::2], edges[1::2]):
            sel = np.zeros(t_common.size, dtype=bool)
            sel[w0:w1] = True
            fig = []
            for p, j in ((pa, ja), (pb, jb)):
                sub = {k: v[j] for k, v in p.items()}
                fig.append(bursts(t_common, loading.flange_normal_force(sub, 0), loading.flange_normal_force(sub, 1),
                                  sel))
            (ca, xa, ma), (cb, xb, mb) = fig
            label = "transition %.2f-%.2f s: flange bursts (count, largest, mean)" % (t_common[w0], t_common[w1 - 1])
            diffs = [relative(abs(cb - ca), ca), relative(abs(xb - xa), xa), relative(abs(mb - ma), ma)]
            if ca == 0 and cb == 0:
                diffs = [0.0, 0.0, 0.0]
            good = max(diffs) <= a.burst_tol
            ok = ok and good
            rows.append((label, "%d / %.1f kN / %.1f kN against %d / %.1f kN / %.1f kN (%+.1f %%, %+.1f %%, %+.1f %%)"
                         % (cb, xb / 1e3, mb / 1e3, ca, xa / 1e3, ma / 1e3, 100 * diffs[0], 100 * diffs[1],
                            100 * diffs[2]), "%.0f %%" % (100 * a.burst_tol), "yes" if good else "NO"))
    print("| %s against %s (%s) | figure | tolerance | within |" % (a.after, a.before, a.run))
    print("|---|---|---|---|")
    for r in rows:
        print("| %s | %s | %s | %s |" % r)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
