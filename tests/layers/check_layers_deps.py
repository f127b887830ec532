#!/usr/bin/python3
"""The layer order, checked from the compiler's own dependency output.

For every translation unit of the model, the C API, the FMU and the command-line tool (compile_commands.json),
the headers it depends on are read from the depfile the compiler wrote when it was built (-MD), or asked of the
compiler (-MM) when there is none; a header of those folders that no translation unit includes is asked of the
compiler on its own. So every include form counts: quotes or angle brackets, relative paths, sub-folders,
.h/.hpp/.inl, and what a header pulls in behind it.

The order: model/<layer> for the layers of JOINTCOMP_LAYERS in model/CMakeLists.txt, lowest first; then the
tools capi, fmu (with modelDescription, its variable table) and cli, each on top of the whole model and none
of another's but cli of fmu's (export-fmu); tests/, bench/ and examples/ are no one's dependency. Inside fmu,
the generic FMI core (fmu/core, fmu/description/variables.hpp) reaches nothing but itself and model/common. Fails naming each file, the header it
should not reach and both layers.

usage: check_layers_deps.py SOURCE_ROOT BUILD_DIR
"""
import json
import os
import re
import shlex
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor

TOOLS = {"capi": "capi", "fmu": "fmu", "modelDescription": "fmu", "cli": "cli"}
# The one step between tools: the command-line tool exports FMUs (jointcomp export-fmu) from the FMU's sources.
TOOL_USES = {("cli", "fmu")}
NOBODYS = ("tests", "bench", "examples")
# Inside the FMU: the generic FMI core knows nothing of robots. It and the variables' description it builds on
# reach only each other and model/common.
FMU_CORE = ("fmu/core/", "fmu/description/variables.hpp")
FMU_CORE_MAY_REACH = FMU_CORE + ("model/common/",)


def read_layers(root):
    text = open(os.path.join(root, "model", "CMakeLists.txt")).read()
    match = re.search(r"^set\(JOINTCOMP_LAYERS ([^)]*)\)", text, re.M)
    if not match:
        sys.exit("check_layers_deps: no 'set(JOINTCOMP_LAYERS ...)' in model/CMakeLists.txt")
    return match.group(1).split()


def classify(path, root, ranks):
    """(kind, name, rank) of a file under the source root; None outside it (system headers, the build tree)."""
    relative = os.path.relpath(os.path.realpath(path), root)
    if relative.startswith("..") or relative.startswith("build" + os.sep):
        return None
    parts = relative.split(os.sep)
    if parts[0] == "model" and len(parts) > 2:
        return ("layer", parts[1], ranks.get(parts[1], -1))
    if parts[0] in TOOLS:
        return ("tool", TOOLS[parts[0]], len(ranks))
    if parts[0] in NOBODYS:
        return ("nobody", parts[0], len(ranks) + 1)
    return ("other", parts[0], -1)


def depfile_headers(text):
    body = text.replace("\\\n", " ")
    _, _, deps = body.partition(":")
    return [d for d in shlex.split(deps.split("\n")[0])]


def compiler_headers(command, directory, source, language=None):
    args = shlex.split(command)
    out = []
    skip = False
    for a in args:
        if skip:
            skip = False
            continue
        if a in ("-o", "-MF", "-MT", "-MQ"):
            skip = True
            continue
        if a in ("-c", "-MD", "-MMD") or a.endswith((".cpp", ".c", ".cc")) and os.path.isabs(a):
            continue
        out.append(a)
    if language:
        out += ["-x", language]
    out += ["-MM", "-MG", source]
    result = subprocess.run(out, cwd=directory, capture_output=True, text=True)
    if result.returncode != 0:
        raise RuntimeError(f"{source}: the compiler's -MM failed: {result.stderr.strip()[:400]}")
    return depfile_headers(result.stdout)


def core_violation(source, header):
    """Why the FMU core's file `source` may not reach `header` (paths relative to the root), or None."""
    if source.startswith(FMU_CORE) and not header.startswith(FMU_CORE_MAY_REACH):
        return "the generic FMI core reaches beyond fmu/core, fmu/description/variables.hpp and model/common"
    return None


