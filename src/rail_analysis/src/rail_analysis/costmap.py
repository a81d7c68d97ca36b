"""The accuracy-cost map: one scene run across a grid of settings, each run's error against the finest run
(the reference) and its wall time, as a table and a Pareto plot (railsim_map).

A grid file (YAML, config/maps/*.yaml) holds:
  name:       the map's name (default: the file stem)
  scene:      the scene, relative to the grid file (or absolute)
  workspace:  optional, the built catkin workspace the runs use (devel/setup.bash and launch/ inside it),
              relative to the grid file or absolute; default: the workspace this module belongs to.
  timeout:    wall seconds per case before it is stopped and recorded as failed (default 900)
  base:       {scene.key: value} overrides applied to every case (e.g. a short solver.end)
  reference:  {name, overrides}: the finest settings; every error is measured against this run
  cases:      [{name, overrides}]: a list of named cases, and/or
  axes:       {scene.key: [values]}: the full product of the listed values, one case per combination
  metrics:    {discard [s] (0.1), wheelset (0 = leading), deflection_section [m] (none),
               pareto_metric (force_z_rms), pareto_time (wall_time | loop_wall_time)}
Overrides are scene keys in dotted form with YAML values, as in docs/scene.md; a case's overrides are
applied on top of `base`. A case is identified by its readable name plus a short hash of its resolved
overrides (case_id); its settings hash covers the scene file's text and those overrides, so a changed
scene or setting reruns it.

Each case runs in <cases>/<case_id>/: scene.yaml (the resolved scene), run.log (the launch's console),
run.bag, run.track.bag (co-simulation), run.cost.yaml, run.track.cost.yaml, and result.yaml, written last
and atomically: settings, settings hash, status, exit code, wall time, cost profile, metrics.

Metrics (SI; each a pair <name>_max, <name>_rms of the absolute deviation from the reference, on the
reference's samples after the discard time, the case interpolated linearly to them):
  lateral, vertical        leading-wheelset lateral / vertical displacement [m]
  force_z, force_y         vertical / lateral contact force of the leading wheelset's two wheels, track
                           frame (/wheelset_kinematics) [N]; both wheels pooled
  deflection_z             vertical rail deflection at the grid's deflection_section, both rails pooled
                           [m]; not available (None) when either run has no /rail_deflection there
"""
import concurrent.futures
import csv
import fnmatch
import hashlib
import itertools
import json
import math
import os
import re
import signal
import sys
import threading
import time

import numpy as np
import yaml

from rail_analysis import loading
from rail_analysis.runner import BAG, DEFAULT_TIMEOUT, read_cost, run_case, stop_all

DEFAULT_DISCARD = 0.1            # s of simulated time skipped at the start (settling of the initial state)
RESULT = "result.yaml"
# (name, unit) of the metric signals, in table order.
SIGNALS = (("lateral", "m"), ("vertical", "m"), ("force_z", "N"), ("force_y", "N"), ("deflection_z", "m"))
# The case's own impact peaks (not deviations): the largest vertical force on the metrics' wheelset after the
# discard, unfiltered (P1) and low-passed at 150 Hz (P2, rail_analysis.safety.p2_force) [N].
IMPACT_METRICS = ("impact_p1", "impact_p2")
DEVIATION_METRICS = tuple("%s_%s" % (s, k) for s, _ in SIGNALS for k in ("max", "rms"))
METRIC_NAMES = DEVIATION_METRICS + IMPACT_METRICS
# Components of the cost profiles copied into the table (seconds).
COST_COLUMNS = (("vehicle", "loop_wall_time"), ("vehicle", "vehicle_integration"), ("vehicle", "transport_wait"),
                ("track", "loop_wall_time"), ("track", "track_step"), ("track", "transport_wait"))


class GridError(RuntimeError):
    """A grid file or an option cannot be used; the message names the file and the field."""


# --------------------------------------------------------------------------------------------- grid file

class _Loader(yaml.SafeLoader):
    """YAML 1.1 loader that also reads 1e-5 (no dot) as a float, as yaml-cpp and the scene files do."""


