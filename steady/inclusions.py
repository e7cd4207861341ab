"""Random non-overlapping circular inclusions of one phase in a matrix (a phase map kind).

The geometry of the pillars argument (paper eq. 16-18): circular inclusions
(phase 1) scattered at random in a matrix (phase 0).  Inclusions are placed by
random sequential addition: radii are drawn first (all equal, or log-normal
about the mean radius), largest first each is put at a uniformly random
position that overlaps no inclusion placed before (touching is allowed).
Centres fill the periodic square ``[-B, B)^2`` with ``B = L + r_max`` (``L``
the face scale, which is ``a`` for a disk; every face lies in
``[-L, L]^2``): the placement has no walls, so the inclusions are as dense
everywhere (also where the rim cuts them), and no periodic image reaches
the face.  The placement is drawn in units of ``L`` (the radius ``r / L``),
so that the same parameters on a face twice as large give the same pattern
scaled; the lengths given and returned are in m.

Random sequential addition of equal disks jams at an area fraction of about
0.547 (Feder, J. Theor. Biol. 87, 1980); placing becomes slow well before.
Fill factors above :data:`MAX_FILL` are refused as impossible packings.
"""

from __future__ import annotations

import dataclasses
import functools
import math

import numpy as np

from .outline import MIN_SIDE_PIXELS, UNIT_DISK, as_grid
from .phases import (
    PHASE_MAPS,
    PhaseMap,
    check_resolution,
    face_words,
    grid_outline,
    scale_units_note,
)
from .schema import Key

__all__ = ["MAX_FILL", "MAX_INCLUSIONS", "MAX_RELATIVE_RADIUS", "Inclusions"]

#: Largest fill factor accepted (random sequential addition jams at about 0.547).
MAX_FILL = 0.5

#: Largest inclusion radius over the face scale ``L`` (the punch radius ``a`` of a disk), 1.
MAX_RELATIVE_RADIUS = 0.5

#: Most inclusions in the placement region (placing is a Python loop).
MAX_INCLUSIONS = 200_000

#: Random positions tried for one inclusion before the packing is declared impossible.
_MAX_TRIES = 20_000

#: Log-normal radii are truncated at this many standard deviations (in log space).
_TAIL = 3.0


def _log_params(radius, spread):
    """``mu, sigma`` of the log-normal radii of mean ``radius`` and relative sd ``spread``."""
    sigma = math.sqrt(math.log1p(spread ** 2))
    return math.log(radius) - 0.5 * sigma * sigma, sigma


def _max_radius(radius, spread):
    """Largest radius the truncated distribution can give, in the unit of ``radius``."""
    mu, sigma = _log_params(radius, spread)
    return math.exp(mu + _TAIL * sigma)


def _mean_square_radius(radius, spread):
    """``<r^2>`` of the truncated log-normal radii, in the unit of ``radius`` squared."""
    mu, sigma = _log_params(radius, spread)
    if sigma == 0:
        return radius ** 2
    # E[exp(2 mu + 2 sigma Z) | |Z| <= T] for a standard normal Z.
    t = _TAIL
    norm = math.erf(t / math.sqrt(2))
    shifted = 0.5 * (math.erf((t - 2 * sigma) / math.sqrt(2))
                     + math.erf((t + 2 * sigma) / math.sqrt(2)))
    return math.exp(2 * mu + 2 * sigma * sigma) * shifted / norm


def _box_area(radius, spread):
    """Area of the placement square ``[-B, B)^2``, ``B = 1 + r_max``, units of ``L^2``."""
    return (2.0 * (1.0 + _max_radius(radius, spread))) ** 2


# The keys of a scene's map, and the checks of the same parameters given in Python.
_RADIUS = Key("radius", "number", unit="m", low=0.0, required=True, doc="mean inclusion radius")
_SEED = Key("seed", "integer", low=0, low_open=False, required=True,
            doc="seed of the random generator")
_FILL_FACTOR = Key("fill_factor", "number", unit="1", low=0.0, high=1.0,
                   doc="expected area fraction of the inclusions, at most 0.5")
_COUNT = Key("count", "number", unit="1", low=0.0,
             doc="expected inclusion centres on the face, instead of fill_factor")
# Beyond a spread of 10 the truncation at three standard deviations of the logarithm
# takes a fifth of the mean radius away, and further out the distribution's numbers
# overflow: no spread of physical radii is that wide.
_RADIUS_SPREAD = Key("radius_spread", "number", unit="1", low=0.0, low_open=False, high=10.0,
                     high_open=False,
                     doc="relative standard deviation of the radii, log-normal (default 0)")


@PHASE_MAPS.register("inclusions", (_RADIUS, _SEED, _FILL_FACTOR, _COUNT, _RADIUS_SPREAD),
                     doc="random non-overlapping circular inclusions (phase 1) in a matrix "
                         "(phase 0)")
