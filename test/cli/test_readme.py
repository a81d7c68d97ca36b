#!/usr/bin/python3
"""The README as a tested contract: every command of its ```sh and ```python blocks runs here and must do
what the README says, with short end times where it would run long and the outputs in a temporary
directory. A command the rules below do not know fails the test, so a new example cannot go untested.

  /usr/bin/python3 test/cli/test_readme.py [--gtest_output=xml:FILE]

The workspace must be built (./railsim runs with RAILSIM_NO_BUILD=1)."""
import os
import re
import shutil
import socket
import subprocess
import sys
import tempfile
import unittest

HERE = os.path.dirname(os.path.realpath(__file__))
ROOT = os.path.dirname(os.path.dirname(HERE))
sys.path.insert(0, os.path.join(ROOT, "test", "scripts"))
import rosunit_main  # noqa: E402

README = os.path.join(ROOT, "README.md")
TIMEOUT = 600.0
SHORT = "solver.end={time: 0.05}"


def free_port():
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def readme_blocks():
    """[(language, first line number, [command lines])]: continuation lines joined, comment-only lines
    kept (they hold expected output)."""
    blocks, lang, start, lines = [], None, 0, []
    with open(README) as f:
        for n, line in enumerate(f, 1):
            if line.startswith("```"):
                if lang is None:
                    lang, start, lines = line[3:].strip(), n, []
                else:
                    if lang in ("sh", "python"):
                        blocks.append((lang, start, lines))
                    lang = None
                continue
            if lang is not None:
                if lines and lines[-1].endswith("\\"):
                    lines[-1] = lines[-1][:-1].rstrip() + " " + line.strip()
                else:
                    lines.append(line.rstrip("\n"))
    return blocks


def strip_comment(line):
    return re.sub(r"\s+#.*$", "", line).strip()