_Loader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
                    |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
                    |\.[0-9_]+(?:[eE][-+][0-9]+)?
                    |[-+]?\.(?:inf|Inf|INF)
                    |\.(?:nan|NaN|NAN))$""", re.X),
    list("-+0123456789."))


def format_value(v):
    """A YAML value as the text of a `key=value` override (flow style; floats as Python's repr)."""
    if isinstance(v, bool):
        return "true" if v else "false"
    if v is None:
        return "null"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        if v == "":
            return "''"
        if re.match(r"^[A-Za-z0-9_./+-]+$", v):
            return v
        return json.dumps(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(format_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join("%s: %s" % (k, format_value(x)) for k, x in v.items()) + "}"
    raise GridError("cannot write %r as an override value" % (v,))


def override_items(overrides):
    """["key=value", ...] of an override mapping, in key order (what the launch and the validator take)."""
    return ["%s=%s" % (k, format_value(overrides[k])) for k in sorted(overrides)]


def _canonical(overrides):
    return json.dumps(override_items(overrides), separators=(",", ":"))


def overrides_hash(overrides, n=8):
    """Short hex hash of an override mapping (independent of key order)."""
    return hashlib.sha256(_canonical(overrides).encode()).hexdigest()[:n]


def settings_hash(scene_text, overrides):
    """Hex hash (16 digits) of what a case's run depends on: the scene file's text and its overrides."""
    h = hashlib.sha256()
    h.update(hashlib.sha256(scene_text.encode()).hexdigest().encode())
    h.update(_canonical(overrides).encode())
    return h.hexdigest()[:16]


def slug(name):
    """A name made safe for a directory name."""
    s = re.sub(r"[^A-Za-z0-9._=+-]+", "_", str(name)).strip("_")
    return s or "case"


def case_id(name, overrides):
    """Directory name of a case: its readable name, '-', a short hash of its (resolved) overrides."""
    return "%s-%s" % (slug(name), overrides_hash(overrides))


class Case(object):
    """One point of the grid: name, own overrides (relative to base), overrides (base + own, what runs),
    case_id, settings_hash, is_reference."""

    def __init__(self, name, own, base, scene_text, is_reference=False):
        self.name = str(name)
        self.own = dict(own)
        self.overrides = dict(base)
        self.overrides.update(own)
        self.case_id = case_id(self.name, self.overrides)
        self.settings_hash = settings_hash(scene_text, self.overrides)
        self.is_reference = is_reference

    def settings_text(self):
        """The case's own settings, e.g. 'solver.track_step=4e-05 effects.track_model=rigid_fe'."""
        return " ".join(override_items(self.own)) if self.own else "(base)"


def _short_key(key):
    return key.rsplit(".", 1)[-1]


class Grid(object):
    """A grid file, read and checked (see the module's docstring). Attributes: path, name, scene (absolute),
    scene_text, workspace, timeout [s], base, reference (Case), cases ([Case], the reference first),
    mode ('cases', 'product' or 'cases+product'), discard [s], wheelset, deflection_section [m] or None,
    pareto_metric, pareto_time, duplicates ([(name, name of the case it equals)])."""

    def __init__(self, path, workspace=None):
        self.path = os.path.abspath(path)
        data = loading.read_yaml(path, _Loader, GridError)
        if not isinstance(data, dict):
            raise GridError("%s: expected a mapping at the top level" % path)
        here = os.path.dirname(self.path)
        known = {"name", "description", "scene", "workspace", "timeout", "base", "reference", "cases", "axes",
                 "metrics"}
        unknown = sorted(set(data) - known)
        if unknown:
            raise GridError("%s: unknown key '%s' (known: %s)" % (path, unknown[0], ", ".join(sorted(known))))
        self.name = str(data.get("name") or os.path.splitext(os.path.basename(path))[0])
        self.description = str(data.get("description") or "")
        if "scene" not in data:
            raise GridError("%s: missing key 'scene'" % path)
        self.scene = os.path.normpath(os.path.join(here, str(data["scene"])))
        try:
            with open(self.scene) as f:
                self.scene_text = f.read()
        except OSError as e:
            raise GridError("%s: scene: cannot read %s: %s" % (path, self.scene, e.strerror))
        ws = workspace or data.get("workspace")
        if ws:
            self.workspace = os.path.normpath(os.path.join(here if not workspace else os.getcwd(), str(ws)))
        else:
            # src/rail_analysis/src/rail_analysis/costmap.py -> the workspace four levels up
            self.workspace = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)),
                                                           "..", "..", "..", ".."))
        self.timeout = self._positive(data, "timeout", DEFAULT_TIMEOUT)
        self.base = self._overrides(data.get("base") or {}, "base")
        metrics = data.get("metrics") or {}
        if not isinstance(metrics, dict):
            raise GridError("%s: metrics: expected a mapping, got %r" % (path, metrics))
        mknown = {"discard", "wheelset", "deflection_section", "pareto_metric", "pareto_time"}
        bad = sorted(set(metrics) - mknown)
        if bad:
            raise GridError("%s: metrics: unknown key '%s' (known: %s)" % (path, bad[0], ", ".join(sorted(mknown))))
        self.discard = self._number(metrics, "discard", DEFAULT_DISCARD, "metrics.", minimum=0.0)
        self.wheelset = int(self._number(metrics, "wheelset", 0, "metrics.", minimum=0))
        sec = metrics.get("deflection_section")
        self.deflection_section = None if sec is None else self._number(metrics, "deflection_section", 0,
                                                                        "metrics.")
        self.pareto_metric = str(metrics.get("pareto_metric", "force_z_rms"))
        if self.pareto_metric not in DEVIATION_METRICS:
            raise GridError("%s: metrics.pareto_metric: unknown metric '%s' (known: %s)"
                            % (path, self.pareto_metric, ", ".join(DEVIATION_METRICS)))
        self.pareto_time = str(metrics.get("pareto_time", "wall_time"))
        if self.pareto_time not in ("wall_time", "loop_wall_time"):
            raise GridError("%s: metrics.pareto_time: must be wall_time or loop_wall_time, got '%s'"
                            % (path, self.pareto_time))
        ref = data.get("reference")
        if not isinstance(ref, dict) or "name" not in ref:
            raise GridError("%s: reference: expected a mapping with name and overrides" % path)
        self.reference = Case(ref["name"], self._overrides(ref.get("overrides") or {}, "reference.overrides"),
                              self.base, self.scene_text, is_reference=True)
        cases = []
        named = data.get("cases")
        axes = data.get("axes")
        if named is None and axes is None:
            raise GridError("%s: neither 'cases' (a list of named cases) nor 'axes' (a product) given" % path)
        if named is not None:
            if not isinstance(named, list) or not named:
                raise GridError("%s: cases: expected a non-empty list of {name, overrides}" % path)
            for i, c in enumerate(named):
                if not isinstance(c, dict) or "name" not in c:
                    raise GridError("%s: cases[%d]: expected a mapping with name and overrides, got %r" % (path, i, c))
                cases.append(Case(c["name"], self._overrides(c.get("overrides") or {}, "cases[%d].overrides" % i),
                                  self.base, self.scene_text))
        if axes is not None:
            if not isinstance(axes, dict) or not axes:
                raise GridError("%s: axes: expected a mapping of scene key to a list of values" % path)
            keys = list(axes)
            for k in keys:
                if not isinstance(axes[k], list) or not axes[k]:
                    raise GridError("%s: axes.%s: expected a non-empty list of values, got %r" % (path, k, axes[k]))
                self._overrides({k: axes[k][0]}, "axes")
            for combo in itertools.product(*(axes[k] for k in keys)):
                own = dict(zip(keys, combo))
                name = ",".join("%s=%s" % (_short_key(k), format_value(v)) for k, v in own.items())
                cases.append(Case(name, own, self.base, self.scene_text))
        self.mode = "cases+product" if (named is not None and axes is not None) else (
            "cases" if named is not None else "product")
        # A case with the reference's settings is the reference; two cases with the same settings run once.
        self.cases = [self.reference]
        self.duplicates = []
        seen = {overrides_hash(self.reference.overrides, 16): self.reference}
        ids = {self.reference.case_id}
        for c in cases:
            h = overrides_hash(c.overrides, 16)
            if h in seen:
                self.duplicates.append((c.name, seen[h].name))
                continue
            if c.case_id in ids:
                raise GridError("%s: two cases named '%s'" % (path, c.name))
            seen[h] = c
            ids.add(c.case_id)
            self.cases.append(c)

    def _positive(self, d, key, default):
        v = self._number(d, key, default, "")
        if v <= 0:
            raise GridError("%s: %s: must be > 0, got %g" % (self.path, key, v))
        return v

    def _number(self, d, key, default, where, minimum=None):
        v = d.get(key, default)
        try:
            v = float(v)
        except (TypeError, ValueError):
            raise GridError("%s: %s%s: not a number (%r)" % (self.path, where, key, v))
        if not math.isfinite(v) or (minimum is not None and v < minimum):
            raise GridError("%s: %s%s: must be a finite number >= %s, got %r" % (self.path, where, key, minimum, v))
        return v

    def _overrides(self, d, where):
        if not isinstance(d, dict):
            raise GridError("%s: %s: expected a mapping of scene key to value, got %r" % (self.path, where, d))
        for k, v in d.items():
            if not isinstance(k, str) or not re.match(r"^[A-Za-z_][A-Za-z0-9_]*(\.[A-Za-z_][A-Za-z0-9_]*)*$", k):
                raise GridError("%s: %s: '%s' is not a dotted scene key" % (self.path, where, k))
            try:
                format_value(v)
            except GridError:
                raise GridError("%s: %s.%s: value %r cannot be written as an override" % (self.path, where, k, v))
        return dict(d)

    def select(self, patterns):
        """The cases whose name or case_id matches one of the shell patterns."""
        return [c for c in self.cases
                if any(fnmatch.fnmatchcase(c.name, p) or fnmatch.fnmatchcase(c.case_id, p) for p in patterns)]


