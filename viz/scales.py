"""Round numbers for axes: plot ranges, grid steps and drawing scales.

The viewer's plots label ticks at multiples of a power of ten only (0.01, 0.1, ...), and
only where labels are at least 20 px apart. A plot of residuals up to 0.05 ms on a 200 px
high plot gets 0.01 ms ticks 20 px apart (too close) and no 0.1 ms tick in range: it shows
a lone "0". Plot ranges are therefore rounded up to a few times a power of ten
(:data:`SYMMETRIC` for ranges about 0, :data:`FROM_ZERO` for ranges from 0), so that the
span holds at most 6 or 8 steps of that power: 25 px or more on a 200 px plot.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

ROUND = (1.0, 2.0, 5.0)
"""Mantissas of round numbers: 1, 2 or 5 times a power of ten."""
SYMMETRIC = (1.0, 2.0, 3.0)
"""Mantissas of the half-span of a plot range about 0 (``-x..x``: at most 6 steps)."""
FROM_ZERO = (1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 8.0)
"""Mantissas of the top of a plot range from 0 (``0..x``: at most 8 steps)."""


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
    unit, size = next(((unit, size) for unit, size in (("km", 1000.0), ("m", 1.0), ("cm", 0.01))
                       if abs(metres) >= size), ("mm", 0.001) if metres else ("m", 1.0))
    return f"{metres / size:.3g} {unit}"


def _positive(value: float) -> float:
    if not (value > 0 and math.isfinite(value)):
        raise ValueError(f"a round number needs a positive finite value, not {value}")
    return value
