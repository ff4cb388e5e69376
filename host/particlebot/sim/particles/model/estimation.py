"""The firmware's four S_n estimators (SI S4), vectorised over a group that all hear each other.

Every function here reproduces firmware/lib/estimation bit for bit, integer arithmetic included
(tests/sim/particles check it against the native library's pb_estimate), for the case the model
assumes: every particle of the group hears every other particle's broadcast, so each particle's
"others" are the whole group but itself. Under that assumption the group's extremes (methods B
and C) and its ladder of intensity levels (method D) are common to all, which turns the
firmware's per-particle loops into one pass over the group.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import numpy.typing as npt

from particlebot.firmware.native import FirmwareConstants
from particlebot.protocol import PARAM_SPECS, Method, Param

IntArray = npt.NDArray[np.int64]
FloatArray = npt.NDArray[np.float64]

# Fraction bits of the firmware's root terms of method C: it rounds g(V) = sqrt((1023 - V) V) to
# 12 bits by taking the floor with 13 and halving (estimation.cpp, root_term).
_ROOT_FLOOR_BITS = 13
# wide_quotient() saturates its 64-bit quotient to 32 bits.
_U32_MAX = 0xFFFFFFFF


@dataclass(frozen=True)
class EstimationParams:
    """The parameters of the same names (REF_DISTANCE_MM, ...), defaults from the protocol."""

    ref_distance_mm: int = PARAM_SPECS[Param.REF_DISTANCE_MM].default
    ref_value: int = PARAM_SPECS[Param.REF_VALUE].default
    diameter_mm: int = PARAM_SPECS[Param.DIAMETER_MM].default
    count_tolerance: int = PARAM_SPECS[Param.COUNT_TOLERANCE].default
    groups: int = PARAM_SPECS[Param.GROUPS].default

    def __post_init__(self) -> None:
        for name, param in (
            ("ref_distance_mm", Param.REF_DISTANCE_MM),
            ("ref_value", Param.REF_VALUE),
            ("diameter_mm", Param.DIAMETER_MM),
            ("count_tolerance", Param.COUNT_TOLERANCE),
            ("groups", Param.GROUPS),
        ):
            check_in_spec(name, getattr(self, name), param)


def check_in_spec(name: str, value: object, param: Param) -> None:
    spec = PARAM_SPECS[param]
    if isinstance(value, bool) or not isinstance(value, int):
        raise ValueError(f"{name} must be an integer, not {value!r}")
    if not spec.min <= value <= spec.max:
        raise ValueError(f"{name} = {value} is outside {spec.min}..{spec.max}")


class GroupEstimator:
    """S_n of every particle of a group from their intensities, as the firmware computes it."""

    def __init__(self, params: EstimationParams, constants: FirmwareConstants) -> None:
        self.params = params
        self._full = constants.adc_full_scale
        self._s_max = constants.s_n_max
        self._direct = self._direct_table()
        self._roots = self._root_table()

    def intensities(self, readings: FloatArray) -> IntArray:
        """The intensity a particle measures and broadcasts when its six photocells all read
        `readings` (eq. 11's value): each conversion rounds to the nearest count, and a sensor
        whose mean is 0 or full scale counts as faulty, so a particle whose six do reads 0."""
        raw = np.clip(np.rint(readings), 0, self._full).astype(np.int64)
        raw[raw >= self._full] = 0
        return raw

    def estimate(self, method: Method, intensities: IntArray) -> IntArray:
        """S_n (1..s_n_max) of every member of a group, each hearing all the others."""
        own = np.asarray(intensities, dtype=np.int64)
        if method is Method.DIRECT:
            return self._direct[np.clip(own, 0, self._full)]
        if own.size <= 1:
            return np.ones(own.shape, dtype=np.int64)
        if method is Method.LINEAR:
            return self._linear(own)
        if method is Method.NONLINEAR:
            return self._nonlinear(own)
        if method is Method.COUNTING:
            return self._counting(own)
        raise ValueError(f"unknown method {method!r}")

    # ---- the methods ---------------------------------------------------------------------------

    def _saturate(self, zero_based: IntArray) -> IntArray:
        return np.minimum(zero_based + 1, self._s_max)

    def _group_count(self, v_max: int, v_min: int) -> int:
        """N_w: GROUPS, or the rows the group spans toward the lamp (the firmware's method-A
        S_n of its weakest reading less that of its strongest, plus one)."""
        if self.params.groups > 0:
            return self.params.groups
        direct = self._direct
        return int(direct[min(v_min, self._full)] - direct[min(v_max, self._full)]) + 1

    def _direct_table(self) -> IntArray:
        """Method A depends on the own reading alone: its S_n for every reading 0..full scale."""
        p, full = self.params, self._full
        table = np.empty(full + 1, dtype=np.int64)
        for own in range(full + 1):
            if own == 0:
                table[own] = self._s_max
            elif own >= full or own >= p.ref_value:
                table[own] = 1
            else:
                # Eqs. 14-16 as the firmware evaluates them: z = floor(sqrt(floor(4 D_n^2 / D^2))),
                # S_n = 1 + (z + 1) / 2; its 32-bit saturation cannot change the saturated S_n.
                numerator = 4 * p.ref_distance_mm**2 * full * (p.ref_value - own)
                denominator = p.diameter_mm**2 * own * (full - p.ref_value)
                z = math.isqrt(numerator // denominator)
                table[own] = min((z + 1) // 2 + 1, self._s_max)
        return table

    def _root_table(self) -> IntArray:
        """g(V) = sqrt((full - V) V) in the firmware's fixed point, for V = 0..full scale."""
        full = self._full
        return np.array(
            [
                (math.isqrt(((full - v) * v) << (2 * _ROOT_FLOOR_BITS)) + 1) >> 1
                for v in range(full + 1)
            ],
            dtype=np.int64,
        )

    def _linear(self, own: IntArray) -> IntArray:
        v_max, v_min = int(own.max()), int(own.min())
        if v_max == v_min:
            return np.ones(own.shape, dtype=np.int64)
        n_w = self._group_count(v_max, v_min)
        index = np.minimum((v_max - own) * n_w // (v_max - v_min), n_w - 1)  # eqs. 17-18
        return self._saturate(index)

    def _nonlinear(self, own: IntArray) -> IntArray:
        usable = np.clip(own, 1, self._full)  # 0 counts as 1, above full scale as full scale
        v_max, v_min = int(usable.max()), int(usable.min())
        if v_max == v_min:
            return np.ones(own.shape, dtype=np.int64)
        g = self._roots
        n_w = self._group_count(v_max, v_min)
        s_n = np.ones(own.shape, dtype=np.int64)  # the brightest keep 1
        below = usable < v_max
        v_n = usable[below]
        # rho = (V_max - V_n)(g_max V_min + g_min V_max) / ((V_max - V_min)(g_max V_n + g_n V_max)),
        # eq. 29 rewritten as the firmware evaluates it (estimation.cpp); all products < 2^63.
        numerator = n_w * (v_max - v_n) * (int(g[v_max]) * v_min + int(g[v_min]) * v_max)
        denominator = (v_max - v_min) * (int(g[v_max]) * v_n + g[v_n] * v_max)
        index = np.minimum(np.minimum(numerator // denominator, _U32_MAX), n_w - 1)  # eq. 30
        s_n[below] = self._saturate(index)
        return s_n

    def _counting(self, own: IntArray) -> IntArray:
        # Algorithm 4 with the firmware's fixed order: from the strongest reading down, each one
        # more than the tolerance below the last counted level is a new level. Walked over the
        # whole group this ladder is the same for every member; a particle counts its rungs above
        # its own reading (the rungs above it are all other particles' readings).
        tolerance = self.params.count_tolerance
        rungs: list[int] = []
        for value in np.unique(own)[::-1].tolist():
            if not rungs or rungs[-1] > value + tolerance:
                rungs.append(value)
        ladder = np.array(rungs[::-1], dtype=np.int64)  # ascending
        above = ladder.size - np.searchsorted(ladder, own, side="right")
        return self._saturate(np.minimum(above, self._s_max))
