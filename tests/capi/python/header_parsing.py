"""The public header as a strict C parser sees it: pycparser (Debian's python3-pycparser), which like
MATLAB's loadlibrary accepts plain C only. pycparser cannot read glibc's headers, so the include of
stdint.h is replaced by the typedefs it would provide before the C preprocessor runs."""

import subprocess

from pycparser import c_ast, c_parser

STDINT_TYPEDEFS = """
typedef signed char int8_t; typedef short int16_t; typedef int int32_t; typedef long long int64_t;
typedef unsigned char uint8_t; typedef unsigned short uint16_t; typedef unsigned int uint32_t;
typedef unsigned long long uint64_t;
"""


def preprocess(header_path):
    text = header_path.read_text()
    assert "#include <stdint.h>" in text, "the header's only include is expected to be stdint.h"
    text = text.replace("#include <stdint.h>", STDINT_TYPEDEFS)
    return subprocess.run(["gcc", "-E", "-P", "-x", "c", "-std=c99", "-"], input=text, capture_output=True,
                          text=True, check=True).stdout


def type_name(node):
    """A parameter's or result's type as C spells it, e.g. 'const double*', 'jc_robot**'."""
    if isinstance(node, c_ast.PtrDecl):
        return type_name(node.type) + "*"
    if isinstance(node, c_ast.TypeDecl):
        qualifiers = "".join(q + " " for q in node.quals)
        return qualifiers + " ".join(node.type.names)
    raise AssertionError("unexpected type node %r" % node)


def functions(header_path):
    """name -> (result type, [parameter types]) of every function the header declares."""
    ast = c_parser.CParser().parse(preprocess(header_path), filename=str(header_path))
    declared = {}
    for node in ast.ext:
        if isinstance(node, c_ast.Decl) and isinstance(node.type, c_ast.FuncDecl):
            parameters = []
            for parameter in (node.type.args.params if node.type.args else []):
                if isinstance(parameter, c_ast.Typename) and type_name(parameter.type) == "void":
                    continue  # f(void)
                parameters.append(type_name(parameter.type))
            declared[node.name] = (type_name(node.type.type), parameters)
    return declared