# ------------------------------------------------------------------------------------- result files

def write_yaml_atomic(path, data, header=""):
    """Writes a YAML file through a temporary file in the same directory and a rename (atomic on POSIX)."""
    tmp = "%s.tmp.%d.%d" % (path, os.getpid(), threading.get_ident())
    with loading.writing(tmp), open(tmp, "w") as f:
        f.write(header)
        yaml.safe_dump(data, f, default_flow_style=False, sort_keys=False)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


def read_result(case_dir):
    """The mapping of <case_dir>/result.yaml, or None when it is missing or unreadable."""
    path = os.path.join(case_dir, RESULT)
    try:
        with open(path) as f:
            data = yaml.safe_load(f)
    except (OSError, yaml.YAMLError):
        return None
    return data if isinstance(data, dict) else None


def is_done(case_dir, settings_hash_):
    """True when the case needs no run: its result.yaml exists, was made with these settings (same hash)
    and the run succeeded. A failed or stale result is rerun."""
    r = read_result(case_dir)
    return bool(r) and r.get("settings_hash") == settings_hash_ and r.get("status") == "ok"


# --------------------------------------------------------------------------------------------- metrics

def deviation(t_ref, y_ref, t, y, discard=0.0):
    """(max, rms) of |y - y_ref| over the reference's samples t_ref >= discard that lie within [t[0], t[-1]];
    y is interpolated linearly to t_ref. y_ref (N,) or (N, k), y (M,) or (M, k): the k columns are pooled.
    Samples where either series is NaN are left out. (nan, nan) when no sample remains."""
    t_ref = np.asarray(t_ref, float)
    t = np.asarray(t, float)
    y_ref = np.asarray(y_ref, float).reshape(len(t_ref), -1)
    y = np.asarray(y, float).reshape(len(t), -1)
    if y.shape[1] != y_ref.shape[1] or len(t) == 0 or len(t_ref) == 0:
        return float("nan"), float("nan")
    sel = (t_ref >= discard) & (t_ref >= t[0]) & (t_ref <= t[-1])
    if not sel.any():
        return float("nan"), float("nan")
    d = np.column_stack([np.interp(t_ref[sel], t, y[:, j]) for j in range(y.shape[1])]) - y_ref[sel]
    d = np.abs(d[np.isfinite(d)])
    if d.size == 0:
        return float("nan"), float("nan")
    return float(d.max()), float(np.sqrt(np.mean(d * d)))


