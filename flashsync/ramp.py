"""A flash band's shape across rows, and its robust fit to a fraction of a row.

A row integrates light over its exposure window, so a flash of pulse shape ``p`` leaves in
a row whose exposure ended ``z`` rows after the flash fired the share
``R(z) - R(z - width)`` of its light, ``R`` the pulse's cumulative share and ``width`` the
exposure in rows: the band. Where the exposure is longer than the pulse the band has a
plateau, its leading edge is ``R`` rising and its trailing edge ``1 - R`` falling, one
exposure later; where it is not (a 0.5 ms exposure, a xenon tail of 1 ms) the band never
reaches its plateau and its half-level crossings are no longer one exposure apart nor at
the same instant of the flash as in other cameras.

The pulse is a hold of ``hold`` rows at full power followed by an exponential decay of
``decay`` rows: an instant-rise flash (hold 0), a xenon tube (its rise of tens of
microseconds is within the blur), an LED strobe (decay near 0); a slow rise is
approximated by the hold. The codec (quantisation, deblocking) and the lens blur the
band across rows, and blur moves the half point of an asymmetric ramp, so the model is
convolved with a Gaussian of ``blur`` rows, in closed form (ramps and exponentially
modified Gaussians).

An edge is the half-light point of the pulse before the blur: the row whose exposure ended
(leading) or started (trailing) when the flash had given half its light, the same instant
in every camera whatever its exposure. A band whose two edges lie in one frame is fitted
whole (:func:`fit_pulse_band`): its two edges are then exactly ``width`` rows apart, the
exposure; a band split across two frames too, its parts one band across the rows hidden
between frames (:func:`fit_split_band`). An edge alone (its partner hidden) is fitted as a
ramp (:func:`fit_pulse_edge`).

A rectangular pulse and the exposure trade places in a band: alone, the longer is taken to
be the exposure. A camera's bands share the exposure while the flashes' pulses differ, so
together they tell a pulse that outlasts the exposure (:func:`common_width`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import minimize_scalar

from flashsync.compiled import cholesky_solve, njit

#: Bounds of the pulse's hold and decay length and of the blur, rows.
MIN_DECAY, MAX_LENGTH = 0.05, 200.0
MAX_BLUR = 3.0
#: Blur the fit starts from, rows.
START_BLUR = 0.3
#: Std of a weak prior that the blur is small, rows: a blur of this many rows costs as much
#: as one row off by the loss scale. Without it the blur wanders where the ramp cannot tell
#: it (a foot lost in a dead zone) and stalls short of 0 in sharp video.
BLUR_PRIOR_STD = 2.0
#: A hold is fitted where it lowers the cost by this many times the residual variance per
#: row (Akaike's criterion asks for 2; a free hold trades with the blur and fits the noise
#: of a blurred exponential ramp by 4-5 times).
HOLD_EVIDENCE = 10.0
#: What the reading of a camera's bands with pulses longer than the exposure is charged
#: for each hold it gives a band whose own fit had none (:func:`common_width`), in units of
#: the band's noise: about what a free hold wins by fitting noise and a ramp's shape
#: (4-5 on a blurred exponential ramp, :data:`HOLD_EVIDENCE`). Uncharged, rig-442's
#: 12.4-row sRGB camera, whose bands' own widths scatter over 11-14.4 rows under its tone
#: curve, was read as a 4.7-row exposure of rectangles each as long as its band (the cost
#: 76 read plainly, 20 so, 50 charged), its times 0.72 ms off; charged 10, rig-322's 5.7-row camera
#: under LED pulses it takes two holds to explain was read plainly, 1.4 rows long.
SPARE_HOLD = 5.0
#: A camera's exposure (:func:`common_width`): the most of its bands used, the widths of
#: the grid searched with every pulse no longer than the exposure, the shortest exposure
#: tried with longer pulses allowed, rows, and the longest as a share of the bands' median
#: width, the step between those (a share) and to how many rows the best is refined, and
#: the most a band's cost counts, in units of its noise.
MAX_WIDTH_BANDS, WIDTH_GRID, SHORTEST_ROWS, SHORTER_SHARE = 10, 9, 1.0, 0.9
REFINED_SHARE, WIDTH_TOLERANCE, BAND_COST_CAP = 0.1, 0.05, 100.0
#: How much better (in units of the bands' noise, :func:`common_width`) an exposure shorter
#: than some of the pulses must explain a camera's bands than the best that is not, and the
#: most of that one's cost it may leave: where neither reading explains the bands (on the 24
#: kept random rigs a 52-row camera whose bands cost 352 read plainly and 288 at 3 rows),
#: the lower cost is no evidence; where pulses outlast the exposure it leaves 0.01-0.44 of it
#: on the 40 rigs and the LED rigs of ``tests/test_exposure.py``.
SWAP_EVIDENCE, SWAP_SHARE = 50.0, 0.5
#: How far apart (10th to 90th percentile, a share of their median) a camera's bands' own
#: widths must lie for their pulses to be told from the exposure (:func:`common_width`):
#: one pulse length for every flash tells the two readings apart no better than one band
#: does. On the 40 kept random rigs and the recipes, of the readings under 0.1 (302 of
#: 486, 60 % of the search's time) none is rightly read the other way round and six were
#: read so at 4.5-12 rows, of cameras whose exposure is 50-130 rows; the benches' numbers
#: are the same with and without it.
PULSES_DIFFER = 0.1
#: A pulse longer than the exposure is a rectangle: its decay at most this share of its
#: hold (:meth:`BandFit.with_width`); and the exposure it is longer than at least this many
#: rows (:func:`common_width`) unless the bands read plainly are :data:`PINNED_SHARE`
#: longer or more (a reading within that changes the exposure little and costs the
#: camera's other edges their weight, flagged ``long_pulse``: on the 40 kept random rigs
#: six cameras under 8 rows read so were no closer to the truth, and rig-2, rig-5 and
#: rig-17 came out 0.015-0.056 ms further off).
RECTANGLE_TAIL, MIN_SWAPPED_ROWS = 0.2, 8.0
#: How much shorter or longer than the exposure that some pulses outlast must cost the
#: bands :data:`SWAP_EVIDENCE` more (:func:`common_width`): on the 24 kept random rigs a
#: 10.4-row camera whose bands cannot tell 8.7 rows from 10.4 was read 1.7 rows short.
PINNED_SHARE = 0.15
#: How much more than the least (in the same units) the bands may cost at the exposure that
#: pulses outlast (:func:`common_width`): the longest that costs no more. Where the pulse
#: is the longer, a band's ramps are the exposure blurred; a shorter exposure blurred more
#: fits them as well, a longer one does not, so the least cost lies short (the LED rig of
#: ``tests/test_exposure.py`` with a 0.35, 0.5, 0.7 or 1 ms camera under 1.2-2 ms pulses:
#: 2.5-7.1 rows, the least 0.1-2.5 rows short); at 10 all four are read within 0.45 rows
#: (long), at 25 within 1.
FLAT_EVIDENCE = 10.0
#: What the fitted model is: a whole band, its rising or falling edge alone, or a band split
#: across two frames (:func:`fit_split_band`), its next frame's part at a level of its own or
#: at the band's.
BAND, RISING, FALLING, SPLIT, SPLIT_ONE_LEVEL = 0, 1, 2, 3, 4
#: Parameters of the model: (start, hold, decay, blur, width, level); ``start`` is the row
#: whose exposure ended when the flash fired, ``width`` the exposure in rows, ``level`` the
#: band's level for a row that saw the whole flash. A split band has three more: the rows
#: hidden between frames, the frame's height (not fitted) and the level in the next frame
#: (:data:`SPLIT`; not used by :data:`SPLIT_ONE_LEVEL`).
N_PARAMETERS = 6
#: A split band's next frame shows the band's level only where its trailing edge lies this
#: many ramps (its 25 %-to-75 % rise) or more below the frame's first row; above, the rows
#: hold the ramp alone, and a level of their own let the fit trade the level for the edge's
#: row: over the 130 kept second-world rigs those trailing edges came out a median 0.51 rows
#: late (median absolute error 0.90 rows, 38 of 81 over a row; 0.09 rows late past two
#: ramps). At the band's level, 0.11 rows late (0.63, 30 over a row); README, "Bands split
#: across frames, fitted whole".
OWN_LEVEL_RISES = 1.3


def fit_pulse_edge(values: np.ndarray, row: float, rise: float, level: float, rising: bool) -> float:
    """Sub-row edge of a flash band from the rows around its half-level crossing.

    Parameters
    ----------
    values : float array of shape (rows,)
        Relative change per readout row, the band positive; NaN where blind.
    row : float
        Where ``values`` crosses half of ``level``, rows (the estimate to refine).
    rise : float
        Rows from 25 % to 75 % of ``level`` (sets the fit window).
    level : float
        The band's plateau near the edge.
    rising : bool
        A leading edge (the light rises with the row); False for a trailing edge.

    Returns
    -------
    float: the fitted edge, rows; ``row`` itself where fewer than six rows are usable, the
    fit does not converge or it would move the edge by more than two rows; NaN where the
    band is degenerate (a level that is not positive, a crossing or rise that is not finite).
    """
    if not (np.isfinite(row) and np.isfinite(rise) and np.isfinite(level) and level > 0):
        return float("nan")
    decay = _decay_guess(rise)
    x = _window(len(values), [row], decay)
    keep = np.isfinite(values[x]) & (x != _censored_foot(values, row, rising))
    if not rising:
        keep &= ~_censored_tail(values, x, row)
    if keep.sum() < 6:
        return row
    free = np.array([True, True, True, True, False, True])
    x, y = x[keep].astype(np.float64), values[x[keep]].astype(np.float64)
    fit = _best_fit(x, y, row, 0.0, rise, level, free, RISING if rising else FALLING)
    refined = fit.p[0] + _half_light(fit.p[1], fit.p[2]) if fit is not None else np.nan
    return float(refined) if abs(refined - row) <= 2.0 else row


@dataclass(frozen=True)
class BandFit:
    """A band fitted whole (:func:`fit_pulse_band`).

    Attributes
    ----------
    x, y : float arrays of shape (n,)
        The rows fitted and their relative change.
    p : float array of shape (6,)
        The model's parameters (start, hold, decay, blur, width, level), rows but the level.
    free : bool array of shape (6,)
        The parameters that were fitted (the hold is fixed at 0 where an exponential pulse
        explained the band).
    noise : float
        The least :attr:`variance` taken (0: the fit's own; :func:`common_width` gives a
        band that cannot measure its own its camera's).
    """

    x: np.ndarray
    y: np.ndarray
    p: np.ndarray
    free: np.ndarray
    noise: float = 0.0

    @property
    def leading(self) -> float:
        """The row whose exposure ended when the flash had given half its light."""
        return float(self.p[0] + _half_light(self.p[1], self.p[2]))

    @property
    def trailing(self) -> float:
        """The row whose exposure started then: one exposure after the leading edge."""
        return self.leading + float(self.p[4])

    @property
    def width(self) -> float:
        """The exposure, rows."""
        return float(self.p[4])

    @property
    def pulse(self) -> float:
        """The pulse's length, rows: its hold and its decay (its light over its peak's)."""
        return float(self.p[1] + self.p[2])

    @property
    def variance(self) -> float:
        """The cost per degree of freedom (about the variance of a row's change), at least
        :attr:`noise`."""
        own = _data_cost(self.x, self.y, self.p, _f_scale(self.p), BAND) / max(self.x.size - self.free.sum(), 1)
        return max(own, self.noise)

    @property
    def measures_noise(self) -> bool:
        """The band has more rows the change reached than fitted parameters: its fit leaves
        a residual to measure its noise by (the rows around it, no change at all, the model
        meets exactly)."""
        return int(np.count_nonzero(self.y)) > int(self.free.sum())

    def excess(self, width: float, longer: bool, unsettled: bool = False) -> tuple[float, BandFit | None]:
        """This band's cost refitted with its exposure fixed at ``width`` rows
        (:meth:`with_width`) above its own fit's, in units of its noise and at most
        :data:`BAND_COST_CAP` (that where the refit does not converge), and the refit."""
        refit = self.with_width(width, longer, unsettled)
        if refit is None:
            return BAND_COST_CAP, None
        least = _data_cost(self.x, self.y, self.p, _f_scale(self.p), BAND)
        return min(max(refit[1] - least, 0.0) / max(self.variance, 1e-12), BAND_COST_CAP), refit[0]

    def with_width(self, width: float, longer: bool = False, unsettled: bool = False) -> tuple[BandFit, float] | None:
        """This band fitted again with its exposure fixed at ``width`` rows, and the fit's
        cost; None where it does not converge. Where the pulse may be ``longer`` than the
        exposure (a rectangular pulse and the exposure trade places, :func:`_clamp`), the
        swapped rectangles are tried too, the hold free and as long as keeps the band's
        length; a pulse longer than the exposure must then be a rectangle (a decay of at
        most :data:`RECTANGLE_TAIL` of its hold: a pulse with a tail does not trade places
        with the exposure). A hold this band did not have is taken where it lowers the cost
        by :data:`HOLD_EVIDENCE` times the band's variance. Where the pulse may be longer, a
        fit that has not settled still counts with the cost it reached: hold, blur and decay
        trade along flat valleys there, and each band counted as failed put a spike of
        :data:`BAND_COST_CAP` into :func:`common_width`'s costs (on the 40 kept random rigs a
        reference's 6.9-row exposure read as 2.7 rows). ``unsettled`` counts such fits where
        the pulse may not be longer too: the plain reading scored as the other one is."""
        f_scale = _f_scale(self.p)
        own = self.free.copy()
        own[4] = False
        start = self.p.copy()
        start[4] = width
        tries = [(start, own)]
        swapped = float(self.p[1] + self.p[4] - width)  # the hold that keeps the band's length
        if longer and swapped > self.p[1]:
            held, other = own.copy(), start.copy()
            held[1], other[1] = True, swapped
            tries.append((other, held))
        best = None
        for p, free in tries:
            fitted, converged = _fit(self.x, self.y, p, free, f_scale, BAND, longer)
            if not (converged or longer or unsettled) or (fitted[1] > width and fitted[2] > RECTANGLE_TAIL * fitted[1]):
                continue
            cost = _data_cost(self.x, self.y, fitted, f_scale, BAND)
            if not np.isfinite(cost):
                continue
            margin = HOLD_EVIDENCE * self.variance if free[1] and not own[1] else 0.0
            if best is None or cost < best[1] - margin:
                best = (BandFit(self.x, self.y, fitted, free), cost)
        return best


def fit_pulse_band(values: np.ndarray, leading: float, trailing: float, rise: float, level: float) -> BandFit | None:
    """A band whose two edges lie in one frame, fitted whole (the pulse integrated over the
    exposure): its leading and trailing edges one exposure apart.

    Parameters
    ----------
    values : float array of shape (rows,)
        Relative change per readout row, the band positive; NaN where blind.
    leading, trailing : float
        The band's edges as located one by one (half-level crossings), rows.
    rise : float
        Rows from 25 % to 75 % of the band's level at its trailing edge (sets the window
        and the first guess of the pulse's decay).
    level : float
        The band's plateau.

    Returns
    -------
    BandFit, or None where the fit has too few rows or does not converge, or it would move
    an edge further than the band's ramp could explain.
    """
    if not all(np.isfinite(v) for v in (leading, trailing, rise, level)) or level <= 0 or trailing <= leading:
        return None
    decay = _decay_guess(rise)
    x = _window(len(values), [leading, trailing], decay)
    keep = np.isfinite(values[x]) & (x != _censored_foot(values, leading, True)) & ~_censored_tail(values, x, trailing)
    if keep.sum() < 8:
        return None
    x, y = x[keep].astype(np.float64), values[x[keep]].astype(np.float64)
    level = max(level, float(np.percentile(y, 90)))  # a short band's peak, above its median
    fit = _best_fit(x, y, leading, trailing - leading, rise, level, np.ones(N_PARAMETERS, dtype=np.bool_), BAND)
    reach = 2.0 + 2.0 * decay
    if fit is None or abs(fit.leading - leading) > reach or abs(fit.trailing - trailing) > reach:
        return None
    return fit


def fit_split_band(
    before: np.ndarray, leading: float, after: np.ndarray, trailing: float, rise: float, level: float
) -> tuple[float, float] | None:
    """A band split across two frames, fitted whole: its leading edge in the first frame and
    its trailing edge in the next.

    The two parts are one band seen through the gap between frames (the rows hidden in the
    blanking), so they share the pulse and the blur; alone, an edge cut by the frame's first
    or last row shows only part of its ramp and its level is a guess (a pulse still rising
    at the frame's last row). The model is the band of :func:`fit_pulse_band` with the next
    frame's rows ``height + hidden`` rows on, ``hidden`` fitted (at least 0), and a level of
    their own (a tone curve makes the relative change depend on the scene's brightness,
    which differs between the bottom and the top of a frame) where they show it; the band's
    where the trailing edge lies within :data:`OWN_LEVEL_RISES` ramps of the next frame's
    first row.

    Parameters
    ----------
    before, after : float arrays of shape (rows,)
        Relative change per readout row of the two frames, the band positive; NaN where blind.
    leading, trailing : float
        The edges as located one by one, rows of ``before`` and of ``after``.
    rise : float
        Rows from 25 % to 75 % of the band's level at an edge (sets the window and the first
        guess of the pulse's decay).
    level : float
        The band's plateau.

    Returns
    -------
    (leading, trailing) rows, or None where the fit has too few rows or does not converge,
    or it would move an edge further than the band's ramp could explain.
    """
    if not all(np.isfinite(v) for v in (leading, trailing, rise, level)) or level <= 0:
        return None
    decay, height = _decay_guess(rise), len(before)
    first = _window(height, [leading], decay)
    first = np.arange(first[0], height) if first.size else first
    last = _window(len(after), [trailing], decay)
    last = np.arange(0, last[-1] + 1) if last.size else last
    keep_first = np.isfinite(before[first]) & (first != _censored_foot(before, leading, True))
    keep_last = np.isfinite(after[last]) & ~_censored_tail(after, last, trailing)
    if keep_first.sum() < 4 or keep_last.sum() < 4:
        return None
    x = np.concatenate([first[keep_first], -1 - last[keep_last]]).astype(np.float64)  # the next frame's rows < 0
    y = np.concatenate([before[first[keep_first]], after[last[keep_last]]]).astype(np.float64)
    hidden = 0.05 * height
    width = trailing + height + hidden - leading  # one exposure from edge to edge
    own_level = trailing >= OWN_LEVEL_RISES * rise
    free = np.array([True, True, True, True, True, True, True, False, own_level])
    mode = SPLIT if own_level else SPLIT_ONE_LEVEL
    fit = _best_fit(x, y, leading, width, rise, level, free, mode, (hidden, float(height), level))
    if fit is None:
        return None
    start, hold, decay_fit, _, width, _, hidden, _, _ = fit.p
    half = _half_light(hold, decay_fit)
    fitted = (start + half, start + half + width - height - hidden)
    reach = 2.0 + 2.0 * decay
    if abs(fitted[0] - leading) > reach or abs(fitted[1] - trailing) > reach:
        return None
    return float(fitted[0]), float(fitted[1])


def common_width(fits: list[BandFit]) -> tuple[float, bool, float | None] | None:
    """The exposure, rows, that explains a camera's whole bands best, whether some of their
    pulses are longer than it, and the exposure of a reading with longer pulses that it
    could not rule out (:func:`_read_width`), at most :data:`MAX_WIDTH_BANDS`
    bands evenly over the recording; None with fewer than three. A reading that finds pulses
    longer than an exposure :data:`PINNED_SHARE` shorter than the shortest band or more is
    read again without the band that asks most for it (its cost at the shortest band's length
    above that at the reading's): where the rest, too, find pulses longer than the exposure
    and read it :data:`PINNED_SHARE` longer or more, the short reading rested on that one band
    and the longer is taken (a shorter exposure blurred more mimics a longer one,
    :func:`_longest_minimum`). rig-415's 5.8-row sRGB camera under 0.3-1.8 ms rectangles was
    read as a 1.2-row exposure for one faint band whose rise the codec had made one row high
    at an 8-row block's edge (the others cost 35 more at 5.8 rows, it 95), its times 0.3 ms
    off. Rest that find no pulse longer read no other exposure: they only lack the evidence
    one band fewer leaves (:data:`SWAP_EVIDENCE`); rig-4's 5.7-row reference under 2.3-17-row
    rectangles, four bands, two of them asking for its exposure, was read 9.1 rows with
    none longer, and every other camera's times came out 0.2 ms off."""
    if len(fits) < 3:
        return None
    fits = _with_camera_noise(fits[:: math.ceil(len(fits) / MAX_WIDTH_BANDS)])  # evenly over the recording
    read = _read_width(fits)
    shortest = min(fit.width for fit in fits)
    if read is None or not read[1] or len(fits) <= 3 or read[0] * (1 + PINNED_SHARE) > shortest:
        return read
    asks = [fit.excess(shortest, True)[0] - fit.excess(read[0], True)[0] for fit in fits]
    k = int(np.argmax(asks))
    again = _read_width(fits[:k] + fits[k + 1 :])
    return again if again is not None and again[1] and again[0] >= (1 + PINNED_SHARE) * read[0] else read


def _with_camera_noise(fits: list[BandFit]) -> list[BandFit]:
    """The bands, each that cannot measure its own noise (:attr:`BandFit.measures_noise`)
    given the median of the others' (its own fit leaves no residual: any other width cost
    it :data:`BAND_COST_CAP`, and that one band chose the camera's exposure; rig-641's
    5.9-row sRGB camera under 0.2-1.8 ms LED pulses, one band of four rows of light among
    nine, was read 1.5 rows, its exposure 0.39 ms short at 18σ)."""
    measured = [fit.variance for fit in fits if fit.measures_noise]
    if not measured or len(measured) == len(fits):
        return fits
    noise = float(np.median(measured))
    return [fit if fit.measures_noise else replace(fit, noise=noise) for fit in fits]


def _read_width(fits: list[BandFit]) -> tuple[float, bool, float | None] | None:
    """The exposure, rows, that explains all of a camera's whole bands best, whether some of
    their pulses are longer than it (the bands then read the other way round where fitted
    alone, :func:`_clamp`), and the rival: the exposure, rows, of a reading with longer
    pulses that explained the bands better at its least cost but not by what a choice
    needs, where the plain one is taken (None otherwise; rig-4's 5.7-row reference under
    LED pulses all longer than it, four bands, two of them 9.4-9.8 rows: read 10.3 rows,
    its rival 7.3); where that reading costs :data:`SWAP_EVIDENCE` less but more than
    :data:`SWAP_SHARE` of the plain one, the longest of its grid's minima (auto-exposure
    rig-89's 15.2-row camera under 0.9-2 ms LED pulses, its bands 302 read plainly, as
    56-row exposures, and 157 at 14.4 rows, had no rival, its exposure 1.14 ms long at 2.5
    sigmas). The exposure is the minimum of the sum of their costs refitted
    with the exposure fixed (:meth:`BandFit.with_width`; each band's cost above its own
    fit, in units of its own noise and at most :data:`BAND_COST_CAP`, so that a band hit by
    a player does not steer it), over at most :data:`MAX_WIDTH_BANDS` bands evenly over
    the recording.

    One band alone cannot tell a short exposure from the pulse's decay to better than a
    row or two (at 0.5-1 ms), nor a rectangular pulse from the exposure where the pulse is
    the longer; the camera's bands share the exposure, the flashes' pulses differ. The
    exposure is first sought with every pulse no longer than it, over a grid of
    :data:`WIDTH_GRID` widths between the 10th and 90th percentile of the bands' own (and
    the parabola through the lowest); then, where that leaves the bands costing
    :data:`SWAP_EVIDENCE` or more and their widths differ (:data:`PULSES_DIFFER`), with
    longer pulses allowed, over widths from :data:`SHORTEST_ROWS` to :data:`SHORTER_SHARE`
    of the bands' median or the plain reading, whichever is longer, in steps of
    :data:`REFINED_SHARE`, and at the own widths of bands that another band's is within
    :data:`PINNED_SHARE` of (a band is as long as the longer of its pulse and the exposure,
    so where some pulses are the shorter their bands are one exposure long; the 10 % steps
    missed a 22-row camera's narrow minimum there, and the plain reading took the majority
    of three longer bands, its times 0.24 ms off): of the minima within
    :data:`SWAP_EVIDENCE` of the least, the longest (:func:`_longest_minimum`), refined to
    :data:`WIDTH_TOLERANCE` rows, then the longest width from there that costs at most
    :data:`FLAT_EVIDENCE` more (:func:`_upper_end`). That reading is taken only where it
    explains the bands better (:func:`_explains_better`) than the plain one scored alike
    (each band's fit that has not settled counted with the cost it reached, as the longer
    pulses' are, :meth:`BandFit.with_width`; the plain exposure itself is read from settled
    fits, which place it better: counted alike there too, a reference's exposure moved
    0.37 ms; compared with spikes of failed fits, slow-rising pulses shorter than a 52-row
    exposure were read as 19-row exposures of 1.6 ms rectangles; each hold it gives a band
    whose own fit had none charged :data:`SPARE_HOLD`) and the pulses it finds longer than
    the exposure differ (:func:`_pulses_differ`: one pulse length for every flash
    tells the two readings apart no better than one band does; a random rig's 98-row
    camera, whose two false bands 23 and 7 rows long made its bands' widths differ, was
    read 10 rows with its three real pulses 98 rows each, its times 5 ms off) or two or
    more bands it finds no longer are one exposure long (:func:`_one_exposure_long`); and
    where the plain reading's exposure is :data:`PINNED_SHARE` longer or more (the band
    lengths are then the pulses'), or bands are one exposure long and those it finds
    longer are :data:`PINNED_SHARE` longer or more, or the exposure is
    :data:`MIN_SWAPPED_ROWS` or more and pinned: :data:`PINNED_SHARE` shorter or longer
    costs the bands :data:`SWAP_EVIDENCE` more. None where the bands' widths are not positive."""
    widths = np.array([fit.width for fit in fits])

    def total(
        width: float, longer: bool, limit: float = np.inf, unsettled: bool = False
    ) -> tuple[float, np.ndarray, np.ndarray]:
        """The bands' summed cost at ``width`` (as soon as it reaches ``limit``, that far),
        which bands' pulses are then the longer, and which are refitted with a hold their
        own fit had not, both shape (n_bands,) (:meth:`BandFit.with_width`)."""
        cost, outlasted, held = 0.0, np.zeros(len(fits), dtype=bool), np.zeros(len(fits), dtype=bool)
        for k, fit in enumerate(fits):
            excess, refit = fit.excess(width, longer, unsettled)
            cost += excess
            outlasted[k] = refit is not None and refit.p[1] > width
            held[k] = refit is not None and refit.free[1] and not fit.free[1]
            if cost >= limit:
                break
        return cost, outlasted, held

    plain = _plain_width(widths, lambda width: total(width, False)[0])
    if plain is None:
        return None
    longest = max(SHORTER_SHARE * float(np.median(widths)), plain[0])
    if plain[1] < SWAP_EVIDENCE or not _pulses_differ(widths) or longest <= SHORTEST_ROWS:
        return plain[0], False, None
    alike = _plain_width(widths, lambda width: total(width, False, unsettled=True)[0])
    plain = (plain[0], min(plain[1], alike[1]))  # the plain reading's cost scored as the other's
    step = 1 + REFINED_SHARE
    grid = SHORTEST_ROWS * step ** np.arange(math.ceil(math.log(longest / SHORTEST_ROWS, step)) + 1)
    paired = (np.abs(widths[:, None] - widths) <= PINNED_SHARE * widths[:, None]).sum(axis=1) >= 2
    shorter = np.union1d(grid, widths[paired & (widths >= SHORTEST_ROWS) & (widths <= longest)])
    cut = plain[1] - SWAP_EVIDENCE  # a cost cut short there is no better than the plain reading
    scored = np.array([total(width, True, cut)[0] for width in shorter])
    scored[scored >= cut] = np.inf
    start = _longest_minimum(scored, scored.min() + SWAP_EVIDENCE) if np.isfinite(scored.min()) else None
    if not _explains_better(scored.min(), plain[1]):
        return plain[0], False, None if start is None else float(shorter[start])
    refined = minimize_scalar(
        lambda w: total(w, True)[0],
        bounds=(shorter[start] / step, shorter[start] * step),
        method="bounded",
        options={"xatol": WIDTH_TOLERANCE},
    )
    width, cost = shorter[start], scored[start]
    if refined.fun < cost:
        width, cost = float(refined.x), float(refined.fun)
    within = shorter[start:][scored[start:] <= cost + FLAT_EVIDENCE]
    width = _upper_end(lambda w: total(w, True)[0], max([width, *within]), cost + FLAT_EVIDENCE, longest)
    cost, outlasted, held = total(width, True)
    exposure_long = _one_exposure_long(widths[~outlasted], width)
    charged = cost + SPARE_HOLD * held.sum()
    if not ((_pulses_differ(widths[outlasted]) or exposure_long) and _explains_better(charged, plain[1])):
        return plain[0], False, width
    apart = exposure_long and bool(np.all(widths[outlasted] >= (1 + PINNED_SHARE) * width))
    if width < (1 - PINNED_SHARE) * plain[0] or apart:
        return width, True, None
    pinned = all(total(k * width, True)[0] >= cost + SWAP_EVIDENCE for k in (1 - PINNED_SHARE, 1 + PINNED_SHARE))
    return (width, True, None) if width >= MIN_SWAPPED_ROWS and pinned else (plain[0], False, width)


def _pulses_differ(widths: np.ndarray) -> bool:
    """Whether bands whose own widths (rows, shape (n,)) are their pulses' would have pulses
    that differ (10th to 90th percentile at least :data:`PULSES_DIFFER` of their median):
    pulses of one length are as likely the exposure (False for fewer than two bands)."""
    if len(widths) < 2:
        return False
    low, high = np.percentile(widths, [10, 90])
    return bool(high - low >= PULSES_DIFFER * float(np.median(widths)))


def _one_exposure_long(widths: np.ndarray, width: float) -> bool:
    """Whether two or more bands, their own widths (rows, shape (n,)), are all within
    :data:`PINNED_SHARE` of the exposure ``width`` (rows): a band whose pulse is shorter
    than the exposure is one exposure long, so bands that a reading finds so must be."""
    return len(widths) >= 2 and bool(np.all(np.abs(widths - width) <= PINNED_SHARE * width))


def _explains_better(cost: float, plain: float) -> bool:
    """Whether bands costing ``cost`` read with pulses longer than the exposure are
    explained better than at the ``plain`` cost by :data:`SWAP_EVIDENCE` and to at most
    :data:`SWAP_SHARE` of it (costs in units of the bands' noise, :func:`common_width`)."""
    return cost + SWAP_EVIDENCE < plain and cost <= SWAP_SHARE * plain


def _longest_minimum(costs: np.ndarray, limit: float) -> int:
    """Index of the last local minimum of ``costs`` (shape (n,), over widths in increasing
    order) that is within ``limit``: a shorter exposure blurred more mimics a longer one, a
    longer one never mimics a shorter, so of two readings that explain the bands nearly
    as well the longer is the exposure."""
    padded = np.concatenate([[np.inf], costs, [np.inf]])
    minima = (costs <= padded[:-2]) & (costs <= padded[2:]) & (costs <= limit)
    return int(np.flatnonzero(minima)[-1])


def _upper_end(cost: Callable[[float], float], width: float, limit: float, bound: float) -> float:
    """The longest width, rows, from ``width`` (where ``cost`` is within ``limit``) up to
    ``bound`` before ``cost`` exceeds ``limit`` at two steps in a row (one refit that does
    not converge costs a band :data:`BAND_COST_CAP`): stepped up by :data:`REFINED_SHARE`
    / 2, then bisected to :data:`WIDTH_TOLERANCE` rows."""
    inside, outside, trial = width, [], width
    while len(outside) < 2 and trial < bound:
        trial = min(trial * (1 + REFINED_SHARE / 2), bound)
        if cost(trial) > limit:
            outside.append(trial)
        else:
            inside, outside = trial, []
    end = outside[0] if outside else inside
    while end - inside > WIDTH_TOLERANCE:
        middle = 0.5 * (inside + end)
        if cost(middle) > limit:
            end = middle
        else:
            inside = middle
    return inside


def _plain_width(widths: np.ndarray, total: Callable[[float], float]) -> tuple[float, float] | None:
    """The width, rows, and the cost ``total(width)`` at the lowest of a grid of
    :data:`WIDTH_GRID` widths between the 10th and 90th percentile of ``widths`` (shape
    (n,)), moved to the vertex of the parabola through its neighbours; None where the
    widths are not positive."""
    low, high = np.percentile(widths, [10, 90])
    if high - low < 0.02:
        middle = float(np.median(widths))
        return (middle, total(middle)) if middle > 0 else None
    grid = np.linspace(low, high, WIDTH_GRID)
    costs = np.array([total(width) for width in grid])
    j = int(np.argmin(costs))
    if 0 < j < grid.size - 1:
        curvature = costs[j - 1] - 2.0 * costs[j] + costs[j + 1]
        if curvature > 0:
            vertex = float(grid[j] + 0.5 * (grid[1] - grid[0]) * (costs[j - 1] - costs[j + 1]) / curvature)
            return vertex, min(total(vertex), float(costs[j]))
    return float(grid[j]), float(costs[j])


def _best_fit(
    x: np.ndarray,
    y: np.ndarray,
    edge: float,
    width: float,
    rise: float,
    level: float,
    free: np.ndarray,
    mode: int,
    more: tuple[float, ...] = (),
) -> BandFit | None:
    """Fit of the model (:func:`_fit`; ``more``: the parameters past the sixth, a split
    band's) to rows ``x``, values ``y`` (float64): an exponential
    pulse (no hold), or where it explains the rows clearly better (its cost on the rows
    lower by :data:`HOLD_EVIDENCE` times the residual variance), a pulse with a hold,
    fitted from a rectangle. Both start with their half-light point at ``edge`` and a
    25 %-to-75 % ramp of ``rise`` rows. A hold and the blur both round a ramp's foot, so a
    hold that is free everywhere moves a blurred exponential edge; and a ramp fitted from
    an exponential can stall in a local minimum where the pulse is a rectangle (an
    exponential ramp blurred to look straight). None where neither converges."""
    decay, hold = _decay_guess(rise), max(2.0 * rise, 0.3)
    f_scale = 0.05 * level
    no_hold = free.copy()
    no_hold[1] = False
    exponential_start = np.array([edge - decay * np.log(2.0), 0.0, decay, START_BLUR, width, level, *more])
    exponential, converged = _fit(x, y, exponential_start, no_hold, f_scale, mode)
    held_start = np.array([edge - 0.5 * hold, hold, MIN_DECAY, START_BLUR, width, level, *more])
    held, held_converged = _fit(x, y, held_start, free, f_scale, mode)
    if held_converged:
        cost = _data_cost(x, y, held, f_scale, mode)
        if not converged or _data_cost(x, y, exponential, f_scale, mode) - cost > HOLD_EVIDENCE * cost / max(
            x.size - free.sum(), 1
        ):
            return BandFit(x, y, held, free)
    return BandFit(x, y, exponential, no_hold) if converged else None


def _f_scale(p: np.ndarray) -> float:
    """The robust loss's scale for the model ``p``: 5 % of its level."""
    return 0.05 * float(p[5])


def _data_cost(x: np.ndarray, y: np.ndarray, p: np.ndarray, f_scale: float, mode: int) -> float:
    """The fit's cost without the blur's prior (the hold, which has none, can stand in for
    the blur: with the prior counted, a hold would win where only the blur is there)."""
    residual, shape = np.empty(x.size), np.empty(x.size)
    return _cost(x, y, p, f_scale, mode, residual, shape) - (f_scale * p[3] / BLUR_PRIOR_STD) ** 2


def _decay_guess(rise: float) -> float:
    """First guess of the pulse's decay, rows, from the 25 %-to-75 % rise of a ramp
    (``decay ln 3`` for an exponential one)."""
    return max(rise / np.log(3.0), 0.3)


def _window(n: int, edges: list[float], decay: float) -> np.ndarray:
    """Rows around the edges that the fit uses: a few rows on the flat side, six decay
    lengths of tail; the union for several edges, inside ``[0, n)``."""
    rows = [np.arange(int(np.floor(e - 3 - 2 * decay)), int(np.ceil(e + 2 + 6 * decay)) + 1) for e in edges]
    x = np.unique(np.concatenate(rows))
    return x[(x >= 0) & (x < n)]


def _half_light(hold: float, decay: float) -> float:
    """Rows from the pulse's start to the instant it has given half its light."""
    total = hold + decay
    if hold >= decay:
        return 0.5 * total
    return hold + decay * np.log(2.0 * decay / total)


def _censored_tail(values: np.ndarray, x: np.ndarray, trailing: float) -> np.ndarray:
    """Which rows ``x`` lie past the last changed row after a trailing edge (bool, shape of
    ``x``). A pulse's tail fades under the codec's dead zone and the detector's 1.5 DN step
    floor and reads exactly 0 long before the light is gone: those rows only say "less than
    that", and fitting them as 0 cuts the tail and with it the exposure short."""
    last = max(int(np.floor(trailing)), -1)
    while last + 1 < len(values) and values[last + 1] != 0 and np.isfinite(values[last + 1]):
        last += 1
    return x > last


def _censored_foot(values: np.ndarray, row: float, rising: bool) -> int:
    """The unchanged row next to a ramp's first changed one (before it for a leading edge,
    after it for a trailing one), or -1. Its light was real but small: under the codec's
    dead zone and the detector's 1.5 DN step floor it reads exactly 0, so it only says
    "less than that", and the fit leaves it out rather than pull the ramp late."""
    step = -1 if rising else 1
    first = int(np.floor(row)) + (1 if rising else 0)  # a row over the half level
    while 0 <= first + step < len(values) and values[first + step] != 0 and np.isfinite(values[first + step]):
        first += step
    foot = first + step
    return foot if 0 <= foot < len(values) and values[foot] == 0 else -1


@njit
def _fit(x, y, p, free, f_scale, mode, longer=False):  # pragma: no cover - compiled
    """Robust fit of the band model ``p`` = (start, hold, decay, blur, width, level) of
    ``mode`` (:data:`BAND`, :data:`RISING`, :data:`FALLING`) to ``y``; ``p`` is the first
    guess, ``free`` (bool, shape (6,)) the parameters fitted (the others stay), ``longer``
    whether the pulse may be longer than the exposure (:func:`_clamp`). x, y: shape (n,).

    Levenberg-Marquardt on the soft-L1 cost ``sum 2 f^2 (sqrt(1 + (r / f)^2) - 1)`` (``f`` =
    ``f_scale``), the normal equations weighted by the loss's derivative (iteratively
    reweighted), so rows hit by a player or a compression artefact barely count; the blur
    has a weak prior at 0 (:data:`BLUR_PRIOR_STD`). Returns (p, converged); not converged
    where ``f_scale`` is not positive or anything turns non-finite (numba's "numpy" error
    model: a division by zero gives inf, it does not raise).
    """
    n = x.size
    p = _clamp(p.copy(), mode, longer)
    if not (f_scale > 0.0 and np.isfinite(f_scale)) or n == 0 or not np.all(np.isfinite(p)):
        return p, False
    residual, shape = np.empty(n), np.empty(n)
    cost = _cost(x, y, p, f_scale, mode, residual, shape)
    if not np.isfinite(cost):
        return p, False
    index = np.flatnonzero(free)
    m = index.size
    damping = 1e-3
    jacobian = np.empty((n, m))
    trial_residual, trial_shape = np.empty(n), np.empty(n)
    for _ in range(300):
        for j in range(m):
            k = index[j]
            moved = p.copy()
            if k == 5:  # the level is linear: d model / d level = model / level
                moved[5] = p[5] + 1.0
            else:  # forward differences
                moved[k] += 1e-6 * max(1.0, abs(p[k]))
            step = moved[k] - p[k]
            for i in range(n):  # the level moves the model by its shape alone
                model = moved[_level_index(x[i], mode)] * shape[i] if k == 5 else _model(x[i], moved, mode)
                jacobian[i, j] = (model - y[i] - residual[i]) / step
        weight = 1.0 / np.sqrt(1.0 + (residual / f_scale) ** 2)
        normal = jacobian.T @ (jacobian * weight[:, None])
        gradient = jacobian.T @ (weight * residual)
        for j in range(m):
            if index[j] == 3:  # the blur's prior: its residual and slope
                normal[j, j] += (f_scale / BLUR_PRIOR_STD) ** 2
                gradient[j] += (f_scale / BLUR_PRIOR_STD) ** 2 * p[3]
        for _ in range(30):
            delta, _ = cholesky_solve(normal + damping * np.diag(np.diag(normal) + 1e-12), gradient)
            trial = p.copy()
            for j in range(m):
                trial[index[j]] -= delta[j]
            trial = _clamp(trial, mode, longer)
            trial_cost = _cost(x, y, trial, f_scale, mode, trial_residual, trial_shape)
            if trial_cost <= cost:
                break
            damping *= 10.0
        else:
            return p, True  # no step lowers the cost: at the minimum
        if not np.all(np.isfinite(trial)):
            return p, False
        moved_most = np.max(np.abs(trial - p))
        p, cost, damping = trial, trial_cost, max(damping * 0.3, 1e-9)
        residual, trial_residual = trial_residual, residual  # the new p's, from its cost
        shape, trial_shape = trial_shape, shape
        if moved_most < 1e-7 * (1.0 + np.max(np.abs(p))):
            return p, True
    return p, False


@njit
def _clamp(p, mode, longer):  # pragma: no cover - compiled
    """``p`` within bounds; in a band no longer a hold than the exposure unless the pulse
    may be ``longer`` (a band is the exposure convolved with the pulse: a rectangular
    pulse and an exposure trade places, and alone the longer of them is taken to be the
    exposure; :func:`common_width` tells them apart over a camera's bands)."""
    edge = mode == RISING or mode == FALLING
    p[1] = min(max(p[1], 0.0), MAX_LENGTH if edge or longer else max(p[4], 0.0))
    p[2] = min(max(p[2], MIN_DECAY), MAX_LENGTH)
    p[3] = min(max(p[3], 0.0), MAX_BLUR)
    p[4] = max(p[4], 0.0)
    if mode == SPLIT or mode == SPLIT_ONE_LEVEL:
        p[6] = max(p[6], 0.0)
    return p


@njit
def _cost(x, y, p, f_scale, mode, residual, shape):  # pragma: no cover - compiled
    """Soft-L1 cost of the model ``p`` against ``y``, plus the blur's prior; ``residual``
    and ``shape`` (shape (n,)) are set to the model less ``y`` and to :func:`_shape`."""
    total = 0.0
    for i in range(x.size):
        shape[i] = _shape(x[i], p, mode)
        residual[i] = p[_level_index(x[i], mode)] * shape[i] - y[i]
        total += 2.0 * f_scale**2 * (math.sqrt(1.0 + (residual[i] / f_scale) ** 2) - 1.0)
    return total + (f_scale * p[3] / BLUR_PRIOR_STD) ** 2


@njit
def _model(x, p, mode):  # pragma: no cover - compiled
    """The band's relative change at row ``x`` for ``p`` = (start, hold, decay, blur,
    width, level): the whole band, its rising edge (the light from 0 to ``level``) or its
    falling edge; split across frames, ``p`` also has (hidden, height, level in the next
    frame, :data:`SPLIT` only) and a row ``x < 0`` is row ``-1 - x`` of the next frame."""
    return p[_level_index(x, mode)] * _shape(x, p, mode)


@njit
def _level_index(x, mode):  # pragma: no cover - compiled
    """Where in ``p`` the level of row ``x`` is (:func:`_model`): 8 in the next frame of a
    :data:`SPLIT` band, else 5."""
    return 8 if mode == SPLIT and x < 0.0 else 5


@njit
def _shape(x, p, mode):  # pragma: no cover - compiled
    """:func:`_model` at a level of 1."""
    if (mode == SPLIT or mode == SPLIT_ONE_LEVEL) and x < 0.0:  # row -1 - x of the next frame, height + hidden rows on
        x = -1.0 - x + p[7] + p[6]
    share = _share(x - p[0], p[1], p[2], p[3])
    if mode == RISING:
        return share
    if mode == FALLING:
        return 1.0 - share
    return share - _share(x - p[0] - p[4], p[1], p[2], p[3])


@njit
def _share(z, hold, decay, blur):  # pragma: no cover - compiled
    """Share of the pulse's light (a hold of ``hold`` rows, then an exponential decay of
    ``decay`` rows) given ``z`` rows past its start, convolved with a Gaussian of ``blur``
    rows."""
    held = _blurred_ramp(z, blur) - _blurred_ramp(z - hold, blur) if hold > 0.0 else 0.0
    return (held + decay * _ramp(z - hold, decay, blur)) / (hold + decay)


@njit
def _blurred_ramp(z, blur):  # pragma: no cover - compiled
    """``max(z, 0)`` convolved with a Gaussian of ``blur`` rows."""
    if blur <= 0.0:
        return max(z, 0.0)
    u = z / blur
    return z * 0.5 * math.erfc(-u / math.sqrt(2.0)) + blur * math.exp(-0.5 * u * u) / math.sqrt(2.0 * math.pi)


@njit
def _ramp(z, scale, blur):  # pragma: no cover - compiled
    """Share of an exponential pulse's light in a row ``z`` rows past its start:
    ``1 - exp(-z / scale)`` (0 before), convolved with a Gaussian of ``blur`` rows. The tail
    term ``exp(a) Phi(b)`` is computed through ``erfcx`` where ``Phi(b)`` underflows."""
    if blur <= 0.0:
        return -math.expm1(-z / scale) if z > 0.0 else 0.0
    b = z / blur - blur / scale
    if b >= 0.0:
        tail = math.exp(-z / scale + 0.5 * (blur / scale) ** 2) * 0.5 * math.erfc(-b / math.sqrt(2.0))
    else:
        tail = 0.5 * math.exp(-0.5 * (z / blur) ** 2) * _erfcx(-b / math.sqrt(2.0))
    return 0.5 * math.erfc(-z / (blur * math.sqrt(2.0))) - tail


@njit
def _erfcx(t):  # pragma: no cover - compiled
    """``exp(t^2) erfc(t)`` for t >= 0 (asymptotic series past 25, where erfc underflows)."""
    if t < 25.0:
        return math.exp(t * t) * math.erfc(t)
    u = 1.0 / (t * t)
    return (1.0 - 0.5 * u + 0.75 * u * u) / (t * math.sqrt(math.pi))
