#!/usr/bin/env python3
"""Fuzz test of railsim's inputs: scenes, the vehicle and track data files and the profile files.

Each case is a copy of the shipped input tree (config/ and test/scenes, test/data) with ONE mutation of one
file: a deleted key, a value of the wrong type (a string for a number, a map for a list, a list for a
scalar), an extreme value (0, -1, 1e300, -1e300, 1e-300), a non-finite value (.nan, .inf, -.inf), a
changed profile coordinate, a truncation at a random byte, or random bytes replacing, inserted into or
added as a line of the file. The cases are drawn from a fixed seed, so every run writes the same cases.
railsim_check_inputs (test/src/check_inputs_main.cpp) loads each case's scene, builds what a run of it
builds and advances it a few steps (20 Newmark steps, 2 ms of vehicle time: the checker cuts every run
short, whatever the scene's solver.end says). A case passes when the checker
  - exits 0 ("ok: ...", no nan or inf in the summary) or 1 ("error: ..."), never by a signal, never with
    2 (a non-finite result), 3 (a failed run) or after the time limit (a hang);
  - on 1, names the mutated file's base name and, for a key mutation, the key (for a coordinate mutation of a
    profile file, the line: the changed line or the next, where a coordinate out of order is found).
Also: a replay bag that is truncated or has no /wheel_states is refused by the track node (~replay_bag),
which is run under a private ROS master when the node and roscore are found.

  /usr/bin/python3 test_fuzz_inputs.py --checker PATH [--track-node PATH] [--gtest_output=xml:FILE]
  /usr/bin/python3 test_fuzz_inputs.py --checker PATH --case N [--keep DIR]   (rerun one case; prints it)
See test/doc/fuzz.md."""
import argparse
import collections
import concurrent.futures
import os
import random
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

import yaml

HERE = os.path.dirname(os.path.realpath(__file__))
sys.path.insert(0, HERE)
import rosunit_main  # noqa: E402  (this directory's shared test main)

TEST_DIR = os.path.dirname(HERE)                    # the railsim_tests package (repo/test)
REPO = os.path.dirname(TEST_DIR)
SEED = 20240611
# s per case: catches a hang, not slowness (the paper scene takes ~3.5 s alone; a truncated profile with many
# robust contact searches ~19 s alone, past 60 s inside a loaded suite)
TIMEOUT = 180.0
WORKERS = 2

# Input files (relative to the repository); copied into every case's tree with these relative paths.
TREE = ["config/scenes/moving_load.yaml", "config/scenes/paper_demo.yaml", "config/scenes/straight_short.yaml",
        "config/scenes/tight_curve.yaml", "test/scenes/paper_demo_60m.yaml", "test/scenes/vehicle_rigid_short.yaml",
        "test/data/moving_load_short.yaml", "config/vehicle/paper_coach.yaml", "config/track/paper_track.yaml",
        "config/profiles/S1002.prw", "config/profiles/S1002.txt", "config/profiles/UIC60_1in20.ban",
        "config/profiles/UIC60_1in20.prr"]
SCENES = TREE[:7]
VEHICLE = "config/vehicle/paper_coach.yaml"
TRACK = "config/track/paper_track.yaml"
# The scene a data/profile file is checked through (+ overrides that make it use the file).
HOST = "config/scenes/straight_short.yaml"   # vehicle, rigid_fe: vehicle, FE track and co-simulation track
PROFILE_USE = {  # the shipped rail files are tilted 1/20 already: no further inclination
    "config/profiles/UIC60_1in20.prr": ["track.rail_profile=../profiles/UIC60_1in20.prr", "track.rail_inclination=0"],
    "config/profiles/UIC60_1in20.ban": ["track.rail_profile=../profiles/UIC60_1in20.ban", "track.rail_inclination=0"],
    "config/profiles/S1002.prw": ["vehicle.wheel_profile=../profiles/S1002.prw"],
    "config/profiles/S1002.txt": ["vehicle.wheel_profile=../profiles/S1002.txt"],
}
# Key mutations per YAML file, text mutations per file (>= 500 cases in all). paper_demo builds a 500 m FE
# track (~3.5 s a case): fewer of its cases keep the test within ~4 minutes.
KEY_CASES = {"config/scenes/moving_load.yaml": 30, "config/scenes/paper_demo.yaml": 14,
             "config/scenes/straight_short.yaml": 34, "config/scenes/tight_curve.yaml": 34,
             "test/scenes/paper_demo_60m.yaml": 24, "test/scenes/vehicle_rigid_short.yaml": 34,
             "test/data/moving_load_short.yaml": 30, VEHICLE: 80, TRACK: 60}