class Readme(unittest.TestCase):
    @classmethod
    def setUpClass(cls):
        cls.dir = tempfile.mkdtemp(prefix="railsim_readme_")
        cls.demo = os.path.join(cls.dir, "demo")
        cls.port = free_port()
        cls.env = dict(os.environ, RAILSIM_NO_BUILD="1", RAILSIM_MASTER_PORT=str(cls.port),
                       ROS_HOME=os.path.join(cls.dir, "ros_home"), PATH="/usr/bin:/bin:" + os.environ.get("PATH", ""))
        cls.ran = []

    @classmethod
    def tearDownClass(cls):
        shutil.rmtree(cls.dir, ignore_errors=True)

    def sh(self, command, timeout=TIMEOUT, env=None, cwd=ROOT):
        """Runs a README command in bash from the repository root, the workspace sourced (as the README's
        blocks do); returns (exit code, output)."""
        script = 'source %s/devel/setup.bash >/dev/null; export ROS_IP=127.0.0.1 ROS_MASTER_URI=http://127.0.0.1:%d; %s' % (
            ROOT, self.port, command)
        p = subprocess.run(["bash", "-c", script], capture_output=True, text=True, env=env or self.env, cwd=cwd,
                           timeout=timeout)
        self.ran.append(command)
        return p.returncode, p.stdout + p.stderr

    def my_scene(self):
        """The README's my_scene.yaml: a scene whose track.segments[2].radius is -500.0 on line 23."""
        path = os.path.join(self.dir, "my_scene.yaml")
        lines = ["# the README's example of a refused scene"] * 14 + [
            "track:",
            "  gauge: 1.668",
            "  data: %s/config/track/paper_track.yaml" % ROOT,
            "  segments:",
            "    - {type: straight, length: 50.0}",
            "    - {type: transition, length: 40.0, direction: left, radius_start: 0, radius_end: 500.0}",
            "    - type: circular",
            "      length: 60.0",
            "      radius: -500.0",
            "      direction: left",
            "vehicle: {data: %s/config/vehicle/paper_coach.yaml, start_arc_length: 25.0, speed: 30.0,"
            " back_to_back: 1.592}" % ROOT]
        self.assertEqual(lines[22].strip(), "radius: -500.0")
        with open(path, "w") as f:
            f.write("\n".join(lines) + "\n")
        return path

    def run_command(self, cmd, expected_comment):
        """One README command, adapted as the rules say; asserts what the README promises."""
        d = self.dir
        c = cmd
        if c in ("source devel/setup.bash",) or c.startswith("export ROS_IP=127.0.0.1"):
            return "environment (every command runs with it)"
        if c == "./railsim test":
            return "skipped: this is the suite itself"
        if "192.168.1." in c or c in ("roscore &", "rosrun rail_track_node track_node") or \
                c.startswith("rosrun rail_vehicle_node vehicle_node") or \
                c.startswith("roslaunch launch/scene.launch"):
            return "skipped: the two-machine recipe runs for real in ./railsim two-hosts (test_cli.test_two_hosts)"
        if c == "./railsim run":
            if os.path.isfile(os.path.join(self.demo, "report", "report.md")):
                return "run above (the same command)"
            rc, out = self.sh("./railsim run --end 0.3 --out %s" % self.demo)
            self.assertEqual(rc, 0, out[-4000:])
            self.assertIn("report: %s/report/report.md" % self.demo, out)
            return "run with --end 0.3 --out"
        if c == "./railsim run -h":
            rc, out = self.sh(c)
            self.assertEqual(rc, 0, out)
            self.assertIn("usage: ./railsim run", out)
            return "as written"
        m = re.match(r"^\./railsim run (config/scenes/\S+\.yaml)(.*)$", c)
        if m:
            rest = m.group(2).replace("{time: 1.0}", "{time: 0.3}").replace("--out output/short",
                                                                              "--out %s/short" % d)
            if "--out" not in rest:
                rest += ' --set "solver.end={time: 0.3}" --out %s/scene' % d
            how = "run to 0.3 s, output in the test directory"
            cmd2 = "./railsim run %s%s" % (m.group(1), rest)
            if "--rviz" in rest:
                cmd2 = "LIBGL_ALWAYS_SOFTWARE=1 xvfb-run -a -s '-screen 0 1024x768x24' " + cmd2
                how += ", rviz on a virtual display"
            rc, out = self.sh(cmd2)
            self.assertEqual(rc, 0, out[-4000:])
            self.assertIn("finished at t = 0.3000 s", out)
            return how
        m = re.match(r"^roslaunch (launch/(cosim|vehicle_standalone)\.launch) (.*)$", c)
        if m:
            args = m.group(3)
            env = dict(self.env, RAILSIM_STATUS_DIR=os.path.join(d, "status_" + m.group(2)))
            how = "as written, to t = 0.05 s"
            if "rviz:=true" in args and not shutil.which("Xvfb"):
                args = args.replace("rviz:=true", "rviz:=false")
                how += " (no Xvfb here: rviz:=false)"
            cmd2 = 'roslaunch -p %d %s %s output_dir:=%s/launch overrides:="%s"' % (self.port, m.group(1), args, d, SHORT)
            if "rviz:=true" in args:
                cmd2 = "xvfb-run -a -s '-screen 0 1024x768x24' " + cmd2
                how += " on a virtual display"
            rc, out = self.sh(cmd2, env=env)
            self.assertEqual(rc, 0, out[-4000:])
            self.assertIn("finished at t = 0.0500 s", out)
            self.assertNotIn("FATAL", out)
            codes = {f[:-5]: open(os.path.join(env["RAILSIM_STATUS_DIR"], f)).read().strip()
                     for f in os.listdir(env["RAILSIM_STATUS_DIR"]) if f.endswith(".exit")}
            self.assertEqual(set(codes.values()), {"0"}, codes)
            return how
        if c.startswith("roslaunch launch/track_replay.launch"):
            bag = os.path.join(self.demo, "flexible.bag")
            self.assertTrue(os.path.isfile(bag), "the demonstration's flexible.bag (run first)")
            scene = os.path.join(d, "my_stiffer_pad_scene.yaml")
            with open(os.path.join(ROOT, "config", "scenes", "paper_demo.yaml")) as f:
                text = f.read().replace("../track/paper_track.yaml", "%s/config/track/paper_track_stiff_pad.yaml" % ROOT)
            text = re.sub(r"\.\./(track|vehicle|profiles)/", ROOT + r"/config/\1/", text)
            with open(scene, "w") as f:
                f.write(text)
            c2 = c.replace("$PWD/my_stiffer_pad_scene.yaml", scene).replace("$PWD/output/paper_demo_1.5s/", self.demo + "/")
            c2 = c2.replace('overrides:="output.bag=stiff_pad.bag"',
                            'overrides:="output.bag=stiff_pad.bag %s" output_dir:=%s/replay' % (SHORT, d))
            rc, out = self.sh(c2.replace("roslaunch ", "roslaunch -p %d " % self.port, 1))
            self.assertEqual(rc, 0, out[-4000:])
            self.assertNotIn("FATAL", out)
            self.assertTrue(os.path.isfile(os.path.join(d, "replay", "stiff_pad.track.bag")), out[-3000:])
            return "the stiff-pad track under the demonstration's flexible bag, to t = 0.05 s"
        m = re.match(r"^\./railsim validate (\S+)(.*)$", c)
        if m:
            if m.group(1) == "my_scene.yaml":
                self.my_scene()
                rc, out = self.sh(c.replace("./railsim", os.path.join(ROOT, "railsim"), 1), cwd=d)
                self.assertEqual(rc, 1, out)
                self.assertIn(expected_comment, out)
                return "a scene made to match the README's error line, which must come out as printed"
            rc, out = self.sh(c)
            self.assertEqual(rc, 0, out[-3000:])
            return "as written"
        if c.startswith("rosrun rail_contact contact_geometry") or c.startswith(
                "/usr/bin/python3 src/rail_contact/scripts/plot_contact_geometry.py"):
            c2 = c.replace("cg.csv", "%s/cg.csv" % d).replace("conicity.csv", "%s/conicity.csv" % d)
            c2 = c2.replace("--out cg", "--out %s/cg" % d)
            rc, out = self.sh(c2)
            self.assertEqual(rc, 0, out[-3000:])
            return "as written, outputs in the test directory"
        self.fail("README command with no rule in test_readme.py: %r" % c)

    def test_every_readme_command(self):
        blocks = readme_blocks()
        self.assertGreater(len(blocks), 5)
        done = []
        # The demonstration first: the replay and the bag-reading example use its bags.
        order = sorted(blocks, key=lambda b: 0 if any(strip_comment(x) == "./railsim run" for x in b[2]) else 1)
        for lang, start, lines in order:
            if lang == "python":
                code = "\n".join(lines).replace("output/paper_demo_1.5s/", self.demo + "/")
                p = subprocess.run(["/usr/bin/python3", "-c", code], capture_output=True, text=True, env=self.env,
                                   cwd=ROOT, timeout=120)
                self.assertEqual(p.returncode, 0, "README line %d: %s" % (start, p.stderr[-2000:]))
                self.assertTrue(p.stdout.strip(), "README line %d printed nothing" % start)
                done.append((start, "python block", "the demonstration's bag"))
                continue
            for i, line in enumerate(lines):
                cmd = strip_comment(line)
                if not cmd or line.lstrip().startswith("#"):
                    continue
                # A comment line right after a command is its expected output.
                nxt = lines[i + 1].lstrip() if i + 1 < len(lines) else ""
                expected = nxt[1:].strip() if nxt.startswith("#") else ""
                with self.subTest(line=start + 1 + i, command=cmd):
                    done.append((start + 1 + i, cmd, self.run_command(cmd, expected)))
        for n, cmd, how in sorted(done):
            print("README line %d: %s: %s" % (n, cmd, how))


def main():
    suite = unittest.TestLoader().loadTestsFromTestCase(Readme)
    return rosunit_main.run(suite, "test_readme", sys.argv[1:])


if __name__ == "__main__":
    sys.exit(main())