@dataclasses.dataclass(frozen=True)
class Inclusions(PhaseMap):
    """Random non-overlapping circular inclusions (phase 1) in a matrix (phase 0).

    Parameters
    ----------
    radius : float, m
        Mean inclusion radius; the largest radius of the distribution must
        stay below :data:`MAX_RELATIVE_RADIUS` times the face scale ``L``
        (checked when the inclusions meet a face, :meth:`check_outline`).
    seed : int
        Seed of :func:`numpy.random.default_rng`; the geometry is a pure
        function of the parameters and the face's scale.
    fill_factor : float, optional
        Expected area fraction of the inclusions, in ``(0, MAX_FILL]``.
    count : float, optional
        Expected number of inclusion centres on the face instead of
        ``fill_factor`` (exactly one of the two): the fill factor is then
        ``count * pi <r^2> / A`` with ``A`` the area of the face the
        inclusions are rasterised on.
    radius_spread : float, optional
        Relative standard deviation of the radii, at most 10 (default 0:
        all equal).  Radii are log-normal with mean ``radius``, truncated
        at three standard deviations of their logarithm.

    Raises
    ------
    ValueError
        A fill factor outside ``(0, 1)``, or above :data:`MAX_FILL` (an
        impossible packing); a radius that is not positive; both or neither
        of ``fill_factor`` and ``count``.  On a face (:meth:`check_outline`):
        a radius too large for it, a count too large for it, too many
        inclusions; a packing that random sequential addition cannot reach
        (found while placing, on first use).

    Notes
    -----
    A pixel belongs to an inclusion when its centre lies strictly inside
    it.  The realised fill factor on the face scatters about the target
    (:func:`steady.labels.realised_fill_factors`).  Resolution:
    ``n >= ceil(6 L / radius)`` (three pixels per mean radius).

    Examples
    --------
    Inclusions of 0.2 mm on a disk of 4 mm:

    >>> from steady.labels import realised_fill_factors
    >>> from steady.outline import Circle
    >>> geometry = Inclusions(radius=0.2e-3, seed=2718, fill_factor=0.2)
    >>> labels = geometry.labels(Circle(4e-3).grid(256))
    >>> print(f"{realised_fill_factors(labels, 2)[1]:.2f}")
    0.20
    """

    radius: float
    seed: int
    fill_factor: float | None = None
    count: float | None = None
    radius_spread: float = 0.0

    def __post_init__(self):
        """Check the parameters; store them as floats and ints."""
        # The radius's scale range is a problem's to check; its size against a face,
        # check_outline's.
        radius = _RADIUS.parse(self.radius, "inclusion", scale=False)
        object.__setattr__(self, "radius", radius)
        object.__setattr__(self, "seed", _SEED.parse(self.seed, "inclusion"))
        object.__setattr__(self, "radius_spread",
                           _RADIUS_SPREAD.parse(self.radius_spread, "inclusion"))
        if (self.fill_factor is None) == (self.count is None):
            raise ValueError("give exactly one of fill_factor and count, got "
                             f"fill_factor={self.fill_factor!r}, count={self.count!r}")
        if self.count is not None:
            object.__setattr__(self, "count", _COUNT.parse(self.count, "inclusion"))
            return
        fill = _FILL_FACTOR.parse(self.fill_factor, "inclusion")
        object.__setattr__(self, "fill_factor", fill)
        if fill > MAX_FILL:
            raise ValueError(self._impossible(f"fill factor {fill:g}"))

    @staticmethod
    def _impossible(what):
        return (f"impossible packing: {what} of random non-overlapping circles; random "
                f"sequential addition jams near 0.547, at most {MAX_FILL} is accepted")

    @classmethod
    def from_values(cls, values, context):
        """From the checked ``[phases] map`` keys (m), checked against the scene's face."""
        geometry = cls(**values)
        geometry.check_outline(context.outline)
        return geometry

    @classmethod
    def declared_phases(cls, values):
        """Two phases, the matrix and the inclusions."""
        return 2

    @property
    def n_phases(self):
        """Number of phases (2: matrix 0, inclusions 1)."""
        return 2

    @property
    def max_radius(self):
        """Largest radius the distribution can give, m."""
        return _max_radius(self.radius, self.radius_spread)

    @property
    def mean_square_radius(self):
        """``<r^2>`` of the truncated log-normal radii, m^2."""
        return _mean_square_radius(self.radius, self.radius_spread)

    def _scaled(self, outline):
        """``(radius / L, fill factor)`` on ``outline``: the numbers the placement uses."""
        L = outline.scale
        radius = self.radius / L
        if self.fill_factor is not None:
            return radius, self.fill_factor
        # The face's area in units of L^2; a disk's is pi exactly.
        face_area = math.pi if outline.kind == "circle" else outline.area / L**2
        return radius, self.count * math.pi * _mean_square_radius(radius,
                                                                  self.radius_spread) / face_area

    def target_fill_factor(self, outline=None):
        """Expected area fraction of the inclusions on ``outline`` (default the unit disk).

        ``fill_factor``, or from ``count`` and the face's area.
        """
        return self._scaled(UNIT_DISK if outline is None else outline)[1]

    def check_outline(self, outline):
        """``ValueError`` unless the inclusions can be placed on the face of ``outline``.

        The largest radius must stay below ``MAX_RELATIVE_RADIUS L``; a
        ``count`` must give a fill factor up to :data:`MAX_FILL`; at most
        :data:`MAX_INCLUSIONS` inclusions.
        """
        radius, fill = self._scaled(outline)
        L, spread = outline.scale, self.radius_spread
        largest = _max_radius(radius, spread)
        if largest >= MAX_RELATIVE_RADIUS:
            words = ("" if spread == 0 else
                     f" (the largest radius of the distribution is {largest * L:.4g} m)")
            note = (scale_units_note(L, radius=self.radius)
                    if self.max_radius < MAX_RELATIVE_RADIUS else "")
            raise ValueError(f"inclusion radius {self.radius:g} m is too large for the face "
                             f"({outline.describe()}){words}: radii must stay below "
                             f"{MAX_RELATIVE_RADIUS:g} L = {MAX_RELATIVE_RADIUS * L:.4g} m{note}")
        what = (f"fill factor {fill:g}" if self.count is None else
                f"count {self.count:g} (fill factor {fill:.4g})")
        if fill > MAX_FILL:
            raise ValueError(self._impossible(what) + f" on the face ({outline.describe()})")
        expected = fill * _box_area(radius, spread) / (math.pi
                                                       * _mean_square_radius(radius, spread))
        if expected > MAX_INCLUSIONS:
            raise ValueError(f"{expected:.3g} inclusions of radius {self.radius:g} m at {what} "
                             f"on the face ({outline.describe()}) are too many (at most "
                             f"{MAX_INCLUSIONS}); use larger inclusions")

    @functools.lru_cache(maxsize=4)  # noqa: B019 -- frozen, hashable; a few faces at most
    def _placement(self, radius, fill, scale):
        """The :class:`_Placement` of radius ``radius`` (units of ``L``) at ``fill``."""
        return _Placement(radius, self.seed, fill, self.radius_spread, scale)

    def placement(self, outline=None):
        """The inclusions placed for the face of ``outline`` (default: the unit disk, 1 m).

        Returns
        -------
        centres : ndarray, shape (N, 2), m, read-only
            In the periodic square ``[-B, B)^2``, ``B = L + r_max``
            (:meth:`placement_half_width`).
        radii : ndarray, shape (N,), m, read-only
            Largest first.
        """
        outline = UNIT_DISK if outline is None else outline
        self.check_outline(outline)
        placed = self._placement(*self._scaled(outline), outline.scale)
        centres, radii = placed.centres * outline.scale, placed.radii * outline.scale
        centres.flags.writeable = False
        radii.flags.writeable = False
        return centres, radii

    def placement_half_width(self, outline=None):
        """Half side ``B`` of the periodic placement square on ``outline``, m."""
        outline = UNIT_DISK if outline is None else outline
        radius, _ = self._scaled(outline)
        return (1.0 + _max_radius(radius, self.radius_spread)) * outline.scale

    def min_grid(self, outline=None):
        """``max(8, ceil(6 L / radius))``: three pixels per mean radius.

        ``L`` is the scale of ``outline`` (default: the unit disk, 1 m).
        """
        radius, _ = self._scaled(UNIT_DISK if outline is None else outline)
        return max(MIN_SIDE_PIXELS, math.ceil(6.0 / radius - 1e-9))

    def check_grid(self, grid):
        """``n`` as an int; ``ValueError`` in m if the grid is too coarse."""
        return check_resolution(grid, self.min_grid(grid_outline(grid)),
                                f"inclusions of radius {self.radius:g} m (3 pixels per radius) "
                                f"on {face_words(grid)}")

    def labels(self, grid):
        """Phase 1 inside the inclusions, 0 elsewhere on the face, -1 off it; shape of the grid."""
        self.check_outline(grid_outline(grid))  # first: it names lengths meant in units of L
        self.check_grid(grid)
        grid = as_grid(grid)
        return self._placement(*self._scaled(grid.outline), grid.outline.scale).labels(grid)