TEXT_CASES = {f: 6 for f in SCENES}
TEXT_CASES.update({"config/scenes/paper_demo.yaml": 3, VEHICLE: 14, TRACK: 14})
TEXT_CASES.update({f: 14 for f in PROFILE_USE})
COORD_CASES = {f: 10 for f in PROFILE_USE}

EXTREMES = [0, -1.0, 1e300, -1e300, 1e-300]
NONFINITE = [float("nan"), float("inf"), float("-inf")]


class Case:
    def __init__(self, index, file, kind, detail, content, expect_key=None, expect_lines=None, alt_keys=()):
        self.index = index
        self.file = file              # the mutated file, relative to the tree
        self.kind = kind              # mutation kind (table column)
        self.detail = detail          # what exactly was changed (for the failure list)
        self.content = content        # the mutated file's bytes
        self.expect_key = expect_key  # key a refusal must name (key mutations)
        self.alt_keys = alt_keys      # keys that may be named instead (a name referenced elsewhere)
        self.expect_lines = expect_lines  # line numbers one of which a refusal must name (profile coordinates)
        self.scene = self.file if self.file in SCENES else HOST
        self.overrides = PROFILE_USE.get(self.file, [])
        self.outcome = None           # "ran" / "refused" / "FAIL"
        self.problem = ""             # why it failed
        self.output = ""              # the checker's stdout + stderr
        self.code = None
        self.seconds = 0.0

    def command(self, checker, root):
        cmd = [checker, os.path.join(root, self.scene)]
        for o in self.overrides:
            cmd += ["--set", o]
        return cmd

    def describe(self):
        return "case %d: %s: %s: %s" % (self.index, self.file, self.kind, self.detail)


# ---- YAML key mutations ----

def plain(node):
    """A copy of a loaded YAML document without shared (aliased) sub-objects."""
    if isinstance(node, dict):
        return {k: plain(v) for k, v in node.items()}
    if isinstance(node, list):
        return [plain(v) for v in node]
    return node


def walk(node, path=()):
    """(path, value) of every node below the root; a path is a tuple of map keys and list indices."""
    if isinstance(node, dict):
        for k, v in node.items():
            yield path + (k,), v
            yield from walk(v, path + (k,))
    elif isinstance(node, list):
        for i, v in enumerate(node):
            yield path + (i,), v
            yield from walk(v, path + (i,))


def path_text(path):
    out = ""
    for p in path:
        out += "[%d]" % p if isinstance(p, int) else ("." if out else "") + str(p)
    return out


def key_name(path):
    """The key a message should name: the last map key on the path."""
    for p in reversed(path):
        if not isinstance(p, int):
            return str(p)
    return None


def is_number(v):
    return isinstance(v, (int, float)) and not isinstance(v, bool)


def key_mutations(path, value):
    """Mutations that apply to the node at path: (kind, detail, new value or DELETE)."""
    out = []
    if not isinstance(path[-1], int):
        out.append(("deleted key", "deleted", DELETE))
    if is_number(value):
        out.append(("wrong type", "string for a number", "not_a_number"))
        out.append(("wrong type", "list for a scalar", [1.0, 2.0]))
        for x in EXTREMES:
            out.append(("extreme value", repr(x), x))
        for x in NONFINITE:
            out.append(("non-finite", repr(x), x))
    elif isinstance(value, list):
        out.append(("wrong type", "map for a list", {"x": 1.0}))
        out.append(("wrong type", "string for a list", "not_a_list"))
    elif isinstance(value, dict):
        out.append(("wrong type", "list for a map", [1.0, 2.0]))
        out.append(("wrong type", "string for a map", "not_a_map"))
    elif isinstance(value, (str, bool)):
        out.append(("wrong type", "list for a scalar", [1.0, 2.0]))
        out.append(("wrong type", "map for a scalar", {"x": 1.0}))
        out.append(("extreme value", "0", 0))
        out.append(("extreme value", "-1e300", -1e300))
    return out


