"""A World's snapshot as data: its arrays, and its set-up (parameters, controller, random state)
as JSON whose objects may only be of the types listed here, so that reading a run folder from
someone else can never run code (no pickle anywhere on the way in)."""

from __future__ import annotations

import dataclasses
import importlib
import json
import zipfile
import zlib
from dataclasses import dataclass, field
from enum import Enum
from pathlib import Path
from typing import Any

import numpy as np
import numpy.typing as npt

from particlebot.errors import ParticlebotError

FORMAT = 2
"""Snapshots of format 1 held their set-up as a pickle; they are refused, not read."""
SETUP_KEY = "setup.json"
SETUP_ARRAY = "setup.array."
"""Arrays inside the set-up (a controller's state) are stored beside the world's under this."""
TYPES = frozenset(
    {
        "particlebot.firmware.native.FirmwareConstants",
        "particlebot.protocol.generated.Method",
        "particlebot.sim.particles.model.estimation.EstimationParams",
        "particlebot.sim.particles.model.estimation.GroupEstimator",
        "particlebot.sim.particles.model.firmware.EpochPlans",
        "particlebot.sim.particles.model.firmware.FirmwareController",
        "particlebot.sim.particles.model.firmware.FirmwareSettings",
        "particlebot.sim.particles.model.published.PublishedController",
        "particlebot.sim.particles.model.published.PublishedSettings",
        "particlebot.sim.world.arena.Arena",
        "particlebot.sim.world.arena.Circle",
        "particlebot.sim.world.arena.Rect",
        "particlebot.sim.world.bodies.DeadParticles",
        "particlebot.sim.world.bodies.PassiveObject",
        "particlebot.sim.world.light.Lamp",
        "particlebot.sim.world.light.ShadowMode",
        "particlebot.sim.world.params.NeighbourSearch",
        "particlebot.sim.world.params.PhysicsParams",
    }
)
"""The only classes a snapshot's set-up may hold (by module and name). Reading one builds them
field by field without calling any of their code; a new controller adds its types here (a
snapshot of an unlisted type fails when written, never silently later)."""
GENERATORS = frozenset({"PCG64", "PCG64DXSM", "Philox", "SFC64", "MT19937"})


class SnapshotError(ParticlebotError, ValueError):
    """A snapshot that cannot be read: damaged, cut short, of an old format, or not one at all."""


@dataclass
class Snapshot:
    """Everything a World needs to continue exactly where it was: its set-up (parameters, the
    controller with its state, the random generator's state) and every array in the kernels'
    order. `save`/`load` keep it in a compressed .npz read with allow_pickle=False."""

    setup: dict[str, Any]
    arrays: dict[str, npt.NDArray[Any]] = field(default_factory=dict)

    def save(self, path: Any) -> None:
        """Writes the snapshot as a compressed .npz at path (a str or Path ending in .npz)."""
        held: dict[str, npt.NDArray[Any]] = {}
        tree = _encode(self.setup, held)
        text = json.dumps({"format": FORMAT, "setup": tree})
        blob = np.frombuffer(text.encode("utf-8"), dtype=np.uint8)
        contents: dict[str, Any] = {SETUP_KEY: blob, **held, **self.arrays}
        np.savez_compressed(path, **contents)

    @staticmethod
    def load(path: Any) -> Snapshot:
        """Reads a snapshot save() wrote; SnapshotError naming the file when it cannot be."""
        name = Path(path)
        try:
            with np.load(path, allow_pickle=False) as data:
                files = set(data.files)
                if SETUP_KEY not in files:
                    old = "setup" in files
                    raise SnapshotError(
                        f"{name}: written by an older particlebot, whose set-up is a pickle "
                        "(it could run code): not read; start the scenario again"
                        if old
                        else f"{name}: not a snapshot (no {SETUP_KEY})"
                    )
                document = json.loads(bytes(data[SETUP_KEY]).decode("utf-8"))
                held = {key: data[key] for key in files if key.startswith(SETUP_ARRAY)}
                arrays = {
                    key: data[key]
                    for key in files
                    if key != SETUP_KEY and not key.startswith(SETUP_ARRAY)
                }
            if not isinstance(document, dict) or document.get("format") != FORMAT:
                raise SnapshotError(f"{name}: not a snapshot of format {FORMAT}")
            setup = _decode(document["setup"], held)
        except SnapshotError:
            raise
        except (
            OSError, EOFError, ValueError, KeyError, TypeError, AttributeError, IndexError,
            zipfile.BadZipFile, zlib.error, UnicodeDecodeError, RecursionError,
        ) as exc:  # fmt: skip
            raise SnapshotError(f"{name}: damaged ({type(exc).__name__}: {exc})") from None
        if not isinstance(setup, dict):
            raise SnapshotError(f"{name}: damaged (its set-up is not a table)")
        return Snapshot(setup, arrays)


