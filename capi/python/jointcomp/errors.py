"""Exceptions raised for the status codes of the C API (JC_ERROR_* in jointcomp.h)."""


class JointcompError(Exception):
    """A call into libjointcomp failed. ``status`` is the C status code, the message the library's."""

    status = None
    status_name = "JC_ERROR"

    def __init__(self, message, status=None):
        super().__init__(message)
        if status is not None:
            self.status = status


class InvalidArgumentError(JointcompError, ValueError):
    """JC_ERROR_INVALID_ARGUMENT: a wrong length, NaN or infinity, a value out of range, a closed handle."""

    status, status_name = -1, "JC_ERROR_INVALID_ARGUMENT"


class FileError(JointcompError):
    """JC_ERROR_FILE: an unreadable or malformed URDF or parameter file or text."""

    status, status_name = -2, "JC_ERROR_FILE"


class UnreachableError(JointcompError):
    """JC_ERROR_UNREACHABLE: a pose outside the workspace or the joint limits."""

    status, status_name = -3, "JC_ERROR_UNREACHABLE"


class SolverError(JointcompError):
    """JC_ERROR_SOLVER: an iteration that did not converge, an integrator that failed."""

    status, status_name = -4, "JC_ERROR_SOLVER"


class WrongHandleError(JointcompError):
    """JC_ERROR_WRONG_HANDLE: a handle of another kind, or one already freed."""

    status, status_name = -5, "JC_ERROR_WRONG_HANDLE"


class OutOfMemoryError(JointcompError, MemoryError):
    """JC_ERROR_OUT_OF_MEMORY."""

    status, status_name = -6, "JC_ERROR_OUT_OF_MEMORY"


class InternalError(JointcompError):
    """JC_ERROR_INTERNAL: a bug in jointcomp; please report it with the message."""

    status, status_name = -7, "JC_ERROR_INTERNAL"


class PlantLimitError(JointcompError):
    """JC_ERROR_PLANT_LIMIT: a simulation that left its joint limits or its tracking envelope."""

    status, status_name = -8, "JC_ERROR_PLANT_LIMIT"


class BusyError(JointcompError):
    """JC_ERROR_BUSY: a handle closed while a call (another thread's, or the one whose progress callback is
    running) still uses it; it was not freed, close it again when that call has returned."""

    status, status_name = -9, "JC_ERROR_BUSY"


_BY_STATUS = {cls.status: cls for cls in (InvalidArgumentError, FileError, UnreachableError, SolverError,
                                          WrongHandleError, OutOfMemoryError, InternalError, PlantLimitError,
                                          BusyError)}


def error_for(status, message):
    """The exception for a status code (JointcompError for codes this version does not know)."""
    cls = _BY_STATUS.get(status)
    if cls is None:
        return JointcompError(message, status)
    return cls(message)
