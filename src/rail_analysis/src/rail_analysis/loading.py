"""Loading of railsim run outputs into numpy arrays.

A run directory holds, per run name (standalone, rigid_fe, flexible):
  <run>.bag         the vehicle node's bag (/wheelset_kinematics, /wheel_states, /contact_wrenches, ...;
                    /contact_points too when the vehicle runs alone)
  <run>.track.bag   the track node's bag in a co-simulation (/contact_points, /rail_deflection)
  <run>.run.yaml    the runner's summary (wall_time, simulated_time, exit_code, ...)
  <run>.scene.yaml  the fully resolved scene

Times are the messages' header stamps (simulated time, s). Lengths in m, forces in N, angles in rad.
Every loader returns plain numpy arrays; a bag without the topic asked for raises MissingTopicError.
"""
import contextlib
import errno
import os
import sys

import numpy as np
import yaml

RUN_NAMES = ("standalone", "rigid_fe", "flexible")

# rail_msgs/ContactPoint.kind and WheelState.side values.
KIND_TREAD = 0
KIND_FLANGE = 1
SIDE_LEFT = 0
SIDE_RIGHT = 1

# Flange contact, as the report counts it: an active contact whose normal leans more than this toward the
# track centre (ContactPoint.contact_angle, to the wheelset's axle): the flange root and the flank, whichever
# of the wheel's two surfaces reported the point. The limit sits in the gap between the tread and the
# flange root: a new S1002 on UIC60 touches its tread below 0.15 rad (0.05 rad in the paper's runs) and its
# flange root from about 0.28 rad up to the flank's 1.22 rad (70 deg). Bags recorded before the message
# carried the angle fall back on the reporting surface (ContactPoint.kind).
FLANGE_CONTACT_ANGLE = 0.20  # rad (11 deg)
FLANGE_CONTACT_DEFINITION = ("flange contact: a contact whose normal leans more than %.2f rad (%.0f deg) toward "
                             "the track centre (flange root and flank)" % (FLANGE_CONTACT_ANGLE,
                                                                           np.degrees(FLANGE_CONTACT_ANGLE)))


def flange_contact_mask(points):
    """(N, P) bool: the active contacts that are flange contacts (FLANGE_CONTACT_ANGLE), or, for a bag
    without contact angles, those the flange surface reported."""
    angle = points.get("contact_angle")
    if angle is not None and np.isfinite(angle).any():
        return points["active"] & (angle >= FLANGE_CONTACT_ANGLE)
    return points["active"] & (points["kind"] == KIND_FLANGE)


# Exit code of an analysis tool whose output could not be written (disk full, read-only): the nodes' code 9.
EXIT_WRITE_FAILED = 9
_WRITE_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG)


@contextlib.contextmanager
def writing(path):
    """Names `path` in an OSError raised while writing it (a write that fails after the open carries no
    file name)."""
    try:
        yield
    except OSError as e:
        if e.filename is None:
            e.filename = path
        raise


def save_figure(fig, path):
    """Writes a matplotlib figure to path (110 dpi) and closes it, naming path in a write error."""
    import matplotlib.pyplot as plt
    try:
        with writing(path):
            fig.savefig(path, dpi=110)
    finally:
        plt.close(fig)


def exit_write_failed(prog, error, where):
    """For an OSError that means an output cannot be written: its one line on stderr (write_failure) and
    EXIT_WRITE_FAILED to return; any other error is raised again."""
    msg = write_failure(error, where)
    if msg is None:
        raise error
    sys.stderr.write("%s: %s\n" % (prog, msg))
    return EXIT_WRITE_FAILED


def write_failure(error, where):
    """One line for an OSError that means an output cannot be written (disk full, quota, read-only file
    system, file too large), naming the file (else `where`) and the system's reason, after removing the
    partial file; None for any other error (the caller re-raises)."""
    if not isinstance(error, OSError) or error.errno not in _WRITE_ERRNOS:
        return None
    name = error.filename or where
    if error.filename and os.path.isfile(error.filename):
        try:
            os.remove(error.filename)
            name += " (partial file removed)"
        except OSError:
            pass
    return "cannot write %s: %s" % (name, error.strerror or os.strerror(error.errno))


