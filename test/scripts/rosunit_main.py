"""The shared main() of the plain-Python test scripts that catkin runs with --gtest_output=xml:FILE (rosunit's
JUnit XML, which ./railsim test counts) and a user runs bare (a verbose text runner)."""
import sys
import unittest


def run(suite, test_name, argv=None, package="railsim_tests"):
    """Runs a unittest suite; with --gtest_output=xml:FILE in argv (default sys.argv) writes rosunit's XML.
    Returns the process exit code: 0 when every test passed, else 1."""
    argv = sys.argv[1:] if argv is None else argv
    xml = [a.split("xml:", 1)[1] for a in argv if a.startswith("--gtest_output=xml:")]
    if xml:
        import rosunit
        result = rosunit.create_xml_runner(package, test_name, xml[0]).run(suite)
        rosunit.print_unittest_summary(result)
    else:
        result = unittest.TextTestRunner(verbosity=2).run(suite)
    return 0 if result.wasSuccessful() else 1
