#!/usr/bin/python3
"""Generates the FMU's variable tables from the single source of truth in this folder.

Inputs (modelDescription/):
  variables.csv     one row per FMU variable: vr, name, causality, variability, initial, type, unit,
                    start, min, max, binding, depends, description
  units.csv         the units the variables use, with their SI base-unit exponents
  enumerations.csv  the items of the enumeration types
  model.json        model-level attributes, default experiment, log categories
and the parameter values of the shipped robot (written at build time by fmu/make_resources.cpp), from
which the start values of bound parameters are taken, so that a number is written down only once; its
joint limits become the min and max of the desired joint positions (null: a continuous joint).

Outputs (into --out-dir, in the build tree):
  fmi2/modelDescription.xml, fmi3/modelDescription.xml   the two model descriptions
  jointcomp_fmu_variables.hpp                           the same table for the instance code
  variables.html                                        the table for the FMU's documentation

The binding column says what a variable is to the instance code:
  a role, name or name[index] (time, compensation, q_desired[0], ...): the code refers to it by that name;
  plant:<parameter>, compensator:<parameter>: a named effect parameter of the plant's (true) or the
    compensator's (nominal) joint-error model; drive:<joint>.<field>: a drive or controller parameter;
    integrator:<option>: an option of the plant (CVODE's, or its watchdog's).
The depends column lists the input roles an output depends on directly (empty: none).

Usage: generate.py --tables <dir> --values <parameter-values.json> --version <x.y.z> --out-dir <dir>
Exit status 1 with a message naming the file, row and column for anything inconsistent.
"""

import argparse
import csv
import hashlib
import html
import json
import math
import os
import re
import sys
import uuid
from xml.sax.saxutils import escape, quoteattr

COLUMNS = ["vr", "name", "causality", "variability", "initial", "type", "unit", "start", "min", "max",
           "binding", "depends", "description"]
CAUSALITIES = {"parameter", "input", "output", "independent"}
VARIABILITIES = {"fixed", "tunable", "discrete", "continuous"}
BASE_UNITS = ["kg", "m", "s", "A", "K", "mol", "cd", "rad"]
BINDING_KINDS = {"plant": "effects", "compensator": "effects", "drive": "drives", "integrator": "integrator"}
IDENTIFIER = re.compile(r"[A-Za-z_][A-Za-z0-9_]*")
ROLE = re.compile(r"([A-Za-z_][A-Za-z0-9_]*)(?:\[(\d+)\])?$")


class TableError(Exception):
    pass


def fail(where, what):
    raise TableError(f"{where}: {what}")


def read_csv(path, columns):
    with open(path, newline="", encoding="utf-8") as f:
        reader = csv.reader(f)
        header = next(reader, None)
        if header != columns:
            fail(path, f"header must be {','.join(columns)}, found {','.join(header or [])}")
        rows = []
        for number, cells in enumerate(reader, start=2):
            if not cells or (len(cells) == 1 and not cells[0].strip()):
                continue
            if len(cells) != len(columns):
                fail(f"{path}:{number}", f"{len(cells)} cells, expected {len(columns)}")
            rows.append((f"{path}:{number}", dict(zip(columns, (c.strip() for c in cells)))))
        return rows


def number(where, column, text, integer=False):
    try:
        value = int(text) if integer else float(text)
    except ValueError:
        fail(where, f"{column} '{text}' is not {'an integer' if integer else 'a number'}")
    if not integer and not math.isfinite(value):
        fail(where, f"{column} '{text}' is not finite")
    return value


def real_text(value):
    """Shortest text that reads back to the same double (XML and C++ alike)."""
    return repr(float(value))