def load_series(case_dir, wheelset=0, deflection_section=None):
    """{signal: (t, values)} of one case's bags for the metrics (see SIGNALS); a signal the bags lack is
    absent. Needs rosbag (rail_analysis.loading)."""
    from . import loading
    out = {}
    bag = os.path.join(case_dir, BAG)
    k = loading.load_wheelset_kinematics(bag)
    t = k["t"]
    if wheelset < k["lateral"].shape[1]:
        out["lateral"] = (t, k["lateral"][:, wheelset])
        out["vertical"] = (t, k["vertical"][:, wheelset])
        if k["left_force"] is not None:
            for name, axis in (("force_z", 2), ("force_y", 1)):
                out[name] = (t, np.column_stack([k["left_force"][:, wheelset, axis],
                                                 k["right_force"][:, wheelset, axis]]))
    track_bag = os.path.join(case_dir, "run.track.bag")
    if deflection_section is not None and os.path.isfile(track_bag) \
            and "/rail_deflection" in loading.bag_topics(track_bag):
        sections = loading.load_rail_deflection(track_bag)
        near = [s for s in sections if abs(s - deflection_section) < 1e-3]
        if near:
            d = sections[near[0]]
            out["deflection_z"] = (d["t"], np.column_stack([d["left"][:, 2], d["right"][:, 2]]))
    return out


def metrics_against(ref_series, series, discard):
    """{metric name: value or None} of a case's series against the reference's (see deviation)."""
    m = {}
    for name, _ in SIGNALS:
        if name in ref_series and name in series:
            mx, rms = deviation(ref_series[name][0], ref_series[name][1], series[name][0], series[name][1], discard)
        else:
            mx = rms = float("nan")
        m[name + "_max"] = mx if math.isfinite(mx) else None
        m[name + "_rms"] = rms if math.isfinite(rms) else None
    m["impact_p1"] = m["impact_p2"] = None
    if "force_z" in series:
        from .safety import p2_force
        t, q = np.asarray(series["force_z"][0], float), np.asarray(series["force_z"][1], float)
        late = t >= discard
        if late.any():
            m["impact_p1"] = float(np.nanmax(q[late]))
            qp2 = p2_force(t, q)
            if qp2 is not None:
                m["impact_p2"] = float(np.nanmax(qp2[late]))
    return m


