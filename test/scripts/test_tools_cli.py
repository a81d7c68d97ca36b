#!/usr/bin/env python3
"""The tools' command-line contract, as a user meets it: every tool, benchmark and script answers -h and
--help with its usage on stdout and exit 0, and refuses an unknown option with exit 2 and a message naming
it; contact_geometry writes exactly the rows it says, lists each row it could not solve on stderr with its
y, yaw and reason, and exits 1 without writing a table when no row solved.

  /usr/bin/python3 test_tools_cli.py [--gtest_output=xml:FILE]
"""
import os
import re
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import rosunit_main  # noqa: E402

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
sys.path.insert(0, os.path.join(REPO, "src", "rail_contact", "scripts"))
import manchester_a22  # noqa: E402  (its SIMPACK point reader)
LIB = os.path.join(REPO, "devel", "lib")
PY = "/usr/bin/python3"

# (command, first word of the usage) for every program a user runs directly (nodes run under roslaunch).
TOOLS = [
    ([os.path.join(LIB, "rail_contact", "contact_geometry")], "usage"),
    ([os.path.join(LIB, "rail_contact", "bench_contact")], "usage"),
    ([os.path.join(LIB, "rail_core", "railsim_bench_shm")], "usage"),
    ([os.path.join(LIB, "rail_ros", "railsim_bench_transports")], "usage"),
    ([os.path.join(LIB, "rail_track_node", "bench_cosim_track")], "usage"),
    ([os.path.join(LIB, "rail_track_node", "bench_newmark")], "usage"),
    ([os.path.join(LIB, "rail_track_node", "bench_track")], "usage"),
    ([os.path.join(LIB, "rail_track_node", "bench_track_window")], "usage"),
    ([os.path.join(LIB, "rail_track_node", "bench_factor_solve")], "usage"),
    ([os.path.join(LIB, "rail_track_node", "track_end_reflection")], "usage"),
    ([os.path.join(LIB, "rail_track_node", "track_receptance")], "usage"),
    ([os.path.join(LIB, "rail_vehicle_node", "bench_vehicle_rhs")], "usage"),
    ([os.path.join(LIB, "rail_vehicle_node", "bench_vehicle_simulator")], "usage"),
    ([os.path.join(LIB, "rail_vehicle_node", "bench_vehicle_accuracy")], "usage"),
    ([PY, os.path.join(REPO, "src", "rail_contact", "scripts", "contact_geometry_for_scene.py")], "usage"),
    ([PY, os.path.join(REPO, "src", "rail_contact", "scripts", "plot_contact_geometry.py")], "Plots"),
    ([PY, os.path.join(REPO, "src", "rail_contact", "scripts", "manchester_a22.py")], "usage"),
    ([PY, os.path.join(REPO, "src", "rail_contact", "scripts", "make_worn_profiles.py")], "Makes"),
    ([PY, os.path.join(REPO, "scripts", "count_tests.py")], "Counts"),
    ([PY, os.path.join(REPO, "scripts", "make_train.py")], "usage"),
    (["/bin/bash", os.path.join(REPO, "scripts", "rviz_screenshot.sh")], "Screenshot"),
    (["/bin/bash", os.path.join(REPO, "scripts", "check_naming")], "check_naming:"),
    (["/bin/bash", os.path.join(REPO, "scripts", "check_format")], "check_format:"),
]

MB = os.path.join(REPO, "config", "profiles", "manchester_a22")


def self_dir():
    return tempfile.mkdtemp(prefix="tools_cli_")


def run(cmd, timeout=60):
    return subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True,
                          timeout=timeout)