def load(tables, values_path):
    units = {}
    for where, row in read_csv(os.path.join(tables, "units.csv"), ["name"] + BASE_UNITS + ["description"]):
        if row["name"] in units:
            fail(where, f"unit '{row['name']}' defined twice")
        units[row["name"]] = {b: number(where, b, row[b], integer=True) for b in BASE_UNITS}
    enumerations = {}
    for where, row in read_csv(os.path.join(tables, "enumerations.csv"), ["type", "item", "value", "description"]):
        if not IDENTIFIER.fullmatch(row["type"]) or not IDENTIFIER.fullmatch(row["item"]):
            fail(where, "type and item must be identifiers")
        items = enumerations.setdefault(row["type"], [])
        value = number(where, "value", row["value"], integer=True)
        if any(i[0] == row["item"] or i[1] == value for i in items):
            fail(where, f"item '{row['item']}' or value {value} appears twice in {row['type']}")
        items.append((row["item"], value, row["description"]))
    with open(os.path.join(tables, "model.json"), encoding="utf-8") as f:
        model = json.load(f)
    with open(values_path, encoding="utf-8") as f:
        values = json.load(f)

    variables = []
    seen_vr, seen_name = {}, {}
    roles = {}
    for where, row in read_csv(os.path.join(tables, "variables.csv"), COLUMNS):
        v = dict(row)
        v["where"] = where
        v["vr"] = number(where, "vr", row["vr"], integer=True)
        if not 0 <= v["vr"] < 2**32:
            fail(where, "vr out of range")
        if v["vr"] in seen_vr:
            fail(where, f"vr {v['vr']} is already used by {seen_vr[v['vr']]}")
        seen_vr[v["vr"]] = where
        name = row["name"]
        if not all(IDENTIFIER.fullmatch(part) for part in name.split(".")):
            fail(where, f"name '{name}' is not a structured name (identifiers separated by dots)")
        if name in seen_name:
            fail(where, f"name '{name}' is already used by {seen_name[name]}")
        seen_name[name] = where
        if row["causality"] not in CAUSALITIES:
            fail(where, f"causality '{row['causality']}' is not one of {sorted(CAUSALITIES)}")
        if row["variability"] not in VARIABILITIES:
            fail(where, f"variability '{row['variability']}' is not one of {sorted(VARIABILITIES)}")
        if row["initial"]:
            fail(where, "initial is left to the FMI defaults (exact for parameters and inputs, calculated for outputs)")
        kind = row["type"]
        v["enum"] = None
        if kind.startswith("Enumeration:"):
            v["enum"] = kind.split(":", 1)[1]
            if v["enum"] not in enumerations:
                fail(where, f"enumeration type '{v['enum']}' is not in enumerations.csv")
            kind = "Enumeration"
        if kind not in ("Real", "Integer", "Boolean", "Enumeration"):
            fail(where, f"type '{row['type']}' is not Real, Integer, Boolean or Enumeration:<type>")
        v["kind"] = kind
        if row["unit"] and kind != "Real":
            fail(where, "only Real variables have units")
        if row["unit"] and row["unit"] not in units:
            fail(where, f"unit '{row['unit']}' is not in units.csv")
        if row["variability"] == "continuous" and kind != "Real":
            fail(where, "only Real variables can be continuous")
        for bound in ("min", "max"):
            v[bound] = None
            if row[bound]:
                if kind not in ("Real", "Integer"):
                    fail(where, f"{bound} is for Real and Integer variables")
                v[bound] = number(where, bound, row[bound], integer=(kind == "Integer"))

        # What the variable is to the code.
        binding = row["binding"]
        v["bind_kind"], v["key"], v["role"] = None, "", None
        if ":" in binding:
            bind_kind, key = binding.split(":", 1)
            if bind_kind not in BINDING_KINDS:
                fail(where, f"binding kind '{bind_kind}' is not one of {sorted(BINDING_KINDS)}")
            if row["causality"] != "parameter":
                fail(where, "only parameters are bound to model parameters")
            section = values.get(BINDING_KINDS[bind_kind], {})
            if key not in section:
                fail(where, f"'{key}' is not among the {BINDING_KINDS[bind_kind]} parameters of the shipped robot "
                            f"(parameter values have: {', '.join(sorted(section))})")
            if row["start"]:
                fail(where, "a bound parameter takes its start value from the parameter file; leave start empty")
            v["bind_kind"], v["key"] = bind_kind, key
            v["start"] = section[key]
        else:
            match = ROLE.fullmatch(binding)
            if not match:
                fail(where, f"binding '{binding}' is neither a role (name or name[index]) nor kind:parameter")
            v["role"] = (match.group(1), match.group(2))
            v["start"] = row["start"]

        # Start values, by causality (the FMI rules for the default initial of each causality).
        causality, start = row["causality"], v["start"]
        if causality in ("parameter", "input"):
            if start == "":
                fail(where, f"{causality}s need a start value")
        elif start != "":
            fail(where, f"{causality}s have no start value")
        if causality == "independent" and (kind != "Real" or row["variability"] != "continuous"):
            fail(where, "the independent variable is a continuous Real")
        if causality == "parameter" and row["variability"] not in ("fixed", "tunable"):
            fail(where, "parameters are fixed or tunable")
        if causality in ("input", "output") and row["variability"] not in ("discrete", "continuous"):
            fail(where, f"{causality}s are discrete or continuous")
        if start != "":
            if kind == "Real":
                v["start"] = number(where, "start", str(start)) if isinstance(start, str) else float(start)
            elif kind == "Boolean":
                if v["bind_kind"] is not None and start in (0, 1, 0.0, 1.0, True, False):
                    start = "true" if start else "false"  # a bound option's value from the parameter file
                if start not in ("true", "false"):
                    fail(where, "a Boolean start is true or false")
                v["start"] = start == "true"
            else:
                v["start"] = number(where, "start", str(start), integer=True) if isinstance(start, str) else start
                if isinstance(v["start"], float):
                    if v["start"] != int(v["start"]):
                        fail(where, "an integer parameter has a fractional value in the parameter file")
                    v["start"] = int(v["start"])
                if kind == "Enumeration" and v["start"] not in [i[1] for i in enumerations[v["enum"]]]:
                    fail(where, f"start {v['start']} is not an item of {v['enum']}")
            if v["min"] is not None and v["start"] < v["min"]:
                fail(where, f"start {v['start']} is below min {v['min']}")
            if v["max"] is not None and v["start"] > v["max"]:
                fail(where, f"start {v['start']} is above max {v['max']}")
        else:
            v["start"] = None
        variables.append(v)

    # The code's table is sorted by value reference; roles and dependencies index into it.
    variables.sort(key=lambda v: v["vr"])
    for position, v in enumerate(variables):
        if v["role"] is None:
            continue
        group, index = v["role"]
        slots = roles.setdefault(group, {"array": index is not None, "members": {}, "causality": v["causality"]})
        if slots["array"] != (index is not None) or slots["causality"] != v["causality"]:
            fail(v["where"], f"role '{group}' is used both as an array and as a scalar, or with two causalities")
        key = int(index) if index is not None else 0
        if key in slots["members"]:
            fail(v["where"], f"role '{v['binding']}' is used twice")
        slots["members"][key] = position
    if sum(1 for v in variables if v["causality"] == "independent") != 1:
        fail("variables.csv", "exactly one variable must be independent (the time)")
    for group, slots in roles.items():
        if slots["array"] and sorted(slots["members"]) != list(range(len(slots["members"]))):
            fail("variables.csv", f"role '{group}' has indices {sorted(slots['members'])}, expected 0..n-1")
    for v in variables:
        v["depends_on"] = []
        for group in v["depends"].split():
            if group not in roles or roles[group]["causality"] != "input":
                fail(v["where"], f"depends on '{group}', which is not an input role")
            v["depends_on"] += [roles[group]["members"][k] for k in sorted(roles[group]["members"])]
        if v["depends"] and v["causality"] != "output":
            fail(v["where"], "only outputs list dependencies")
        v["depends_on"].sort()
    dof = values["dof"]
    for group in ("q_desired", "q_ref", "q_link"):
        if group not in roles or len(roles[group]["members"]) != dof:
            fail("variables.csv", f"role '{group}' must have one variable per joint ({dof})")
    # The desired positions are bounded by the robot's joint limits (from its URDF, through the values
    # file), so that the FMU declares them and refuses a position the robot cannot take.
    limits = values.get("joint_limits")
    if limits is not None:
        for k, index in roles["q_desired"]["members"].items():
            v = variables[index]
            for bound, value in (("min", limits["lower"][k]), ("max", limits["upper"][k])):
                if value is not None and v[bound] is None:
                    v[bound] = float(value)
            if v["start"] is not None and ((v["min"] is not None and v["start"] < v["min"]) or
                                           (v["max"] is not None and v["start"] > v["max"])):
                fail(v["where"], f"start {v['start']} is outside the joint's limits [{v['min']}, {v['max']}]")
    return units, enumerations, model, values, variables, roles