def pareto_front(points):
    """Indices of the points (cost, error) that no other point dominates (both <=, one <), sorted by cost.
    Points with a non-finite coordinate are left out."""
    pts = [(i, float(c), float(e)) for i, (c, e) in enumerate(points)
           if c is not None and e is not None and math.isfinite(float(c)) and math.isfinite(float(e))]
    front = []
    for i, c, e in pts:
        dominated = any((c2 <= c and e2 <= e) and (c2 < c or e2 < e) for j, c2, e2 in pts if j != i)
        if not dominated:
            front.append((c, e, i))
    return [i for _, _, i in sorted(front)]


# ------------------------------------------------------------------------------------------------ sweep

def _spec(grid, case, cases_dir):
    return {"case_dir": os.path.join(cases_dir, case.case_id), "name": case.name, "case_id": case.case_id,
            "settings_hash": case.settings_hash, "scene": grid.scene, "overrides": override_items(case.overrides),
            "workspace": grid.workspace, "timeout": grid.timeout}


def plan(grid, cases_dir, only=None):
    """(to_run, skipped): the cases to run and those whose result.yaml is current (see is_done). With only
    (shell patterns), just the matching cases, plus the reference when it has no current result."""
    chosen = grid.cases if not only else grid.select(only)
    if only and grid.reference not in chosen and not is_done(os.path.join(cases_dir, grid.reference.case_id),
                                                             grid.reference.settings_hash):
        chosen = [grid.reference] + chosen
    to_run, skipped = [], []
    for c in chosen:
        (skipped if is_done(os.path.join(cases_dir, c.case_id), c.settings_hash) else to_run).append(c)
    return to_run, skipped


class _Metrics(object):
    """The reference's series (loaded once) and the metrics of a case directory against them."""

    def __init__(self, grid, cases_dir):
        self.grid = grid
        self.ref_dir = os.path.join(cases_dir, grid.reference.case_id)
        self.series = None
        self.error = None

    def load_reference(self, status=None):
        """Loads the reference's series; status: its run's status (default: from its result.yaml)."""
        if status is None:
            r = read_result(self.ref_dir)
            status = r.get("status") if r else None
        if status != "ok":
            self.error = "the reference run failed or has not run"
            return False
        try:
            self.series = load_series(self.ref_dir, self.grid.wheelset, self.grid.deflection_section)
        except Exception as e:  # a reference bag that cannot be read makes every metric unavailable
            self.error = "reference: %s" % e
            return False
        return True

    def of(self, case_dir):
        if self.series is None:
            return {k: None for k in METRIC_NAMES}, self.error
        try:
            s = load_series(case_dir, self.grid.wheelset, self.grid.deflection_section)
        except Exception as e:  # one unreadable bag: that case has no metrics, the sweep goes on
            return {k: None for k in METRIC_NAMES}, str(e)
        return metrics_against(self.series, s, self.grid.discard), None


def _result(grid, case, rec, metrics, note, cases_dir):
    case_dir = os.path.join(cases_dir, case.case_id)
    cost = read_cost(case_dir) if rec.get("status") == "ok" else {}
    loops = [p.get("loop_wall_time") for p in cost.values() if isinstance(p.get("loop_wall_time"), (int, float))]
    return {
        "name": case.name, "case_id": case.case_id, "reference": case.is_reference,
        "settings_hash": case.settings_hash, "reference_hash": grid.reference.settings_hash,
        "scene": grid.scene, "settings": dict(case.own), "overrides": override_items(case.overrides),
        "status": rec.get("status"), "exit_code": rec.get("exit_code"), "wall_time": rec.get("wall_time"),
        "loop_wall_time": max(loops) if loops else None,
        "host": rec.get("host"), "port": rec.get("port"), "plan": rec.get("plan"),
        "date": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "metrics_discard": grid.discard, "metrics": metrics, "metrics_note": note,
        "cost": cost, "log_tail": rec.get("log_tail", ""),
    }


def _write_result(grid, case, rec, mx, cases_dir):
    case_dir = os.path.join(cases_dir, case.case_id)
    if rec.get("status") == "ok":
        metrics, note = mx.of(case_dir)
    else:
        metrics, note = {k: None for k in METRIC_NAMES}, "the run did not succeed"
    write_yaml_atomic(os.path.join(case_dir, RESULT), _result(grid, case, rec, metrics, note, cases_dir),
                      header="# railsim_map: one case of the accuracy-cost map '%s' (SI units)\n" % grid.name)


def _refresh_metrics(grid, case, mx, cases_dir):
    """Recomputes a current result's metrics when they were made against another reference run."""
    case_dir = os.path.join(cases_dir, case.case_id)
    r = read_result(case_dir)
    if r and r.get("status") == "ok" and (r.get("reference_hash") != grid.reference.settings_hash or r.get("metrics_discard") != grid.discard
              or (r.get("metrics_note") and mx.series is not None)):
        _write_result(grid, case, r, mx, cases_dir)