class AnalysisInputError(RuntimeError):
    """A run's files cannot be used (missing, malformed, or a bag without a needed topic)."""


class MissingTopicError(AnalysisInputError):
    """A bag lacks a topic the analysis needs. Attributes: bag (path), topic."""

    def __init__(self, bag, topic, purpose=""):
        self.bag = bag
        self.topic = topic
        msg = "%s: topic %s not in the bag" % (bag, topic)
        if purpose:
            msg += " (needed for %s)" % purpose
        super().__init__(msg)


def _open_bag(path):
    import rosbag  # imported here so that the pure-numpy parts work without ROS
    if not os.path.isfile(path):
        raise AnalysisInputError("%s: no such bag" % path)
    try:
        return rosbag.Bag(path)
    except Exception as e:  # rosbag raises several exception types for unreadable files
        raise AnalysisInputError("%s: not a readable bag: %s" % (path, e))


def bag_topics(path):
    """The set of topics recorded in a bag (with at least one message)."""
    with _open_bag(path) as bag:
        info = bag.get_type_and_topic_info()
        return {t for t, i in info.topics.items() if i.message_count > 0}


def _messages(path, topic, purpose):
    """The messages of one topic in bag order; raises MissingTopicError when the bag has none."""
    with _open_bag(path) as bag:
        info = bag.get_type_and_topic_info()
        if topic not in info.topics or info.topics[topic].message_count == 0:
            raise MissingTopicError(path, topic, purpose)
        msgs = [m for _, m, _ in bag.read_messages(topics=[topic])]
    return msgs


def load_wheelset_kinematics(path):
    """The /wheelset_kinematics topic of a bag (rail_msgs/WheelsetKinematics), sorted by time.

    Returns a dict of arrays, N samples by W wheelsets (index 0 = leading):
      t [s] (N,), arc_length [m], lateral [m] (y, left > 0), vertical [m] (z, up > 0),
      angle_of_attack [rad] (> 0 turning left), roll [rad], spin_speed [rad/s]  (N, W);
      left_force, right_force [N] (N, W, 3): total contact force on the left/right wheel in track-frame
      components (x along the track, y left, z up), or None when the bag's messages lack the fields
      left_force_in_track / right_force_in_track.
    """
    msgs = _messages(path, "/wheelset_kinematics", "the wheelset motion")
    n = len(msgs)
    w = max(len(m.wheelsets) for m in msgs)
    t = np.array([m.header.stamp.to_sec() for m in msgs])
    out = {"t": t}
    for key, field in (("arc_length", "arc_length"), ("lateral", "lateral_displacement"),
                       ("vertical", "vertical_displacement"), ("angle_of_attack", "angle_of_attack"),
                       ("roll", "roll"), ("spin_speed", "spin_speed")):
        a = np.full((n, w), np.nan)
        for i, m in enumerate(msgs):
            for ws in m.wheelsets:
                a[i, ws.wheelset] = getattr(ws, field)
        out[key] = a
    has_forces = all(hasattr(ws, "left_force_in_track") and hasattr(ws, "right_force_in_track")
                     for m in msgs[:1] for ws in m.wheelsets)
    for side in ("left", "right"):
        if not has_forces:
            out[side + "_force"] = None
            continue
        f = np.full((n, w, 3), np.nan)
        for i, m in enumerate(msgs):
            for ws in m.wheelsets:
                v = getattr(ws, side + "_force_in_track")
                f[i, ws.wheelset] = (v.x, v.y, v.z)
        out[side + "_force"] = f
    order = np.argsort(t, kind="stable")
    for k, v in out.items():
        if v is not None:
            out[k] = v[order]
    return out