class ToolsAnswerHelp(unittest.TestCase):
    def test_help_and_h_exit_0_with_usage(self):
        for cmd, first in TOOLS:
            for flag in ("--help", "-h"):
                with self.subTest(tool=os.path.basename(cmd[-1]), flag=flag):
                    p = run(cmd + [flag])
                    self.assertEqual(p.returncode, 0, p.stderr)
                    self.assertIn(first, p.stdout.split("\n\n")[0] + p.stdout[:200])

    def test_unknown_option_is_refused(self):
        for cmd, _ in TOOLS:
            if os.path.basename(cmd[-1]) in ("count_tests.py",):
                continue  # its first two arguments are paths: checked by its own usage line below
            with self.subTest(tool=os.path.basename(cmd[-1])):
                # A script whose required arguments argparse checks first gets them, so that the unknown
                # option is what it refuses.
                needs = ["scene.yaml", "--out-dir", self_dir()] if cmd[-1].endswith("contact_geometry_for_scene.py") else []
                needs = ["coach.yaml", "2"] if cmd[-1].endswith("make_train.py") else needs
                p = run(cmd + needs + ["--no-such-option"])
                self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
                self.assertIn("--no-such-option", p.stderr)
        p = run([PY, os.path.join(REPO, "scripts", "count_tests.py")])
        self.assertEqual(p.returncode, 2)
        self.assertIn("usage: count_tests.py", p.stderr)

    def test_a_bad_option_value_is_named(self):
        # The tools that read named options (rail::tools::Options): a missing value, a value that is not a
        # number and a rule between options are one line naming the option, exit 2.
        cases = [
            ([os.path.join(LIB, "rail_contact", "contact_geometry"), "--gauge"],
             "contact_geometry: --gauge needs a value (contact_geometry --help lists the options)"),
            ([os.path.join(LIB, "rail_track_node", "track_receptance"), "--points", "x"],
             "track_receptance: --points: not a number (x)"),
            ([os.path.join(LIB, "rail_track_node", "track_end_reflection"), "--freqs", "300,-5"],
             "track_end_reflection: --freqs: not a positive number (-5)"),
            ([os.path.join(LIB, "rail_contact", "contact_geometry"), "--load", "1e5"],
             "contact_geometry: --load needs --speed > 0"),
        ]
        for cmd, msg in cases:
            with self.subTest(cmd=" ".join(os.path.basename(c) for c in cmd)):
                p = run(cmd)
                self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
                self.assertIn(msg, p.stderr)
                self.assertEqual(len(p.stderr.strip().splitlines()), 1, p.stderr)


class TrainMaker(unittest.TestCase):
    """scripts/make_train.py: the shipped train is what it writes from the shipped coach; bad input exits 2
    naming the file, option or field, and writes nothing."""

    TOOL = [PY, os.path.join(REPO, "scripts", "make_train.py")]
    COACH = os.path.join(REPO, "config", "vehicle", "paper_coach.yaml")

    def test_the_shipped_train_is_the_coach_twice(self):
        p = run(self.TOOL + [self.COACH, "2"])
        self.assertEqual(p.returncode, 0, p.stderr)
        with open(os.path.join(REPO, "config", "vehicle", "paper_coach_x2.yaml")) as f:
            shipped = f.read()
        # The header names the coach file by its base name only, so the text does not depend on the path.
        self.assertEqual(p.stdout, shipped)

    def test_bad_input_is_named_and_nothing_written(self):
        d = self_dir()
        out = os.path.join(d, "train.yaml")
        cases = [
            ([self.COACH, "0"], "N: at least 1 coach, got 0"),
            ([os.path.join(d, "missing.yaml"), "2"], "missing.yaml: No such file or directory"),
            ([self.COACH, "2", "--carbody", "body"], "no body named 'body' (--carbody)"),
            ([self.COACH, "2", "--coupler-stiffness", "1,2"], "--coupler-stiffness: three values >= 0"),
            ([self.COACH, "2", "--length", "-1"], "--length: must be > 0 m, got -1.0"),
        ]
        for args, message in cases:
            with self.subTest(args=args):
                p = run(self.TOOL + args + ["--out", out])
                self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
                self.assertIn(message, p.stderr)
                self.assertFalse(os.path.exists(out))