def sweep(grid, cases_dir, jobs=None, scheduler=None, only=None, progress=print):
    """Runs the cases that need it (see plan) locally on `jobs` threads, each running its case as a subprocess,
    or on a Dask cluster (scheduler address); writes each case's result.yaml as soon as the case and the
    reference are done. Returns (ran, skipped) as lists of cases."""
    os.makedirs(cases_dir, exist_ok=True)
    to_run, skipped = plan(grid, cases_dir, only)
    for c in skipped:
        progress("%s: current result, skipped" % c.name)
    mx = _Metrics(grid, cases_dir)
    ref_pending = grid.reference in to_run
    if not ref_pending:
        mx.load_reference()
        for c in skipped:
            _refresh_metrics(grid, c, mx, cases_dir)
    if not to_run:
        return [], skipped
    waiting = []   # (case, record) finished before the reference

    def finished(case, rec):
        nonlocal ref_pending
        progress("%s: %s (exit %s, %s s wall)" % (case.name, rec.get("status"), rec.get("exit_code"),
                                                   rec.get("wall_time")))
        if case.is_reference:
            # The reference's result first (its metrics against itself are 0), then the ones that waited.
            ref_pending = False
            mx.load_reference(rec.get("status"))
            _write_result(grid, case, rec, mx, cases_dir)
            for c, r in waiting:
                _write_result(grid, c, r, mx, cases_dir)
            for c in skipped:
                _refresh_metrics(grid, c, mx, cases_dir)
            waiting.clear()
        elif ref_pending:
            waiting.append((case, rec))
        else:
            _write_result(grid, case, rec, mx, cases_dir)

    specs = [(c, _spec(grid, c, cases_dir)) for c in to_run]   # the reference first: the longest run
    progress("%d case(s) to run%s" % (len(specs), " on %s" % scheduler if scheduler else " on %d job(s)" % jobs))
    if scheduler:
        from distributed import Client, as_completed
        with Client(scheduler) as client:
            futs = {}
            for c, s in specs:
                futs[client.submit(run_case, s, key="railsim-%s-%s" % (c.case_id, c.settings_hash),
                                   pure=False, retries=0)] = c
            for fut in as_completed(list(futs)):
                c = futs[fut]
                try:
                    rec = fut.result()
                except Exception as e:  # a worker lost or an error outside the run itself
                    rec = {"status": "failed", "exit_code": None, "wall_time": None, "log_tail": repr(e)}
                finished(c, rec)
    else:
        with concurrent.futures.ThreadPoolExecutor(max_workers=jobs) as pool:
            futs = {pool.submit(run_case, s): c for c, s in specs}
            try:
                for fut in concurrent.futures.as_completed(futs):
                    c = futs[fut]
                    try:
                        rec = fut.result()
                    except Exception as e:  # an error outside the run (e.g. disk full): recorded, sweep goes on
                        rec = {"status": "failed", "exit_code": None, "wall_time": None, "log_tail": repr(e)}
                    finished(c, rec)
            except BaseException:
                for f in futs:
                    f.cancel()
                stop_all()
                raise
    if ref_pending:
        for c, r in waiting:
            _write_result(grid, c, r, mx, cases_dir)
    return to_run, skipped


# ---------------------------------------------------------------------------------------------- report

def collect(grid, cases_dir):
    """The result.yaml mappings of the grid's cases that have one with current settings, in grid order."""
    rows = []
    for c in grid.cases:
        r = read_result(os.path.join(cases_dir, c.case_id))
        if r and r.get("settings_hash") == c.settings_hash:
            r["settings_text"] = c.settings_text()
            rows.append(r)
    return rows


def _cost_value(r, who, comp):
    v = (r.get("cost") or {}).get(who, {}).get(comp)
    return v if isinstance(v, (int, float)) else None


