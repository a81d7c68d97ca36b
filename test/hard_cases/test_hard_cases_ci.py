#!/usr/bin/env python3
"""CI subset of the hard-case suite (hard_cases.py, subset 'ci': the vehicle alone on the rigid track for
lift-off, two-point contact, standstill, creep speed, derailment and a wheel flat, and the dipped joint and
hanging sleepers on the flexible track, each with its refined run): every check of every case must pass. The runs start their own ROS
masters (rail_analysis.runner.run_case), so no rostest master is needed. Takes about 3 minutes on two cores.

  /usr/bin/python3 test_hard_cases_ci.py [--gtest_output=xml:FILE]
"""
import os
import shutil
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "..", "scripts", "hard_cases"))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", "scripts"))
import hard_cases  # noqa: E402
import rosunit_main  # noqa: E402


class HardCasesCi(unittest.TestCase):
    rows = None

    @classmethod
    def setUpClass(cls):
        cls.out = tempfile.mkdtemp(prefix="hard_cases_ci_")
        ws = os.environ.get("RAILSIM_WORKSPACE", hard_cases.REPO)
        cls.rows, cls.wall = hard_cases.run_suite("ci", hard_cases.MODELS, 2, cls.out, ws, 300.0,
                                                  progress=lambda s: print(s, flush=True))

    @classmethod
    def tearDownClass(cls):
        if all(hard_cases.row_passed(r) for r in cls.rows or []):
            shutil.rmtree(cls.out, ignore_errors=True)   # a failing run's bags and logs are kept

    def _row(self, key):
        rows = [r for r in self.rows if r["case"].key == key]
        self.assertTrue(rows, "case %s did not run" % key)
        return rows[0]

    def _assert_row(self, key):
        r = self._row(key)
        ev = r["eval"]
        for name, st, txt in ev["checks"]:
            self.assertNotEqual(st, "fail", "%s/%s: %s: %s (run %s)" % (key, r["model"], name, txt, r["run"]))
        self.assertNotEqual(ev["converge"][0], "fail", "%s/%s: convergence: %s" % (key, r["model"], ev["converge"][1]))

    def test_lift_off_bump(self):
        self._assert_row("lift_off_bump")

    def test_tight_curve_flange_root(self):
        self._assert_row("tight_curve_flange_root")

    def test_standstill(self):
        self._assert_row("standstill")

    def test_creep_speed(self):
        self._assert_row("creep_speed")

    def test_derailment_climb(self):
        self._assert_row("derailment_climb")

    def test_dipped_joint_impact(self):
        self._assert_row("dipped_joint_impact")

    def test_wheel_flat_impact(self):
        self._assert_row("wheel_flat_impact")

    def test_hanging_sleepers_closing(self):
        self._assert_row("hanging_sleepers_closing")

    def test_every_ci_case_is_asserted(self):
        asserted = {n[len("test_"):] for n in dir(self) if n.startswith("test_") and n != "test_every_ci_case_is_asserted"}
        self.assertEqual({r["case"].key for r in self.rows}, asserted)


def main():
    suite = unittest.TestLoader().loadTestsFromTestCase(HardCasesCi)
    return rosunit_main.run(suite, "test_hard_cases_ci")


if __name__ == "__main__":
    sys.exit(main())