def xml_attributes(pairs):
    return " ".join(f"{k}={quoteattr(str(v))}" for k, v in pairs if v is not None and v != "")


def value_text(v, value):
    if v["kind"] == "Real":
        return real_text(value)
    if v["kind"] == "Boolean":
        return "true" if value else "false"
    return str(int(value))


def unit_definitions(units, used, indent):
    lines = [f"{indent}<UnitDefinitions>"]
    for name, exponents in units.items():
        if name not in used:
            continue
        base = xml_attributes((b, e) for b, e in exponents.items() if e != 0)
        lines.append(f"{indent}  <Unit name={quoteattr(name)}>")
        lines.append(f"{indent}    <BaseUnit {base}/>")
        lines.append(f"{indent}  </Unit>")
    lines.append(f"{indent}</UnitDefinitions>")
    return lines


def log_categories(model, indent):
    lines = [f"{indent}<LogCategories>"]
    for name, description in model["logCategories"]:
        lines.append(f"{indent}  <Category {xml_attributes([('name', name), ('description', description)])}/>")
    lines.append(f"{indent}</LogCategories>")
    return lines


def default_experiment(model, indent):
    e = model["defaultExperiment"]
    return [f"{indent}<DefaultExperiment "
            f"{xml_attributes([(k, real_text(e[k])) for k in ('startTime', 'stopTime', 'stepSize') if k in e])}/>"]


