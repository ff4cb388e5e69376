#!/usr/bin/env python3
"""Turns shared/protocol.toml into the firmware's C++ header and the host's Python module."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable
from pathlib import Path

from protocolgen.emit_cpp import generate_cpp
from protocolgen.emit_python import generate_python
from protocolgen.parse import DEFINITION, Definition, DefinitionError, parse

REPO_ROOT = Path(__file__).resolve().parent.parent
CPP_OUTPUT = "firmware/lib/protocol/protocol_gen.h"
PY_OUTPUT = "host/particlebot/protocol/generated.py"


def outputs(definition: Definition) -> dict[str, str]:
    return {"cpp": generate_cpp(definition), "py": generate_python(definition)}


def main(argv: Iterable[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--input", type=Path, default=REPO_ROOT / DEFINITION)
    parser.add_argument("--cpp-out", type=Path, default=REPO_ROOT / CPP_OUTPUT)
    parser.add_argument("--py-out", type=Path, default=REPO_ROOT / PY_OUTPUT)
    parser.add_argument(
        "--check",
        action="store_true",
        help="write nothing; exit 1 naming each output that regeneration would change",
    )
    parser.add_argument(
        "--print-hash", action="store_true", help="print the definition hash and write nothing"
    )
    args = parser.parse_args(None if argv is None else list(argv))
    try:
        definition = parse(args.input.read_text(encoding="utf-8"))
    except DefinitionError as error:
        print(f"{args.input}: invalid protocol definition:\n{error}", file=sys.stderr)
        return 2
    if args.print_hash:
        print(f"0x{definition.hash:08X}")
        return 0
    texts = outputs(definition)
    targets = {"cpp": args.cpp_out, "py": args.py_out}
    if args.check:
        stale = [
            path
            for key, path in targets.items()
            if not path.exists() or path.read_text(encoding="utf-8") != texts[key]
        ]
        for path in stale:
            print(f"stale generated file: {path} (run `make generate`)", file=sys.stderr)
        return 1 if stale else 0
    for key, path in targets.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        if not path.exists() or path.read_text(encoding="utf-8") != texts[key]:
            path.write_text(texts[key], encoding="utf-8", newline="\n")
            print(f"wrote {path}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