class NamingCheck(unittest.TestCase):
    """scripts/check_naming, which ./railsim test (and so CI) runs over the whole tree: a name against the
    convention of .clang-tidy fails it, naming file, line and the name."""

    def test_a_violation_fails_naming_file_line_and_name(self):
        d = self_dir()
        bad, good = os.path.join(d, "bad.cpp"), os.path.join(d, "good.cpp")
        with open(bad, "w") as f:
            f.write("namespace rail {\nvoid load_scene_file();\nstruct wheel_state {};\nvoid AdvanceTo(double t);\n}\n")
        with open(good, "w") as f:
            f.write("namespace rail {\nvoid loadSceneFile();\nstruct WheelState { double speed() const; };\n}\n")
        p = run(["/bin/bash", os.path.join(REPO, "scripts", "check_naming"), bad], timeout=120)
        self.assertEqual(p.returncode, 1, p.stdout + p.stderr)
        self.assertIn("%s:2:6: invalid case style for function 'load_scene_file'" % bad, p.stdout)
        self.assertIn("%s:3:8: invalid case style for struct 'wheel_state'" % bad, p.stdout)
        self.assertIn("%s:4:6: invalid case style for function 'AdvanceTo'" % bad, p.stdout)
        self.assertIn("3 name(s) break the convention", p.stderr)
        p = run(["/bin/bash", os.path.join(REPO, "scripts", "check_naming"), good], timeout=120)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        self.assertIn("every name follows the convention", p.stdout)


class FormatCheck(unittest.TestCase):
    """scripts/check_format, which ./railsim test (and so CI) runs over every C++ file: a file not laid out as
    .clang-format says fails it, named; a file laid out so passes."""

    def test_a_file_out_of_layout_fails_named(self):
        d = self_dir()
        bad, good = os.path.join(d, "bad_layout.cpp"), os.path.join(d, "good_layout.cpp")
        with open(bad, "w") as f:
            f.write("int  twice( int x ){return 2*x;}\n")
        with open(good, "w") as f:
            f.write("int twice(int x) { return 2 * x; }\n")
        p = run(["/bin/bash", os.path.join(REPO, "scripts", "check_format"), bad, good], timeout=120)
        self.assertEqual(p.returncode, 1, p.stdout + p.stderr)
        self.assertEqual(p.stdout.split(), [bad])
        self.assertIn("1 of 2 file(s) are not laid out as .clang-format says", p.stderr)
        p = run(["/bin/bash", os.path.join(REPO, "scripts", "check_format"), good], timeout=120)
        self.assertEqual(p.returncode, 0, p.stdout + p.stderr)
        self.assertIn("1 file(s) follow .clang-format", p.stdout)
        p = run(["/bin/bash", os.path.join(REPO, "scripts", "check_format"), os.path.join(d, "missing.cpp")])
        self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
        self.assertIn("missing.cpp: no such file", p.stderr)