def header_attributes(model, version, token_name, token, fmi_version):
    return xml_attributes([
        ("fmiVersion", fmi_version), ("modelName", model["modelName"]), (token_name, token),
        ("description", model["description"]), ("author", model["author"]), ("version", version),
        ("copyright", model["copyright"]), ("license", model["license"]),
        ("generationTool", "jointcomp modelDescription/generate.py"), ("variableNamingConvention", "structured")])


def fmi2(model, units, enumerations, variables, version, token):
    used = {v["unit"] for v in variables if v["unit"]}
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           f"<fmiModelDescription {header_attributes(model, version, 'guid', token, '2.0')} "
           'numberOfEventIndicators="0">',
           "  <CoSimulation " + xml_attributes([
               ("modelIdentifier", model["modelIdentifier"]), ("canHandleVariableCommunicationStepSize", "true"),
               ("canInterpolateInputs", "false"), ("maxOutputDerivativeOrder", "0"),
               ("canRunAsynchronuously", "false"), ("canBeInstantiatedOnlyOncePerProcess", "false"),
               ("canNotUseMemoryManagementFunctions", "true"), ("canGetAndSetFMUstate", "true"),
               ("canSerializeFMUstate", "true"), ("providesDirectionalDerivative", "false")]) + "/>"]
    out += unit_definitions(units, used, "  ")
    out.append("  <TypeDefinitions>")
    for name, items in enumerations.items():
        out.append(f"    <SimpleType name={quoteattr(name)}>")
        out.append("      <Enumeration>")
        for item, value, description in items:
            out.append(f"        <Item {xml_attributes([('name', item), ('value', value), ('description', description)])}/>")
        out.append("      </Enumeration>")
        out.append("    </SimpleType>")
    out.append("  </TypeDefinitions>")
    out += log_categories(model, "  ")
    out += default_experiment(model, "  ")
    out.append("  <ModelVariables>")
    for index, v in enumerate(variables, start=1):
        out.append(f"    <!-- {index} -->")
        out.append("    <ScalarVariable " + xml_attributes([
            ("name", v["name"]), ("valueReference", v["vr"]), ("description", v["description"]),
            ("causality", v["causality"]), ("variability", v["variability"])]) + ">")
        attributes = []
        if v["enum"]:
            attributes.append(("declaredType", v["enum"]))
        attributes += [("unit", v["unit"]),
                       ("start", None if v["start"] is None else value_text(v, v["start"])),
                       ("min", None if v["min"] is None else value_text(v, v["min"])),
                       ("max", None if v["max"] is None else value_text(v, v["max"]))]
        out.append(f"      <{v['kind']} {xml_attributes(attributes)}/>".replace(" />", "/>"))
        out.append("    </ScalarVariable>")
    out.append("  </ModelVariables>")
    out.append("  <ModelStructure>")
    position = {id(v): i for i, v in enumerate(variables, start=1)}
    outputs = [v for v in variables if v["causality"] == "output"]
    out.append("    <Outputs>")
    for v in outputs:
        deps = " ".join(str(position[id(variables[k])]) for k in v["depends_on"])
        out.append(f'      <Unknown index="{position[id(v)]}" dependencies="{deps}"/>')
    out.append("    </Outputs>")
    out.append("    <InitialUnknowns>")
    for v in outputs:
        out.append(f'      <Unknown index="{position[id(v)]}"/>')
    out.append("    </InitialUnknowns>")
    out.append("  </ModelStructure>")
    out.append("</fmiModelDescription>")
    return "\n".join(out) + "\n"


