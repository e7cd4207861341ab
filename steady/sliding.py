"""Sliding kinematics: the local sliding speed over the face (``[sliding]``).

The paper assumes that every point of the face slides at the same speed
(a translation).  On a real tribometer it does not: a pin on a rotating
disk slides faster on its outer side, and a face seal or a thrust washer
turns about its own axis.  With the angular velocity ``omega`` about an
axis normal to the face through ``x_axis``, the local sliding speed is
``v(x) = |omega x (x - x_axis)| = omega |x - x_axis|``, and the wear law
``dw/ds = k_i p^m`` becomes::

    dw/ds = k_i (v(x) / v_ref) p^m,

``s`` the sliding distance of a reference point and ``v_ref`` its speed.
Each kind gives the speed ratio ``v / v_ref`` at the pixel centres
(:meth:`~PinOnDisk.speed_ratio`):

- ``translation`` -- uniform, ratio 1 (the paper; the default);
- ``pin_on_disk`` -- the disk's axis at ``(-track_radius, 0)`` from the
  face's centre; the reference point is the face's centre (on the track),
  ``v / v_ref = |x - x_axis| / track_radius``;
- ``rotation`` -- the axis is the face's centre; the reference point lies at
  the outline's scale ``L`` from it (the outer radius of an annulus),
  ``v / v_ref = |x| / L``.

In the steady state every point wears at the same rate, ``k_i v p^m / v_ref
= C``, so ``p(x) = (C v_ref / (k_i v(x)))^(1/m)`` with ``C`` from the load:
the speed multiplies the coefficients of a wear law ``k_i g(p)``, whose
factorisation gives the pixel-wise steady pressure
(:meth:`steady.wear.Factorisation.pixel_pressures`); the face is ``K p`` as
before.  The axis must
lie off the closed face: where the speed vanishes a face does not wear, and
its steady pressure ``p ~ r^(-1/m)`` is unbounded at the axis (a rotating
disk; an annulus about its centre is regular).

Kinds are registered in :data:`SLIDING` with their keys.

Examples
--------
>>> from steady.outline import Circle
>>> grid = Circle(4e-3).grid(16)
>>> ratio = PinOnDisk(0.02).speed_ratio(grid)
>>> bool(ratio[grid.mask].min() > 0.8 and ratio[grid.mask].max() < 1.2)
True
"""

from __future__ import annotations

import dataclasses

import numpy as np

from .schema import Context, Key, KindRegistry

__all__ = ["SLIDING", "PinOnDisk", "Rotation", "Translation", "sliding_file_attributes",
           "sliding_from_file", "sliding_from_table"]

#: Registered sliding kinematics, by ``[sliding] kind`` (default ``"translation"``).
SLIDING = KindRegistry("sliding kind", "kind", default="translation",
                       entry_point_group="runin.sliding")


class _Kinematics:
    """What every kind shares: the axis, the speed ratio, the check against a face."""

    #: Whether the speed is the same everywhere (the paper's assumption).
    uniform = False
    #: What to change when the axis lies on the face, for the message.
    _remedy = "use a face that leaves the axis out"

    def axis(self, outline):
        """``(x, y)`` of the rotation axis, m, relative to the face's centre."""
        raise NotImplementedError

    def reference_radius(self, outline):
        """Distance of the reference point from the axis, m (``v_ref = omega r_ref``)."""
        raise NotImplementedError

    def speed_ratio(self, grid):
        """``v / v_ref`` at every pixel centre of ``grid``, shape ``grid.shape``, 1.

        Parameters
        ----------
        grid : steady.outline.FaceGrid

        Returns
        -------
        ndarray, shape (nx, ny)
            Positive on the face (the axis lies off it, :meth:`check_outline`).
        """
        ax, ay = self.axis(grid.outline)
        r = np.hypot(grid.x[:, None] - ax, grid.y[None, :] - ay)
        return r / self.reference_radius(grid.outline)

    def check_outline(self, outline, where="[sliding]"):
        """``ValueError`` unless the rotation axis lies off the closed face, naming both."""
        ax, ay = self.axis(outline)
        if bool(np.asarray(outline.covers(np.float64(ax), np.float64(ay)))):
            raise ValueError(
                f"{where} {self.describe()}: the rotation axis at (x, y) = ({ax:g}, {ay:g}) m "
                f"lies on the {outline.describe()}; the sliding speed vanishes there and the "
                f"steady pressure p ~ r^(-1/m) is unbounded at the axis ({self._remedy})")


@SLIDING.register("translation", (), doc="uniform sliding speed: the paper's assumption")
@dataclasses.dataclass(frozen=True)
class Translation(_Kinematics):
    """Every point slides at the same speed (the paper's assumption 3)."""

    uniform = True

    @classmethod
    def from_values(cls, values, context):
        """From the (no) checked keys."""
        return cls()

    def describe(self):
        """The kind in words."""
        return "translation"

    def speed_ratio(self, grid):
        """Ones, shape ``grid.shape``."""
        return np.ones(grid.shape)

    def check_outline(self, outline, where="[sliding]"):
        """Any face slides uniformly."""


#: The pin on disk's key; a PinOnDisk built in Python checks its radius through it too.
_TRACK_RADIUS = Key("track_radius", "number", unit="m", low=0.0, required=True,
                    doc="distance of the face's centre from the disk's axis, which lies at "
                        "(x, y) = (-track_radius, 0)")