def load_contact_points(path, purpose="the flange contact forces"):
    """The /contact_points topic of a bag (rail_msgs/ContactPoints), sorted by time; purpose names what needs
    it in the message of a bag without the topic.

    Returns a dict: t [s] (N,); per point slot (N, P) arrays wheel_id, side, kind (KIND_TREAD/KIND_FLANGE),
    active (bool), normal_force [N], creep_force_longitudinal [N], creep_force_lateral [N], creepage_longitudinal,
    creepage_lateral [-], creepage_spin [1/m], arc_length [m], penetration [m], contact_angle [rad] (NaN in
    bags recorded before the message carried it).
    Messages with fewer than P points are padded with inactive slots (wheel_id -1, forces 0).
    """
    msgs = _messages(path, "/contact_points", purpose)
    n = len(msgs)
    p = max(len(m.points) for m in msgs)
    t = np.array([m.header.stamp.to_sec() for m in msgs])
    out = {"t": t}
    ints = {"wheel_id": -1, "side": -1, "kind": -1}
    floats = ("normal_force", "creep_force_longitudinal", "creep_force_lateral", "creepage_longitudinal",
              "creepage_lateral", "creepage_spin", "arc_length", "penetration")
    for k, fill in ints.items():
        out[k] = np.full((n, p), fill, dtype=int)
    for k in floats:
        out[k] = np.zeros((n, p))
    out["contact_angle"] = np.full((n, p), np.nan)  # NaN: recorded before the message carried it
    out["active"] = np.zeros((n, p), dtype=bool)
    for i, m in enumerate(msgs):
        for j, c in enumerate(m.points):
            out["wheel_id"][i, j] = c.wheel_id
            out["side"][i, j] = c.side
            out["kind"][i, j] = c.kind
            out["active"][i, j] = c.active
            for k in floats:
                out[k][i, j] = getattr(c, k)
            out["contact_angle"][i, j] = getattr(c, "contact_angle", np.nan)
    order = np.argsort(t, kind="stable")
    return {k: v[order] for k, v in out.items()}


def flange_normal_force(points, wheel_id):
    """Sum of the normal forces [N] of the flange contacts (flange_contact_mask) of one wheel, per sample (N,)."""
    sel = flange_contact_mask(points) & (points["wheel_id"] == wheel_id)
    return np.where(sel, points["normal_force"], 0.0).sum(axis=1)


def load_rail_deflection(path):
    """The /rail_deflection topic of a bag (rail_msgs/RailDeflection, one message per section and instant).

    Returns {section arc length [m] (float, as recorded): dict} with, per section, arrays sorted by time:
      t [s] (N,), left, right [m] (N, 3): rail displacement in the section's track frame
      (x along, y left, z up), left_rotation, right_rotation [rad] (N, 3).
    """
    msgs = _messages(path, "/rail_deflection", "the rail displacements")
    by_section = {}
    for m in msgs:
        by_section.setdefault(round(m.arc_length, 6), []).append(m)
    out = {}
    for s, ms in sorted(by_section.items()):
        t = np.array([m.header.stamp.to_sec() for m in ms])
        order = np.argsort(t, kind="stable")
        d = {"t": t[order]}
        for key, field in (("left", "left_displacement"), ("right", "right_displacement"),
                           ("left_rotation", "left_rotation"), ("right_rotation", "right_rotation")):
            a = np.array([[getattr(m, field).x, getattr(m, field).y, getattr(m, field).z] for m in ms])
            d[key] = a[order]
        out[s] = d
    return out