DELETE = object()


def apply(doc, path, new):
    doc = plain(doc)
    parent = doc
    for p in path[:-1]:
        parent = parent[p]
    if new is DELETE:
        del parent[path[-1]]
    else:
        parent[path[-1]] = new
    return doc


# Keys whose value is a name referenced elsewhere: a refusal may name the referencing key instead.
REFERENCED = {"name": ("body", "body_i", "body_j", "load_points", "wheelsets", "joints", "forces", "bodies")}
# Keys whose default (when deleted) or value is checked through another key's range: a refusal may name
# that key. track.gauge bounds track.cant_reference_width (gauge .. gauge + 0.2 m).
DEPENDENT = {"gauge": ("cant_reference_width",)}


def alternatives(path):
    """Besides the key itself: the keys a refusal may name instead, and the enclosing list element (e.g.
    "track.segments[3]" for track.segments[3].cant_start: the chain checks of the segments name the segment)."""
    name = key_name(path)
    alt = REFERENCED.get(name, ()) + DEPENDENT.get(name, ())
    for i in range(len(path) - 1, 0, -1):
        if isinstance(path[i - 1], int) and not isinstance(path[i], int):
            alt += (path_text(path[:i]),)
            break
    return alt


def make_key_cases(rng, rel, count, start):
    with open(os.path.join(REPO, rel)) as f:
        doc = plain(yaml.safe_load(f))
    nodes = [(p, v) for p, v in walk(doc) if key_name(p) is not None]
    candidates = [(p, v, m) for p, v in nodes for m in key_mutations(p, v)]
    # Spread over the kinds first, then over the nodes: each kind gets its share of the count.
    by_kind = collections.defaultdict(list)
    for c in candidates:
        by_kind[c[2][0]].append(c)
    kinds = sorted(by_kind)
    cases = []
    for i in range(count):
        p, v, (kind, detail, new) = rng.choice(by_kind[kinds[i % len(kinds)]])
        mutated = apply(doc, p, new)
        text = "# %s with %s: %s\n" % (os.path.basename(rel), path_text(p), detail)
        text += yaml.safe_dump(mutated, default_flow_style=None, sort_keys=False, width=100)
        name = key_name(p)
        cases.append(Case(start + i, rel, kind, "%s: %s" % (path_text(p), detail), text.encode(),
                          expect_key=name, alt_keys=alternatives(p)))
    return cases


# ---- byte and line mutations ----

def garbage(rng, n):
    """n random bytes, no line break (so that line numbers stay those of the original)."""
    return bytes(rng.choice([b for b in range(256) if b not in (10, 13)]) for _ in range(n))


def make_text_cases(rng, rel, count, start):
    with open(os.path.join(REPO, rel), "rb") as f:
        data = f.read()
    lines = data.split(b"\n")
    kinds = ["truncation", "garbage replaced", "garbage inserted", "garbage line"]
    cases = []
    for i in range(count):
        kind = kinds[i % len(kinds)]
        if kind == "truncation":
            at = rng.randrange(1, len(data))
            content, detail = data[:at], "cut at byte %d of %d" % (at, len(data))
        elif kind == "garbage replaced":
            n, at = rng.randint(1, 16), rng.randrange(len(data))
            g = garbage(rng, n)
            content, detail = data[:at] + g + data[at + n:], "%d bytes at %d replaced by %s" % (n, at, g.hex())
        elif kind == "garbage inserted":
            n, at = rng.randint(1, 16), rng.randrange(len(data))
            g = garbage(rng, n)
            content, detail = data[:at] + g + data[at:], "%s inserted at byte %d" % (g.hex(), at)
        else:
            at = rng.randrange(len(lines))
            g = garbage(rng, rng.randint(4, 40))
            content = b"\n".join(lines[:at] + [g] + lines[at:])
            detail = "line of %s inserted as line %d" % (g.hex(), at + 1)
        cases.append(Case(start + i, rel, kind, detail, content))
    return cases


