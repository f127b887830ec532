"""The bindings and the tests keep up with the header: every function of jointcomp.h has a ctypes prototype
of the same types, is used by the Python package, and is called by the C test (tests/capi/test_capi.c)."""

import ctypes
import inspect
import pathlib
import re

import jointcomp
from jointcomp import _native
from conftest import CHECKOUT, HEADER
from header_parsing import functions

C_TO_CTYPES = {
    "jc_status": ctypes.c_int32,
    "int32_t": ctypes.c_int32,
    "double": ctypes.c_double,
    "const char*": ctypes.c_char_p,
    "char*": ctypes.c_char_p,
    "const double*": ctypes.POINTER(ctypes.c_double),
    "double*": ctypes.POINTER(ctypes.c_double),
    "int32_t*": ctypes.POINTER(ctypes.c_int32),
    "int64_t*": ctypes.POINTER(ctypes.c_int64),
    "int64_t": ctypes.c_int64,
    "jc_spiral_job*": ctypes.c_void_p,
    "jc_spiral_job**": ctypes.POINTER(ctypes.c_void_p),
    "jc_robot*": ctypes.c_void_p,
    "jc_plant*": ctypes.c_void_p,
    "jc_robot**": ctypes.POINTER(ctypes.c_void_p),
    "jc_plant**": ctypes.POINTER(ctypes.c_void_p),
    "jc_report*": ctypes.c_void_p,
    "jc_report**": ctypes.POINTER(ctypes.c_void_p),
    "jc_progress_callback": _native.PROGRESS_CALLBACK,
    "void*": ctypes.c_void_p,
}


def test_prototypes_match_the_header():
    declared = functions(HEADER)
    assert len(declared) >= 40
    assert set(declared) == set(_native.PROTOTYPES)
    for name, (result, parameters) in declared.items():
        prototype_result, prototype_arguments = _native.PROTOTYPES[name]
        assert C_TO_CTYPES[result] is prototype_result, name
        assert [C_TO_CTYPES[p] for p in parameters] == prototype_arguments, name


def test_every_function_is_used_by_the_package_and_the_c_test():
    package = pathlib.Path(jointcomp.__file__).parent
    sources = "".join(path.read_text() for path in package.glob("*.py") if path.name != "_native.py")
    c_test = "".join(path.read_text() for path in (CHECKOUT / "tests" / "capi").glob("test_capi*.c"))
    for name in functions(HEADER):
        assert re.search(r"\blib\.%s\b" % name, sources), name + " is not wrapped"
        assert name + "(" in c_test, name + " is not called by tests/capi/test_capi*.c"


def test_public_api_has_docstrings():
    for name in jointcomp.__all__:
        member = getattr(jointcomp, name)
        if inspect.isclass(member) or inspect.isfunction(member):
            assert member.__doc__, name
            for attribute, value in vars(member).items() if inspect.isclass(member) else []:
                if not attribute.startswith("_") and (inspect.isfunction(value) or isinstance(value, property)):
                    assert value.__doc__ or attribute in ("dof",), name + "." + attribute
