"""Internal plumbing: the cffi module, status checks, long calls with the GIL
released, progress and Ctrl+C.

A long library call (render, filter, isosurface, voxelize, compress, movie)
runs through :func:`call_long`. cffi releases the GIL around every C call.
From the main thread the call runs on a worker thread while the main thread
waits in short, interruptible steps: it polls the fraction the library
reported (a C-side progress state, so the library's threads never enter
Python), feeds it to the caller's progress callable or tqdm bar, and on
KeyboardInterrupt sets the state's cancel flag, which the library sees at its
next progress report and answers with VV_ERR_CANCELLED; the wait then ends
and KeyboardInterrupt is raised again. Off the main thread (where no
KeyboardInterrupt is delivered) the call runs in the calling thread unless a
progress report was asked for.
"""
import concurrent.futures
import os
import threading

from ._volvis import ffi, lib
from .errors import CancelledError, InvalidError, error_for

_POLL_S = 0.02
_executor_lock = threading.Lock()
_executor = None


def message():
    """The calling thread's library error trace."""
    return ffi.string(lib.vv_error_message()).decode("utf-8", "replace")


def check(status, msg=None):
    """Raises the Error of a non-zero status with the library's message."""
    if status != 0:
        raise error_for(status, message() if msg is None else msg)


def cstr(text):
    """A Python str or path as bytes for a const char * argument (None: NULL)."""
    if text is None:
        return ffi.NULL
    if hasattr(text, "__fspath__"):
        text = text.__fspath__()
    if isinstance(text, bytes):
        return text
    if not isinstance(text, str):
        raise InvalidError("expected a string, got %s" % type(text).__name__)
    return text.encode("utf-8")


def pystr(ptr):
    """A const char * as str ("" for NULL)."""
    return "" if ptr == ffi.NULL else ffi.string(ptr).decode("utf-8", "replace")


def _pool():
    global _executor
    with _executor_lock:
        if _executor is None:
            _executor = concurrent.futures.ThreadPoolExecutor(
                max_workers=32, thread_name_prefix="volvis")
        return _executor


class _Reporter:
    """Feeds fractions to a callable (returning true cancels) or a tqdm bar."""

    def __init__(self, progress, desc):
        self.fn = None
        self.bar = None
        self.own_bar = False
        self.last = -1.0
        if progress is None or progress is False:
            return
        if progress is True:
            try:
                if os.environ.get("VOLVIS_WIDGETS", "1") == "0":
                    from tqdm import tqdm  # text bar: no notebook widget
                else:
                    from tqdm.auto import tqdm
            except ImportError:
                return
            self.bar = tqdm(total=100, desc=desc, unit="%",
                            bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f}% [{elapsed}<{remaining}]")
            self.own_bar = True
        elif hasattr(progress, "update") and hasattr(progress, "total"):
            self.bar = progress
        elif callable(progress):
            self.fn = progress
        else:
            raise InvalidError("progress: expected None, True, a callable or a tqdm bar, got %r"
                               % (progress,))

    @property
    def active(self):
        return self.fn is not None or self.bar is not None

    def update(self, fraction):
        """Reports a fraction; returns True when the caller asked to cancel."""
        if fraction == self.last:
            return False
        self.last = fraction
        if self.bar is not None:
            total = self.bar.total or 100
            target = fraction * total
            if target > self.bar.n:
                self.bar.update(target - self.bar.n)
            return False
        if self.fn is not None:
            return bool(self.fn(fraction))
        return False

    def close(self, ok):
        if ok and self.active:
            self.update(1.0)
        if self.bar is not None and self.own_bar:
            self.bar.close()


def call_long(fn, progress=None, desc="volvis", allow=()):
    """Runs ``fn(vv_progress) -> vv_status`` with progress and Ctrl+C handling
    (see the module docstring); raises the library's Error on failure (but
    for the statuses in ``allow``, returned), KeyboardInterrupt when
    interrupted, CancelledError when the progress callable asked to stop.
    Returns the status (0, or one of ``allow``)."""
    reporter = _Reporter(progress, desc)
    on_main = threading.current_thread() is threading.main_thread()
    state = ffi.gc(lib.vvpy_progress_new(), lib.vvpy_progress_free)
    if state == ffi.NULL:
        raise MemoryError("volvis: out of memory for a progress state")
    prog = lib.vvpy_progress_get(state)

    def work():
        st = fn(prog)
        return st, (message() if st != 0 else "")

    if not on_main and not reporter.active:
        st, msg = work()
        if st in allow:
            return st
        check(st, msg)
        return 0
    fut = _pool().submit(work)
    interrupted = False
    asked = False
    try:
        while True:
            try:
                st, msg = fut.result(timeout=_POLL_S)
                break
            except concurrent.futures.TimeoutError:
                if reporter.update(lib.vvpy_progress_fraction(state)) and not asked:
                    asked = True
                    lib.vvpy_progress_cancel(state)
    except KeyboardInterrupt:
        interrupted = True
        lib.vvpy_progress_cancel(state)
        while True:
            try:
                st, msg = fut.result()
                break
            except KeyboardInterrupt:
                continue
    if not interrupted:
        reporter.update(lib.vvpy_progress_fraction(state))
    reporter.close(st == 0 and not interrupted)
    if interrupted:
        raise KeyboardInterrupt
    if st == lib.VV_ERR_CANCELLED and asked:
        raise CancelledError(msg or "cancelled by the progress callback")
    if st in allow:
        return st
    check(st, msg)
    return 0