NUMBER = re.compile(rb"[-+]?(\d+\.?\d*|\.\d+)([eE][-+]?\d+)?")
COORDS = [b"abc", b"1e300", b"-1e300", b"nan", b"inf", b"0", b"1e-300", b""]


def make_coord_cases(rng, rel, count, start):
    """A profile point's coordinate replaced (text files: the refusal names the line)."""
    with open(os.path.join(REPO, rel), "rb") as f:
        lines = f.read().split(b"\n")
    point_lines = [i for i, ln in enumerate(lines)
                   if len(NUMBER.findall(ln)) >= 2 and re.fullmatch(rb"[\s0-9eE.+\-,\t]+", ln)]
    cases = []
    for i in range(count):
        at = rng.choice(point_lines)
        tokens = list(NUMBER.finditer(lines[at]))
        tok = rng.choice(tokens)
        new = COORDS[i % len(COORDS)]
        ln = lines[at][:tok.start()] + new + lines[at][tok.end():]
        content = b"\n".join(lines[:at] + [ln] + lines[at + 1:])
        cases.append(Case(start + i, rel, "coordinate", "line %d: %s -> %r" % (at + 1, tok.group().decode(), new.decode()),
                          content, expect_lines=(at + 1, at + 2)))
    return cases


def all_cases():
    rng = random.Random(SEED)
    cases = []
    for rel in TREE:
        if rel in KEY_CASES:
            cases += make_key_cases(rng, rel, KEY_CASES[rel], len(cases))
        if rel in COORD_CASES:
            cases += make_coord_cases(rng, rel, COORD_CASES[rel], len(cases))
        cases += make_text_cases(rng, rel, TEXT_CASES[rel], len(cases))
    return cases


# ---- running and judging ----

def write_tree(root, case=None):
    for rel in TREE:
        dst = os.path.join(root, rel)
        os.makedirs(os.path.dirname(dst), exist_ok=True)
        if case is not None and rel == case.file:
            with open(dst, "wb") as f:
                f.write(case.content)
        else:
            shutil.copyfile(os.path.join(REPO, rel), dst)


def judge(case):
    """Sets case.outcome and case.problem from case.code and case.output."""
    base = os.path.basename(case.file)
    if case.code is None:
        case.outcome, case.problem = "FAIL", "hang: no exit within %.0f s" % TIMEOUT
    elif case.code < 0:
        case.outcome, case.problem = "FAIL", "crash: killed by signal %d (%s)" % (
            -case.code, signal.Signals(-case.code).name if -case.code in signal.Signals._value2member_map_ else "?")
    elif case.code == 0:
        ok = [ln for ln in case.output.splitlines() if ln.startswith("ok: ")]
        if not ok:
            case.outcome, case.problem = "FAIL", "exit 0 without an 'ok:' line"
        elif re.search(r"\b(nan|inf)\b", ok[-1], re.IGNORECASE):
            case.outcome, case.problem = "FAIL", "non-finite value in the summary"
        else:
            case.outcome = "ran"
    elif case.code == 1:
        errors = [ln for ln in case.output.splitlines() if ln.startswith("error: ")]
        msg = errors[-1] if errors else ""
        case.outcome = "refused"
        if not msg:
            case.outcome, case.problem = "FAIL", "exit 1 without an 'error:' line"
        elif base not in msg:
            case.outcome, case.problem = "FAIL", "the message does not name the file %s" % base
        elif case.expect_key is not None and not any(
                re.search(r"(^|[^A-Za-z0-9_])%s([^A-Za-z0-9_]|$)" % re.escape(k), msg)
                for k in (case.expect_key,) + tuple(case.alt_keys)):
            case.outcome, case.problem = "FAIL", "the message does not name the key %s" % case.expect_key
        elif case.expect_lines is not None and not any(
                re.search(r"%s:%d\b" % (re.escape(base), n), msg) for n in case.expect_lines):
            case.outcome, case.problem = "FAIL", "the message does not name line %s" % " or ".join(
                str(n) for n in case.expect_lines)
    else:
        what = {2: "non-finite result", 3: "run failed on an accepted input"}.get(case.code, "unexpected exit code")
        case.outcome, case.problem = "FAIL", "%s (exit %d)" % (what, case.code)