@dataclasses.dataclass(frozen=True)
class _Placement:
    """Inclusions placed in units of the face scale ``L``: the numbers of the rasteriser.

    ``radius`` is the mean radius over ``L``, ``fill`` the target fill
    factor; ``scale`` (``L``, m) only words the messages.
    """

    radius: float
    seed: int
    fill: float
    spread: float
    scale: float

    @property
    def box_half_width(self):
        """Half width ``1 + r_max`` of the periodic placement square, units of ``L``."""
        return 1.0 + _max_radius(self.radius, self.spread)

    @functools.cached_property
    def _placed(self):
        rng = np.random.default_rng(self.seed)
        mu, sigma = _log_params(self.radius, self.spread)
        target = self.fill * _box_area(self.radius, self.spread)
        radii = []
        area = 0.0
        while area < target:  # draw radii until their area reaches the target
            z = np.clip(rng.standard_normal(1024), -_TAIL, _TAIL)
            chunk = np.exp(mu + sigma * z)
            cum = area + np.cumsum(np.pi * chunk ** 2)
            stop = int(np.searchsorted(cum, target)) + 1
            radii.extend(chunk[:stop].tolist())
            area = float(cum[min(stop, chunk.size) - 1])
        # Round to the nearer total: keep the last radius only if it brings the
        # area closer to the target than leaving it out.
        last = math.pi * radii[-1] ** 2
        if len(radii) > 1 and area - target > target - (area - last):
            radii.pop()
        radii = np.sort(np.asarray(radii))[::-1]
        centres = _random_sequential_addition(
            radii, self.box_half_width, 2 * _max_radius(self.radius, self.spread), rng,
            self.scale)
        centres.flags.writeable = False
        radii.flags.writeable = False
        return centres, radii

    @property
    def centres(self):
        """Inclusion centres, shape (N, 2), units of ``L`` (read-only)."""
        return self._placed[0]

    @property
    def radii(self):
        """Inclusion radii, shape (N,), units of ``L`` (read-only), largest first."""
        return self._placed[1]

    def labels(self, grid):
        """Phase 1 inside the inclusions, 0 elsewhere on the face, -1 off it."""
        nx, ny = grid.shape
        x, y = grid.unit_x, grid.unit_y
        bx, by = grid.unit_half_extent
        h = 2.0 / grid.n
        inside = np.zeros((nx, ny), dtype=bool)
        for (cx, cy), r in zip(self.centres, self.radii, strict=True):
            i0, i1 = max(0, int((cx - r + bx) / h)), min(nx, int((cx + r + bx) / h) + 1)
            j0, j1 = max(0, int((cy - r + by) / h)), min(ny, int((cy + r + by) / h) + 1)
            if i0 >= i1 or j0 >= j1:
                continue
            dx = x[i0:i1, None] - cx
            dy = y[None, j0:j1] - cy
            inside[i0:i1, j0:j1] |= dx * dx + dy * dy < r * r
        return np.where(grid.mask, inside.astype(np.int64), -1)