def write_csv(rows, path):
    cols = (["case", "case_id", "reference", "settings", "status", "exit_code", "wall_time", "loop_wall_time"]
            + list(METRIC_NAMES) + ["%s_%s" % wc for wc in COST_COLUMNS])
    with loading.writing(path), open(path, "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(cols)
        for r in rows:
            m = r.get("metrics") or {}
            w.writerow([r["name"], r["case_id"], r.get("reference"), r["settings_text"], r.get("status"),
                        r.get("exit_code"), r.get("wall_time"), r.get("loop_wall_time")]
                       + ["" if m.get(k) is None else repr(m.get(k)) for k in METRIC_NAMES]
                       + ["" if _cost_value(r, *wc) is None else _cost_value(r, *wc) for wc in COST_COLUMNS])


def _g(x, scale=1.0, spec="%.3g"):
    return "n/a" if x is None or not math.isfinite(float(x)) else spec % (float(x) * scale)


def write_markdown(grid, rows, path, front_names):
    # Displacements in mm, forces in kN (the table's units; the CSV keeps SI).
    unit = {"m": ("mm", 1e3), "N": ("kN", 1e-3)}
    head = ["case", "settings", "status", "wall [s]", "loop [s]"]
    for s, u in SIGNALS:
        head += ["%s max [%s]" % (s, unit[u][0]), "%s rms [%s]" % (s, unit[u][0])]
    lines = ["# Accuracy-cost map: %s" % grid.name, ""]
    if grid.description:
        lines += [grid.description, ""]
    lines += ["Scene `%s`; every case runs with the base overrides `%s`. Errors: deviation from the reference "
              "case `%s` on its samples after %g s (max and RMS of the absolute difference; forces of both "
              "leading wheels pooled; rail deflection at s = %s m, both rails). wall: launch to exit; loop: "
              "the slower node's run loop (set-up excluded). Pareto front (by %s and %s): **bold**."
              % (os.path.relpath(grid.scene, os.path.dirname(grid.path)), " ".join(override_items(grid.base)),
                 grid.reference.name, grid.discard, _g(grid.deflection_section), grid.pareto_metric,
                 grid.pareto_time), ""]
    lines += ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for r in rows:
        m = r.get("metrics") or {}
        name = r["name"] + (" (reference)" if r.get("reference") else "")
        if r["name"] in front_names:
            name = "**%s**" % name
        cells = [name, "`%s`" % r["settings_text"], str(r.get("status")), _g(r.get("wall_time"), spec="%.1f"),
                 _g(r.get("loop_wall_time"), spec="%.1f")]
        for s, u in SIGNALS:
            for k in ("max", "rms"):
                cells.append(_g(m.get("%s_%s" % (s, k)), unit[u][1]))
        lines.append("| " + " | ".join(cells) + " |")
    failed = [r for r in rows if r.get("status") != "ok"]
    for r in failed:
        lines += ["", "%s: %s, exit code %s; last lines of its log:" % (r["name"], r.get("status"), r.get("exit_code")),
                  "", "```", r.get("log_tail", ""), "```"]
    if grid.duplicates:
        lines += [""] + ["%s has the settings of %s and is not run again." % d for d in grid.duplicates]
    with loading.writing(path), open(path, "w") as f:
        f.write("\n".join(lines) + "\n")


def front_of(grid, rows):
    """Names of the rows on the Pareto front of (time, pareto metric); the reference (error 0) included."""
    pts = []
    for r in rows:
        e = 0.0 if r.get("reference") else (r.get("metrics") or {}).get(grid.pareto_metric)
        pts.append((r.get(grid.pareto_time) if r.get("status") == "ok" else None, e))
    return [rows[i]["name"] for i in pareto_front(pts)]


def plot_pareto(grid, rows, path, front_names):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    fig, ax = plt.subplots(figsize=(9, 6))
    pts = [(r, r.get(grid.pareto_time), (r.get("metrics") or {}).get(grid.pareto_metric)) for r in rows
           if r.get("status") == "ok" and not r.get("reference")]
    pts = [(r, x, y) for r, x, y in pts if x and y and x > 0 and y > 0]
    placed = []   # (log10 x, log10 y, row) of the labels so far: close points get their labels stacked
    for r, x, y in sorted(pts, key=lambda p: (p[1], p[2])):
        on = r["name"] in front_names
        ax.scatter([x], [y], s=50 if on else 30, c="tab:red" if on else "tab:gray", zorder=3)
        lx, ly = math.log10(x), math.log10(y)
        used = {pk for px, py, pk in placed if abs(px - lx) < 0.15 and abs(py - ly) < 0.08}
        k = min(set(range(len(used) + 1)) - used)
        placed.append((lx, ly, k))
        ax.annotate(r["name"], (x, y), textcoords="offset points", xytext=(5, 4 - 10 * k), fontsize=8)
    fr = sorted((x, y) for r, x, y in pts if r["name"] in front_names)
    if fr:
        ax.step([p[0] for p in fr], [p[1] for p in fr], where="post", c="tab:red", lw=1.2, label="Pareto front")
    ref = [r for r in rows if r.get("reference") and r.get("status") == "ok" and r.get(grid.pareto_time)]
    if ref:
        ax.axvline(ref[0][grid.pareto_time], ls=":", c="k",
                   label="reference case '%s' (error 0 by definition)" % ref[0]["name"])
    ax.set_xscale("log")
    ax.set_yscale("log")
    unit = dict(SIGNALS)[grid.pareto_metric.rsplit("_", 1)[0]]
    ax.set_xlabel("%s [s]" % grid.pareto_time.replace("_", " "))
    ax.set_ylabel("%s [%s] against the reference" % (grid.pareto_metric, unit))
    ax.set_title("Accuracy-cost map: %s" % grid.name)
    ax.grid(True, which="both", alpha=0.3)
    if fr or ref:
        ax.legend(loc="best", fontsize=8)
    fig.tight_layout()
    loading.save_figure(fig, path)


def report(grid, cases_dir, out_dir):
    """map.csv, map.md and pareto.png of the current results into out_dir; returns the rows."""
    os.makedirs(out_dir, exist_ok=True)
    rows = collect(grid, cases_dir)
    front = front_of(grid, rows)
    write_csv(rows, os.path.join(out_dir, "map.csv"))
    write_markdown(grid, rows, os.path.join(out_dir, "map.md"), front)
    plot_pareto(grid, rows, os.path.join(out_dir, "pareto.png"), front)
    return rows


# ------------------------------------------------------------------------------------------------- main

USAGE_EXIT = 2


def _write_failed(error, where):
    """An output that cannot be written (disk full, read-only): the running cases stopped, one line and the
    nodes' exit code 9; any other OSError is raised."""
    stop_all()
    return loading.exit_write_failed("railsim_map", error, where)


def main(argv=None):
    import argparse
    ap = argparse.ArgumentParser(prog="railsim_map", description="Accuracy-cost map of a scene over a grid of "
                                 "settings (see rail_analysis.costmap and config/maps/).")
    ap.add_argument("grid", help="grid file (YAML)")
    ap.add_argument("--out", help="output directory for map.csv, map.md, pareto.png (default output/maps/<name> "
                    "under the current directory)")
    ap.add_argument("--cases", help="directory of the case directories (default OUT/cases)")
    ap.add_argument("--jobs", type=int, default=os.cpu_count() or 1, help="cases run at once (default: cores)")
    ap.add_argument("--scheduler", help="Dask scheduler address (tcp://host:port): run the cases on its workers")
    ap.add_argument("--workspace", help="built workspace the runs use, as seen by the workers (default: the "
                    "grid's workspace, else this tool's own)")
    ap.add_argument("--only", action="append", metavar="CASE", help="run only this case (name or id, shell "
                    "pattern; repeatable); the reference too when it has no current result")
    ap.add_argument("--report-only", action="store_true", help="run nothing, rewrite the table and plot")
    ap.add_argument("--timeout", type=float, help="wall seconds per case (default: the grid's, else %g)"
                    % DEFAULT_TIMEOUT)
    a = ap.parse_args(argv)
    try:
        if a.jobs < 1:
            raise GridError("--jobs: must be >= 1, got %d" % a.jobs)
        grid = Grid(a.grid, workspace=a.workspace)
        if a.timeout is not None:
            if not a.timeout > 0:
                raise GridError("--timeout: must be > 0, got %g" % a.timeout)
            grid.timeout = a.timeout
        if a.only and not grid.select(a.only):
            raise GridError("--only %s: no case of %s matches (cases: %s)"
                            % (" ".join(a.only), a.grid, ", ".join(c.name for c in grid.cases)))
    except GridError as e:
        print("railsim_map: %s" % e, file=sys.stderr)
        return USAGE_EXIT
    out = os.path.abspath(a.out or os.path.join("output", "maps", grid.name))
    cases_dir = os.path.abspath(a.cases or os.path.join(out, "cases"))
    print("map %s: %d case(s) (%s), reference %s; cases in %s" % (grid.name, len(grid.cases), grid.mode,
                                                                  grid.reference.name, cases_dir), flush=True)

    def on_signal(signum, frame):
        raise KeyboardInterrupt()
    signal.signal(signal.SIGTERM, on_signal)
    try:
        if not a.report_only:
            sweep(grid, cases_dir, jobs=a.jobs, scheduler=a.scheduler, only=a.only,
                  progress=lambda s: print(s, flush=True))
        else:
            mx = _Metrics(grid, cases_dir)
            mx.load_reference()
            for c in grid.cases:
                _refresh_metrics(grid, c, mx, cases_dir)
    except KeyboardInterrupt:
        stop_all()
        print("railsim_map: interrupted; finished cases keep their result.yaml, a rerun resumes", file=sys.stderr)
        return 130
    except OSError as e:
        return _write_failed(e, cases_dir)
    try:
        rows = report(grid, cases_dir, out)
    except OSError as e:
        return _write_failed(e, out)
    ok = sum(1 for r in rows if r.get("status") == "ok")
    print("map: %d case(s) ok, %d failed, %d without a result; table %s" % (
        ok, len(rows) - ok, len(grid.cases) - len(rows), os.path.join(out, "map.md")), flush=True)
    # The sweep's exit code tells whether every case finished: the worst code of a failed case's nodes.
    codes = [r.get("exit_code") if isinstance(r.get("exit_code"), int) and r.get("exit_code") > 0 else 1
             for r in rows if r.get("status") != "ok"]
    return min(max(codes), 255) if codes else 0