def run_case(case, checker, work, keep=False):
    root = os.path.join(work, "case_%04d" % case.index)
    write_tree(root, case)
    t0 = time.time()
    try:
        p = subprocess.run(case.command(checker, root), stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                           timeout=TIMEOUT)
        case.code, case.output = p.returncode, p.stdout.decode("utf-8", "replace")
    except subprocess.TimeoutExpired as e:
        case.code, case.output = None, (e.output or b"").decode("utf-8", "replace")
    case.seconds = time.time() - t0
    judge(case)
    if case.outcome != "FAIL" and not keep:
        shutil.rmtree(root, ignore_errors=True)
    return case


def table(cases):
    kinds = sorted({c.kind for c in cases})
    files = [f for f in TREE if any(c.file == f for c in cases)]
    w = max(len(f) for f in files)
    head = "%-*s" % (w, "file") + "".join(" | %-22s" % k for k in kinds) + " | total"
    lines = [head, "-" * len(head)]
    for f in files:
        row = "%-*s" % (w, f)
        for k in kinds:
            cs = [c for c in cases if c.file == f and c.kind == k]
            cell = "%d ran / %d refused" % (sum(c.outcome == "ran" for c in cs), sum(c.outcome == "refused" for c in cs))
            nf = sum(c.outcome == "FAIL" for c in cs)
            if nf:
                cell += " / %d FAIL" % nf
            row += " | %-22s" % (cell if cs else "")
        row += " | %d" % sum(c.file == f for c in cases)
        lines.append(row)
    return "\n".join(lines)


ARGS = None  # parsed command line (checker, track node)


