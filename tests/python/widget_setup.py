"""The widget tests' start-up (widget_unit.py, widget_nbclient.py,
widget_jupyterlab.py): their paths from the command line, and a skip (exit
77, never a pass) when a module they need, the CT head of ../shared/data or
the built Python package is missing; then the package first on sys.path.

    PYDIR, OUT, ARGS = widget_setup.start("widget_unit", ["anywidget", "numpy", "PIL"])

Each test's usage: NAME.py [BUILD_PYTHON_DIR [OTHER ...] OUT_DIR], OUT_DIR
last of the arguments it takes (its `n_args`), defaults under
build/release."""
import importlib
import pathlib
import sys

ROOT = pathlib.Path(__file__).resolve().parents[2]
DATA = ROOT.parent / "shared" / "data"
HEAD = DATA / "volumes" / "ct_head.nrrd"


def skip(name, why):
    print("%s: skipped: %s" % (name, why))
    sys.exit(77)


def start(name, modules, n_args=2, extra_skip=None):
    """Checks what test @name needs (@modules importable, the CT head, the
    package built; @extra_skip: None, or a function returning why it cannot
    run) and returns (PYDIR, OUT, args): the package's folder (argument 1),
    the output folder (argument @n_args, default build/release/test-out/NAME)
    and the command line's arguments."""
    args = sys.argv[1:]
    pydir = pathlib.Path(args[0] if args else ROOT / "build" / "release" / "python").resolve()
    out = pathlib.Path(args[n_args - 1] if len(args) >= n_args else
                       ROOT / "build" / "release" / "test-out" / name).resolve()
    for m in modules:
        try:
            importlib.import_module(m)
        except ImportError as e:
            skip(name, "%s (bash scripts/install-deps.sh test makes .venv)" % e)
    why = extra_skip() if extra_skip else None
    if why:
        skip(name, why)
    if not HEAD.exists():
        skip(name, "%s is missing" % HEAD)
    if not (pydir / "volvis" / "widgets.py").exists():
        skip(name, "the Python package was not built in %s" % pydir)
    sys.path.insert(0, str(pydir))
    return pydir, out, args
