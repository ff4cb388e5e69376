"""mkdocs hook: each command page shows its command's --help, generated at build time, and the
protocol page shows the messages and parameters of the generated protocol module.

A page marks where a help text goes with `<!-- particlebot-help: simulate -->` (or a subcommand:
`<!-- particlebot-help: fleet init -->`). After the build, every command of the CLI must have a
page under commands/ and every subcommand's help must appear somewhere, or the build fails: the
reference cannot fall behind the parser.
"""

from __future__ import annotations

import argparse
import os
import re
import sys
from pathlib import Path
from typing import Any

from mkdocs.exceptions import PluginError

MARKER = re.compile(r"<!-- particlebot-help:([a-z -]*?) ?-->")
WIDTH = "96"  # argparse wraps to $COLUMNS; fixed so the pages do not depend on the terminal

PROTOCOL = re.compile(r"<!-- particlebot-protocol: (messages|params|hash) -->")

_used: set[tuple[str, ...]] = set()


def _parser() -> argparse.ArgumentParser:
    host = str(Path(__file__).resolve().parents[2] / "host")
    if host not in sys.path:
        sys.path.insert(0, host)
    os.environ["COLUMNS"] = WIDTH
    from particlebot.cli import build_parser

    return build_parser()


def _subparsers(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:  # argparse keeps its subparsers nowhere public
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _find(path: tuple[str, ...]) -> argparse.ArgumentParser:
    parser = _parser()
    for name in path:
        children = _subparsers(parser)
        if name not in children:
            raise PluginError(f"particlebot-help: no command 'particlebot {' '.join(path)}'")
        parser = children[name]
    return parser


def _all_paths(parser: argparse.ArgumentParser, prefix: tuple[str, ...] = ()) -> list[tuple]:
    paths = []
    for name, child in _subparsers(parser).items():
        paths.append((*prefix, name))
        paths.extend(_all_paths(child, (*prefix, name)))
    return paths


def on_pre_build(config: Any) -> None:
    _used.clear()  # `mkdocs serve` builds again in the same process


def on_page_markdown(markdown: str, page: Any, config: Any, files: Any) -> str:
    def help_block(found: re.Match[str]) -> str:
        path = tuple(found.group(1).split())
        _used.add(path)
        text = _find(path).format_help().rstrip()
        command = " ".join(("particlebot", *path))
        return f"```text\n$ {command} --help\n{text}\n```"

    markdown = MARKER.sub(help_block, markdown)
    return PROTOCOL.sub(lambda found: _protocol_table(found.group(1)), markdown)


def _cell(text: str) -> str:
    return " ".join(text.split()).replace("|", "\\|")


def _protocol_table(which: str) -> str:
    """A table from the generated module: the values the firmware defines, never copied by hand."""
    _parser()  # puts host/ on the path
    from particlebot.protocol import generated

    if which == "hash":
        return f"`0x{generated.DEFINITION_HASH:08X}`"
    if which == "params":
        rows = ["| parameter | default | range | meaning |", "| --- | ---: | --- | --- |"]
        for param, spec in generated.PARAM_SPECS.items():
            rows.append(
                f"| `{param.name}` | {spec.default} | {spec.min}-{spec.max} "
                f"| {_cell(spec.description)} |"
            )
        return "\n".join(rows)
    rows = ["| TYPE | message | what it does |", "| ---: | --- | --- |"]
    messages = [
        cls
        for cls in vars(generated).values()
        if isinstance(cls, type)
        and issubclass(cls, generated.Message)
        and cls is not generated.Message
    ]
    for cls in sorted(messages, key=lambda cls: int(cls.MESSAGE_TYPE)):
        doc = (cls.__doc__ or "").split(":", 1)[-1]
        rows.append(f"| 0x{int(cls.MESSAGE_TYPE):02X} | {cls.MESSAGE_TYPE.name} | {_cell(doc)} |")
    return "\n".join(rows)


def on_post_build(config: Any) -> None:
    parser = _parser()
    missing_pages = [
        name
        for name in _subparsers(parser)
        if not (Path(config["docs_dir"]) / "commands" / f"{name}.md").is_file()
    ]
    if missing_pages:
        raise PluginError(f"commands without a page under docs/commands/: {missing_pages}")
    unshown = [" ".join(path) for path in _all_paths(parser) if path not in _used]
    if unshown:
        raise PluginError(f"commands whose --help no page shows: {unshown}")