def load_contact_wrenches(path):
    """The /contact_wrenches topic (rail_msgs/ContactWrenches): t [s] (N,), wheel_id (W,),
    force [N] and moment [N m] (N, W, 3) at the wheel centres, world frame; sorted by time."""
    msgs = _messages(path, "/contact_wrenches", "the wheel-centre wrenches")
    ids = sorted({w.wheel_id for m in msgs for w in m.wrenches})
    col = {wid: k for k, wid in enumerate(ids)}
    n = len(msgs)
    force = np.full((n, len(ids), 3), np.nan)
    moment = np.full((n, len(ids), 3), np.nan)
    for i, m in enumerate(msgs):
        for w in m.wrenches:
            force[i, col[w.wheel_id]] = (w.force.x, w.force.y, w.force.z)
            moment[i, col[w.wheel_id]] = (w.moment.x, w.moment.y, w.moment.z)
    t = np.array([m.header.stamp.to_sec() for m in msgs])
    order = np.argsort(t, kind="stable")
    return {"t": t[order], "wheel_id": np.array(ids), "force": force[order], "moment": moment[order]}


def read_yaml(path, loader=yaml.SafeLoader, error=None):
    """The YAML document of a file, read with loader. An unreadable file or invalid YAML raises error (an
    exception class, AnalysisInputError by default) with the file, the line and the reason."""
    error = error or AnalysisInputError
    try:
        with open(path) as f:
            return yaml.load(f, Loader=loader)
    except OSError as e:
        raise error("%s: cannot read: %s" % (path, e.strerror))
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = ":%d" % (mark.line + 1) if mark is not None else ""
        raise error("%s%s: not valid YAML: %s" % (path, where, getattr(e, "problem", e)))


def load_yaml(path, required=()):
    """A YAML mapping from a file; required: keys that must be present. Raises AnalysisInputError."""
    data = read_yaml(path)
    if not isinstance(data, dict):
        raise AnalysisInputError("%s: expected a mapping at the top level, got %s" % (path, type(data).__name__))
    for k in required:
        if k not in data:
            raise AnalysisInputError("%s: missing key '%s'" % (path, k))
    return data


class Scene(object):
    """What the analysis needs from a resolved scene: speed [m/s], sleeper spacing [m], track segments as
    (type, s_start, s_end, direction) with arc lengths in m, the deflection sections [m]."""

    def __init__(self, data, path="scene"):
        def get(d, key, where):
            if not isinstance(d, dict) or key not in d:
                raise AnalysisInputError("%s: missing key '%s'" % (path, where + key))
            return d[key]

        def number(d, key, where):
            v = get(d, key, where)
            try:
                v = float(v)
            except (TypeError, ValueError):
                raise AnalysisInputError("%s: %s%s: not a number (%r)" % (path, where, key, v))
            if not np.isfinite(v):
                raise AnalysisInputError("%s: %s%s: not finite (%r)" % (path, where, key, v))
            return v

        track = get(data, "track", "")
        self.sleeper_spacing = number(track, "sleeper_spacing", "track.")
        if self.sleeper_spacing <= 0:
            raise AnalysisInputError("%s: track.sleeper_spacing: must be > 0, got %g" % (path, self.sleeper_spacing))
        s = number(track, "start_arc_length", "track.") if "start_arc_length" in track else 0.0
        self.segments = []
        segs = get(track, "segments", "track.")
        if not isinstance(segs, list) or not segs:
            raise AnalysisInputError("%s: track.segments: expected a non-empty list" % path)
        for i, seg in enumerate(segs):
            where = "track.segments[%d]." % i
            kind = str(get(seg, "type", where))
            length = number(seg, "length", where)
            if length <= 0:
                raise AnalysisInputError("%s: %slength: must be > 0, got %g" % (path, where, length))
            self.segments.append((kind, s, s + length, str(seg.get("direction", ""))))
            s += length
        vehicle = data.get("vehicle")
        self.speed = number(vehicle, "speed", "vehicle.") if isinstance(vehicle, dict) else float("nan")
        output = data.get("output") or {}
        self.deflection_sections = [float(x) for x in (output.get("deflection_sections") or [])]
        effects = data.get("effects") or {}
        self.track_model = str(effects.get("track_model", ""))

    def sleeper_frequency(self):
        """Sleeper-passing frequency [Hz]: speed / sleeper spacing."""
        return self.speed / self.sleeper_spacing

    def first_straight(self):
        """(s_start, s_end) [m] of the first segment when it is straight, else None."""
        kind, s0, s1, _ = self.segments[0]
        return (s0, s1) if kind == "straight" else None

    def curved_segments(self):
        """[(type, s_start, s_end, direction)] of the transitions and circular curves, in order."""
        return [seg for seg in self.segments if seg[0] in ("transition", "circular")]

    def curve_direction(self):
        """'left' or 'right': the direction of the first curved segment, or None without one."""
        for seg in self.curved_segments():
            if seg[3] in ("left", "right"):
                return seg[3]
        return None

    def segment_at(self, s):
        """The segment (type, s_start, s_end, direction) holding arc length s [m], or None."""
        for seg in self.segments:
            if seg[1] <= s < seg[2]:
                return seg
        return None


