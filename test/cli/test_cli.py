#!/usr/bin/python3
"""Black-box tests of the command line as a user meets it (issue 18, "Honest runs"): each case runs
./railsim (or roslaunch) as a user would and asserts the exit code, the message text and that nothing is
left behind: no process naming the case's directory or master port, no new /dev/shm region, every bag in
the case's output directory readable.

  /usr/bin/python3 test/cli/test_cli.py [--gtest_output=xml:FILE] [TestCli.test_name ...]

The workspace must be built (the tests run ./railsim with RAILSIM_NO_BUILD=1). Each case gets its own
directory, ROS_HOME and master port; runs are kept short (test/scenes, end times of 0.1-2 s)."""
import fcntl
import os
import re
import shutil
import signal
import socket
import subprocess
import sys
import tempfile
import time
import unittest

HERE = os.path.dirname(os.path.realpath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "test", "scripts"))
import rosunit_main  # noqa: E402

RAILSIM = os.path.join(ROOT, "railsim")
SHORT = os.path.join(ROOT, "test", "scenes", "vehicle_rigid_short.yaml")  # vehicle alone, 60 m, 0.5 s
COSIM = os.path.join(ROOT, "test", "scenes", "paper_demo_60m.yaml")       # flexible co-simulation, 100 m
CASE_TIMEOUT = 120.0


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def processes_naming(*needles):
    """(pid, cmdline) of this user's live processes whose command line contains one of needles."""
    out = []
    for d in os.listdir("/proc"):
        if not d.isdigit() or int(d) == os.getpid():
            continue
        try:
            with open("/proc/%s/cmdline" % d, "rb") as f:
                cmd = f.read().replace(b"\0", b" ").decode(errors="replace")
            with open("/proc/%s/stat" % d) as f:
                state = f.read().rsplit(")", 1)[1].split()[0]
        except OSError:
            continue
        if state != "Z" and any(n in cmd for n in needles):
            out.append((int(d), cmd))
    return out


def mapped_shm():
    """Names of the /dev/shm regions some live process maps (a run in progress, maybe another's)."""
    names = set()
    for d in os.listdir("/proc"):
        if not d.isdigit():
            continue
        try:
            with open("/proc/%s/maps" % d) as f:
                for line in f:
                    if "/dev/shm/" in line:
                        names.add(line.rsplit("/dev/shm/", 1)[1].split()[0])
        except OSError:
            continue
    return names


def leaked_shm(before):
    """railsim regions created since `before` that no process maps, still there 2 s later: left behind. (A
    region of a run going on beside the test is mapped by its nodes.)"""
    def unmapped():
        return {n for n in set(os.listdir("/dev/shm")) - before if "railsim" in n} - mapped_shm()
    first = unmapped()
    if first:
        time.sleep(2.0)
        return sorted(first & unmapped())
    return []


