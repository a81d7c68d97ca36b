"""rail_analysis: loading of railsim bags into numpy arrays (loading), their analysis against the paper's
section 6 (analysis), its figures (figures) and the Markdown report with the railsim_analyze command (report)."""
from .loading import (AnalysisInputError, MissingTopicError, RUN_NAMES, Run, Scene, bag_topics,  # noqa: F401
                      flange_normal_force, load_contact_points, load_contact_wrenches, load_rail_deflection,
                      load_run, load_wheelset_kinematics, load_yaml)
