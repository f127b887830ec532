"""Loading libjointcomp and declaring its C functions for ctypes.

The library is looked for, in this order:

1. the path in the environment variable ``JOINTCOMP_LIBRARY``;
2. an installed tree: ``<prefix>/lib[/<multiarch>]/libjointcomp.so.<ABI>`` when this package lives under
   ``<prefix>/lib`` (``cmake --install``, the .deb: ``<prefix>/lib/python3/dist-packages``);
3. the system's loader (``LD_LIBRARY_PATH``, ``ldconfig``) by its soname ``libjointcomp.so.<ABI>``;
4. the build trees of a source checkout, ``<checkout>/build/*/capi/libjointcomp.so.<ABI>``, newest first.
"""

import ctypes
import glob
import operator
import os
import pathlib

from . import errors

# The binary interface these bindings are written for: JC_ABI_VERSION of jointcomp.h.
ABI_VERSION = 1
SONAME = "libjointcomp.so.%d" % ABI_VERSION

_double_p = ctypes.POINTER(ctypes.c_double)
_int32_p = ctypes.POINTER(ctypes.c_int32)
_int64_p = ctypes.POINTER(ctypes.c_int64)
_handle_p = ctypes.POINTER(ctypes.c_void_p)
_i32 = ctypes.c_int32
_f64 = ctypes.c_double
_text = ctypes.c_char_p
_handle = ctypes.c_void_p
INT32_MAX = 2**31 - 1


class _Int32Argument(ctypes.c_int32):
    """An int32 argument of a C function (array sizes above all), checked: ctypes alone wraps a Python int
    silently into 32 bits, so that 2^32 + 1 values became 1 and a metric of a huge array was that of its first
    value. Refused with an OverflowError naming the number (ctypes reports it as "argument k: ...")."""

    @classmethod
    def from_param(cls, value):
        value = operator.index(value)
        if not -INT32_MAX - 1 <= value <= INT32_MAX:
            raise OverflowError("%d is beyond the library's 32-bit sizes (at most %d values in one call)"
                                % (value, INT32_MAX))
        return ctypes.c_int32(value)


# void (*jc_progress_callback)(const char* message, void* user_data)
PROGRESS_CALLBACK = ctypes.CFUNCTYPE(None, ctypes.c_char_p, ctypes.c_void_p)

