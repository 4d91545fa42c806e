"""The ``volvis`` command of the pip wheel (pyproject.toml,
``[project.scripts]``): runs the volvis program the wheel carries in the
package, volvis/bin/volvis, in place of this process.

The program finds what it needs relative to itself: volvis-reader in
volvis/libexec, the browser client of ``volvis serve`` in
volvis/share/volvis/web, the device files in volvis/share/volvis/devices.
"""
import os
import sys


def program():
    """The path of the volvis program shipped in this package."""
    return os.path.join(os.path.dirname(os.path.abspath(__file__)), "bin", "volvis")


def main():
    exe = program()
    if not os.access(exe, os.X_OK):
        sys.stderr.write("volvis: %s is missing: this volvis package was not installed "
                         "from the wheel (pip install volvis-*.whl)\n" % exe)
        return 127
    os.execv(exe, ["volvis"] + sys.argv[1:])
    return 127  # not reached: execv returns only by raising


if __name__ == "__main__":
    sys.exit(main())
