"""Independent references for the protocol tests: bitwise CRC, naive frame scan, vectors loader."""

from __future__ import annotations

import tomllib
from dataclasses import dataclass, field
from typing import Any

from tests.support.repo import REPO_ROOT

VECTORS = REPO_ROOT / "shared" / "vectors.toml"
DEFINITION = REPO_ROOT / "shared" / "protocol.toml"

SYNC0, SYNC1, MAX_PAYLOAD = 0xA5, 0x5A, 48


def bitwise_crc16(data: bytes) -> int:
    """CRC-16/CCITT-FALSE one bit at a time, straight from its definition."""
    crc = 0xFFFF
    for byte in data:
        crc ^= byte << 8
        for _ in range(8):
            crc = ((crc << 1) ^ 0x1021) if crc & 0x8000 else crc << 1
            crc &= 0xFFFF
    return crc


@dataclass
class ScanResult:
    frames: list[tuple[int, int, int, bytes]] = field(default_factory=list)
    counts: dict[str, int] = field(
        default_factory=lambda: dict.fromkeys(
            ("frames", "bad_crc", "bad_length", "truncated", "skipped_bytes"), 0
        )
    )


def reference_scan(stream: bytes) -> ScanResult:
    """What a resynchronising decoder must make of a whole, ended stream, position by position:
    a failed candidate resumes at the byte after its sync marker."""
    result = ScanResult()
    i, n = 0, len(stream)
    while i < n:
        if stream[i] != SYNC0 or i + 1 >= n or stream[i + 1] != SYNC1:
            result.counts["skipped_bytes"] += 1
            i += 1
            continue
        if i + 2 >= n:
            result.counts["truncated"] += 1
            i += 2
            continue
        length = stream[i + 2]
        if length > MAX_PAYLOAD:
            result.counts["bad_length"] += 1
            i += 2
            continue
        end = i + 8 + length
        if end > n:
            result.counts["truncated"] += 1
            i += 2
            continue
        if bitwise_crc16(stream[i + 2 : end - 2]) != stream[end - 2] | stream[end - 1] << 8:
            result.counts["bad_crc"] += 1
            i += 2
            continue
        result.frames.append((stream[i + 3], stream[i + 4], stream[i + 5], stream[i + 6 : end - 2]))
        result.counts["frames"] += 1
        i = end
    return result


def hex_bytes(text: str) -> bytes:
    return bytes.fromhex(text.replace(" ", ""))


def load_vectors() -> dict[str, Any]:
    with VECTORS.open("rb") as handle:
        return tomllib.load(handle)
