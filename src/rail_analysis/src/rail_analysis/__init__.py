"""rail_analysis: loading of railsim bags into numpy arrays (loading), their analysis against the paper's
section 6 (analysis), its figures (figures) and the Markdown report with the railsim_analyze command (report)."""
import sys

# The third-party modules every command needs, checked first: a Python without them (a pyenv or conda
# interpreter ahead of /usr/bin on PATH) gets one line naming the module and the interpreter, not a traceback.
try:
    import matplotlib  # noqa: F401
    import numpy  # noqa: F401
    import yaml  # noqa: F401
except ModuleNotFoundError as missing:
    sys.exit("rail_analysis: %s has no Python module '%s' (Debian: apt install python3-%s), or run the command with "
             "/usr/bin/python3" % (sys.executable, missing.name, missing.name))

from .loading import (AnalysisInputError, MissingTopicError, RUN_NAMES, Run, Scene, bag_topics,  # noqa: F401
                      flange_normal_force, load_contact_points, load_contact_wrenches, load_rail_deflection,
                      load_run, load_wheelset_kinematics, load_yaml)