def _random_sequential_addition(radii, half_width, cell, rng, scale):
    """Centres of non-overlapping disks on the periodic square ``[-B, B)^2``, in order.

    Lengths in units of the face scale ``scale`` (m, for the message).

    Periodic: the placement is statistically the same everywhere (no
    crowding at walls).  A cell list of side ``>= cell >= 2 r_max`` holds the
    disks placed so far; a candidate is compared with the disks of its
    3 x 3 cells, at the nearest periodic image.

    Raises
    ------
    ValueError
        A disk finds no free place in ``_MAX_TRIES`` tries.
    """
    period = 2 * half_width
    m = max(1, int(period / cell))
    side = period / m
    cells = {}
    centres = np.empty((radii.size, 2))
    xy = rng.uniform(-half_width, half_width, size=(4096, 2))
    used = 0
    for k, r in enumerate(radii):
        for _ in range(_MAX_TRIES):
            if used == xy.shape[0]:
                xy = rng.uniform(-half_width, half_width, size=(4096, 2))
                used = 0
            x, y = xy[used]
            used += 1
            ci = min(m - 1, int((x + half_width) / side))
            cj = min(m - 1, int((y + half_width) / side))
            neighbours = {((ci + a) % m, (cj + b) % m) for a in (-1, 0, 1) for b in (-1, 0, 1)}
            free = True
            for key in neighbours:
                for q in cells.get(key, ()):
                    dx = x - centres[q, 0]
                    dy = y - centres[q, 1]
                    dx -= period * round(dx / period)
                    dy -= period * round(dy / period)
                    reach = r + radii[q]
                    if dx * dx + dy * dy < reach * reach:
                        free = False
                        break
                if not free:
                    break
            if free:
                centres[k] = x, y
                cells.setdefault((ci, cj), []).append(k)
                break
        else:
            fill = np.sum(np.pi * radii[:k] ** 2) / period ** 2
            raise ValueError(f"impossible packing: inclusion {k + 1} of {radii.size} (radius "
                             f"{r * scale:.4g} m) found no free place in {_MAX_TRIES} random "
                             f"tries at fill factor {fill:.3f}; lower the fill factor or the "
                             f"radius spread")
    return centres
