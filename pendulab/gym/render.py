"""RGB frames of the pendulum by NumPy rasterisation (no figure, about a millisecond per frame).

Each primitive (thick segment, disc) is a distance test on the pixel centres inside its own
bounding box, so the cost follows the drawn area, not the image. The bob positions come from the
model's ``positions`` function (translated to Python once), springs are drawn as the zig-zag of
:func:`pendulab.viz.drawing.spring_polyline`.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .._inputs import checked
from ..model.model import Model
from ..model.pycode import to_python
from ..viz.drawing import spring_polyline

__all__ = ["FrameRenderer", "COLORS"]

#: RGB colours of the frame's parts.
COLORS: dict[str, tuple[int, int, int]] = {
    "background": (255, 255, 255),
    "line": (200, 200, 200),
    "link": (60, 60, 70),
    "pivot": (0, 0, 0),
    "bob1": (31, 119, 180),
    "bob2": (214, 39, 40),
}


@checked(size="render_size")
@dataclass
class FrameRenderer:
    """Draws states of one model into (size, size, 3) uint8 frames, pivot at the centre, y up.

    Attributes
    ----------
    model : Model
        The pendulum drawn.
    size : int
        Frame width and height [pixel] (>= 32).
    extent : float
        Half-width of the square of the world shown [m] (default 1.2 (L1 + L2)).
    goal_fraction : float
        A light horizontal line is drawn at ``goal_fraction (L1 + L2)`` above the pivot
        (the bonus line of the "realai" reward); 0 draws none.

    Raises
    ------
    ValueError
        ``size`` smaller than 32.

    Examples
    --------
    >>> import numpy as np
    >>> import pendulab as pl
    >>> from pendulab.gym import FrameRenderer
    >>> renderer = FrameRenderer(pl.rigid(), size=200)  # 200 x 200 pixels, pivot at the centre
    >>> frame = renderer.render(np.array([np.pi, np.pi, 0.0, 0.0]))  # balanced upright
    >>> frame.shape, frame.dtype
    ((200, 200, 3), dtype('uint8'))
    >>> column, row = renderer.to_pixel(np.array([0.0, 2.0]))  # where the tip is drawn, 2 m above the pivot
    >>> (column, row), bool((frame[row, column] != frame[0, 0]).any())  # not the background colour
    ((100, 16), True)
    """

    model: Model
    size: int = 400
    extent: float | None = None
    goal_fraction: float = 0.9
    _positions: Callable = field(init=False, repr=False)
    _p: list = field(init=False, repr=False)
    _background: np.ndarray = field(init=False, repr=False)

    def __post_init__(self) -> None:
        if isinstance(self.size, bool) or not isinstance(self.size, (int, np.integer)) or self.size < 32:
            raise ValueError(f"size must be an integer >= 32 [pixel], got {self.size!r}")
        values = self.model.params.resolved()
        reach = float(values["L1"] + values["L2"])
        if self.extent is None:
            self.extent = 1.2 * reach
        self._positions = to_python(self.model.functions["positions"])
        self._p = [float(v) for v in self.model.p]
        n = int(self.size)
        self._background = np.empty((n, n, 3), dtype=np.uint8)
        self._background[:] = COLORS["background"]
        if self.goal_fraction:
            row = self.to_pixel(np.array([0.0, self.goal_fraction * reach]))[1]
            if 0 <= row < n:
                self._background[row, ::4] = COLORS["line"]  # dotted: every fourth pixel
        self._scale = n / (2.0 * self.extent)

    def __reduce__(self) -> tuple[Any, tuple[Any, ...]]:
        # The translated kinematics is generated code: rebuild it from the settings instead of pickling it.
        return (FrameRenderer, (self.model, self.size, self.extent, self.goal_fraction))

    def to_pixel(self, point: np.ndarray) -> tuple[int, int]:
        """The (column, row) of the pixel containing a world point.

        Parameters
        ----------
        point : ndarray, shape (2,)
            (x, y) [m], y up, origin at the pivot.

        Returns
        -------
        tuple of int
            Column and row (row 0 at the top); may lie outside the frame.
        """
        n = int(self.size)
        scale = n / (2.0 * self.extent)
        return int(np.floor(n / 2 + point[0] * scale)), int(np.floor(n / 2 - point[1] * scale))

    def positions(self, x: np.ndarray) -> np.ndarray:
        """Bob positions of a state.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            State.

        Returns
        -------
        ndarray, shape (2, 2)
            Rows (x1, y1), (x2, y2) [m].
        """
        return np.asarray(self._positions(x, self._p), dtype=float).reshape(2, 2)

    def render(self, x: np.ndarray) -> np.ndarray:
        """One frame of state ``x``.

        Parameters
        ----------
        x : ndarray, shape (nx,)
            State.

        Returns
        -------
        ndarray, shape (size, size, 3), uint8
            RGB frame: links (springs as zig-zags) dark grey, bob 1 blue, bob 2 red, pivot black.
        """
        img = self._background.copy()
        b1, b2 = self.positions(x)
        pivot = np.zeros(2)
        ext = self.extent
        width = 0.012 * ext
        radius = 0.045 * ext
        for a, b in ((pivot, b1), (b1, b2)):
            if self.model.kind == "elastic":
                pts = spring_polyline(a, b, coils=7, width=0.035 * ext)
                for k in range(len(pts) - 1):
                    self._segment(img, pts[k], pts[k + 1], width, COLORS["link"])
            else:
                self._segment(img, a, b, width, COLORS["link"])
        self._disc(img, pivot, 0.6 * radius, COLORS["pivot"])
        self._disc(img, b1, radius, COLORS["bob1"])
        self._disc(img, b2, radius, COLORS["bob2"])
        return img

    # -- rasterisation: distance tests on the pixel centres of a bounding box ------------------------
    def _box(self, lo: np.ndarray, hi: np.ndarray) -> tuple[slice, slice, np.ndarray, np.ndarray] | None:
        n = int(self.size)
        s = self._scale
        c0 = max(int(np.floor(n / 2 + lo[0] * s)), 0)
        c1 = min(int(np.ceil(n / 2 + hi[0] * s)) + 1, n)
        r0 = max(int(np.floor(n / 2 - hi[1] * s)), 0)
        r1 = min(int(np.ceil(n / 2 - lo[1] * s)) + 1, n)
        if c0 >= c1 or r0 >= r1:
            return None
        xs = (np.arange(c0, c1) + 0.5 - n / 2) / s
        ys = (n / 2 - np.arange(r0, r1) - 0.5) / s
        return slice(r0, r1), slice(c0, c1), xs[None, :], ys[:, None]

    def _segment(self, img: np.ndarray, a: np.ndarray, b: np.ndarray, half_width: float, color: tuple[int, int, int]) -> None:
        box = self._box(np.minimum(a, b) - half_width, np.maximum(a, b) + half_width)
        if box is None:
            return
        rows, cols, xs, ys = box
        d = b - a
        dd = float(d @ d)
        px, py = xs - a[0], ys - a[1]
        s = np.clip((px * d[0] + py * d[1]) / dd, 0.0, 1.0) if dd > 0 else np.zeros_like(px + py)
        mask = (px - s * d[0]) ** 2 + (py - s * d[1]) ** 2 <= half_width**2
        img[rows, cols][mask] = color

    def _disc(self, img: np.ndarray, c: np.ndarray, radius: float, color: tuple[int, int, int]) -> None:
        box = self._box(c - radius, c + radius)
        if box is None:
            return
        rows, cols, xs, ys = box
        mask = (xs - c[0]) ** 2 + (ys - c[1]) ** 2 <= radius**2
        img[rows, cols][mask] = color