class FuzzInputs(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.work = tempfile.mkdtemp(prefix="railsim_fuzz_")
        cls.cases = all_cases()
        t0 = time.time()
        # The shipped inputs themselves (no mutation) must run.
        cls.baseline = []
        for i, rel in enumerate(SCENES + list(PROFILE_USE)):
            c = Case(-1 - i, rel, "none", "unchanged", open(os.path.join(REPO, rel), "rb").read())
            cls.baseline.append(c)
        with concurrent.futures.ThreadPoolExecutor(WORKERS) as pool:
            list(pool.map(lambda c: run_case(c, ARGS.checker, cls.work), cls.baseline + cls.cases))
        cls.wall = time.time() - t0
        print("\n%d cases in %.0f s (%d workers, checker %s); work directory %s" % (
            len(cls.cases), cls.wall, WORKERS, ARGS.checker, cls.work))
        print(table(cls.cases))
        failed = [c for c in cls.baseline + cls.cases if c.outcome == "FAIL"]
        for c in failed:
            print("FAIL %s\n     %s\n     rerun: %s %s --checker %s --case %d\n     output: %s" % (
                c.describe(), c.problem, sys.executable, os.path.realpath(__file__), ARGS.checker, c.index,
                c.output.strip().replace("\n", "\n             ")[-600:]))
        slow = sorted(cls.cases, key=lambda c: -c.seconds)[:3]
        print("slowest cases: " + ", ".join("%d (%.1f s)" % (c.index, c.seconds) for c in slow))

    @classmethod
    def tearDownClass(cls):
        if not any(c.outcome == "FAIL" for c in cls.baseline + cls.cases):
            shutil.rmtree(cls.work, ignore_errors=True)

    def failures(self, cases, pred):
        bad = [c for c in cases if pred(c)]
        return "\n".join("%s -> %s" % (c.describe(), c.problem) for c in bad)

    def test_at_least_500_cases_of_every_kind_and_file(self):
        self.assertGreaterEqual(len(self.cases), 500)
        for rel in TREE:
            self.assertTrue(any(c.file == rel for c in self.cases), rel)
        self.assertEqual(len({c.index for c in self.cases}), len(self.cases))

    def test_shipped_inputs_run(self):
        msg = self.failures(self.baseline, lambda c: c.outcome != "ran")
        if msg:
            self.fail("shipped inputs that do not run:\n" + msg)

    def test_no_crash_hang_nonfinite_or_failed_run(self):
        msg = self.failures(self.cases, lambda c: c.code not in (0, 1) or (c.code == 0 and c.outcome == "FAIL"))
        if msg:
            self.fail("cases that crashed, hung, produced NaN or failed their run:\n" + msg)

    def test_refusals_name_the_file_and_key_or_line(self):
        msg = self.failures(self.cases, lambda c: c.code == 1 and c.outcome == "FAIL")
        if msg:
            self.fail("refusals that do not name the file and key / line:\n" + msg)

    def test_both_outcomes_occur(self):
        # A fuzz test whose every case is refused (or runs) would test the mutation, not the loaders.
        self.assertGreater(sum(c.outcome == "ran" for c in self.cases), 50)
        self.assertGreater(sum(c.outcome == "refused" for c in self.cases), 200)


# ---- bad replay bags (track node, ~replay_bag) ----

REPLAY_SCENE = os.path.join(TEST_DIR, "scenes", "vehicle_rigid_short.yaml")
EXIT_BAD_INPUT = 2  # rail_core/exit_codes.hpp kExitBadInput


def free_port():
    s = socket.socket()
    s.bind(("127.0.0.1", 0))
    port = s.getsockname()[1]
    s.close()
    return port


class BadReplayBag(unittest.TestCase):
    """The track node refuses a replay bag that is truncated or has no /wheel_states, naming the bag."""

    @classmethod
    def setUpClass(cls):
        cls.skip = None
        node = ARGS.track_node or shutil.which("track_node") or os.path.join(
            REPO, "devel", "lib", "rail_track_node", "track_node")
        if not os.path.exists(node) or shutil.which("roscore") is None:
            cls.skip = "track_node (%s) or roscore not found" % node
            return
        try:
            import rosbag  # noqa: F401
            import rospy  # noqa: F401
            from rail_msgs.msg import WheelStates  # noqa: F401
        except ImportError as e:
            cls.skip = "ROS Python packages not found: %s" % e
            return
        cls.node = node
        cls.work = tempfile.mkdtemp(prefix="railsim_fuzz_bag_")
        cls.env = dict(os.environ)
        cls.env["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % free_port()
        cls.env["ROS_IP"] = "127.0.0.1"
        cls.env["ROS_HOME"] = os.path.join(cls.work, "ros_home")
        port = int(cls.env["ROS_MASTER_URI"].rsplit(":", 1)[1])
        cls.master = subprocess.Popen(["roscore", "-p", str(port)], env=cls.env, stdout=subprocess.DEVNULL,
                                      stderr=subprocess.DEVNULL, start_new_session=True)
        for _ in range(100):
            if subprocess.run(["rosparam", "list"], env=cls.env, stdout=subprocess.DEVNULL,
                              stderr=subprocess.DEVNULL).returncode == 0:
                break
            time.sleep(0.2)
        with open(REPLAY_SCENE) as f:
            text = f.read()
        track_data = os.path.join(REPO, TRACK)
        overrides = "effects.track_model=rigid_fe track.data=%s" % track_data
        import xmlrpc.client  # strings as they are (rosparam set would parse the scene text as YAML)
        master = xmlrpc.client.ServerProxy(cls.env["ROS_MASTER_URI"])
        for k, v in (("scene_yaml", text), ("scene_file", REPLAY_SCENE), ("scene_overrides", overrides)):
            master.setParam("/test_fuzz_inputs", "/fuzz/" + k, v)
        cls.good = os.path.join(cls.work, "good.bag")
        cls.write_wheel_states(cls.good, 50)

    @classmethod
    def tearDownClass(cls):
        if getattr(cls, "master", None) is not None:
            os.killpg(cls.master.pid, signal.SIGINT)
            try:
                cls.master.wait(timeout=20)
            except subprocess.TimeoutExpired:
                os.killpg(cls.master.pid, signal.SIGKILL)
                cls.master.wait()
        if getattr(cls, "work", None):
            shutil.rmtree(cls.work, ignore_errors=True)

    @staticmethod
    def write_wheel_states(path, n):
        import rosbag
        import rospy
        from rail_msgs.msg import WheelState, WheelStates
        with rosbag.Bag(path, "w") as bag:
            for k in range(n):
                m = WheelStates()
                m.header.stamp = rospy.Time.from_sec(max(k * 1e-3, 1e-9))
                for i in range(8):
                    w = WheelState(wheel_id=i, wheelset=i // 2, side=i % 2, arc_length=25.0 - 2.7 * (i // 2))
                    w.orientation.w = 1.0
                    m.wheels.append(w)
                bag.write("/wheel_states", m, m.header.stamp)

    def run_node(self, bag):
        p = subprocess.run([self.node, "__name:=fuzz_replayer", "_scene_ns:=/fuzz", "_replay_bag:=" + bag,
                            "_output_dir:=" + self.work], env=self.env, stdout=subprocess.PIPE,
                           stderr=subprocess.STDOUT, timeout=120)
        return p.returncode, p.stdout.decode("utf-8", "replace")

    def setUp(self):
        if self.skip:
            self.skipTest(self.skip)

    def test_truncated_bags_are_refused(self):
        size = os.path.getsize(self.good)
        for frac in (0.1, 0.5, 0.9):
            bad = os.path.join(self.work, "truncated_%02d.bag" % int(frac * 100))
            with open(self.good, "rb") as f:
                data = f.read()[:int(frac * size)]
            with open(bad, "wb") as f:
                f.write(data)
            code, out = self.run_node(bad)
            self.assertEqual(code, EXIT_BAD_INPUT, "%s: exit %d\n%s" % (bad, code, out))
            self.assertIn(os.path.basename(bad), out)

    def test_a_bag_without_wheel_states_is_refused(self):
        import rosbag
        import rospy
        from std_msgs.msg import String
        bad = os.path.join(self.work, "no_wheel_states.bag")
        with rosbag.Bag(bad, "w") as bag:
            bag.write("/other", String(data="x"), rospy.Time(1))
        code, out = self.run_node(bad)
        self.assertEqual(code, EXIT_BAD_INPUT, out)
        self.assertIn(bad + ": no /wheel_states in the bag", out)


def main():
    global ARGS
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--checker", required=True, help="railsim_check_inputs executable")
    parser.add_argument("--track-node", help="track_node executable (bad replay bags; default: devel)")
    parser.add_argument("--case", type=int, help="rerun this case only and print it")
    parser.add_argument("--keep", help="with --case: write the case's tree here and keep it")
    ARGS, rest = parser.parse_known_args()
    ARGS.checker = os.path.realpath(ARGS.checker)
    if ARGS.case is not None:
        case = {c.index: c for c in all_cases()}[ARGS.case]
        work = ARGS.keep or tempfile.mkdtemp(prefix="railsim_fuzz_case_")
        run_case(case, ARGS.checker, work, keep=True)
        root = os.path.join(work, "case_%04d" % case.index)
        print("%s\ncommand: %s\nexit: %s\n%s\noutcome: %s %s" % (
            case.describe(), " ".join(case.command(ARGS.checker, root)), case.code, case.output.strip(),
            case.outcome, case.problem))
        return 0 if case.outcome != "FAIL" else 1
    sys.argv = [sys.argv[0]] + rest
    suite = unittest.TestSuite()
    only = [a for a in rest if a in ("FuzzInputs", "BadReplayBag")]  # run one class: its name
    for cls in (FuzzInputs, BadReplayBag):
        if not only or cls.__name__ in only:
            suite.addTests(unittest.defaultTestLoader.loadTestsFromTestCase(cls))
    return rosunit_main.run(suite, "test_fuzz_inputs", rest)  # both classes in one XML file


if __name__ == "__main__":
    sys.exit(main())