class ScriptsOnBadInput(unittest.TestCase):
    def test_benchmark_script_without_a_built_tool_says_so_and_leaves_nothing(self):
        ws = os.path.join(tempfile.mkdtemp(prefix="tools_cli_ws_"), "ws")
        p = run([PY, os.path.join(REPO, "src", "rail_contact", "scripts", "manchester_a22.py"), "--workspace", ws])
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn("contact_geometry: not built", p.stderr)
        self.assertNotIn("Traceback", p.stderr)
        self.assertFalse(os.path.exists(ws))

    def test_vehicle_benchmark_refuses_a_value_it_would_ignore(self):
        # Each word-valued argument is one of its choices; another word must not fall back to a default.
        bench = os.path.join(LIB, "rail_vehicle_node", "bench_vehicle_simulator")
        scene = os.path.join(REPO, "config", "scenes", "paper_demo.yaml")
        base = [bench, scene, "0.01", "auto", "0", "1", "1", "-1", "0", "coloured", "klu", "1", "1"]
        for i, bad in ((3, "bfd"), (5, "2"), (10, "kl"), (12, "yes"), (13, "bogus")):
            with self.subTest(argument=i, value=bad):
                cmd = (base + ["accepted"])[:]
                cmd[i] = bad
                p = run(cmd)
                self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
                self.assertIn("argument %d: '%s' is not one of" % (i, bad), p.stderr)
                self.assertEqual(p.stdout, "")
        p = run(base + ["accepted", "extra"])
        self.assertEqual(p.returncode, 2, p.stderr)
        self.assertIn("unexpected argument 'extra'", p.stderr)
        p = run(base + ["every"])
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("median of 1 runs", p.stdout)

    def test_vehicle_accuracy_benchmark_refuses_bad_candidates_before_any_run(self):
        # A candidate is method max_step rtol atol; a bad word, a negative number or an incomplete group
        # exits 2 naming the argument, before the reference run (minutes) starts and without writing it.
        bench = os.path.join(LIB, "rail_vehicle_node", "bench_vehicle_accuracy")
        scene = os.path.join(REPO, "config", "scenes", "paper_demo.yaml")
        with tempfile.TemporaryDirectory() as d:
            ref = os.path.join(d, "reference.csv")
            cases = (
                ([scene, ref, "bfd", "0", "0", "0"], "argument 3: 'bfd' is not one of bdf|adams|auto"),
                (["--sample", "1e-4", scene, ref, "auto", "0", "-1", "0"], "argument 7: '-1' is not a number >= 0"),
                ([scene, ref, "bdf", "1e-4", "0"], "3 candidate arguments, expected groups of four"),
            )
            for args, message in cases:
                with self.subTest(args=args):
                    p = run([bench] + args)
                    self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
                    self.assertIn(message, p.stderr)
                    self.assertEqual(p.stdout, "")
            p = run([bench, scene, os.path.join(d, "no", "such", "dir", "reference.csv")])
            self.assertEqual(p.returncode, 1, p.stdout + p.stderr)
            self.assertIn("reference.csv: cannot write the reference there", p.stderr)
            self.assertEqual(os.listdir(d), [])

    def test_vehicle_accuracy_benchmark_refuses_a_reference_it_did_not_make(self):
        # A cached reference is compared against only when its first line names this scene, sampling
        # interval and results revision; one from an older build or another scene would be a silent wrong
        # table. Refused with exit 2 before any run, and left as it was.
        bench = os.path.join(LIB, "rail_vehicle_node", "bench_vehicle_accuracy")
        scene = os.path.join(REPO, "config", "scenes", "paper_demo.yaml")
        with tempfile.TemporaryDirectory() as d:
            ref = os.path.join(d, "reference.csv")
            old = "t,s,lateral,vertical,attack,flange_left,flange_right\n0,0,0,0,0,0,0\n"
            with open(ref, "w") as f:
                f.write(old)
            p = run([bench, scene, ref])
            self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
            self.assertIn("reference.csv has no provenance line (made by an older build); delete it", p.stderr)
            self.assertEqual(p.stdout, "")
            with open(ref) as f:
                self.assertEqual(f.read(), old)
            with open(ref, "w") as f:
                f.write("# bench_vehicle_accuracy reference: scene_hash 0123456789abcdef, adams max_step 5e-06 s, "
                        "sample 0.001 s, results_revision 1\n" + old)
            p = run([bench, "--sample", "1e-4", scene, ref])
            self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
            self.assertIn("reference.csv was made from another scene, setting or build", p.stderr)
            needed = re.search(r"needed:  (bench_vehicle_accuracy reference: scene_hash ([0-9a-f]{16}), .*)", p.stderr)
            self.assertIsNotNone(needed, p.stderr)
            self.assertNotEqual(needed.group(2), "0123456789abcdef")
            self.assertIn("sample 0.0001 s, results_revision", needed.group(1))
            # The line this run needs, over a sample that is not seven numbers: read, then refused at its line.
            with open(ref, "w") as f:
                f.write("# " + needed.group(1) + "\n" + old + "0.001,1,2,3,4,5\n")
            p = run([bench, "--sample", "1e-4", scene, ref])
            self.assertEqual(p.returncode, 2, p.stdout + p.stderr)
            self.assertIn("reference.csv:4: expected seven numbers", p.stderr)
            self.assertEqual(p.stdout, "")

    def test_vehicle_benchmarks_name_a_missing_scene_and_exit_1(self):
        for tool in ("bench_vehicle_accuracy", "bench_vehicle_simulator"):
            with self.subTest(tool=tool):
                p = run([os.path.join(LIB, "rail_vehicle_node", tool), "/nonexistent/scene.yaml", "1"])
                self.assertEqual(p.returncode, 1, p.stdout + p.stderr)
                self.assertIn("%s: /nonexistent/scene.yaml: cannot read the scene file" % tool, p.stderr)
                self.assertNotIn("terminate called", p.stderr)

    def test_analysis_commands_name_a_missing_python_module(self):
        # A Python without the system's site packages (as a pyenv or conda interpreter ahead of /usr/bin):
        # one line naming the interpreter and the module, exit 1, no traceback.
        for script in ("railsim_map", "railsim_safety", "railsim_analyze"):
            with self.subTest(script=script):
                p = run([PY, "-S", os.path.join(REPO, "src", "rail_analysis", "scripts", script), "x.yaml"])
                self.assertEqual(p.returncode, 1, p.stdout + p.stderr)
                self.assertRegex(p.stderr, r"^rail_analysis: %s has no Python module '(matplotlib|numpy|yaml)' "
                                 r"\(Debian: apt install python3-\1\)" % re.escape(PY))
                self.assertNotIn("Traceback", p.stderr)
                self.assertEqual(p.stdout, "")

    def test_worn_profile_maker_names_the_missing_standard_shape(self):
        d = os.path.join(tempfile.mkdtemp(prefix="tools_cli_prof_"), "none")
        p = run([PY, os.path.join(REPO, "src", "rail_contact", "scripts", "make_worn_profiles.py"), "--profiles", d])
        self.assertEqual(p.returncode, 1, p.stderr)
        self.assertIn(os.path.join(d, "S1002.txt"), p.stderr)
        self.assertNotIn("Traceback", p.stderr)