FMI3_TYPES = {"Real": "Float64", "Integer": "Int32", "Boolean": "Boolean", "Enumeration": "Enumeration"}


def fmi3(model, units, enumerations, variables, version, token):
    used = {v["unit"] for v in variables if v["unit"]}
    out = ['<?xml version="1.0" encoding="UTF-8"?>',
           f"<fmiModelDescription {header_attributes(model, version, 'instantiationToken', token, '3.0')}>",
           "  <CoSimulation " + xml_attributes([
               ("modelIdentifier", model["modelIdentifier"]), ("canBeInstantiatedOnlyOncePerProcess", "false"),
               ("canGetAndSetFMUState", "true"), ("canSerializeFMUState", "true"),
               ("providesDirectionalDerivatives", "false"), ("providesAdjointDerivatives", "false"),
               ("providesPerElementDependencies", "true"),
               ("canHandleVariableCommunicationStepSize", "true"), ("maxOutputDerivativeOrder", "0"),
               ("providesIntermediateUpdate", "false"), ("mightReturnEarlyFromDoStep", "false"),
               ("canReturnEarlyAfterIntermediateUpdate", "false"), ("hasEventMode", "false")]) + "/>"]
    out += unit_definitions(units, used, "  ")
    out.append("  <TypeDefinitions>")
    for name, items in enumerations.items():
        out.append(f"    <EnumerationType name={quoteattr(name)}>")
        for item, value, description in items:
            out.append(f"      <Item {xml_attributes([('name', item), ('value', value), ('description', description)])}/>")
        out.append("    </EnumerationType>")
    out.append("  </TypeDefinitions>")
    out += log_categories(model, "  ")
    out += default_experiment(model, "  ")
    out.append("  <ModelVariables>")
    for v in variables:
        attributes = [("name", v["name"]), ("valueReference", v["vr"]), ("description", v["description"]),
                      ("causality", v["causality"]), ("variability", v["variability"])]
        if v["enum"]:
            attributes.append(("declaredType", v["enum"]))
        attributes += [("unit", v["unit"]),
                       ("start", None if v["start"] is None else value_text(v, v["start"])),
                       ("min", None if v["min"] is None else value_text(v, v["min"])),
                       ("max", None if v["max"] is None else value_text(v, v["max"]))]
        out.append(f"    <{FMI3_TYPES[v['kind']]} {xml_attributes(attributes)}/>")
    out.append("  </ModelVariables>")
    out.append("  <ModelStructure>")
    outputs = [v for v in variables if v["causality"] == "output"]
    for v in outputs:
        deps = " ".join(str(variables[k]["vr"]) for k in v["depends_on"])
        out.append(f'    <Output valueReference="{v["vr"]}" dependencies="{deps}"/>')
    for v in outputs:
        out.append(f'    <InitialUnknown valueReference="{v["vr"]}"/>')
    out.append("  </ModelStructure>")
    out.append("</fmiModelDescription>")
    return "\n".join(out) + "\n"


