"""The build every command starts with: catkin_make when a source changed since the last build by this
command, with its progress on the console; nothing (a scan of the tree's times) when none did."""
import os
import re
import subprocess
import sys
import time

from .common import DEVEL, OUTPUT, ROOT, Stop, log

STAMP = os.path.join(ROOT, "build", ".railsim_build_stamp")
# What the build reads: the packages' sources, data and build files.
SOURCE_DIRS = ("src", "test")
SKIP_DIRS = {"__pycache__", ".git"}
PROGRESS_PERIOD = 10.0  # s at least between two progress lines (each says a new percentage)


def jobs():
    return os.environ.get("RAILSIM_JOBS") or str(os.cpu_count() or 1)


def newest_source_time():
    """Newest modification time of a file or folder the build reads (a folder's time catches removals)."""
    newest = os.stat(os.path.join(ROOT, "CMakeLists.txt")).st_mtime if os.path.exists(
        os.path.join(ROOT, "CMakeLists.txt")) else 0.0
    for top in SOURCE_DIRS:
        for base, dirs, files in os.walk(os.path.join(ROOT, top)):
            dirs[:] = [d for d in dirs if d not in SKIP_DIRS]
            newest = max(newest, os.stat(base).st_mtime)
            for f in files:
                try:
                    newest = max(newest, os.lstat(os.path.join(base, f)).st_mtime)
                except OSError:
                    pass
    return newest


def up_to_date():
    try:
        stamp = os.stat(STAMP).st_mtime
    except OSError:
        return False
    return os.path.isfile(os.path.join(DEVEL, "setup.bash")) and newest_source_time() <= stamp


def run_with_progress(cmd, log_path, what):
    """Runs cmd with its output to log_path; says the build's percentage every few seconds. Returns its
    exit code."""
    percent = re.compile(rb"^\[\s*(\d+)%\]")
    last_said, said_percent = time.monotonic(), None
    with open(log_path, "wb") as logf:
        proc = subprocess.Popen(cmd, cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT)
        for line in iter(proc.stdout.readline, b""):
            logf.write(line)
            m = percent.match(line)
            if m and int(m.group(1)) != said_percent and time.monotonic() - last_said >= PROGRESS_PERIOD:
                said_percent = int(m.group(1))
                log("%s: %d %%" % (what, said_percent))
                last_said = time.monotonic()
        return proc.wait()


def build():
    """Builds the workspace unless RAILSIM_NO_BUILD is set or nothing changed since the last build."""
    if os.environ.get("RAILSIM_NO_BUILD"):
        return
    if up_to_date():
        return
    os.makedirs(OUTPUT, exist_ok=True)
    log("building with catkin_make (-j%s)" % jobs())
    started = time.time()
    build_log = os.path.join(OUTPUT, "build.log")
    # compile_commands.json: what scripts/check_naming (clang-tidy) reads.
    rc = run_with_progress(["catkin_make", "-j" + jobs(), "-DCMAKE_BUILD_TYPE=Release",
                            "-DCMAKE_EXPORT_COMPILE_COMMANDS=ON"], build_log, "build")
    if rc != 0:
        with open(build_log, errors="replace") as f:
            tail = f.readlines()[-60:]
        sys.stderr.write("".join(tail))
        log("build failed; the whole log is output/build.log")
        raise Stop(1)
    os.makedirs(os.path.dirname(STAMP), exist_ok=True)
    with open(STAMP, "w") as f:
        f.write("built by ./railsim\n")
    os.utime(STAMP, (started, started))  # a source saved during the build is newer: the next command rebuilds
    log("build done (%.0f s)" % (time.time() - started))
