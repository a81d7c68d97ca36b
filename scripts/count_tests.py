#!/usr/bin/python3
"""Counts the results of every test (gtest, rostest, Python) from the JUnit XML files catkin writes, and
prints the closing line "tests: N passed, M failed". Exits non-zero on any failure or when no test ran.

rostest prints "[Testcase: ...] ok" even for a failed case, and its wrapper file rostest-<name>.xml shows one
passing case however its tests went: the cases are counted from the rosunit-<name>.xml file its test
program wrote, and from the wrapper only its failures (a test program that never ran or crashed). A test
whose program never wrote its results appears as MISSING-*.xml and counts as failed.

usage: count_tests.py <test_results_dir> <log> [--extra NAME 0|1 ...]
"""
import glob
import os
import sys
import xml.etree.ElementTree as ET


def count(results_dir, files=None, complete_only=False):
    """(passed, failed labels) of the XML files under results_dir (or of `files`), as the module's comment
    says. complete_only: a file that does not parse is passed over (a suite still writing it), not failed."""
    passed, failed = 0, []
    if files is None:
        files = sorted(glob.glob(os.path.join(results_dir, "**", "*.xml"), recursive=True))
    for path in files:
        name = os.path.relpath(path, results_dir)
        if os.path.basename(path).startswith("MISSING-"):
            if complete_only and not os.path.getsize(path):
                continue
            failed.append(name + ": the test wrote no results (crashed, timed out or was not built)")
            continue
        try:
            root = ET.parse(path).getroot()
        except ET.ParseError as e:
            if not complete_only:
                failed.append("%s: unreadable results (%s)" % (name, e))
            continue
        wrapper = os.path.basename(path).startswith("rostest-")
        cases = root.iter("testcase")
        n = 0
        for case in cases:
            n += 1
            bad = case.find("failure") is not None or case.find("error") is not None
            label = "%s: %s.%s" % (name, case.get("classname", ""), case.get("name", ""))
            if bad:
                failed.append(label)
            elif not wrapper:
                passed += 1
        if n == 0 and not wrapper:
            # A suite with no case at all: rostest writes this when its test node never ran.
            errors = int(root.get("errors", "0") or 0) + int(root.get("failures", "0") or 0)
            failed.append(name + (": %d errors and no test case" % errors if errors else ": no test case ran"))

    return passed, failed


def main(argv):
    if any(a in ("-h", "--help") for a in argv[1:]):
        print(__doc__)
        return 0
    if len(argv) < 3:
        print("usage: count_tests.py <dir> <log> [--extra NAME 0|1 ...] (--help for more)", file=sys.stderr)
        return 2
    results_dir, log = argv[1], argv[2]
    extras = []
    rest = argv[3:]
    while rest:
        if rest[0] != "--extra" or len(rest) < 3:
            print("usage: count_tests.py <dir> <log> [--extra NAME 0|1 ...]", file=sys.stderr)
            return 2
        extras.append((rest[1], rest[2] == "1"))
        rest = rest[3:]

    passed, failed = count(results_dir)

    for label, ok in extras:
        if ok:
            passed += 1
        else:
            failed.append(label)

    for f in failed:
        print("FAILED " + f)
    if failed:
        print("(details: %s and the XML files under %s)" % (log, results_dir))
    print("tests: %d passed, %d failed" % (passed, len(failed)))
    if passed + len(failed) == 0:
        print("no test ran", file=sys.stderr)
        return 1
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
