"""MATLAB's side without MATLAB: the header parses with a strict C parser (pycparser, about as strict as
loadlibrary's), and every calllib('jointcomp', 'jc_...', args...) in the MATLAB wrapper and example names a
function of the header with as many arguments as it takes."""

import re

from conftest import CHECKOUT, HEADER
from header_parsing import functions, preprocess

MATLAB_FILES = sorted((CHECKOUT / "capi" / "matlab").glob("*.m")) + sorted((CHECKOUT / "examples" / "matlab").glob("*.m"))


def tokens(source):
    """MATLAB tokens (kind, text, line): strings, names, numbers and punctuation; comments and line
    continuations dropped. A quote after a value is the transpose operator, not a string."""
    result = []
    i, line = 0, 1
    while i < len(source):
        c = source[i]
        if c == "\n":
            line += 1
            i += 1
        elif c in " \t\r":
            i += 1
        elif source.startswith("...", i):
            i = source.find("\n", i)  # continuation: the rest of the line is a comment
            i = len(source) if i < 0 else i
        elif c == "%":
            i = source.find("\n", i)
            i = len(source) if i < 0 else i
        elif c in "'\"" and not (c == "'" and result and (result[-1][0] in ("name", "number")
                                                          or result[-1][1] in (")", "]", "}", "'"))):
            j = i + 1
            while True:
                if j >= len(source) or source[j] == "\n":
                    raise AssertionError("unterminated string at line %d" % line)
                if source[j] == c:
                    if source.startswith(c * 2, j):  # doubled quote inside a string
                        j += 2
                        continue
                    break
                j += 1
            result.append(("string", source[i + 1:j].replace(c * 2, c), line))
            i = j + 1
        elif c.isalpha() or c == "_":
            name = re.match(r"[A-Za-z_]\w*", source[i:]).group(0)
            result.append(("name", name, line))
            i += len(name)
        elif c.isdigit() or (c == "." and i + 1 < len(source) and source[i + 1].isdigit()):
            number = re.match(r"(\d+\.?\d*|\.\d+)([eE][+-]?\d+)?", source[i:]).group(0)
            result.append(("number", number, line))
            i += len(number)
        else:
            result.append(("punctuation", c, line))
            i += 1
    return result


def calllib_calls(source):
    """(library, function, argument count, line) of every calllib(...) call."""
    stream = tokens(source)
    calls = []
    for k, (kind, text, line) in enumerate(stream):
        if kind != "name" or text != "calllib" or k + 1 >= len(stream) or stream[k + 1][1] != "(":
            continue
        depth, arguments, current = 0, [], []
        for token in stream[k + 2:]:
            if token[1] in "([{":
                depth += 1
            elif token[1] in ")]}":
                if depth == 0:
                    break
                depth -= 1
            if token[1] == "," and depth == 0:
                arguments.append(current)
                current = []
            else:
                current.append(token)
        else:
            raise AssertionError("unbalanced calllib( at line %d" % line)
        arguments.append(current)
        assert len(arguments) >= 2, "calllib at line %d needs a library and a function" % line
        library, function = arguments[0], arguments[1]
        assert len(library) == 1 and library[0][0] == "string", "line %d: library is not a literal" % line
        assert len(function) == 1 and function[0][0] == "string", "line %d: function is not a literal" % line
        calls.append((library[0][1], function[0][1], len(arguments) - 2, line))
    return calls


def test_header_parses_as_plain_c():
    text = preprocess(HEADER)
    assert "__attribute__" not in text and "extern \"C\"" not in text
    declared = functions(HEADER)
    assert "jc_robot_load" in declared and "jc_spiral_experiment" in declared


def test_tokens_handle_strings_transposes_and_comments():
    source = "x = a' * b'; % calllib('no', 'call')\ny = 'it''s'; z = [q', ...\n 1];\n"
    kinds = [(kind, text) for kind, text, _ in tokens(source)]
    assert ("string", "it's") in kinds
    assert ("string", "no") not in kinds
    assert kinds.count(("punctuation", "'")) == 3
    assert calllib_calls("s = calllib('jointcomp', 'jc_f', a(1, 2), [1, 2], ...\n 'x,y');") == [
        ("jointcomp", "jc_f", 3, 1)]


def test_matlab_calls_match_the_header():
    declared = functions(HEADER)
    assert MATLAB_FILES, "no MATLAB files found"
    called = set()
    for path in MATLAB_FILES:
        for library, function, count, line in calllib_calls(path.read_text()):
            where = "%s:%d" % (path.name, line)
            assert library == "jointcomp", where
            assert function in declared, "%s: %s is not in jointcomp.h" % (where, function)
            expected = len(declared[function][1])
            assert count == expected, "%s: %s takes %d arguments, called with %d" % (where, function, expected, count)
            called.add(function)
    # The wrapper and the example run the spiral: loading, the experiment, the checks, the release.
    for function in ("jc_abi_version", "jc_robot_load", "jc_robot_free", "jc_spiral_experiment", "jc_status_name",
                     "jc_last_error", "jc_forward_kinematics", "jc_spiral_plan"):
        assert function in called, function
