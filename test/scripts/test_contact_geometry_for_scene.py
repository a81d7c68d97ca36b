#!/usr/bin/env python3
"""contact_geometry_for_scene.py (rail_contact/scripts): a scene's wheelset tabulated with the values the scene
resolves to. Checks: the table equals contact_geometry's with the same values given by hand (the paper scene:
Iberian gauge 1.668 m, back-to-back 1.592 m, r0 0.445 m, 1/20, Q0 from Table 3's 59 480 kg); an override
reaches the table (a wider back-to-back distance narrows the flangeway, so flange contact starts at a smaller
lateral shift); a refused scene and a moving-load scene are reported with exit 2 and a message naming them.

  /usr/bin/python3 test_contact_geometry_for_scene.py [--gtest_output=xml:FILE]
"""
import csv
import os
import subprocess
import sys
import tempfile
import unittest

sys.path.insert(0, os.path.dirname(os.path.realpath(__file__)))
import rosunit_main  # noqa: E402

REPO = os.path.normpath(os.path.join(os.path.dirname(os.path.realpath(__file__)), "..", ".."))
TOOL = os.path.join(REPO, "src", "rail_contact", "scripts", "contact_geometry_for_scene.py")
CG = os.path.join(REPO, "devel", "lib", "rail_contact", "contact_geometry")
SCENE = os.path.join(REPO, "config", "scenes", "paper_demo.yaml")


def rows(path):
    with open(path) as f:
        return list(csv.DictReader(f))


def flange_onset(path):
    """Smallest lateral shift |y| [m] at which the right wheel's contact is on its flange."""
    return min(abs(float(r["y_m"])) for r in rows(path) if r["right_kind"] == "flange")


class ContactGeometryForScene(unittest.TestCase):
    def setUp(self):
        self.dir = tempfile.mkdtemp(prefix="cg_scene_")

    def run_tool(self, *args):
        return subprocess.run([sys.executable, TOOL] + list(args) + ["--workspace", REPO, "--no-plot"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, universal_newlines=True, timeout=120)

    def test_table_is_contact_geometry_with_the_scenes_values(self):
        p = self.run_tool(SCENE, "--out-dir", self.dir)
        self.assertEqual(p.returncode, 0, p.stderr)
        ref = os.path.join(self.dir, "by_hand.csv")
        q0 = 59480.0 * 9.81 / 8.0  # Table 3's masses (config/vehicle/paper_coach.yaml), 8 wheels
        subprocess.run([CG, "--out", ref, "--gauge", "1.668", "--back-to-back", "1.592", "--radius", "0.445",
                        "--inclination", "0.05", "--load", repr(q0), "--speed", "30.5556", "--friction", "0.3"],
                       check=True, stdout=subprocess.DEVNULL, timeout=120)
        got, want = rows(os.path.join(self.dir, "paper_demo.csv")), rows(ref)
        self.assertEqual(len(got), len(want))
        self.assertGreater(len(got), 100)
        for g, w in zip(got, want):
            self.assertEqual(g, w)

    def test_an_override_reaches_the_table(self):
        self.assertEqual(self.run_tool(SCENE, "--out-dir", os.path.join(self.dir, "a"), "--no-load").returncode, 0)
        p = self.run_tool(SCENE, "--out-dir", os.path.join(self.dir, "b"), "--no-load",
                          "--set", "vehicle.back_to_back=1.600")
        self.assertEqual(p.returncode, 0, p.stderr)
        a = flange_onset(os.path.join(self.dir, "a", "paper_demo.csv"))
        b = flange_onset(os.path.join(self.dir, "b", "paper_demo.csv"))
        # 8 mm more back-to-back distance: the flangeway of each wheel is 4 mm narrower (0.1 mm table step).
        self.assertAlmostEqual(a - b, 0.004, delta=0.00021)

    def test_a_refused_scene_is_reported(self):
        p = self.run_tool(SCENE, "--out-dir", self.dir, "--set", "vehicle.back_to_back=2.0")
        self.assertEqual(p.returncode, 2)
        self.assertIn("paper_demo.yaml: vehicle.back_to_back: must be between track.gauge - 0.2 and track.gauge",
                      p.stderr)
        moving = os.path.join(REPO, "config", "scenes", "moving_load.yaml")
        p = self.run_tool(moving, "--out-dir", self.dir)
        self.assertEqual(p.returncode, 2)
        self.assertIn("moving_load.yaml: has no vehicle (a moving-load scene): no wheelset to tabulate", p.stderr)


def main():
    suite = unittest.TestLoader().loadTestsFromTestCase(ContactGeometryForScene)
    return rosunit_main.run(suite, "test_contact_geometry_for_scene")


if __name__ == "__main__":
    sys.exit(main())