def _name(kind: type) -> str:
    return f"{kind.__module__}.{kind.__qualname__}"


def _encode(value: Any, held: dict[str, npt.NDArray[Any]]) -> Any:
    """A JSON tree for value; its arrays go into `held` under SETUP_ARRAY names."""
    if isinstance(value, Enum):  # before int: an IntEnum is an int too
        if _name(type(value)) not in TYPES:
            raise TypeError(f"a snapshot cannot hold a {_name(type(value))}")
        return {"enum": _name(type(value)), "value": _encode(value.value, held)}
    if value is None or isinstance(value, bool | int | float | str):
        return value
    if isinstance(value, np.ndarray):
        if value.dtype.hasobject:
            raise TypeError("a snapshot cannot hold an array of Python objects")
        key = f"{SETUP_ARRAY}{len(held)}"
        held[key] = value
        return {"array": key}
    if isinstance(value, np.generic):
        return {"scalar": value.dtype.str, "value": value.item()}
    if isinstance(value, np.random.Generator):
        return {"generator": _encode(value.bit_generator.state, held)}
    if isinstance(value, tuple | list):
        items = [_encode(item, held) for item in value]
        return {"tuple": items} if isinstance(value, tuple) else items
    if isinstance(value, dict):
        return {"dict": [[_encode(k, held), _encode(v, held)] for k, v in value.items()]}
    kind = _name(type(value))
    if kind not in TYPES:
        raise TypeError(f"a snapshot cannot hold a {kind} (add it to snapshot.TYPES)")
    return {"object": kind, "fields": {k: _encode(v, held) for k, v in vars(value).items()}}


def _decode(tree: Any, held: dict[str, npt.NDArray[Any]]) -> Any:
    """The value _encode() made `tree` of; ValueError for anything it cannot have made."""
    if tree is None or isinstance(tree, bool | int | float | str):
        return tree
    if isinstance(tree, list):
        return [_decode(item, held) for item in tree]
    if not isinstance(tree, dict) or len(tree) not in (1, 2):
        raise ValueError(f"unexpected {type(tree).__name__} in the set-up")
    if "array" in tree:
        return held[tree["array"]]
    if "scalar" in tree:
        return np.array(tree["value"], dtype=np.dtype(tree["scalar"]))[()]
    if "tuple" in tree:
        return tuple(_decode(item, held) for item in tree["tuple"])
    if "dict" in tree:
        return {_decode(k, held): _decode(v, held) for k, v in tree["dict"]}
    if "generator" in tree:
        state = _decode(tree["generator"], held)
        kind = state.get("bit_generator") if isinstance(state, dict) else None
        if kind not in GENERATORS:
            raise ValueError(f"unknown random generator {kind!r}")
        generator = np.random.Generator(getattr(np.random, kind)())
        generator.bit_generator.state = state
        return generator
    if "enum" in tree:
        return _type(tree["enum"])(_decode(tree["value"], held))
    if "object" in tree:
        kind = _type(tree["object"])
        fields = tree["fields"]
        if not isinstance(fields, dict):
            raise ValueError(f"{tree['object']}: its fields are not a table")
        if dataclasses.is_dataclass(kind):
            expected = {f.name for f in dataclasses.fields(kind)}
            if not set(fields) <= expected | {k for k in fields if k.startswith("_")}:
                raise ValueError(f"{tree['object']}: fields {sorted(set(fields) - expected)}")
        instance: Any = object.__new__(kind)  # no __init__, no __setstate__: nothing of it runs
        for key, item in fields.items():
            object.__setattr__(instance, key, _decode(item, held))
        return instance
    raise ValueError(f"unexpected entry {sorted(tree)} in the set-up")


def _type(name: Any) -> type:
    if not isinstance(name, str) or name not in TYPES:
        raise ValueError(f"a snapshot may not hold a {name!r}")
    module, _, qualname = name.rpartition(".")
    kind = getattr(importlib.import_module(module), qualname)
    assert isinstance(kind, type)
    return kind
