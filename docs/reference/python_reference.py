"""Writes the Python package's reference (pydoc HTML, one page per module) and fails on an undocumented name.

usage: /usr/bin/python3 docs/reference/python_reference.py OUT_DIR
(run by docs/build-reference.sh, with JOINTCOMP_LIBRARY naming the library and capi/python on PYTHONPATH)

Every module of the jointcomp package is imported and written with pydoc. A public module, class, function,
method or property (a name without a leading underscore, defined in the package; in a module with __all__,
the names it lists) without a docstring is reported with its file and line, and so is any warning the
package's own code raises while it is imported; either makes the exit status 1.
"""

import importlib
import inspect
import os
import pkgutil
import pydoc
import sys
import warnings


def public_members(module):
    """(name, object) of the module's public classes and functions that the module itself defines."""
    names = getattr(module, "__all__", None)
    if names is None:
        names = [name for name in vars(module) if not name.startswith("_")]
    for name in names:
        value = getattr(module, name, None)
        if (inspect.isclass(value) or inspect.isfunction(value)) and value.__module__ == module.__name__:
            yield name, value


def where(value):
    """file:line of a class or function, for the report."""
    try:
        return "%s:%d" % (inspect.getsourcefile(value), inspect.getsourcelines(value)[1])
    except (OSError, TypeError):
        return getattr(value, "__module__", "?")


def undocumented(module):
    """The public names of the module without a docstring, each as 'file:line: qualified name'."""
    missing = []
    if not (module.__doc__ or "").strip():
        missing.append("%s: module %s" % (module.__file__, module.__name__))
    for name, value in public_members(module):
        if not (value.__doc__ or "").strip() or (inspect.isclass(value) and value.__doc__ is None):
            missing.append("%s: %s.%s" % (where(value), module.__name__, name))
        if not inspect.isclass(value):
            continue
        for member_name, member in vars(value).items():
            if member_name.startswith("_"):
                continue
            target = member.fget if isinstance(member, property) else member
            if isinstance(target, (staticmethod, classmethod)):
                target = target.__func__
            if not inspect.isfunction(target):
                continue
            if not (target.__doc__ or "").strip():
                missing.append("%s: %s.%s.%s" % (where(target), module.__name__, name, member_name))
    return missing


def main():
    out = os.path.abspath(sys.argv[1])
    os.makedirs(out, exist_ok=True)
    import jointcomp
    package_dir = os.path.dirname(jointcomp.__file__)
    modules = ["jointcomp"] + [info.name for info in pkgutil.walk_packages(jointcomp.__path__, "jointcomp.")
                               if not info.name.endswith("__main__")]
    problems = []
    written = []
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        loaded = [importlib.import_module(name) for name in modules]
    for warning in caught:
        if os.path.abspath(warning.filename).startswith(package_dir):
            problems.append("%s:%d: warning: %s" % (warning.filename, warning.lineno, warning.message))
    for module in loaded:
        if module.__name__.split(".")[-1].startswith("_"):
            continue  # private modules are documented for the maintainers, not in the reference
        problems.extend(undocumented(module))
        os.chdir(out)
        pydoc.writedoc(module)
        written.append(module.__name__)
    for problem in problems:
        print("python_reference: " + problem, file=sys.stderr)
    if problems:
        print("python_reference: %d undocumented name(s) or warning(s)" % len(problems), file=sys.stderr)
        return 1
    print("python_reference: %d modules documented in %s" % (len(written), out))
    return 0


if __name__ == "__main__":
    sys.exit(main())