def cpp_string(text):
    return json.dumps(text, ensure_ascii=True)  # a valid C++ string literal for ASCII and escapes


def cpp_number(v, value, fallback):
    if value is None:
        return fallback
    if v["kind"] == "Real":
        return real_text(value)
    return f"{float(int(value))!r}" if v["kind"] != "Boolean" else ("1.0" if value else "0.0")


def header(model, values, enumerations, variables, roles, token):
    enum_names = {"Real": "Real", "Integer": "Integer", "Boolean": "Boolean", "Enumeration": "Enumeration"}
    bind_names = {None: "None", "plant": "Plant", "compensator": "Compensator", "drive": "Drive",
                  "integrator": "Integrator"}
    out = ["// Generated by modelDescription/generate.py from modelDescription/variables.csv and the shipped",
           "// parameter values; edit those, not this file.",
           "#pragma once",
           "",
           "#include <cstdint>",
           "#include <limits>",
           "",
           "namespace jointcomp::fmu::table {",
           "",
           "enum class Type : std::uint8_t { Real, Integer, Boolean, Enumeration };",
           "enum class Causality : std::uint8_t { Parameter, Input, Output, Independent };",
           "enum class Variability : std::uint8_t { Fixed, Tunable, Discrete, Continuous };",
           "// What a parameter sets in the model (None: the instance code reads it by its role).",
           "enum class Binding : std::uint8_t { None, Plant, Compensator, Drive, Integrator };",
           "",
           "struct Variable {",
           "  std::uint32_t vr;",
           "  const char* name;",
           "  Type type;",
           "  Causality causality;",
           "  Variability variability;",
           "  double start;  // 0 for variables without a start value (outputs, time)",
           "  double min;    // -infinity when there is no minimum; the smallest item of an enumeration",
           "  double max;    // +infinity when there is no maximum; the largest item of an enumeration",
           "  Binding binding;",
           "  const char* key;  // the bound parameter's name in the model, \"\" otherwise",
           "  const char* unit;",
           "};",
           "",
           "inline constexpr double kInfinity = std::numeric_limits<double>::infinity();",
           f"inline constexpr char kModelName[] = {cpp_string(model['modelName'])};",
           f"inline constexpr char kInstantiationToken[] = {cpp_string(token)};",
           f"inline constexpr char kRobotName[] = {cpp_string(values['robot'])};",
           f"inline constexpr int kDof = {values['dof']};",
           f"inline constexpr int kCount = {len(variables)};",
           "",
           "// Sorted by value reference.",
           "inline constexpr Variable kVariables[kCount] = {"]
    causality_names = {"parameter": "Parameter", "input": "Input", "output": "Output", "independent": "Independent"}
    variability_names = {"fixed": "Fixed", "tunable": "Tunable", "discrete": "Discrete", "continuous": "Continuous"}
    for v in variables:
        low, high = v["min"], v["max"]
        if v["enum"]:
            low = min(i[1] for i in enumerations[v["enum"]])
            high = max(i[1] for i in enumerations[v["enum"]])
        out.append(
            f"    {{{v['vr']}u, {cpp_string(v['name'])}, Type::{enum_names[v['kind']]}, "
            f"Causality::{causality_names[v['causality']]}, Variability::{variability_names[v['variability']]}, "
            f"{cpp_number(v, v['start'], '0.0')}, {cpp_number(v, low, '-kInfinity')}, "
            f"{cpp_number(v, high, 'kInfinity')}, Binding::{bind_names[v['bind_kind']]}, "
            f"{cpp_string(v['key'])}, {cpp_string(v['unit'])}}},")
    out.append("};")
    out.append("")
    out.append("// Indices into kVariables of the variables the instance code refers to by name.")
    out.append("namespace role {")
    for group, slots in roles.items():
        members = [slots["members"][k] for k in sorted(slots["members"])]
        if slots["array"]:
            out.append(f"inline constexpr int {group}[{len(members)}] = {{{', '.join(map(str, members))}}};")
        else:
            out.append(f"inline constexpr int {group} = {members[0]};")
    out.append("}  // namespace role")
    out.append("")
    out.append("// The inputs each variable depends on directly (indices into kVariables), as in ModelStructure:")
    out.append("// those of variable i are kDependencies[kDependencyStart[i]] .. kDependencies[kDependencyStart[i + 1] - 1].")
    starts, flat = [0], []
    for v in variables:
        flat += v["depends_on"]
        starts.append(len(flat))
    out.append(f"inline constexpr int kDependencyStart[kCount + 1] = {{{', '.join(map(str, starts))}}};")
    out.append(f"inline constexpr int kDependencies[{max(1, len(flat))}] = {{{', '.join(map(str, flat or [0]))}}};")
    out.append("")
    out.append(f"inline constexpr int kLogCategoryCount = {len(model['logCategories'])};")
    out.append("inline constexpr const char* kLogCategories[kLogCategoryCount] = {"
               + ", ".join(cpp_string(c[0]) for c in model["logCategories"]) + "};")
    out.append("")
    out.append("}  // namespace jointcomp::fmu::table")
    return "\n".join(out) + "\n"


