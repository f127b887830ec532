"""What the classes owning a library handle share: release on close, ``with`` and garbage collection; and
the options_json text of keyword options."""

import json
import threading

import numpy as np

from . import _native
from .errors import BusyError, InvalidArgumentError

_closing = threading.Lock()  # one close at a time, so that two threads never free one handle twice


def float_array(values):
    """Values as a contiguous float64 array, flattened row by row (the C API's row-major order)."""
    return np.ascontiguousarray(values, dtype=np.float64).reshape(-1)


class OwnedHandle:
    """A handle from the library, released exactly once by the subclass's ``_release`` (its jc_*_free)."""

    _handle = None

    @staticmethod
    def _release(handle):
        raise NotImplementedError

    def close(self):
        """Releases the library's handle; the object cannot be used afterwards.

        While a call on it runs in another thread (or this thread's progress callback runs inside a call on
        it), the library refuses: :class:`jointcomp.BusyError`, and the object stays open and usable; close
        it again when that call has returned."""
        with _closing:
            if self._handle is None:
                return
            status = self._release(self._handle)
            if status != BusyError.status:
                self._handle = None
            _native.check(status)

    def __enter__(self):
        return self

    def __exit__(self, *exception):
        self.close()

    def __del__(self):
        if getattr(self, "_handle", None) is not None and _native is not None and _native.lib is not None:
            self._release(self._handle)
            self._handle = None

    @property
    def handle(self):
        """The C handle, for calls not wrapped here."""
        if self._handle is None:
            raise InvalidArgumentError("this %s was closed" % type(self).__name__)
        return self._handle


def options_json(options):
    """Keyword options as the C API's options_json text (numpy scalars and arrays become plain JSON)."""
    def plain(value):
        if hasattr(value, "tolist"):
            return value.tolist()
        if isinstance(value, (list, tuple)):
            return [plain(v) for v in value]
        return value
    return json.dumps({key: plain(value) for key, value in options.items()}).encode("utf-8")
