"""Versions, status names, the last-error message and the exceptions of every status."""

import ctypes
import threading

import pytest

import jointcomp
from jointcomp import _native


def test_versions_agree():
    assert jointcomp.abi_version() == jointcomp.ABI_VERSION == 1
    major, minor, patch = (int(part) for part in jointcomp.version().split("."))
    assert major >= 0 and minor >= 0 and patch >= 0
    assert jointcomp.library_path.endswith("libjointcomp.so.1")


def test_status_names():
    assert jointcomp.status_name(0) == "JC_OK"
    for cls in (jointcomp.InvalidArgumentError, jointcomp.FileError, jointcomp.UnreachableError,
                jointcomp.SolverError, jointcomp.WrongHandleError, jointcomp.OutOfMemoryError,
                jointcomp.InternalError, jointcomp.PlantLimitError, jointcomp.BusyError):
        assert jointcomp.status_name(cls.status) == cls.status_name
    assert jointcomp.status_name(-99) == "JC_UNKNOWN_STATUS"


def test_every_status_becomes_its_exception():
    for status, cls in [(-1, jointcomp.InvalidArgumentError), (-2, jointcomp.FileError),
                        (-3, jointcomp.UnreachableError), (-4, jointcomp.SolverError),
                        (-5, jointcomp.WrongHandleError), (-6, jointcomp.OutOfMemoryError),
                        (-7, jointcomp.InternalError), (-8, jointcomp.PlantLimitError),
                        (-9, jointcomp.BusyError)]:
        with pytest.raises(cls) as raised:
            _native.check(status)
        assert raised.value.status == status
        assert isinstance(raised.value, jointcomp.JointcompError)
    with pytest.raises(jointcomp.JointcompError) as raised:
        _native.check(-42)
    assert raised.value.status == -42
    assert issubclass(jointcomp.InvalidArgumentError, ValueError)
    assert issubclass(jointcomp.OutOfMemoryError, MemoryError)
    _native.check(0)


def test_last_error_is_per_thread_and_cleared_by_success():
    with pytest.raises(jointcomp.InvalidArgumentError, match=r"^jc_average_absolute_deviation: z_len is 0"):
        jointcomp.average_absolute_deviation([])
    assert jointcomp.last_error().startswith("jc_average_absolute_deviation")
    seen_in_thread = []
    thread = threading.Thread(target=lambda: seen_in_thread.append(jointcomp.last_error()))
    thread.start()
    thread.join()
    assert seen_in_thread == [""]
    jointcomp.average_absolute_deviation([1.0])
    assert jointcomp.last_error() == ""


def test_raw_calls_reject_null_pointers():
    # The bindings never pass NULL where the header forbids it; the library checks anyway.
    assert _native.lib.jc_robot_load(None, None, None) == -1
    assert "robot is NULL" in jointcomp.last_error()
    assert _native.lib.jc_robot_dof(None, None) == -1
    assert _native.lib.jc_plant_free(None) == 0
    assert _native.lib.jc_robot_free(None) == 0
    assert _native.lib.jc_plant_create(None, ctypes.byref(ctypes.c_void_p())) == -1
