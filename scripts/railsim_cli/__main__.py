"""./railsim COMMAND [ARGS]: the one entry point.

  ./railsim run [--full]          the paper's demonstration: three runs, bags, figures and report
  ./railsim run scene.yaml        run one scenario
  ./railsim test                  run every test; the last line is "tests: N passed, M failed"
  ./railsim validate scene.yaml   check a scene without starting ROS (exit 0 valid, 1 refused)
  ./railsim hard-cases [args]     the hard-case suite on every track model (docs/hard_cases.md); args go
                                  to scripts/hard_cases/run_hard_cases.py (default: --subset all)
  ./railsim two-hosts             the two-machine recipe across two network namespaces (root)
  ./railsim setup                 install the Debian packages and build (catkin_make)
"""
import os
import signal
import sys

from . import common, run, test_cmd, two_hosts, validate
from .build import build
from .common import ROOT, Parser, Refused, Stop, log


def usage():
    return "usage: ./railsim COMMAND [ARGS] (./railsim COMMAND -h for a command's own)\n" + __doc__.split("\n\n", 1)[1]


def hard_cases(argv):
    script = os.path.join(ROOT, "scripts", "hard_cases", "run_hard_cases.py")
    if argv[:1] in (["-h"], ["--help"]):
        print("usage: ./railsim hard-cases [args of scripts/hard_cases/run_hard_cases.py] (default: --subset all)\n")
        sys.stdout.flush()
        os.execv("/usr/bin/python3", ["/usr/bin/python3", script, "--help"])
    build()
    args = argv or ["--subset", "all", "--out", os.path.join(ROOT, "output", "hard_cases"), "--docs",
                    os.path.join(ROOT, "output", "hard_cases", "hard_cases.md")]
    log("hard-case suite: scripts/hard_cases/run_hard_cases.py %s" % " ".join(args))
    env = common.ros_env()
    os.execve("/usr/bin/python3", ["/usr/bin/python3", script, "--workspace", ROOT] + args, env)


def setup(argv):
    Parser("setup", "usage: ./railsim setup\n  installs the Debian packages (./railsim does) and builds the workspace",
           unknown="unknown argument '%s' (setup takes none)").parse(argv)
    build()
    log("set up: the workspace is built")
    return 0


COMMANDS = {"run": run.main, "test": test_cmd.main, "validate": validate.main, "hard-cases": hard_cases,
            "two-hosts": two_hosts.main, "setup": setup}


def main():
    command, args = (sys.argv[1], sys.argv[2:]) if len(sys.argv) > 1 else (None, [])
    if command in ("-h", "--help", "help"):
        sys.stdout.write(usage())
        return 0
    if command is None:
        sys.stderr.write(usage())
        return 1
    if command not in COMMANDS:
        log("unknown command '%s'" % command)
        sys.stderr.write(usage())
        return 1
    # Ctrl-C reaches the whole process group: the runs' own runner stops its nodes and reports exit 5; this
    # process waits for it instead of stopping with a traceback.
    signal.signal(signal.SIGINT, lambda *_: None)
    os.makedirs(common.OUTPUT, exist_ok=True)
    try:
        return COMMANDS[command](args)
    except Refused as e:
        log(str(e))
        if e.usage:
            sys.stderr.write(e.usage + "\n")
        return 1
    except Stop as e:
        return e.code


if __name__ == "__main__":
    sys.exit(main())