def documentation(model, variables, enumerations, version):
    rows = []
    for v in variables:
        start = "" if v["start"] is None else value_text(v, v["start"])
        kind = v["kind"] + (f" ({v['enum']})" if v["enum"] else "")
        rows.append("<tr>" + "".join(f"<td>{html.escape(str(c))}</td>" for c in (
            v["vr"], v["name"], v["causality"], v["variability"], kind, v["unit"], start, v["description"])) + "</tr>")
    items = "".join(f"<li>{html.escape(t)}: " + ", ".join(f"{html.escape(i)} = {n} ({html.escape(d)})"
                                                           for i, n, d in its) + "</li>"
                    for t, its in enumerations.items())
    return (f"<!DOCTYPE html>\n<html><head><meta charset=\"utf-8\"><title>{html.escape(model['modelName'])} "
            f"variables</title></head><body>\n<h1>{html.escape(model['modelName'])} {html.escape(version)}: "
            "variables</h1>\n<p>Generated from modelDescription/variables.csv.</p>\n"
            f"<ul>{items}</ul>\n<table border=\"1\"><tr><th>vr</th><th>name</th><th>causality</th>"
            "<th>variability</th><th>type</th><th>unit</th><th>start</th><th>description</th></tr>\n"
            + "\n".join(rows) + "\n</table></body></html>\n")


def write(path, text):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    temporary = path + ".tmp"
    with open(temporary, "w", encoding="utf-8", newline="\n") as f:
        f.write(text)
    os.replace(temporary, path)


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--tables", required=True)
    parser.add_argument("--values", required=True)
    parser.add_argument("--version", required=True)
    parser.add_argument("--out-dir", required=True)
    args = parser.parse_args()
    try:
        units, enumerations, model, values, variables, roles = load(args.tables, args.values)
    except (TableError, OSError, json.JSONDecodeError, KeyError) as error:
        print(f"generate.py: {error}", file=sys.stderr)
        return 1
    digest = hashlib.sha256()
    for name in ("variables.csv", "units.csv", "enumerations.csv", "model.json"):
        with open(os.path.join(args.tables, name), "rb") as f:
            digest.update(f.read())
    with open(args.values, "rb") as f:
        digest.update(f.read())
    digest.update(args.version.encode())
    token = "{" + str(uuid.UUID(bytes=digest.digest()[:16], version=5)) + "}"

    write(os.path.join(args.out_dir, "fmi2", "modelDescription.xml"),
          fmi2(model, units, enumerations, variables, args.version, token))
    write(os.path.join(args.out_dir, "fmi3", "modelDescription.xml"),
          fmi3(model, units, enumerations, variables, args.version, token))
    write(os.path.join(args.out_dir, "jointcomp_fmu_variables.hpp"), header(model, values, enumerations, variables, roles, token))
    write(os.path.join(args.out_dir, "variables.html"), documentation(model, variables, enumerations, args.version))
    return 0


if __name__ == "__main__":
    sys.exit(main())
