#!/usr/bin/env python3
"""Runs the Python package's pytest suite for CTest (test_python).

Exit status: pytest's when tests failed or errored; 77 (CTest's
SKIP_RETURN_CODE) when pytest is missing or when any test was skipped (a
skipped test is never reported as passed; the skip reasons are printed);
0 when every test ran and passed. pytest's "no tests ran" (5) is a failure.
"""
import sys

try:
    import pytest
except ImportError:
    print("test_python: skipped: pytest (python3-pytest) is not installed")
    sys.exit(77)


class Skips:
    def __init__(self):
        self.skipped = []

    def pytest_runtest_logreport(self, report):
        if report.skipped:
            self.skipped.append("%s: %s" % (report.nodeid, report.longrepr[2]
                                            if isinstance(report.longrepr, tuple) else ""))


def main():
    here = sys.argv[1]
    skips = Skips()
    rc = pytest.main(["-q", "-rs", "-p", "no:cacheprovider", here] + sys.argv[2:],
                     plugins=[skips])
    if rc != 0:
        return int(rc) if int(rc) != 77 else 1
    if skips.skipped:
        print("test_python: skipped tests:\n  " + "\n  ".join(skips.skipped))
        return 77
    return 0


if __name__ == "__main__":
    sys.exit(main())
