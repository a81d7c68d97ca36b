"""What every subcommand of ./railsim shares: the workspace's paths, the console line, refusals, the ROS
environment of the built workspace and a master of the run's own on loopback."""
import argparse
import os
import re
import subprocess
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
DEVEL = os.path.join(ROOT, "devel")
OUTPUT = os.path.join(ROOT, "output")
VALIDATE = os.path.join(DEVEL, "lib", "rail_core", "railsim_validate_scene")
CHECK_INPUTS = os.path.join(DEVEL, "lib", "railsim_tests", "railsim_check_inputs")

# Exit codes of the runner itself (README, exit codes); the nodes' own come through unchanged.
EXIT_REFUSED = 1
EXIT_INTERRUPTED = 5  # rail_core/exit_codes.hpp kExitInterrupted
EXIT_WRITE_FAILED = 9  # rail_core/exit_codes.hpp kExitWriteFailed


class Refused(Exception):
    """A bad option or argument: one line naming it, then the subcommand's usage, exit 1."""

    def __init__(self, message, usage=None):
        super().__init__(message)
        self.usage = usage


class Stop(Exception):
    """Ends the command with `code` after its message was said."""

    def __init__(self, code):
        super().__init__(code)
        self.code = code


class Parser(argparse.ArgumentParser):
    """argparse with the runner's own refusals: one line naming the option or argument, then the command's
    usage, exit 1 (README). -h prints the usage text and exits 0.
      command: the subcommand's name in the messages; usage_text: its usage;
      unknown: the message of an unknown option or argument (%s: the word);
      needs: the message per option whose value is missing (default "needs a value");
      missing: the message when a required positional argument is missing."""

    def __init__(self, command, usage_text, unknown="unknown option '%s'", needs=None, missing=None):
        super().__init__(prog="./railsim " + command, add_help=False, allow_abbrev=False)
        self.command, self.usage_text, self.unknown = command, usage_text, unknown
        self.needs, self.missing = needs or {}, missing
        self.add_argument("-h", "--help", action="store_true")

    def error(self, message):
        m = re.match(r"unrecognized arguments: (\S+)", message)
        if m:
            raise Refused("%s: %s" % (self.command, self.unknown % m.group(1)), self.usage_text)
        m = re.match(r"argument (-\S+?)(/\S+)?: expected one argument", message)
        if m:
            raise Refused("%s: %s %s" % (self.command, m.group(1), self.needs.get(m.group(1), "needs a value")),
                          self.usage_text)
        if self.missing and "required" in message:
            raise Refused("%s: %s" % (self.command, self.missing), self.usage_text)
        raise Refused("%s: %s" % (self.command, message), self.usage_text)

    def parse(self, argv):
        """The parsed arguments; -h anywhere prints the usage and ends the command with 0."""
        if "-h" in argv or "--help" in argv:
            print(self.usage_text)
            raise Stop(0)
        return self.parse_args(argv)


def log(message):
    sys.stderr.write("[railsim] %s\n" % message)
    sys.stderr.flush()


def user_path(path):
    """A path the user gave, taken from the directory the command was started in."""
    return os.path.abspath(path)


def put(path, text):
    """Writes `text` to `path`. When it cannot (disk full, unwritable): one line naming the file and the
    system's reason, no partial file left, exit 9 (README, exit codes)."""
    try:
        with open(path, "w") as f:
            f.write(text)
    except OSError as e:
        try:
            os.remove(path)
        except OSError:
            pass
        log("cannot write %s: %s" % (path, e.strerror or e))
        raise Stop(EXIT_WRITE_FAILED)


_ros_env = None


def ros_env():
    """os.environ with the built workspace sourced (devel/setup.bash), once per command."""
    global _ros_env
    if _ros_env is None:
        setup = os.path.join(DEVEL, "setup.bash")
        out = subprocess.run(["bash", "-c", 'source "$0" >/dev/null 2>&1 && env -0', setup], capture_output=True,
                             check=True).stdout
        _ros_env = dict(item.split("=", 1) for item in out.decode().split("\0") if "=" in item)
    return dict(_ros_env)


def loopback_master(env):
    """A ROS master of the run's own on the loopback interface, on a port no other run uses."""
    env["ROS_IP"] = "127.0.0.1"
    env.pop("ROS_HOSTNAME", None)
    port = env.get("RAILSIM_MASTER_PORT") or str(20000 + os.getpid() % 20000)
    env["ROS_MASTER_URI"] = "http://127.0.0.1:%s" % port
    return env


def isolation_probe(env):
    """Each launch of a run goes into a network namespace with only loopback (scripts/railsim_isolate); where
    that is not possible the console says why, once."""
    subprocess.run([os.path.join(ROOT, "scripts", "railsim_isolate"), "--probe"], env=env)
    env["RAILSIM_NETNS_QUIET"] = "1"