class TestCli(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="railsim_cli_")
        self.out = os.path.join(self.dir, "out")
        self.port = free_port()
        self.shm0 = set(os.listdir("/dev/shm"))
        self.env = dict(os.environ, RAILSIM_NO_BUILD="1", RAILSIM_MASTER_PORT=str(self.port),
                        ROS_HOME=os.path.join(self.dir, "ros_home"),
                        PATH="/usr/bin:/bin:" + os.environ.get("PATH", ""))

    def tearDown(self):
        # Nothing left behind: processes, shm regions, unreadable bags.
        deadline = time.monotonic() + 10.0
        left = processes_naming(self.dir, "-p %d " % self.port, ":%d" % self.port)
        while left and time.monotonic() < deadline:
            time.sleep(0.2)
            left = processes_naming(self.dir, "-p %d " % self.port, ":%d" % self.port)
        for pid, _ in left:
            try:
                os.kill(pid, signal.SIGKILL)
            except OSError:
                pass
        shm = leaked_shm(self.shm0)
        bags = []
        for base, _, files in os.walk(self.dir):
            bags += [os.path.join(base, f) for f in files if f.endswith(".bag")]
        unreadable = []
        for b in bags:
            p = subprocess.run(["/usr/bin/python3", "-c", "import rosbag, sys; rosbag.Bag(sys.argv[1]).close()", b],
                               capture_output=True, text=True, env=self.env)
            if p.returncode != 0:
                unreadable.append("%s: %s" % (b, p.stderr.strip().splitlines()[-1:]))
        shutil.rmtree(self.dir, ignore_errors=True)
        self.assertEqual(left, [], "processes left behind")
        self.assertEqual(shm, [], "/dev/shm regions left behind")
        self.assertEqual(unreadable, [], "unreadable bags")

    # -- helpers ---------------------------------------------------------------------------------------
    def railsim(self, *args, cwd=None, timeout=CASE_TIMEOUT):
        p = subprocess.run([RAILSIM] + list(args), capture_output=True, text=True, env=self.env, cwd=cwd or ROOT,
                           timeout=timeout)
        return p.returncode, p.stdout + p.stderr

    def start(self, *args):
        """./railsim in the background (its own session, as a terminal's job), output to a file."""
        self.log = os.path.join(self.dir, "console.log")
        f = open(self.log, "w")
        p = subprocess.Popen([RAILSIM] + list(args), stdout=f, stderr=subprocess.STDOUT, env=self.env, cwd=ROOT,
                             start_new_session=True)
        f.close()
        return p

    def wait_for(self, pattern, timeout=60.0, path=None):
        """Waits until pattern appears in the console (or in the file path)."""
        deadline = time.monotonic() + timeout
        while time.monotonic() < deadline:
            if os.path.isfile(path or self.log):
                with open(path or self.log) as f:
                    if re.search(pattern, f.read()):
                        return
            time.sleep(0.1)
        self.fail("'%s' did not appear in the console within %.0f s" % (pattern, timeout))

    def console(self):
        with open(self.log) as f:
            return f.read()

    def run_yaml(self, stem):
        import yaml
        with open(os.path.join(self.out, stem + ".run.yaml")) as f:
            return yaml.safe_load(f)

    def scene(self, name, text_from, *subs):
        """A copy of scene text_from in the case directory with the data paths made absolute and each
        (old, new) of subs replaced."""
        with open(text_from) as f:
            text = f.read().replace("../../config/", os.path.join(ROOT, "config") + "/")
        for old, new in subs:
            self.assertIn(old, text)
            text = text.replace(old, new, 1)
        path = os.path.join(self.dir, name)
        with open(path, "w") as f:
            f.write(text)
        return path

    def pid_of(self, exe):
        # A node names the case directory in its __log:= (ROS_HOME).
        found = [p for p, c in processes_naming(self.dir) if c.startswith(exe + " ")]
        self.assertTrue(found, "no process %s" % exe)
        return found[0]

    # -- options ---------------------------------------------------------------------------------------
    def test_help_of_every_subcommand(self):
        for args in (["--help"], ["run", "-h"], ["run", "--help"], ["run", SHORT, "-h"], ["validate", "-h"],
                     ["test", "-h"], ["setup", "--help"], ["hard-cases", "-h"], ["two-hosts", "-h"]):
            rc, text = self.railsim(*args)
            self.assertEqual(rc, 0, "%s: %s" % (args, text))
            self.assertIn("usage", text.lower(), args)

    def test_bootstrap_installs_packages_never_installed(self):
        # On a fresh machine dpkg-query exits 1 for packages it has never seen; the bootstrap (set -euo
        # pipefail) must still list them and hand them to apt-get, not stop silently.
        with open(RAILSIM) as f:
            text = f.read()
        body = re.search(r"^install_packages\(\) \{\n.*?^\}\n", text, re.S | re.M)
        self.assertIsNotNone(body, "install_packages() in ./railsim")
        script = ("set -euo pipefail\nPACKAGES=(bash railsim-no-such-package)\n"
                  "apt-get() { echo \"apt-get $*\"; }\nid() { echo 0; }\n" + body.group(0) + "install_packages\n")
        p = subprocess.run(["/bin/bash", "-c", script], capture_output=True, text=True, env=self.env, timeout=30)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        self.assertIn("installing Debian packages: railsim-no-such-package", p.stderr)
        self.assertIn("apt-get install -y -q railsim-no-such-package", p.stdout)
        self.assertNotIn(" bash", p.stdout.split("install", 1)[-1])

    def test_unknown_options_refused(self):
        for args, msg in ((["run", "--bogus"], "unknown option '--bogus'"),
                          (["run", SHORT, "--bogus"], "unknown argument '--bogus'"),
                          (["run", SHORT, "--set"], "--set needs key=value"),
                          (["validate", SHORT, "--bogus"], "unknown option '--bogus'"),
                          (["test", "extra"], "unknown argument 'extra'"),
                          (["frobnicate"], "unknown command 'frobnicate'")):
            rc, text = self.railsim(*args)
            self.assertEqual(rc, 1, "%s: %s" % (args, text))
            self.assertIn(msg, text, args)

    def test_set_obeyed_and_short_run_exits_0(self):
        rc, text = self.railsim("run", SHORT, "--set", "solver.end={time: 0.1}", "--out", self.out)
        self.assertEqual(rc, 0, text)
        self.assertIn("finished at t = 0.1000 s", text)
        self.assertIn("too short for this analysis", text)
        info = self.run_yaml("vehicle_rigid_short")
        self.assertEqual(info["exit_code"], 0)
        self.assertEqual(info["nodes"], {"rail_vehicle": 0})
        self.assertIsNone(info["incomplete"])

    def test_override_form_of_scene_launch_comment(self):
        # scene.launch's comment writes solver.end={time:1.0} (no space after ':').
        rc, text = self.railsim("run", SHORT, "--set", "solver.end={time:0.05}", "--out", self.out)
        self.assertEqual(rc, 0, text)
        self.assertIn("finished at t = 0.0500 s", text)

    def test_relative_paths_from_the_callers_directory(self):
        rc, text = self.railsim("validate", os.path.relpath(SHORT, self.dir), "--summary", cwd=self.dir)
        self.assertEqual(rc, 0, text)
        rc, text = self.railsim("validate", "nothere.yaml", cwd=self.dir)
        self.assertEqual(rc, 1, text)
        self.assertIn("error: nothere.yaml: cannot read the scene file (looked for %s/nothere.yaml): No such file"
                      % os.path.realpath(self.dir), text)
        rc, text = self.railsim("run", "nothere.yaml", cwd=self.dir)
        self.assertEqual(rc, 1, text)
        self.assertIn("error: %s/nothere.yaml: cannot read the scene file: No such file" % self.dir, text)
        # The validator itself, given a relative path, says where it looked.
        p = subprocess.run([os.path.join(ROOT, "devel", "lib", "rail_core", "railsim_validate_scene"), "nothere.yaml"],
                           capture_output=True, text=True, cwd=self.dir)
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn("(looked for %s/nothere.yaml)" % os.path.realpath(self.dir), p.stderr)

    # -- validation of what a run reads -----------------------------------------------------------------
    def test_duplicate_key_refused_naming_both_lines(self):
        s = self.scene("dup.yaml", SHORT, ("  speed: 30.5556\n", "  speed: 30.5556\n  speed: 10.0\n"))
        rc, text = self.railsim("validate", s)
        self.assertEqual(rc, 1, text)
        self.assertRegex(text, r"vehicle\.speed: given twice \(lines 13 and 14\)")

    def test_validate_refuses_bad_data_files(self):
        empty = os.path.join(self.dir, "empty.txt")
        open(empty, "w").close()
        binary = os.path.join(self.dir, "binary.txt")
        with open(binary, "wb") as f:
            f.write(bytes(range(256)) * 2)
        irr = os.path.join(self.dir, "irr.csv")
        with open(os.path.join(ROOT, "config", "scenes", "hard", "alignment_kink_4mm.csv")) as f:
            lines = f.read().splitlines()
        lines.insert(len(lines) // 2, "12.5, oops, 0, 0")
        with open(irr, "w") as f:
            f.write("\n".join(lines) + "\n")
        cases = [
            ("empty profile", ("  rail_inclination: 1/20\n", "  rail_inclination: 1/20\n  rail_profile: %s\n" % empty),
             "empty.txt:0: too few points"),
            ("binary profile", ("  rail_inclination: 1/20\n", "  rail_inclination: 1/20\n  rail_profile: %s\n" % binary),
             "track.rail_profile: %s" % binary),
            ("bad irregularity line", ("  rail_inclination: 1/20\n",
                                       "  rail_inclination: 1/20\n  irregularities: {source: file, file: %s}\n" % irr),
             "irr.csv"),
            ("wheelsets 3 of a 4-wheelset file", ("  speed: 30.5556\n", "  speed: 30.5556\n  wheelsets: 3\n"),
             "4 wheelsets (bodies with two wheel centres), the scene says vehicle.wheelsets: 3"),
            ("1e308 m segment", ("length: 60.0", "length: 1e308"),
             "track.segments[0].length: must be at most 1e+06 m"),
        ]
        for what, sub, msg in cases:
            extra = []
            if what == "bad irregularity line":
                extra = ["--set", "effects.irregularities=true"]
            s = self.scene(what.replace(" ", "_") + ".yaml", SHORT, sub)
            for args in (["validate", s] + extra, ["validate", s, "--summary"] + extra):
                rc, text = self.railsim(*args)
                self.assertEqual(rc, 1, "%s: %s" % (what, text))
                self.assertIn(msg, text, what)
                self.assertNotIn("-9223372036854775807", text)
            rc, text = self.railsim("run", s, "--out", self.out, *extra)
            self.assertEqual(rc, 1, "%s: run: %s" % (what, text))
            self.assertIn(msg, text, what)

    def test_a_checker_that_crashed_is_named(self):
        # A checker ended by a signal writes no error of its own: the command says which one, and exits 1.
        sys.path.insert(0, os.path.join(ROOT, "scripts"))
        import contextlib
        import io
        from railsim_cli import common, validate
        crash = os.path.join(self.dir, "crashing_checker")
        with open(crash, "w") as f:
            f.write("#!/bin/sh\nkill -SEGV $$\n")
        os.chmod(crash, 0o755)
        saved = validate.CHECK_INPUTS, validate.VALIDATE
        try:
            for name in ("CHECK_INPUTS", "VALIDATE"):
                validate.CHECK_INPUTS, validate.VALIDATE = saved
                setattr(validate, name, crash)
                err = io.StringIO()
                with contextlib.redirect_stderr(err), self.assertRaises(common.Stop) as stop:
                    validate.check_data([SHORT]) if name == "CHECK_INPUTS" else validate.validator([SHORT])
                self.assertEqual(stop.exception.code, 1, name)
                self.assertIn("crashing_checker ended by signal 11 before it checked the scene", err.getvalue(), name)
        finally:
            validate.CHECK_INPUTS, validate.VALIDATE = saved

    def test_data_file_key_given_twice_refused(self):
        # The vehicle's and the track's data files: yaml-cpp would keep the first value without a word.
        def copy_with(src, name, old, new):
            with open(os.path.join(ROOT, "config", src)) as f:
                text = f.read()
            self.assertIn(old, text)
            path = os.path.join(self.dir, name)
            with open(path, "w") as f:
                f.write(text.replace(old, new, 1))
            return path
        coach = copy_with("vehicle/paper_coach.yaml", "coach.yaml", "gravity: [0.0, 0.0, -9.81]\n",
                          "gravity: [0.0, 0.0, -9.81]\ngravity: [0.0, 0.0, -9.80]\n")
        track = copy_with("track/paper_track.yaml", "track.yaml", "  E: 2.10e11 ", "  E: 2.10e12\n  E: 2.10e11 ")
        s = self.scene("dup_vehicle.yaml", SHORT, ("data: %s/config/vehicle/paper_coach.yaml" % ROOT, "data: " + coach))
        for args in (["validate", s], ["run", s, "--out", self.out]):
            rc, text = self.railsim(*args)
            self.assertEqual(rc, 1, text)
            self.assertIn("%s: gravity: given twice (lines 34 and 35): remove one" % coach, text)
        s = self.scene("dup_track.yaml", COSIM, ("data: %s/config/track/paper_track.yaml" % ROOT, "data: " + track))
        rc, text = self.railsim("validate", s)
        self.assertEqual(rc, 1, text)
        self.assertIn("%s: rail.E: given twice (lines 9 and 10): remove one" % track, text)

    # -- exit codes of runs ------------------------------------------------------------------------------
    def test_track_end_exits_7_and_marks_table_incomplete(self):
        # 25 m + 30.6 m/s * 2 s goes past the 60 m track: the vehicle stops at its end (exit 7).
        rc, text = self.railsim("run", SHORT, "--set", "solver.end={time: 2.0}", "--out", self.out)
        self.assertEqual(rc, 7, text)
        info = self.run_yaml("vehicle_rigid_short")
        self.assertEqual(info["exit_code"], 7)
        self.assertEqual(info["nodes"], {"rail_vehicle": 7})
        self.assertIn("rail_vehicle exited 7", info["incomplete"])
        self.assertIn("vehicle_rigid_short: incomplete: rail_vehicle exited 7", text)

    def test_demo_too_short_for_the_analysis_exits_0(self):
        rc, text = self.railsim("run", "--end", "0.1", "--runs", "standalone", "--out", self.out)
        self.assertEqual(rc, 0, text)
        self.assertIn("railsim_analyze: the run is too short for this analysis", text)
        self.assertIn("railsim_safety: the run is too short for this analysis", text)
        self.assertEqual(self.run_yaml("standalone")["exit_code"], 0)

    def test_demo_run_reaching_the_track_end_marks_report_incomplete(self):
        rc, text = self.railsim("run", "--scene", SHORT, "--end", "2.0", "--runs", "standalone", "--out", self.out)
        self.assertEqual(rc, 7, text)
        info = self.run_yaml("standalone")
        self.assertEqual(info["exit_code"], 7)
        self.assertEqual(info["nodes"], {"rail_vehicle": 7})
        with open(os.path.join(self.out, "report", "report.md")) as f:
            self.assertIn("**standalone: incomplete: rail_vehicle exited 7", f.read())
        self.assertIn("standalone: incomplete: rail_vehicle exited 7", text)  # the safety table

    def test_demo_options_refused_before_anything_runs(self):
        for args, msg in ((["run", "--runs", "bogus"], "unknown run 'bogus'"),
                          (["run", "--end"], "--end needs a value"),
                          (["run", SHORT, "--out"], "--out needs a directory"),
                          (["validate"], "no scene given")):
            rc, text = self.railsim(*args)
            self.assertEqual(rc, 1, "%s: %s" % (args, text))
            self.assertIn(msg, text, args)
        self.assertFalse(os.path.exists(self.out))

    def test_output_dir_in_use_refused_naming_pid(self):
        os.makedirs(self.out)
        with open(os.path.join(self.out, ".railsim.lock"), "w") as lock:
            fcntl.flock(lock, fcntl.LOCK_EX | fcntl.LOCK_NB)
            lock.write("pid 4242: ./railsim run x.yaml (since 12:00:00Z)\n")
            lock.flush()
            rc, text = self.railsim("run", SHORT, "--set", "solver.end={time: 0.05}", "--out", self.out)
        self.assertEqual(rc, 1, text)
        self.assertIn("output directory %s is in use by another run: pid 4242" % self.out, text)
        self.assertFalse(os.path.exists(os.path.join(self.out, "vehicle_rigid_short.bag")))
        # Once the first run let go, the directory is free again.
        rc, text = self.railsim("run", SHORT, "--set", "solver.end={time: 0.05}", "--out", self.out)
        self.assertEqual(rc, 0, text)

    def test_two_runs_into_one_directory(self):
        p = self.start("run", COSIM, "--set", "solver.end={time: 2.0}", "--out", self.out)
        self.wait_for("integrating with")
        rc, text = self.railsim("run", COSIM, "--set", "solver.end={time: 0.1}", "--out", self.out)
        self.assertEqual(rc, 1, text)
        self.assertIn("is in use by another run: pid %d" % p.pid, text)
        os.killpg(p.pid, signal.SIGINT)
        self.assertEqual(p.wait(timeout=60), 5, self.console())

    def test_ctrl_c_exits_5_with_closed_bags(self):
        p = self.start("run", COSIM, "--set", "solver.end={time: 2.0}", "--out", self.out)
        self.wait_for("integrating with")
        os.killpg(p.pid, signal.SIGINT)  # what Ctrl-C in the terminal does
        self.assertEqual(p.wait(timeout=60), 5, self.console())
        info = self.run_yaml("paper_demo_60m")
        self.assertEqual(info["exit_code"], 5)
        self.assertIn("stopped by", info["incomplete"])

    def test_ctrl_c_stops_the_demonstration(self):
        p = self.start("run", "--scene", SHORT, "--end", "1.0", "--runs", "standalone rigid_fe", "--out", self.out)
        self.wait_for("integrating with", path=os.path.join(self.out, "standalone.log"))
        os.killpg(p.pid, signal.SIGINT)
        self.assertEqual(p.wait(timeout=60), 5, self.console())
        self.assertIn("demonstration stopped", self.console())
        self.assertEqual(self.run_yaml("standalone")["exit_code"], 5)
        self.assertFalse(os.path.exists(os.path.join(self.out, "rigid_fe.run.yaml")), "the next run started")

    def test_kill_9_of_a_node_reindexes_its_bag(self):
        p = self.start("run", COSIM, "--set", "solver.end={time: 2.0}", "--out", self.out)
        self.wait_for("integrating with")
        time.sleep(0.5)
        os.kill(self.pid_of(os.path.join(ROOT, "devel", "lib", "rail_vehicle_node", "vehicle_node")), signal.SIGKILL)
        self.assertEqual(p.wait(timeout=60), 137, self.console())
        text = self.console()
        self.assertIn("paper_demo_60m.bag was left unindexed (rail_vehicle killed by SIGKILL); reindexed", text)
        self.assertIn("rail_vehicle exited -9: killed by SIGKILL", text)
        info = self.run_yaml("paper_demo_60m")
        self.assertEqual(info["nodes"]["rail_vehicle"], -9)
        self.assertEqual(info["nodes"]["rail_track"], 4)
        self.assertEqual(info["bags"][os.path.join(self.out, "paper_demo_60m.bag")], "reindexed")

    def test_kill_9_of_the_track_node_reindexes_its_bag(self):
        p = self.start("run", COSIM, "--set", "solver.end={time: 2.0}", "--out", self.out)
        self.wait_for("integrating with")
        time.sleep(0.5)
        os.kill(self.pid_of(os.path.join(ROOT, "devel", "lib", "rail_track_node", "track_node")), signal.SIGKILL)
        self.assertEqual(p.wait(timeout=60), 137, self.console())
        text = self.console()
        self.assertIn("paper_demo_60m.track.bag was left unindexed (rail_track killed by SIGKILL); reindexed", text)
        info = self.run_yaml("paper_demo_60m")
        self.assertEqual(info["nodes"], {"rail_track": -9, "rail_vehicle": 4})

    def test_kill_9_of_roslaunch_leaves_nothing(self):
        p = self.start("run", COSIM, "--set", "solver.end={time: 2.0}", "--out", self.out)
        self.wait_for("integrating with")
        launch = [pid for pid, c in processes_naming("-p %d " % self.port) if c.startswith("/usr/bin/python3 /usr/bin/roslaunch")]
        self.assertEqual(len(launch), 1)
        os.kill(launch[0], signal.SIGKILL)
        rc = p.wait(timeout=90)
        self.assertNotEqual(rc, 0, self.console())
        self.assertIn("roslaunch left", self.console())
        self.assertIn("roslaunch was killed by SIGKILL", self.run_yaml("paper_demo_60m")["incomplete"])

    def start_bare_roslaunch(self):
        """roslaunch of the co-simulation used directly (no runner), until both nodes integrate."""
        env = dict(self.env, ROS_IP="127.0.0.1", ROS_MASTER_URI="http://127.0.0.1:%d" % self.port)
        env.pop("RAILSIM_STATUS_DIR", None)
        self.log = os.path.join(self.dir, "console.log")
        with open(self.log, "w") as f:
            p = subprocess.Popen(["bash", "-c", 'source "$0/devel/setup.bash" && exec "$@"', ROOT, "roslaunch", "-p",
                                  str(self.port), os.path.join(ROOT, "launch", "cosim.launch"), "scene:=" + COSIM,
                                  "output_dir:=" + self.out, "overrides:=solver.end={time: 2.0}"],
                                 stdout=f, stderr=subprocess.STDOUT, env=env, cwd=ROOT, start_new_session=True)
        self.wait_for("integrating with")
        return p

    def left_after(self, timeout):
        """The case's processes still alive after up to timeout s (killed, so that none outlives the test)."""
        deadline = time.monotonic() + timeout
        while processes_naming(self.dir) and time.monotonic() < deadline:
            time.sleep(0.2)
        left = processes_naming(self.dir)
        for pid, _ in left:
            os.kill(pid, signal.SIGKILL)
        return left

    def test_kill_9_of_a_bare_roslaunch_leaves_nothing(self):
        # roslaunch used directly (README): its nodes' guards stop them when it dies, so they close their
        # bags; then one guard stops the master and rosout that roslaunch had started.
        p = self.start_bare_roslaunch()
        master = [pid for pid, c in processes_naming(self.dir) if "rosmaster" in c]
        self.assertEqual(len(master), 1, "the master roslaunch started")
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
        self.assertEqual(self.left_after(45.0), [])
        text = self.console()
        # The vehicle's guard stops it, unless the vehicle ended on its own first (its peer stopped).
        self.assertRegex(text, r"railsim_node_guard: roslaunch \(pid %d\) went away: (stopping rail_vehicle|"
                               r"rail_vehicle had ended)" % p.pid)
        self.assertIn("bag closed", text)
        self.assertRegex(text, r"railsim_node_guard: stopping what roslaunch \(pid %d\) left running: "
                               r"rosmaster \(pid %d\), rosout \(pid \d+\)" % (p.pid, master[0]))
        # Bags are checked readable by tearDown.

    def test_kill_9_of_a_bare_roslaunch_while_a_node_ends_leaves_nothing(self):
        # The node of the lowest-pid guard (the one that stops what roslaunch started) ends on its own at
        # the instant roslaunch dies: its guard, which then had no node to stop, still stops the master
        # and rosout.
        p = self.start_bare_roslaunch()
        guards = sorted(pid for pid, c in processes_naming(self.dir) if "railsim_node_guard" in c)
        self.assertEqual(len(guards), 2, "a guard per node")

        def parent_of(pid):
            with open("/proc/%d/stat" % pid) as f:
                return int(f.read().rsplit(")", 1)[1].split()[1])
        node = [pid for pid, c in processes_naming(self.dir) if "railsim_node_guard" not in c and
                parent_of(pid) == guards[0]]
        self.assertEqual(len(node), 1, "the lowest guard's node")
        os.kill(node[0], signal.SIGINT)
        os.kill(p.pid, signal.SIGKILL)
        p.wait()
        self.assertEqual(self.left_after(45.0), [])
        text = self.console()
        self.assertIn("bag closed", text)
        self.assertRegex(text, r"railsim_node_guard: stopping what roslaunch \(pid %d\) left running: "
                               r"rosmaster \(pid \d+\), rosout \(pid \d+\)" % p.pid)

    def test_kill_9_of_the_runner_leaves_nothing(self):
        p = self.start("run", COSIM, "--set", "solver.end={time: 2.0}", "--out", self.out)
        self.wait_for("integrating with")
        os.kill(p.pid, signal.SIGKILL)  # ./railsim itself (bash)
        p.wait(timeout=10)
        deadline = time.monotonic() + 40.0
        while processes_naming(self.dir, "-p %d " % self.port) and time.monotonic() < deadline:
            time.sleep(0.2)
        self.assertEqual(processes_naming(self.dir, "-p %d " % self.port), [])
        # The vehicle was stopped by SIGINT and closed its bag (tearDown opens it).
        self.assertIn("bag closed", open(os.path.join(self.out, "paper_demo_60m.log")).read())

    def test_peer_dead_before_handshake_reported_at_once(self):
        env = dict(self.env)
        env["ROS_MASTER_URI"] = "http://127.0.0.1:%d" % self.port
        env["ROS_IP"] = "127.0.0.1"
        scene = self.scene("peer.yaml", COSIM, ("  end: {time: 1.0}", "  end: {time: 0.2}")) \
            if "  end: {time: 1.0}" in open(COSIM).read() else COSIM
        t0 = time.monotonic()
        cmd = ["bash", "-c", 'source "$0/devel/setup.bash" && exec "$@"', ROOT, "/usr/bin/python3",
               os.path.join(ROOT, "scripts", "railsim_launch.py"), "--status-dir", os.path.join(self.dir, "status"),
               "--", "roslaunch", "--disable-title", "-p", str(self.port), os.path.join(HERE, "peer_dies.launch"),
               "scene:=" + scene, "output_dir:=" + self.out]
        p = subprocess.run(cmd, capture_output=True, text=True, env=env, timeout=CASE_TIMEOUT)
        wall = time.monotonic() - t0
        text = p.stdout + p.stderr
        self.assertEqual(p.returncode, 4, text)
        self.assertIn("the track node died before the handshake: rail_track exited with code 2", text)
        # Far below the scene's 120 s handshake timeout; the wall includes roslaunch starting the master and
        # both nodes (5-16 s seen on 2 loaded cores), so the tight bound is the one below.
        self.assertLess(wall, 40.0, "the run took %.1f s" % wall)
        # From the track node's last word to the vehicle's report: within the 1-2 s the issue asks for.
        t_track = [float(t) for t in re.findall(r"\[FATAL\] \[(\d+\.\d+)\]: /rail_track", text)]
        t_vehicle = [float(t) for t in re.findall(r"\[FATAL\] \[(\d+\.\d+)\]: /rail_vehicle: the track node died", text)]
        self.assertTrue(t_track and t_vehicle, text)
        self.assertLess(t_vehicle[0] - t_track[-1], 2.0, text)

    @unittest.skipUnless(os.geteuid() == 0, "needs root (ip netns, veth), as CI has")
    def test_two_hosts(self):
        rc, text = self.railsim("two-hosts", "--out", os.path.join(self.dir, "two_hosts"), timeout=300)
        self.assertEqual(rc, 0, text)
        self.assertIn("two-hosts: service: both nodes finished across the hosts", text)
        self.assertIn("two-hosts: topic: both nodes finished across the hosts", text)
        self.assertRegex(text, r"two-hosts: shm refused across the hosts .*created on host 'railsim-[ab]', "
                               r"this is host 'railsim-[ab]'")
        left = subprocess.run(["ip", "netns", "list"], capture_output=True, text=True).stdout
        self.assertNotRegex(left, r"railsim_[ab]_\d+", "network namespaces left behind")

    @unittest.skipUnless(os.geteuid() == 0, "needs root (mount a small tmpfs), as CI has")
    def test_disk_full_stops_cleanly(self):
        # The output directory on a 400 kB tmpfs fills up during a co-simulation: each node stops with one line
        # naming its file and the system's reason, exit 9; no abort, no traceback; no unreadable bag and no
        # partial cost file left; the runner says it in one line.
        mnt = tempfile.mkdtemp(prefix="railsim_full_")
        subprocess.run(["mount", "-t", "tmpfs", "-o", "size=400k", "tmpfs", mnt], check=True)
        try:
            out = os.path.join(mnt, "out")
            rc, text = self.railsim("run", COSIM, "--set", "effects.track_model=rigid_fe", "--set",
                                    "solver.end={time: 1.0}", "--out", out)
            self.assertEqual(rc, 9, text)
            self.assertRegex(text, r"\[FATAL\] \[[\d.]+\]: /rail_(track|vehicle): cannot write %s/paper_demo_60m"
                                   r"(\.track)?\.bag: No space left on device \(.*\); stopped at t = [\d.]+ s"
                             % re.escape(out))
            self.assertRegex(text, r"\[railsim\] rail_(track|vehicle) exited 9: could not write an output")
            self.assertRegex(text, r"\[railsim\] run of .*paper_demo_60m.yaml could not write its outputs \(exit 9\)")
            for bad in ("Traceback", "terminate called", "SIGABRT", "internal error", "counted as 6"):
                self.assertNotIn(bad, text)
            left = sorted(os.listdir(out))
            for f in left:
                path = os.path.join(out, f)
                if f.endswith(".bag"):
                    p = subprocess.run(["/usr/bin/python3", "-c", "import rosbag, sys; rosbag.Bag(sys.argv[1]).close()",
                                        path], capture_output=True, text=True, env=self.env)
                    self.assertEqual(p.returncode, 0, "%s unreadable: %s" % (f, p.stderr))
                if f.endswith(".yaml"):
                    import yaml
                    with open(path) as fh:
                        self.assertIsInstance(yaml.safe_load(fh), dict, "%s is empty or partial" % f)
            import yaml
            with open(os.path.join(out, "paper_demo_60m.run.yaml")) as fh:
                info = yaml.safe_load(fh)
            self.assertEqual(info["exit_code"], 9)
            self.assertIn("could not write an output", info["incomplete"])
        finally:
            subprocess.run(["umount", "-l", mnt])
            os.rmdir(mnt)

    def test_rviz_inside_the_isolated_run(self):
        # ./railsim run --rviz: rviz runs inside the run's network namespace (it reaches the run's master on
        # loopback and the X display by its socket file), subscribes to the markers, and ends with the run.
        env = dict(self.env)
        env.pop("DISPLAY", None)
        p = subprocess.run([RAILSIM, "run", SHORT, "--out", self.out, "--rviz"], capture_output=True, text=True,
                           env=env, cwd=ROOT, timeout=CASE_TIMEOUT)
        self.assertEqual(p.returncode, 1, p.stdout + p.stderr)
        self.assertIn("run: --rviz needs a display (DISPLAY is not set)", p.stderr)
        display = ":%d" % (50 + os.getpid() % 40)
        xvfb = subprocess.Popen(["Xvfb", display, "-screen", "0", "1024x768x24"], stdout=subprocess.DEVNULL,
                                stderr=subprocess.DEVNULL)
        try:
            time.sleep(1.0)
            env = dict(self.env, DISPLAY=display, LIBGL_ALWAYS_SOFTWARE="1")
            p = subprocess.run([RAILSIM, "run", SHORT, "--out", self.out, "--rviz"], capture_output=True, text=True,
                               env=env, cwd=ROOT, timeout=CASE_TIMEOUT)
        finally:
            xvfb.terminate()
            xvfb.wait()
        text = p.stdout + p.stderr
        self.assertEqual(p.returncode, 0, text)
        self.assertNotIn("not isolating", text)
        with open(os.path.join(self.out, "vehicle_rigid_short.log")) as f:
            log = f.read()
        self.assertRegex(log, r"process\[rviz-\d+\]: started with pid")
        self.assertIn("finished at t = 0.5000 s", log)
        self.assertNotRegex(log, r"(?i)could not connect to display|cannot (open|connect to) (the )?display")
        self.assertIn("effects.rviz_markers=true", self.run_yaml("vehicle_rigid_short")["overrides"])
        self.assertEqual([c for _, c in processes_naming("/usr/lib/rviz/rviz") if self.dir in c], [])

    def test_readme_standalone_example(self):
        env = dict(self.env, ROS_IP="127.0.0.1", ROS_MASTER_URI="http://127.0.0.1:%d" % self.port)
        cmd = ["bash", "-c", 'source "$0/devel/setup.bash" && exec "$@"', ROOT, "roslaunch", "-p", str(self.port),
               "launch/vehicle_standalone.launch", "scene:=%s/config/scenes/paper_demo.yaml" % ROOT,
               "track_model:=rigid", "output_dir:=" + self.out, "overrides:=solver.end={time: 0.05}"]
        p = subprocess.run(cmd, capture_output=True, text=True, env=env, cwd=ROOT, timeout=CASE_TIMEOUT)
        text = p.stdout + p.stderr
        self.assertNotIn("needs a track node", text)
        self.assertIn("finished at t = 0.0500 s", text)


def main():
    argv = sys.argv[1:]
    names = [a for a in argv if not a.startswith("--")]
    loader = unittest.TestLoader()
    suite = (loader.loadTestsFromNames(names, sys.modules[__name__]) if names
             else loader.loadTestsFromTestCase(TestCli))
    return rosunit_main.run(suite, "test_cli", [a for a in argv if a.startswith("--")])


if __name__ == "__main__":
    sys.exit(main())
