"""The simulated world: a textured rink, skating players, a bouncing puck, camera poses.

Rink coordinates are metres on the ice plane: x along the 60 m length, y across the
30 m width, origin at a corner. Object positions are functions of world time (ms).
Each camera sees the ice through a homography between image pixels (pixel centres at
integer coordinates, x right, y down) and rink metres.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING

import cv2
import numpy as np

from flashsync.errors import FlashsyncError

if TYPE_CHECKING:
    from flashsync.simulation.scenario import CameraSpec

RINK_LENGTH_M = 60.0
RINK_WIDTH_M = 30.0
RINK_CORNER_RADIUS_M = 8.5
TEXTURE_PX_PER_M = 20.0
TEXTURE_MARGIN_M = 20.0
_FAR = 28.0  # reflectance of the unlit upper stands beyond the texture, DN
_ICE = (150, 140, 132)  # reflectances are BGR, DN at illumination 1
_RED = (45, 40, 150)
_BLUE = (140, 70, 35)
_TEAM_COLORS = ((40, 35, 120), (110, 60, 25), (225, 225, 225), (30, 30, 30))


def _fold(x: np.ndarray, lo: np.ndarray, hi: np.ndarray) -> np.ndarray:
    """Reflect `x` into [lo, hi] as a ball bouncing between two walls."""
    span = hi - lo
    y = np.mod(x - lo, 2.0 * span)
    return lo + np.where(y > span, 2.0 * span - y, y)


@dataclass(frozen=True)
class Puck:
    """A small dark disc moving in straight lines, bouncing off the boards.

    Attributes
    ----------
    start_m : (float, float)
        Position at world time 0, metres.
    velocity_mps : (float, float)
        Velocity, m/s.
    radius_m : float
        Disc radius, metres (4x a real puck, so that it spans pixels in wide views).
    color : (int, int, int)
        BGR reflectance, DN.
    blur_samples : int
        Sub-instants averaged over the exposure (motion blur).
    """

    start_m: tuple
    velocity_mps: tuple
    radius_m: float = 0.3
    color: tuple = (12, 12, 12)
    blur_samples: int = 7

    def position(self, w_ms: np.ndarray) -> np.ndarray:
        """Position (metres) at world times `w_ms` (ms), shape ``w_ms.shape + (2,)``."""
        w = np.asarray(w_ms, dtype=float)[..., None] / 1000.0
        free = np.asarray(self.start_m) + np.asarray(self.velocity_mps) * w
        margin = self.radius_m + 0.3
        lo = np.array([margin, margin])
        hi = np.array([RINK_LENGTH_M - margin, RINK_WIDTH_M - margin])
        return _fold(free, lo, hi)


@dataclass(frozen=True)
class Player:
    """A skater seen as a disc on the ice, moving on a Lissajous path.

    Attributes
    ----------
    centre_m : (float, float)
        Centre of the path, metres.
    amplitude_m : (float, float)
        Amplitudes along x and y, metres.
    period_ms : (float, float)
        Periods along x and y, ms.
    phase : (float, float)
        Phases at world time 0, radians.
    radius_m : float
        Disc radius, metres.
    color : (int, int, int)
        BGR reflectance, DN.
    blur_samples : int
        Sub-instants averaged over the exposure.
    """

    centre_m: tuple
    amplitude_m: tuple
    period_ms: tuple
    phase: tuple
    radius_m: float = 0.5
    color: tuple = _TEAM_COLORS[0]
    blur_samples: int = 1

    def position(self, w_ms: np.ndarray) -> np.ndarray:
        """Position (metres) at world times `w_ms` (ms), shape ``w_ms.shape + (2,)``."""
        w = np.asarray(w_ms, dtype=float)[..., None]
        arg = 2.0 * np.pi * w / np.asarray(self.period_ms) + np.asarray(self.phase)
        return np.asarray(self.centre_m) + np.asarray(self.amplitude_m) * np.sin(arg)


@dataclass(frozen=True)
class Scene:
    """The rink texture and the moving objects.

    Attributes
    ----------
    texture : ndarray, shape (Ht, Wt, 3), uint8
        BGR reflectance of the ice and its surroundings, DN at illumination 1. Texture
        pixel ``(u, v)`` is at rink ``(u / px_per_m - margin_m, v / px_per_m - margin_m)``.
    px_per_m : float
        Texture resolution, px per metre.
    margin_m : float
        Width of the boards and stands around the ice in the texture, metres.
    players : tuple of Player
    puck : Puck
    """

    texture: np.ndarray
    px_per_m: float
    margin_m: float
    players: tuple
    puck: Puck

    @property
    def objects(self) -> tuple:
        """Players then the puck, in drawing order."""
        return self.players + (self.puck,)


def _smooth_noise(rng: np.random.Generator, shape: tuple, cell_px: int, amplitude: float) -> np.ndarray:
    """Band-limited noise: a coarse random grid upsampled with cubic interpolation."""
    coarse = rng.normal(0.0, amplitude, (shape[0] // cell_px + 2, shape[1] // cell_px + 2))
    return cv2.resize(
        coarse.astype(np.float32), (shape[1] + cell_px * 2, shape[0] + cell_px * 2), interpolation=cv2.INTER_CUBIC
    )[: shape[0], : shape[1]]


def make_texture(
    rng: np.random.Generator, px_per_m: float = TEXTURE_PX_PER_M, margin_m: float = TEXTURE_MARGIN_M
) -> np.ndarray:
    """Draw the rink: ice with scratches and markings, boards with ads, stands around.

    Parameters
    ----------
    rng : numpy.random.Generator
    px_per_m : float
        Texture resolution, px per metre.
    margin_m : float
        Width of boards and stands around the ice, metres.

    Returns
    -------
    ndarray, shape (Ht, Wt, 3), uint8
        BGR reflectance, see `Scene`.
    """
    s = px_per_m
    h = int(round((RINK_WIDTH_M + 2 * margin_m) * s))
    w = int(round((RINK_LENGTH_M + 2 * margin_m) * s))

    def px(x_m: float, y_m: float) -> tuple[int, int]:
        return int(round((x_m + margin_m) * s)), int(round((y_m + margin_m) * s))

    def ln(metres: float) -> int:
        return max(1, int(round(metres * s)))

    # Stands, in 0.5 m seats: sections of seat rows around the rink, half the seats taken.
    cell = 0.5
    yy, xx = np.mgrid[0 : h / s : cell, 0 : w / s : cell] - margin_m
    outside = np.maximum(np.maximum(-xx, xx - RINK_LENGTH_M), np.maximum(-yy, yy - RINK_WIDTH_M))
    angle = np.arctan2(yy - RINK_WIDTH_M / 2, (xx - RINK_LENGTH_M / 2) / 2)
    section = ((angle + np.pi) / (2 * np.pi) * 24).astype(int)
    seats = np.array([(70, 45, 35), (40, 40, 75), (60, 60, 60)], dtype=np.float32)[section % 3]
    seats *= (0.8 + 0.2 * ((outside // (2 * cell)) % 2))[..., None]
    people = rng.uniform(35, 130, xx.shape)[..., None] + rng.uniform(-20, 20, xx.shape + (3,))
    taken = rng.random(xx.shape + (1,)) < 0.5
    seats = np.clip(np.where(taken, people, seats), 0, 255).astype(np.uint8)
    img = cv2.resize(seats, (w, h), interpolation=cv2.INTER_NEAREST)

    # Boards with advertising panels, then the ice inside the rounded rectangle.
    corner = ln(RINK_CORNER_RADIUS_M)
    x0, y0 = px(-1.2, -1.2)
    x1, y1 = px(RINK_LENGTH_M + 1.2, RINK_WIDTH_M + 1.2)
    cv2.rectangle(img, (x0, y0), (x1, y1), (60, 60, 60), -1)
    for _ in range(40):
        along = rng.uniform(0, RINK_LENGTH_M - 4)
        color = tuple(int(c) for c in rng.integers(40, 230, 3))
        side = rng.integers(0, 2)
        ya, yb = (-1.1, -0.2) if side == 0 else (RINK_WIDTH_M + 0.2, RINK_WIDTH_M + 1.1)
        cv2.rectangle(img, px(along, ya), px(along + rng.uniform(1.5, 4), yb), color, -1)
    mask = np.zeros((h, w), np.uint8)
    rx0, ry0 = px(0, 0)
    rx1, ry1 = px(RINK_LENGTH_M, RINK_WIDTH_M)
    cv2.rectangle(mask, (rx0 + corner, ry0), (rx1 - corner, ry1), 255, -1)
    cv2.rectangle(mask, (rx0, ry0 + corner), (rx1, ry1 - corner), 255, -1)
    for cx, cy in (
        (rx0 + corner, ry0 + corner),
        (rx1 - corner, ry0 + corner),
        (rx0 + corner, ry1 - corner),
        (rx1 - corner, ry1 - corner),
    ):
        cv2.circle(mask, (cx, cy), corner, 255, -1, cv2.LINE_AA)
    ice = np.empty_like(img)
    ice[:] = _ICE
    shade = _smooth_noise(rng, (h, w), ln(2.0), 6.0) + _smooth_noise(rng, (h, w), ln(0.3), 2.5)
    ice = np.clip(ice + shade[..., None], 0, 255).astype(np.uint8)
    for _ in range(600):  # skate scratches
        a = px(rng.uniform(0, RINK_LENGTH_M), rng.uniform(0, RINK_WIDTH_M))
        ang, length = rng.uniform(0, np.pi), rng.uniform(0.5, 4.0) * s
        b = (int(a[0] + length * np.cos(ang)), int(a[1] + length * np.sin(ang)))
        tone = int(rng.uniform(-18, 18))
        cv2.line(ice, a, b, tuple(min(255, max(0, c + tone)) for c in _ICE), 1, cv2.LINE_AA)

    # Markings: centre red line, blue lines, goal lines, circles, creases.
    cv2.line(ice, px(30, 0), px(30, RINK_WIDTH_M), _RED, ln(0.3))
    for x in (30 - 8.5, 30 + 8.5):
        cv2.line(ice, px(x, 0), px(x, RINK_WIDTH_M), _BLUE, ln(0.3))
    for x in (4.0, RINK_LENGTH_M - 4.0):
        cv2.line(ice, px(x, 0.8), px(x, RINK_WIDTH_M - 0.8), _RED, ln(0.08))
    cv2.circle(ice, px(30, 15), ln(4.5), _BLUE, ln(0.08), cv2.LINE_AA)
    for x in (10.0, RINK_LENGTH_M - 10.0):
        for y in (7.5, RINK_WIDTH_M - 7.5):
            cv2.circle(ice, px(x, y), ln(4.5), _RED, ln(0.08), cv2.LINE_AA)
            cv2.circle(ice, px(x, y), ln(0.3), _RED, -1, cv2.LINE_AA)
    for x, (start, end) in ((4.0, (-90, 90)), (RINK_LENGTH_M - 4.0, (90, 270))):  # goal creases
        cv2.ellipse(ice, px(x, 15), (ln(1.8), ln(1.8)), 0, start, end, (190, 150, 120), -1, cv2.LINE_AA)
    for x in (20.0, 40.0):  # neutral-zone dots
        for y in (7.5, RINK_WIDTH_M - 7.5):
            cv2.circle(ice, px(x, y), ln(0.3), _RED, -1, cv2.LINE_AA)
    inside = mask[..., None].astype(np.float32) / 255.0
    img = (ice * inside + img * (1.0 - inside)).astype(np.uint8)
    return cv2.GaussianBlur(img, (0, 0), 0.7)


def rink_outline_m(points_per_corner: int = 12) -> np.ndarray:
    """The edge of the ice: a 60 x 30 m rectangle from the origin with rounded corners.

    Returns
    -------
    ndarray, shape (4 * points_per_corner + 1, 2)
        Closed polyline (first point repeated last), rink metres.
    """
    r = RINK_CORNER_RADIUS_M
    arc = np.linspace(0.0, np.pi / 2, points_per_corner)
    corners = (
        ((RINK_LENGTH_M - r, RINK_WIDTH_M - r), 0.0),
        ((r, RINK_WIDTH_M - r), np.pi / 2),
        ((r, r), np.pi),
        ((RINK_LENGTH_M - r, r), 1.5 * np.pi),
    )
    outline = np.concatenate(
        [np.stack([cx + r * np.cos(start + arc), cy + r * np.sin(start + arc)], axis=1) for (cx, cy), start in corners]
    )
    return np.concatenate([outline, outline[:1]])


def make_scene(
    seed: int, n_players: int = 8, puck_speed_mps: float = 36.0, player_radius_m: tuple[float, float] = (0.4, 0.55)
) -> Scene:
    """Generate the rink and its objects from a seed.

    Parameters
    ----------
    seed : int
    n_players : int
        Number of skaters (dark and bright team colours in turn), on paths that cross.
    puck_speed_mps : float
        Puck speed, m/s.
    player_radius_m : (float, float)
        Range of the skaters' disc radii, metres (uniform).

    Returns
    -------
    Scene
    """
    rng = np.random.default_rng([seed, 1000])
    texture = make_texture(rng)
    players = []
    for i in range(n_players):
        centre = (rng.uniform(15, 45), rng.uniform(9, 21))
        amp = (rng.uniform(5, 13), rng.uniform(3, 7))
        players.append(
            Player(
                centre_m=centre,
                amplitude_m=amp,
                period_ms=(rng.uniform(9000, 20000), rng.uniform(7000, 16000)),
                phase=(rng.uniform(0, 2 * np.pi), rng.uniform(0, 2 * np.pi)),
                radius_m=rng.uniform(*player_radius_m),
                color=_TEAM_COLORS[i % len(_TEAM_COLORS)],
            )
        )
    angle = rng.uniform(0, 2 * np.pi)
    puck = Puck(
        start_m=(rng.uniform(10, 50), rng.uniform(5, 25)),
        velocity_mps=(puck_speed_mps * np.cos(angle), puck_speed_mps * np.sin(angle)),
    )
    return Scene(texture, TEXTURE_PX_PER_M, TEXTURE_MARGIN_M, tuple(players), puck)


def rink_to_image(camera: CameraSpec) -> np.ndarray:
    """Projection of the ice plane into the image of a pinhole camera above it.

    Parameters
    ----------
    camera : CameraSpec
        Uses ``position_m``, ``look_at_m``, ``hfov_deg``, ``width`` and ``height``.

    Returns
    -------
    ndarray, shape (3, 3)
        ``[u, v, 1] ~ P @ [X, Y, 1]`` with ``(X, Y)`` in metres and ``(u, v)`` in px; the
        third coordinate is the depth (metres), positive in front of the camera.

    Raises
    ------
    FlashsyncError
        If the top of the image would look at or above the horizon.
    """
    centre = np.asarray(camera.position_m, dtype=float)
    target = np.array([camera.look_at_m[0], camera.look_at_m[1], 0.0])
    z_c = target - centre
    z_c /= np.linalg.norm(z_c)
    x_c = np.cross(z_c, [0.0, 0.0, 1.0])
    if np.linalg.norm(x_c) < 1e-6:  # looking straight down
        x_c = np.array([1.0, 0.0, 0.0])
    x_c /= np.linalg.norm(x_c)
    y_c = np.cross(z_c, x_c)
    rot = np.stack([x_c, y_c, z_c])
    f = 0.5 * camera.width / np.tan(np.radians(camera.hfov_deg) / 2.0)
    k = np.array([[f, 0.0, (camera.width - 1) / 2.0], [0.0, f, (camera.height - 1) / 2.0], [0, 0, 1]])
    corners = np.array([[0, 0, 1], [camera.width - 1, 0, 1]], dtype=float)
    rays = (rot.T @ np.linalg.solve(k, corners.T)).T
    if np.any(rays[:, 2] / np.linalg.norm(rays, axis=1) > -np.sin(np.radians(1.0))):
        raise FlashsyncError(
            f"camera {camera.name}: the top of the image looks above the horizon; "
            "aim it lower (look_at_m closer, position_m higher) or narrow hfov_deg"
        )
    return k @ np.column_stack([rot[:, 0], rot[:, 1], -rot @ centre])


def camera_homography(camera: CameraSpec) -> np.ndarray:
    """Homography from image pixels to rink metres, ``H[2, 2] = 1``.

    ``[X, Y, 1] ~ H @ [u, v, 1]``; the inverse of `rink_to_image`, scaled so that the
    third coordinate stays positive for image points that see the ice.
    """
    h = np.linalg.inv(rink_to_image(camera))
    return h / h[2, 2]


def apply_homography(h: np.ndarray, points: np.ndarray) -> np.ndarray:
    """Map points through a homography.

    Parameters
    ----------
    h : ndarray, shape (3, 3)
        Scaled so that mappable points have a positive third coordinate (as the
        matrices of this module are).
    points : ndarray, shape (..., 2)

    Returns
    -------
    ndarray, shape (..., 2)
        Mapped points; NaN for points behind the camera or above the horizon.
    """
    p = np.asarray(points, dtype=float)
    num = p @ h[:2, :2].T + h[:2, 2]
    den = p @ h[2, :2] + h[2, 2]
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(den[..., None] > 0, num / den[..., None], np.nan)


def camera_background(scene: Scene, homography: np.ndarray, width: int, height: int, color: bool) -> np.ndarray:
    """The static rink as a camera sees it, before lighting.

    Parameters
    ----------
    scene : Scene
    homography : ndarray, shape (3, 3)
        Image px -> rink metres.
    width, height : int
        Image size, px.
    color : bool
        BGR (True) or grey (False).

    Returns
    -------
    ndarray, float32, shape (height, width, 3) or (height, width)
        Reflectance, DN at illumination 1, rendered at 2x and area-averaged. Ground
        beyond the texture (far stands) is a dark constant.
    """
    s, m = scene.px_per_m, scene.margin_m
    rink_to_texture = np.array([[s, 0, m * s], [0, s, m * s], [0, 0, 1.0]])
    half = np.array([[0.5, 0, -0.25], [0, 0.5, -0.25], [0, 0, 1.0]])
    image2_to_texture = rink_to_texture @ homography @ half
    big = cv2.warpPerspective(
        scene.texture,
        image2_to_texture,
        (2 * width, 2 * height),
        flags=cv2.INTER_LINEAR | cv2.WARP_INVERSE_MAP,
        borderMode=cv2.BORDER_CONSTANT,
        borderValue=(_FAR, _FAR, _FAR),
    )
    img = cv2.resize(big, (width, height), interpolation=cv2.INTER_AREA).astype(np.float32)
    return img if color else cv2.cvtColor(img, cv2.COLOR_BGR2GRAY)