# Every function of jointcomp.h: name -> (result type, argument types). test_bindings.py checks this table
# against the header.
PROTOTYPES = {
    "jc_version": (ctypes.c_char_p, []),
    "jc_abi_version": (_i32, []),
    "jc_last_error": (ctypes.c_char_p, []),
    "jc_status_name": (ctypes.c_char_p, [_i32]),
    "jc_set_progress_callback": (_i32, [PROGRESS_CALLBACK, ctypes.c_void_p]),
    "jc_robot_load": (_i32, [_text, _text, _handle_p]),
    "jc_robot_load_json": (_i32, [_text, _text, _handle_p]),
    "jc_robot_load_chain": (_i32, [_text, _text, _text, _text, _text, _handle_p]),
    "jc_robot_free": (_i32, [_handle]),
    "jc_robot_dof": (_i32, [_handle, _int32_p]),
    "jc_robot_name": (_i32, [_handle, ctypes.c_char_p, _i32, _int32_p]),
    "jc_robot_joint_limits": (_i32, [_handle, _double_p, _i32, _double_p, _i32]),
    "jc_robot_has_drives": (_i32, [_handle, _int32_p]),
    "jc_robot_parameters_json": (_i32, [_handle, ctypes.c_char_p, _i32, _int32_p]),
    "jc_robot_tool_target": (_i32, [_handle, _double_p, _i32, _int32_p]),
    "jc_robot_base_frame": (_i32, [_handle, _double_p, _i32, _int32_p]),
    "jc_robot_save": (_i32, [_handle, _text, _text]),
    "jc_robot_set_payload": (_i32, [_handle, _f64, _double_p, _i32]),
    "jc_robot_set_tool_wrench": (_i32, [_handle, _double_p, _i32]),
    "jc_forward_kinematics": (_i32, [_handle, _double_p, _i32, _double_p, _i32]),
    "jc_inverse_kinematics": (_i32, [_handle, _double_p, _i32, _double_p, _i32, _double_p, _i32, _int32_p]),
    "jc_inverse_kinematics_all": (_i32, [_handle, _double_p, _i32, _double_p, _i32, _double_p, _i32, _int32_p]),
    "jc_jacobian": (_i32, [_handle, _double_p, _i32, _double_p, _i32]),
    "jc_gravity_torques": (_i32, [_handle, _double_p, _i32, _double_p, _i32]),
    "jc_predict_joint_errors": (_i32, [_handle, _text, _double_p, _i32, _double_p, _i32, _double_p, _i32]),
    "jc_compensate_point": (_i32, [_handle, _text, _double_p, _i32, _double_p, _i32, _double_p, _i32, _int32_p]),
    "jc_compensate_trajectory": (
        _i32, [_handle, _text, _double_p, _i32, _double_p, _i32, _double_p, _i32, _int32_p, _double_p]),
    "jc_compensate_trajectory_dynamic": (
        _i32, [_handle, _double_p, _i32, _double_p, _i32, _double_p, _i32, _double_p, _i32, _double_p, _i32, _int32_p,
               _double_p]),
    "jc_spiral_sample_count": (_i32, [_handle, _int32_p]),
    "jc_spiral_plan": (_i32, [_handle, _double_p, _i32, _double_p, _i32, _double_p, _i32, _double_p, _i32]),
    "jc_spiral_experiment": (_i32, [_handle, _i32, _double_p, _i32, _double_p, _i32]),
    "jc_plant_create": (_i32, [_handle, _handle_p]),
    "jc_plant_create_with_options": (_i32, [_handle, _text, _handle_p]),
    "jc_plant_free": (_i32, [_handle]),
    "jc_plant_dof": (_i32, [_handle, _int32_p]),
    "jc_plant_reset": (_i32, [_handle, _double_p, _i32, _f64]),
    "jc_plant_set_reference": (_i32, [_handle, _double_p, _i32, _double_p, _i32]),
    "jc_plant_set_tool_wrench": (_i32, [_handle, _double_p, _i32]),
    "jc_plant_set_payload": (_i32, [_handle, _f64, _double_p, _i32]),
    "jc_plant_advance": (_i32, [_handle, _f64]),
    "jc_plant_set_watchdog": (_i32, [_handle, _f64, _f64]),
    "jc_plant_time": (_i32, [_handle, _double_p]),
    "jc_plant_link_positions": (_i32, [_handle, _double_p, _i32]),
    "jc_plant_link_velocities": (_i32, [_handle, _double_p, _i32]),
    "jc_plant_motor_positions": (_i32, [_handle, _double_p, _i32]),
    "jc_plant_motor_velocities": (_i32, [_handle, _double_p, _i32]),
    "jc_plant_motor_torques": (_i32, [_handle, _double_p, _i32]),
    "jc_plant_state": (_i32, [_handle, _double_p, _i32]),
    "jc_plant_statistics": (_i32, [_handle, _int64_p, _i32]),
    "jc_plant_snapshot_size": (_i32, [_handle, _int32_p]),
    "jc_plant_save": (_i32, [_handle, _double_p, _i32]),
    "jc_plant_restore": (_i32, [_handle, _double_p, _i32]),
    "jc_simulate_campaign": (_i32, [_handle, _text, _text]),
    "jc_identify_stiffness": (_i32, [_handle, _text, _text, _handle_p, _handle_p]),
    "jc_identify_transmission_error": (_i32, [_handle, _text, _text, _handle_p, _handle_p]),
    "jc_calibrate": (_i32, [_handle, _text, _text, _text, _handle_p, _handle_p]),
    "jc_discover": (_i32, [_handle, _text, _text, _text, _handle_p, _handle_p]),
    "jc_report_json": (_i32, [_handle, ctypes.c_char_p, _i32, _int32_p]),
    "jc_report_summary": (_i32, [_handle, ctypes.c_char_p, _i32, _int32_p]),
    "jc_report_free": (_i32, [_handle]),
    "jc_accuracy_metrics": (_i32, [_double_p, _i32, _double_p, _i32]),
    "jc_average_absolute_deviation": (_i32, [_double_p, _i32, _double_p]),
    "jc_peak_to_peak_deviation": (_i32, [_double_p, _i32, _double_p]),
    "jc_spiral_experiment_truth": (_i32, [_handle, _handle, _i32, _double_p, _i32, _double_p, _i32]),
    "jc_spiral_job_create": (_i32, [_handle, _i32, _handle_p]),
    "jc_spiral_job_free": (_i32, [_handle]),
    "jc_spiral_job_sizes": (_i32, [_handle, _int32_p, _int32_p]),
    "jc_spiral_job_time": (_i32, [_handle, _double_p, _i32]),
    "jc_spiral_job_parameters": (_i32, [_handle, ctypes.c_char_p, _i32, _int32_p]),
    "jc_spiral_job_run": (_i32, [_handle, _double_p, _i32, ctypes.c_int64, _double_p, _i32, _double_p, _i32]),
    "jc_forward_kinematics_batch": (_i32, [_handle, _i32, _double_p, _i32, _double_p, _i32]),
    "jc_robot_load_text": (_i32, [_text, _text, _handle_p]),
    "jc_identify_and_compensate": (_i32, [_handle, _handle, _text, _double_p, _i32, _handle_p, _handle_p]),
}


