"""Errors of the volvis package: one class per library status.

Every failure of the library raises a subclass of :class:`Error` whose
message is the library's thread-local error trace (``vv_error_message()``),
e.g. ``slc: nut.slc: slice 12: run of 40 bytes overflows the slice``.

=====================  =========================  ==========================
library status         class                      also a
=====================  =========================  ==========================
VV_ERR_NOMEM           :class:`NoMemoryError`     ``MemoryError``
VV_ERR_IO              :class:`FileError`         ``OSError``
VV_ERR_FORMAT          :class:`FormatError`       ``ValueError``
VV_ERR_INVALID         :class:`InvalidError`      ``ValueError``
VV_ERR_UNSUPPORTED     :class:`UnsupportedError`  ``NotImplementedError``
VV_ERR_LIMIT           :class:`LimitError`        ``ValueError``
VV_ERR_CANCELLED       :class:`CancelledError`
=====================  =========================  ==========================

A render or another long operation interrupted by Ctrl+C raises
``KeyboardInterrupt`` (the library was cancelled through its progress
callback and has returned); one stopped by a progress callable returning a
true value raises :class:`CancelledError`.
"""

__all__ = ["Error", "NoMemoryError", "FileError", "FormatError", "InvalidError",
           "UnsupportedError", "LimitError", "CancelledError"]


class Error(Exception):
    """A library error. ``status`` is the vv_status value (negative) and
    ``status_name`` its constant name ("VV_ERR_FORMAT"); ``str(e)`` is the
    library's message."""

    status = None
    status_name = "VV_ERR"

    def __init__(self, message, status=None):
        super().__init__(message)
        if status is not None:
            self.status = status

    def __str__(self):
        return self.args[0] if self.args else ""


class NoMemoryError(Error, MemoryError):
    """VV_ERR_NOMEM: an allocation failed."""
    status, status_name = -1, "VV_ERR_NOMEM"


class FileError(Error, OSError):
    """VV_ERR_IO: a file could not be opened, read or written."""
    status, status_name = -2, "VV_ERR_IO"

    def __str__(self):
        return self.args[0] if self.args else ""


class FormatError(Error, ValueError):
    """VV_ERR_FORMAT: a file is malformed, truncated or not of its format."""
    status, status_name = -3, "VV_ERR_FORMAT"


class InvalidError(Error, ValueError):
    """VV_ERR_INVALID: an argument is out of its domain."""
    status, status_name = -4, "VV_ERR_INVALID"


class UnsupportedError(Error, NotImplementedError):
    """VV_ERR_UNSUPPORTED: valid, but not something this build can do."""
    status, status_name = -5, "VV_ERR_UNSUPPORTED"


class LimitError(Error, ValueError):
    """VV_ERR_LIMIT: a size is over a limit (absurd header, overflow, memory budget)."""
    status, status_name = -6, "VV_ERR_LIMIT"


class CancelledError(Error):
    """VV_ERR_CANCELLED: a progress callback asked the operation to stop."""
    status, status_name = -7, "VV_ERR_CANCELLED"


_BY_STATUS = {c.status: c for c in (NoMemoryError, FileError, FormatError, InvalidError,
                                     UnsupportedError, LimitError, CancelledError)}


def error_for(status, message):
    """The exception for a vv_status and its message (never for VV_OK)."""
    cls = _BY_STATUS.get(status, Error)
    if cls is Error:
        return Error("%s (status %d)" % (message, status), status)
    return cls(message)
