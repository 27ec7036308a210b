"""Round numbers for axes: plot ranges, grid steps and drawing scales.

The viewer's plots label ticks at multiples of a power of ten only (0.01, 0.1, ...), and
only where labels are more than 20 px apart (fully drawn from 30 px). A plot of residuals
up to 0.05 ms on a 170 px high plot gets 0.01 ms ticks 17 px apart (not drawn) and no
0.1 ms tick in range: it shows a lone "0". :func:`ticked_range` therefore rounds a plot's
range up to a few times a power of ten, few enough that ticks of that power are far
enough apart on the plot's height.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

ROUND = (1.0, 2.0, 5.0)
"""Mantissas of round numbers: 1, 2 or 5 times a power of ten."""
RANGE_TOPS = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0)
"""Mantissas a plot range's limit may have."""
TICK_SPACING_PX = 25.0
"""Least distance between labelled ticks :func:`ticked_range` allows, px."""
RANGE_PAD = 1.1
"""A plot range reaches this far past its round limit, so that the limit's label is not cut."""


def ticked_range(extent: float, height_px: float, *, symmetric: bool) -> tuple[float, float]:
    """A plot range holding ``0..extent`` (or ``-extent..extent``) whose labelled ticks are
    :data:`TICK_SPACING_PX` or more apart on a plot ``height_px`` high.

    The limit is the smallest ``m * 10**k`` (``m`` in :data:`RANGE_TOPS`) at least
    ``extent`` whose ``10**k`` ticks are far enough apart, else ``10**(k + 1)``; the range
    reaches :data:`RANGE_PAD` times the limit (and as far below 0 as it does above it,
    from 0).
    """
    power = 10.0 ** math.floor(math.log10(_positive(extent)))
    tops = [m * power for m in RANGE_TOPS if m * power >= extent * (1 - 1e-12)] + [10 * power]
    for top in tops:
        low, high = (-RANGE_PAD * top, RANGE_PAD * top) if symmetric else ((1 - RANGE_PAD) * top, RANGE_PAD * top)
        step = 10.0 ** math.floor(math.log10(top) + 1e-9)
        if height_px * step / (high - low) >= TICK_SPACING_PX:
            break
    return low, high


def nice_ceiling(value: float, mantissas: Sequence[float] = ROUND) -> float:
    """The smallest ``m * 10**k`` at least ``value`` (> 0), ``m`` one of ``mantissas``."""
    power = 10.0 ** math.floor(math.log10(_positive(value)))
    return next(m * power for m in (*mantissas, 10.0) if m * power >= value * (1 - 1e-12))


def nice_floor(value: float, mantissas: Sequence[float] = ROUND) -> float:
    """The largest ``m * 10**k`` at most ``value`` (> 0), ``m`` one of ``mantissas``."""
    power = 10.0 ** math.floor(math.log10(_positive(value)))
    return max(m * power for m in (*mantissas, 10.0) if m * power <= value * (1 + 1e-12))


def format_length(metres: float) -> str:
    """A length to 3 significant digits in the unit that reads best: ``"5 mm"``, ``"2 cm"``,
    ``"10 m"``, ``"32.5 km"``."""
    unit, size = next(
        ((unit, size) for unit, size in (("km", 1000.0), ("m", 1.0), ("cm", 0.01)) if abs(metres) >= size),
        ("mm", 0.001) if metres else ("m", 1.0),
    )
    return f"{metres / size:.3g} {unit}"


def _positive(value: float) -> float:
    if not (value > 0 and math.isfinite(value)):
        raise ValueError(f"a round number needs a positive finite value, not {value}")
    return value
