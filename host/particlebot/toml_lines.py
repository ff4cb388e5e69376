"""Where each key of a TOML text is written: the one line locator behind every "FILE:LINE: key:
what" message about a TOML file (scenarios, experiments). tomllib gives line numbers for syntax
errors only; this is for the others (a misspelt key, a value out of range)."""

from __future__ import annotations

import re

_HEADER = re.compile(r"^\s*(\[\[?)\s*([^\]]+?)\s*\]\]?\s*(#.*)?$")
_KEY = re.compile(
    r"""^\s*((?:[A-Za-z0-9_\-]+|"[^"]*"|'[^']*')(?:\s*\.\s*(?:[A-Za-z0-9_\-]+|"[^"]*"|'[^']*'))*)\s*="""
)
_STRING = re.compile(r""""(?:[^"\\]|\\.)*"|'[^']*'""")


def key_lines(text: str) -> dict[str, int]:
    """The line (1-based) of every table header and key of a TOML text, by dotted path; the
    n-th [[name]] table is `name[n]` (counted from 1). Keys inside inline tables share the line
    of their parent key. tomllib gives line numbers for syntax errors only: this is for the
    others (a misspelt key, a value out of range)."""
    lines: dict[str, int] = {}
    current = ""
    arrays: dict[str, int] = {}
    depth = 0  # brackets still open from a multi-line array
    in_string = False  # inside a multi-line basic or literal string
    for number, line in enumerate(text.splitlines(), start=1):
        if in_string:
            if line.count('"""') % 2 or line.count("'''") % 2:
                in_string = False
            continue
        if depth > 0:
            depth += _bracket_balance(line)
            continue
        header = _HEADER.match(line)
        if header and not _KEY.match(line):
            name = _dotted(header.group(2))
            if header.group(1) == "[[":
                arrays[name] = arrays.get(name, 0) + 1
                name = f"{name}[{arrays[name]}]"
            else:
                name = _resolve_arrays(name, arrays)
            current = name
            lines.setdefault(current, number)
            continue
        key = _KEY.match(line)
        if key:
            path = _dotted(key.group(1))
            lines.setdefault(f"{current}.{path}" if current else path, number)
            rest = line[key.end() :]
            if rest.count('"""') % 2 or rest.count("'''") % 2:
                in_string = True
            else:
                depth = max(0, _bracket_balance(rest))
    return lines


def _dotted(text: str) -> str:
    """a . "b" . c -> a.b.c (quoted keys with dots inside are beyond this locator)."""
    return ".".join(part.strip().strip("\"'") for part in text.split("."))


def _resolve_arrays(name: str, arrays: dict[str, int]) -> str:
    """[object.extra] after [[object]] belongs to the latest object: `object[n].extra`."""
    parts = name.split(".")
    for cut in range(len(parts), 0, -1):
        head = ".".join(parts[:cut])
        if head in arrays:
            return ".".join([f"{head}[{arrays[head]}]", *parts[cut:]])
    return name


def _bracket_balance(text: str) -> int:
    code = _STRING.sub("", text).split("#", 1)[0]
    return code.count("[") + code.count("{") - code.count("]") - code.count("}")


def line_of(lines: dict[str, int], path: str) -> int:
    """The line of the key at a dotted path (as key_lines names it), or else of the nearest
    table or key above it that is written; 1 when none is (a value given by default)."""
    parts = path.split(".")
    for end in range(len(parts), 0, -1):
        found = lines.get(".".join(parts[:end]))
        if found:
            return found
    return 1
