"""./railsim test: every test (catkin_make run_tests: gtest, rostest, Python), the colcon build, the naming and
layout checks; each suite on the console as it finishes with the running count; the last line is
"tests: N passed, M failed" (scripts/count_tests.py)."""
import glob
import os
import re
import shutil
import subprocess
import sys
import time

from .build import build, jobs
from .common import OUTPUT, ROOT, Parser, log, loopback_master, ros_env

sys.path.insert(0, os.path.join(ROOT, "scripts"))
import count_tests  # noqa: E402

RESULTS = os.path.join(ROOT, "build", "test_results")
POLL = 1.0  # s between two looks at the test log
PROGRESS_PERIOD = 10.0  # s between two lines of the tests' build percentage

USAGE = """usage: ./railsim test
  builds and runs every test (gtest, rostest, Python), checks that colcon builds the workspace, the naming
  convention and the C++ layout; each suite is said as it finishes; the last line is
  "tests: N passed, M failed" (exit 0 only when none failed). Logs in output/test.log."""


def suite_count():
    """Test suites catkin registered (one add_test each), known once the workspace was configured."""
    n = 0
    for path in glob.glob(os.path.join(ROOT, "build", "**", "CTestTestfile.cmake"), recursive=True):
        with open(path, errors="replace") as f:
            n += sum(1 for line in f if line.startswith("add_test("))
    return n


def run_tests(env, log_path):
    """catkin_make run_tests with a line per finished suite; True when it built and ran (a failing test
    does not fail run_tests: the XML files count those)."""
    total = suite_count()
    verify = re.compile(r'^-- run_tests\.py: verify result "(.+)"')
    percent = re.compile(r"^\[\s*(\d+)%\] Built target (?!_?run_tests)")
    done, failed0 = 0, []
    last_percent_said = time.monotonic()
    with open(log_path, "w") as logf:
        proc = subprocess.Popen(["catkin_make", "-j" + jobs(), "run_tests"], cwd=ROOT, env=env, stdout=logf,
                                stderr=subprocess.STDOUT)
    with open(log_path, errors="replace") as follow:
        pending = ""
        while True:
            finished = proc.poll() is not None
            pending += follow.read()
            *lines, pending = pending.split("\n")
            for line in lines:
                m = verify.match(line)
                if m:
                    # Suites run two at a time: the running count takes the result files that are complete.
                    done += 1
                    passed, failed = count_tests.count(RESULTS, complete_only=True)
                    new_failures = [f for f in failed if f not in failed0]
                    path = m.group(1)
                    name = os.path.relpath(path, RESULTS)
                    if os.path.basename(path).startswith("rostest-"):
                        own = "done"  # its cases are in the test nodes' own files, in the running count
                    else:
                        own_passed, own_failed = count_tests.count(RESULTS, files=[path])
                        own = "%d passed%s" % (own_passed, ", %d FAILED" % len(own_failed) if own_failed else "")
                    log("test %d/%s %s: %s (so far %d passed, %d failed)"
                        % (done, total or "?", name, own, passed, len(failed)))
                    for f in new_failures:
                        log("  FAILED " + f)
                    failed0 = failed
                    continue
                m = percent.match(line)
                if m and done == 0 and time.monotonic() - last_percent_said >= PROGRESS_PERIOD:
                    log("building the tests: %s %%" % m.group(1))
                    last_percent_said = time.monotonic()
            if finished:
                break
            time.sleep(POLL)
    return proc.returncode == 0


def quiet_check(cmd, log_path, env=None):
    """Runs a check with its output to log_path; on failure its last 20 lines on the console."""
    with open(log_path, "w") as f:
        rc = subprocess.run(cmd, cwd=ROOT, env=env, stdout=f, stderr=subprocess.STDOUT).returncode
    if rc != 0:
        with open(log_path, errors="replace") as f:
            sys.stderr.write("".join(f.readlines()[-20:]))
    return rc == 0


def main(argv):
    Parser("test", USAGE, unknown="unknown argument '%s' (test takes none)").parse(argv)
    build()
    env = loopback_master(ros_env())
    shutil.rmtree(RESULTS, ignore_errors=True)
    os.makedirs(OUTPUT, exist_ok=True)
    log("building and running the tests (%d suites; details in output/test.log)" % suite_count())
    started = time.monotonic()
    tests_built = run_tests(env, os.path.join(OUTPUT, "test.log"))
    log("tests ran in %.1f min" % ((time.monotonic() - started) / 60.0))
    log("checking that colcon builds the workspace too")
    colcon_ok = quiet_check(["colcon", "--log-base", os.path.join(OUTPUT, "log_colcon"), "build", "--base-paths", "src",
                             "--build-base", os.path.join(OUTPUT, "build_colcon"), "--install-base",
                             os.path.join(OUTPUT, "install_colcon"), "--cmake-args", "-DCATKIN_ENABLE_TESTING=OFF"],
                            os.path.join(OUTPUT, "colcon.log"), env)
    log("checking the naming convention (.clang-tidy) over every translation unit")
    naming_ok = quiet_check([os.path.join(ROOT, "scripts", "check_naming")], os.path.join(OUTPUT, "naming.log"))
    log("checking the C++ layout (.clang-format) of every C++ file")
    format_ok = quiet_check([os.path.join(ROOT, "scripts", "check_format")], os.path.join(OUTPUT, "format.log"))
    extras = [("build and run of the tests (catkin_make run_tests)", tests_built), ("colcon build", colcon_ok),
              ("naming convention (scripts/check_naming)", naming_ok), ("C++ layout (scripts/check_format)", format_ok)]
    args = ["count_tests.py", RESULTS, os.path.join(OUTPUT, "test.log")]
    for name, ok in extras:
        args += ["--extra", name, "1" if ok else "0"]
    sys.stdout.flush()
    return count_tests.main(args)