class NodesStartedByHand(unittest.TestCase):
    """The two nodes are started by roslaunch; started by hand they say so on --help, and without a master
    they wait for it with a deadline and stop on SIGTERM at once (roscpp's own registration would retry
    for ever, deaf to the node's signal handler)."""

    NODES = [os.path.join(LIB, "rail_vehicle_node", "vehicle_node"), os.path.join(LIB, "rail_track_node", "track_node")]

    def test_help_says_how_the_node_is_started(self):
        for node in self.NODES:
            with self.subTest(node=os.path.basename(node)):
                p = run([node, "--help"], timeout=10)
                self.assertEqual(p.returncode, 0, p.stderr)
                self.assertIn("Started by roslaunch", p.stdout)

    def test_sigterm_while_waiting_for_the_master_stops_the_node(self):
        env = dict(os.environ, ROS_MASTER_URI="http://127.0.0.1:%d" % (29000 + os.getpid() % 900),
                   ROS_HOME=tempfile.mkdtemp(prefix="tools_cli_rh_"))
        for node in self.NODES:
            with self.subTest(node=os.path.basename(node)):
                proc = subprocess.Popen([node], stdout=subprocess.PIPE, stderr=subprocess.PIPE, env=env,
                                        universal_newlines=True)
                try:
                    _, err = proc.communicate(timeout=3)
                    self.fail("the node ended without a master before the signal: %s" % err)
                except subprocess.TimeoutExpired:
                    pass
                proc.terminate()
                try:
                    _, err = proc.communicate(timeout=3)
                finally:
                    if proc.poll() is None:
                        proc.kill()
                self.assertEqual(proc.returncode, 5, err)
                self.assertIn("waiting for the ROS master at", err)


