"""./railsim validate: the resolved scene, or the one error naming file and field."""
import os
import subprocess
import sys

from .build import build
from .common import CHECK_INPUTS, VALIDATE, Parser, Stop, log

USAGE = """usage: ./railsim validate SCENE.yaml [--set key=value ...] [--summary | --hash | --plan | --topics]
  prints the resolved scene (exit 0) or the one error naming file and field (exit 1)"""

OUTPUT_OPTIONS = ("--summary", "--hash", "--plan", "--topics")


def validator(args, cwd=None):
    """railsim_validate_scene's output for args; its error on stderr and exit 1 when the scene is refused."""
    p = subprocess.run([VALIDATE] + list(args), cwd=cwd, stdout=subprocess.PIPE, text=True)
    if p.returncode != 0:
        crashed(VALIDATE, p.returncode)
        raise Stop(1)
    return p.stdout


def crashed(program, returncode):
    """Says so when a checker ended by a signal (it wrote no error of its own): a broken build or library."""
    if returncode < 0:
        log("%s ended by signal %d before it checked the scene (a broken build? rebuild with ./railsim setup)"
            % (program, -returncode))


def check_data(args, cwd=None):
    """What the nodes read beyond the scene (profile, irregularity, vehicle and track data files, against the
    scene's wheel count and sizes): railsim_check_inputs builds the nodes' ROS-free models from them and
    briefly runs them, so whatever a node would refuse is refused here, with the node's message (its
    "error: <message>" line names the file and field). args: the validator's (output options dropped)."""
    if not os.access(CHECK_INPUTS, os.X_OK):
        log("validate: %s is not built: data files not checked" % CHECK_INPUTS)
        return
    a = [x for x in args if x not in OUTPUT_OPTIONS]
    p = subprocess.run([CHECK_INPUTS] + a + ["--steps", "1", "--vehicle-time", "0.0001"], cwd=cwd,
                       stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if p.returncode != 0:
        sys.stderr.write(p.stdout)
        crashed(CHECK_INPUTS, p.returncode)
        raise Stop(1)


def parse(argv):
    """The validator's arguments: the scene, its overrides and the output option."""
    parser = Parser("validate", USAGE, needs={"--set": "needs key=value"}, missing="no scene given")
    parser.add_argument("scene")
    parser.add_argument("--set", action="append", default=[])
    for option in OUTPUT_OPTIONS:
        parser.add_argument(option, action="store_true")
    a = parser.parse(argv)
    args = [a.scene]
    for o in a.set:
        args += ["--set", o]
    return args + [o for o in OUTPUT_OPTIONS if getattr(a, o[2:])]


def main(argv):
    args = parse(argv)
    if not os.access(VALIDATE, os.X_OK):
        build()
    # From the caller's directory, so that the messages name the scene as it was given.
    text = validator(args)
    check_data(args)
    sys.stdout.write(text)
    return 0