def _candidates():
    """Paths (or sonames) to try, in order, and where each comes from."""
    explicit = os.environ.get("JOINTCOMP_LIBRARY")
    if explicit:
        return [(explicit, "JOINTCOMP_LIBRARY")]
    found = []
    here = pathlib.Path(__file__).resolve().parent
    # <prefix>/lib/python3/dist-packages/jointcomp, or a virtual environment's lib/python3.X/site-packages.
    libs = [parent for parent in here.parents if parent.name == "lib"]
    if libs:
        lib = libs[0]
        for path in sorted(glob.glob(str(lib / SONAME)) + glob.glob(str(lib / "*" / SONAME))):
            found.append((path, "the installed tree"))
    found.append((SONAME, "the system's library path"))
    checkout = here.parents[2] if len(here.parents) > 2 else here
    builds = glob.glob(str(checkout / "build" / "*" / "capi" / SONAME))
    for path in sorted(builds, key=os.path.getmtime, reverse=True):
        found.append((path, "a build tree"))
    return found


def _load():
    tried = []
    for path, origin in _candidates():
        try:
            library = ctypes.CDLL(path)
        except OSError as error:
            tried.append("%s (%s): %s" % (path, origin, error))
            if origin == "JOINTCOMP_LIBRARY":
                break
            continue
        for name, (result, arguments) in PROTOTYPES.items():
            function = getattr(library, name)
            function.restype = result
            function.argtypes = [_Int32Argument if a is _i32 else a for a in arguments]
        if library.jc_abi_version() != ABI_VERSION:
            raise ImportError("%s has ABI version %d, these bindings need %d"
                              % (path, library.jc_abi_version(), ABI_VERSION))
        return library, path
    raise ImportError("libjointcomp not found; set JOINTCOMP_LIBRARY to its path. Tried:\n  " + "\n  ".join(tried))


lib, library_path = _load()


def check(status):
    """Raises the exception of a failed call's status, with the library's message."""
    if status != 0:
        raise errors.error_for(status, lib.jc_last_error().decode("utf-8", "replace"))


def text(value, name):
    """A str or path as the C string the library expects."""
    if value is None:
        return None
    if isinstance(value, bytes):
        return value
    if isinstance(value, (str, os.PathLike)):
        return os.fsencode(value)
    raise TypeError("%s must be a str or a path, not %s" % (name, type(value).__name__))


def pointer(array):
    """The data pointer of a contiguous float64 numpy array (None for None)."""
    if array is None:
        return None
    return array.ctypes.data_as(_double_p)