def violation(source_class, header_class):
    kind, name, rank = source_class
    hkind, hname, hrank = header_class
    if hkind == "nobody" and kind != "nobody":
        return f"'{name}' reaches {hname}/, which nothing may depend on"
    if kind == "layer":
        if hkind == "layer" and hrank < 0:
            return f"'{name}' reaches model/{hname}, which is no layer of JOINTCOMP_LAYERS"
        if hkind == "layer" and hrank > rank:
            return f"layer '{name}' reaches the higher layer '{hname}'"
        if hkind == "tool":
            return f"layer '{name}' reaches '{hname}', a tool on top of the model"
    if kind == "tool" and hkind == "tool" and hname != name and (name, hname) not in TOOL_USES:
        return f"tool '{name}' reaches the tool '{hname}' (each stands on the model alone)"
    return None


def main():
    root = os.path.realpath(sys.argv[1])
    build = os.path.realpath(sys.argv[2])
    layers = read_layers(root)
    ranks = {layer: i for i, layer in enumerate(layers)}
    entries = json.load(open(os.path.join(build, "compile_commands.json")))
    checked = {}
    jobs = []
    command_of_folder = {}
    for e in entries:
        source = os.path.realpath(os.path.join(e["directory"], e["file"]))
        c = classify(source, root, ranks)
        if c is None or c[0] not in ("layer", "tool"):
            continue
        command_of_folder.setdefault(os.path.dirname(source), e)
        args = shlex.split(e["command"])
        depfile = None
        if "-o" in args:
            depfile = os.path.join(e["directory"], args[args.index("-o") + 1] + ".d")
        jobs.append((source, c, e, depfile))

    def headers_of(job):
        source, c, e, depfile = job
        deps = None
        if depfile and os.path.exists(depfile):
            # The build's depfile while it is newer than the source and every file it lists (else stale).
            written = os.path.getmtime(depfile)
            listed = depfile_headers(open(depfile).read())
            paths = [os.path.join(e["directory"], d) for d in listed]
            if all(os.path.exists(p) and os.path.getmtime(p) <= written for p in paths + [source]):
                deps = listed
        if deps is None:
            deps = compiler_headers(e["command"], e["directory"], source)
        return source, c, [os.path.realpath(os.path.join(e["directory"], d)) for d in deps]

    with ThreadPoolExecutor(max_workers=2) as pool:
        results = list(pool.map(headers_of, jobs))
    reached = set()
    for source, c, deps in results:
        checked[source] = (c, deps)
        reached.update(deps)
    # Headers no translation unit includes, each on its own with a command of its folder (or its tool's).
    lone = []
    for top in ["model"] + sorted(TOOLS):
        for folder, _, files in os.walk(os.path.join(root, top)):
            for f in files:
                path = os.path.realpath(os.path.join(folder, f))
                if f.endswith((".hpp", ".h", ".inl")) and path not in reached:
                    c = classify(path, root, ranks)
                    e = command_of_folder.get(folder) or next(
                        (v for k, v in command_of_folder.items() if k.startswith(os.path.join(root, top))), None)
                    if c and e:
                        lone.append((path, c, e))
    for path, c, e in lone:
        deps = compiler_headers(e["command"], e["directory"], path, "c++")
        checked[path] = (c, [os.path.realpath(os.path.join(e["directory"], d)) for d in deps])
    problems = []
    for source, (c, deps) in sorted(checked.items()):
        for d in deps:
            hc = classify(d, root, ranks)
            if hc is None or os.path.realpath(d) == source:
                continue
            why = violation(c, hc) or core_violation(os.path.relpath(source, root), os.path.relpath(d, root))
            if why:
                problems.append(f"{os.path.relpath(source, root)}: depends on {os.path.relpath(d, root)}: {why}")
    if not checked:
        sys.exit("check_layers_deps: no translation unit of the model or the tools in compile_commands.json")
    for p in problems:
        print(p, file=sys.stderr)
    if problems:
        print(f"check_layers_deps: {len(problems)} dependencies against the order {' < '.join(layers)} < tools",
              file=sys.stderr)
        return 1
    print(f"check_layers_deps: {len(checked)} files ({len(lone)} headers on their own) follow the order "
          f"{' < '.join(layers)} < capi | fmu | cli")
    return 0


if __name__ == "__main__":
    sys.exit(main())