class Run(object):
    """One run's data as numpy arrays (see the loaders): name, kinematics, points (or None), deflection
    ({section: ...} or None), info (run.yaml mapping or {}), scene (Scene or None), notes ([str]) and the
    bag paths used."""

    def __init__(self, name):
        self.name = name
        self.kinematics = None
        self.points = None
        self.deflection = None
        self.info = {}
        self.scene = None
        self.notes = []
        self.bag = None
        self.track_bag = None


def run_present(directory, name):
    """True when the run's vehicle bag is in the directory."""
    return os.path.isfile(os.path.join(directory, name + ".bag"))


def load_run(directory, name):
    """Loads one run of a run directory. Needs <run>.bag with /wheelset_kinematics; the contact points
    from <run>.track.bag (co-simulation) or <run>.bag (standalone); /rail_deflection from the track bag of
    the flexible run. Raises MissingTopicError / AnalysisInputError naming the bag and the topic."""
    run = Run(name)
    run.bag = os.path.join(directory, name + ".bag")
    run.kinematics = load_wheelset_kinematics(run.bag)
    if run.kinematics["left_force"] is None:
        run.notes.append("%s: the wheel forces in the track frame (left_force_in_track, right_force_in_track) "
                         "are not recorded in /wheelset_kinematics" % os.path.basename(run.bag))
    track_bag = os.path.join(directory, name + ".track.bag")
    cosim = name != "standalone"
    if cosim and os.path.isfile(track_bag):
        run.track_bag = track_bag
        topics = bag_topics(track_bag)
        if "/contact_points" not in topics:
            raise MissingTopicError(track_bag, "/contact_points", "the flange contact forces")
        run.points = load_contact_points(track_bag)
        if "/rail_deflection" in topics:
            run.deflection = load_rail_deflection(track_bag)
        elif name == "flexible":
            raise MissingTopicError(track_bag, "/rail_deflection", "the rail displacements")
    else:
        # The vehicle alone records its contact points in its own bag.
        if "/contact_points" in bag_topics(run.bag):
            run.points = load_contact_points(run.bag)
        elif cosim:
            raise AnalysisInputError("%s: missing (needed for /contact_points of the co-simulation)" % track_bag)
        else:
            raise MissingTopicError(run.bag, "/contact_points", "the flange contact forces")
        if name == "flexible":
            raise AnalysisInputError("%s: missing (needed for /rail_deflection)" % track_bag)
    info_path = os.path.join(directory, name + ".run.yaml")
    if os.path.isfile(info_path):
        run.info = load_yaml(info_path)
    else:
        run.notes.append("%s.run.yaml: missing; wall and simulated times unknown" % name)
    scene_path = os.path.join(directory, name + ".scene.yaml")
    if os.path.isfile(scene_path):
        run.scene = Scene(load_yaml(scene_path, required=("track",)), scene_path)
    else:
        run.notes.append("%s.scene.yaml: missing" % name)
    return run
