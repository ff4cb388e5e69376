"""tools/gen_protocol.py and its protocolgen package: validation, definition hash, determinism and
the --check mode."""

from __future__ import annotations

import json
import re
import subprocess
import sys
import zlib
from pathlib import Path

import pytest

from particlebot.protocol import DEFINITION_HASH
from protocolgen.parse import DefinitionError, parse
from tests.protocol.protocol_reference import DEFINITION, REPO_ROOT

GENERATOR = REPO_ROOT / "tools" / "gen_protocol.py"
CPP = REPO_ROOT / "firmware" / "lib" / "protocol" / "protocol_gen.h"
PY = REPO_ROOT / "host" / "particlebot" / "protocol" / "generated.py"
TEXT = DEFINITION.read_text()


def _run(*args: str | Path) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, str(GENERATOR), *map(str, args)],
        capture_output=True,
        text=True,
        check=False,
        timeout=60,
    )


def _hash(text: str) -> int:
    return int(parse(text).hash)


def test_check_passes_on_the_committed_outputs() -> None:
    result = _run("--check")
    assert result.returncode == 0, result.stderr


def test_check_fails_and_names_a_tampered_output(tmp_path: Path) -> None:
    cpp, py = tmp_path / "protocol_gen.h", tmp_path / "generated.py"
    cpp.write_text(CPP.read_text())
    py.write_text(PY.read_text())
    assert _run("--check", "--cpp-out", cpp, "--py-out", py).returncode == 0
    py.write_text(PY.read_text().replace("MAX_PAYLOAD = 48", "MAX_PAYLOAD = 47"))
    result = _run("--check", "--cpp-out", cpp, "--py-out", py)
    assert result.returncode == 1
    assert str(py) in result.stderr
    assert str(cpp) not in result.stderr
    assert py.read_text() != PY.read_text()  # --check writes nothing


def test_check_fails_when_the_definition_changed(tmp_path: Path) -> None:
    definition = tmp_path / "protocol.toml"
    definition.write_text(
        TEXT.replace('name = "uptime_ms", type = "u32"', 'name = "uptime_ms", type = "u16"')
    )
    result = _run("--check", "--input", definition, "--cpp-out", CPP, "--py-out", PY)
    assert result.returncode == 1
    assert str(CPP) in result.stderr and str(PY) in result.stderr


def test_generation_is_deterministic_and_reproduces_the_committed_files(tmp_path: Path) -> None:
    for run in ("first", "second"):
        out = tmp_path / run
        result = _run("--cpp-out", out / "protocol_gen.h", "--py-out", out / "generated.py")
        assert result.returncode == 0, result.stderr
    for name, committed in (("protocol_gen.h", CPP), ("generated.py", PY)):
        first = (tmp_path / "first" / name).read_bytes()
        assert first == (tmp_path / "second" / name).read_bytes()
        assert first == committed.read_bytes()


def test_outputs_open_with_a_purpose_line_then_the_generated_notice() -> None:
    for path in (CPP, PY):
        lines = path.read_text().splitlines()
        notice = "generated from shared/protocol.toml by tools/gen_protocol.py; do not edit"
        assert notice in " ".join(lines[:3]).lower()
        assert f"{DEFINITION_HASH:08X}" in path.read_text()


def test_hash_is_crc32_of_the_canonical_json_and_matches_both_outputs() -> None:
    definition = parse(TEXT)
    canonical = json.dumps(definition.canonical(), sort_keys=True, separators=(",", ":"))
    assert "description" not in canonical
    assert definition.hash == zlib.crc32(canonical.encode()) == DEFINITION_HASH
    assert f"kDefinitionHash = 0x{DEFINITION_HASH:08X}UL;" in CPP.read_text()
    assert _run("--print-hash").stdout.strip() == f"0x{DEFINITION_HASH:08X}"


def test_hash_is_unchanged_when_only_a_description_changes() -> None:
    edited = TEXT.replace(
        'description = "Ask for a STATUS frame now."',
        'description = "Ask the particle for a STATUS frame right away."',
    )
    edited = edited.replace("Contracted and waiting for START.", "Contracted, waiting.")
    assert edited.count("right away") == 1 and "Contracted, waiting." in edited
    assert _hash(edited) == _hash(TEXT)


@pytest.mark.parametrize(
    ("old", "new"),
    [
        ('name = "uptime_ms", type = "u32"', 'name = "uptime_ms", type = "i32"'),
        ('name = "sensors", type = "u16", count = 6', 'name = "sensors", type = "u16", count = 5'),
        ('name = "round", type = "u16"', 'name = "rounds", type = "u16"'),
        ("id = 0x05", "id = 0x09"),
        ("max_payload = 48", "max_payload = 47"),
        ("IDLE = { value = 0,", "IDLE = { value = 9,"),
        ("default = 150, min = 10,", "default = 151, min = 10,"),
    ],
    ids=["field_type", "array_count", "field_name", "message_id", "max_payload", "enum", "default"],
)
def test_hash_changes_with_the_layout_or_meaning(old: str, new: str) -> None:
    assert TEXT.count(old) == 1
    assert _hash(TEXT.replace(old, new)) != _hash(TEXT)


@pytest.mark.parametrize(
    ("old", "new", "complaint"),
    [
        ("id = 0x05", "id = 0x04", "already used"),
        ('name = "PING"', 'name = "STOP"', "name used twice"),
        ('name = "uptime_ms", type = "u32"', 'name = "uptime_ms", type = "f32"', "unknown type"),
        ('enum = "param_result"', 'enum = "param_results"', "unknown enum"),
        ("count = 6", "count = 20", "exceeds max_payload"),
        ("default = 150, min = 10,", "default = 5, min = 10,", "outside 10..3000"),
        ("DONE = { value = 6,", "DONE = { value = 5,", "already used"),
        ('name = "resets", type = "u8"', 'name = "rx_frames", type = "u8"', "used twice"),
        ('from = "base"', 'from = "nobody"', "from must be"),
        (
            '{ name = "new_id", type = "u8",',
            '{ name = "new_id", type = "u8", size = 3,',
            "unknown key",
        ),
    ],
)
def test_invalid_definitions_are_refused_with_a_reason(
    tmp_path: Path, old: str, new: str, complaint: str
) -> None:
    assert old in TEXT
    with pytest.raises(DefinitionError, match=re.escape(complaint)):
        parse(TEXT.replace(old, new, 1))
    definition = tmp_path / "protocol.toml"
    definition.write_text(TEXT.replace(old, new, 1))
    result = _run(
        "--input", definition, "--cpp-out", tmp_path / "a.h", "--py-out", tmp_path / "b.py"
    )
    assert result.returncode == 2
    assert complaint in result.stderr
    assert not (tmp_path / "a.h").exists()