class ContactGeometryIsHonest(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="cg_cli_")
        # The benchmark's rail cut 4 mm gauge side of its top: the running band half gone, as a careless
        # export of a measurement might leave it. Some rows solve, some cannot.
        pts = [p for p in manchester_a22.simpack_points(os.path.join(MB, "MBench_UIC60_v3.prr"), -1.0, -1.0)
               if p[0] >= 4.0]
        self.cut = os.path.join(self.dir, "rail_cut.txt")
        with open(self.cut, "w") as f:
            f.write("# units: mm\n")
            for y, z in pts:
                f.write("%.6f %.6f\n" % (y, z))

    def tool(self, *args):
        return run([os.path.join(LIB, "rail_contact", "contact_geometry")] + list(args))

    def test_the_issue_command_on_the_benchmark_files_fills_its_table(self):
        out = os.path.join(self.dir, "t.csv")
        p = self.tool("--out", out, "--wheel", os.path.join(MB, "MBench_S1002_v3.prw"), "--rail",
                      os.path.join(MB, "MBench_UIC60_v3.prr"), "--inclination", "0", "--gauge", "1.435",
                      "--back-to-back", "1.360", "--radius", "0.46", "--y-max", "0.010", "--dy", "0.0005",
                      "--load", "10000", "--speed", "2", "--friction", "0.3")
        self.assertEqual(p.returncode, 0, p.stderr)
        self.assertIn("wrote %s (41 rows)" % out, p.stdout)
        with open(out) as f:
            self.assertEqual(len(f.read().splitlines()), 42)  # header + 41 rows
        self.assertEqual(p.stderr, "")

    def test_unsolved_rows_are_listed_and_not_counted(self):
        out = os.path.join(self.dir, "part.csv")
        p = self.tool("--out", out, "--rail", self.cut, "--inclination", "0", "--wheel",
                      os.path.join(MB, "MBench_S1002_v3.prw"), "--y-min", "-0.010", "--y-max", "0.002", "--dy", "0.002")
        self.assertEqual(p.returncode, 0, p.stderr)
        m = re.search(r"wrote .* \((\d+) rows; (\d+) of (\d+) rows not solved, listed above\)", p.stdout)
        self.assertIsNotNone(m, p.stdout)
        written, failed, total = (int(g) for g in m.groups())
        self.assertEqual(total, 7)
        self.assertEqual(written + failed, total)
        self.assertGreater(failed, 0)
        self.assertGreater(written, 0)
        with open(out) as f:
            self.assertEqual(len(f.read().splitlines()) - 1, written)
        listed = [l for l in p.stderr.splitlines() if "not solved:" in l]
        self.assertEqual(len(listed), failed, p.stderr)
        for line in listed:
            self.assertRegex(line, r"row y = \S+ m, yaw = \S+ rad not solved: (no contact point found on|the rigid)")

    def test_no_solved_row_exits_1_and_writes_nothing(self):
        out = os.path.join(self.dir, "none.csv")
        p = self.tool("--out", out, "--rail", self.cut, "--inclination", "0", "--wheel",
                      os.path.join(MB, "MBench_S1002_v3.prw"), "--y-min", "0", "--y-max", "0", "--dy", "0.001")
        self.assertEqual(p.returncode, 1, p.stdout)
        self.assertIn("no row of 1 solved", p.stderr)
        self.assertIn("rail_cut.txt", p.stderr)
        self.assertFalse(os.path.exists(out))
        self.assertNotIn("wrote", p.stdout)

    def test_load_without_speed_is_refused(self):
        p = self.tool("--out", os.path.join(self.dir, "x.csv"), "--load", "10000")
        self.assertEqual(p.returncode, 2)
        self.assertIn("--load needs --speed", p.stderr)


def main():
    loader = unittest.TestLoader()
    cases = (ToolsAnswerHelp, ScriptsOnBadInput, NodesStartedByHand, ContactGeometryIsHonest, TrainMaker, NamingCheck,
             FormatCheck)
    suite = unittest.TestSuite([loader.loadTestsFromTestCase(c) for c in cases])
    return rosunit_main.run(suite, "test_tools_cli")


if __name__ == "__main__":
    sys.exit(main())