@SLIDING.register("pin_on_disk", (_TRACK_RADIUS,),
                  doc="a pin on a rotating disk: v = omega |x - x_axis|, v_ref at the face's "
                      "centre")
@dataclasses.dataclass(frozen=True)
class PinOnDisk(_Kinematics):
    """A pin on a rotating disk whose axis lies at ``(-track_radius, 0)``.

    Parameters
    ----------
    track_radius : float, m
        Distance of the face's centre from the disk's axis, positive and
        finite; the face's centre is the reference point.
    """

    track_radius: float

    _remedy = "use a track_radius beyond the face's reach along -x"

    def __post_init__(self):
        """Check the radius."""
        # Its scale range is a problem's to check; its reach, check_outline's.
        object.__setattr__(self, "track_radius",
                           _TRACK_RADIUS.parse(self.track_radius, "", scale=False))

    @classmethod
    def from_values(cls, values, context):
        """From the checked keys; the axis must lie off the face (``context.outline``)."""
        kinematics = cls(values["track_radius"])
        if context.outline is not None:
            kinematics.check_outline(context.outline, context.where)
        return kinematics

    def describe(self):
        """The kind in words."""
        return f"pin_on_disk, track_radius = {self.track_radius!r} m"

    def axis(self, outline):
        """``(-track_radius, 0)``, m."""
        return -self.track_radius, 0.0

    def reference_radius(self, outline):
        """``track_radius``, m: the face's centre is the reference point."""
        return self.track_radius


@SLIDING.register("rotation", (),
                  doc="rotation about the face's centre: v = omega |x|, v_ref at radius L")
@dataclasses.dataclass(frozen=True)
class Rotation(_Kinematics):
    """Rotation about the face's centre (a face seal, a thrust washer).

    The reference point lies at the outline's scale ``L`` from the axis (the
    outer radius of an annulus); the face must leave its centre out.
    """

    @classmethod
    def from_values(cls, values, context):
        """From the (no) checked keys; the axis must lie off the face (``context.outline``)."""
        kinematics = cls()
        if context.outline is not None:
            kinematics.check_outline(context.outline, context.where)
        return kinematics

    def describe(self):
        """The kind in words."""
        return "rotation about the face's centre"

    def axis(self, outline):
        """``(0, 0)``: the face's centre."""
        return 0.0, 0.0

    def reference_radius(self, outline):
        """``L``, the outline's scale, m."""
        return outline.scale


def sliding_from_table(table, outline, base_dir="."):
    """The kinematics of a scene's ``[sliding]`` table, checked against the face's outline.

    Raises
    ------
    ValueError
        An unknown kind or key, a bad value, or an axis on the face; the
        message names ``[sliding]`` and the value.

    Examples
    --------
    >>> from steady.outline import Circle
    >>> sliding_from_table({"kind": "pin_on_disk", "track_radius": 0.02}, Circle(4e-3))
    PinOnDisk(track_radius=0.02)
    """
    import pathlib

    context = Context(base_dir=pathlib.Path(base_dir), outline=outline, where="[sliding]")
    return SLIDING.build(table, context)


def sliding_file_attributes(kinematics):
    """What a run file records of the sliding kinematics: ``name -> (value, unit)``.

    ``sliding_kind`` (its ``[sliding] kind``) and each of the kind's keys as
    ``sliding_<key>`` in the key's unit; nothing for a translation (None,
    or a uniform kind): a file without them was a translation.
    :func:`sliding_from_file` reads them back.

    Examples
    --------
    >>> sliding_file_attributes(PinOnDisk(0.02))
    {'sliding_kind': ('pin_on_disk', None), 'sliding_track_radius': (0.02, 'm')}
    >>> sliding_file_attributes(None)
    {}
    """
    if kinematics is None or kinematics.uniform:
        return {}
    attrs = {"sliding_kind": (kinematics.kind, None)}
    for key in kinematics.keys:
        attrs[f"sliding_{key.name}"] = (getattr(kinematics, key.name), key.unit or None)
    return attrs


def sliding_from_file(attrs):
    """The kinematics a file recorded (:func:`sliding_file_attributes`), or None if unknown.

    Parameters
    ----------
    attrs : mapping
        The file's attributes (``h5py`` attributes, or a dict of them).

    Returns
    -------
    kinematics or None
        A :class:`Translation` when the file records none; None when it
        names a kind that is not registered here.

    Raises
    ------
    ValueError
        A registered kind whose attributes are missing or bad.

    Examples
    --------
    >>> sliding_from_file({"sliding_kind": "pin_on_disk", "sliding_track_radius": 0.02})
    PinOnDisk(track_radius=0.02)
    >>> sliding_from_file({})
    Translation()
    """
    import pathlib

    kind = attrs.get("sliding_kind", "translation")
    if isinstance(kind, bytes):
        kind = kind.decode()
    kind = str(kind)
    if kind not in SLIDING:
        return None
    table = {"kind": kind}
    for key in SLIDING[kind].keys:
        name = f"sliding_{key.name}"
        if name not in attrs:
            raise ValueError(f"the file records the sliding kind {kind!r} without {name}")
        value = attrs[name]
        table[key.name] = value.item() if hasattr(value, "item") else value
    return SLIDING.build(table, Context(base_dir=pathlib.Path("."),
                                        where="the file's sliding kinematics"))
