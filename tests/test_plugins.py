"""A new kind is defined and registered outside the packages: registries and plug-ins.

A phase-map kind defined here alone -- parallel stripes of two phases, lengths in m -- is
registered through the public registry (``steady.phases.PHASE_MAPS``) and runs end to end
through ``runin-steady`` and ``runin-transient`` without an edit to any module of ``steady``
or ``transient``.  The registry class every choice by name shares (``steady.registry``) is
tested here too: lookup, its message, iteration, unregistering, and the modules and entry
points it loads on first use.
"""

import dataclasses
import importlib.metadata
import math
import sys

import h5py
import numpy as np
import pytest
from conftest import run_cli

import steady.cli.solve as steady_cli
import steady.registry
import transient.__main__ as transient_cli
from steady.outline import Rectangle
from steady.output import read_result
from steady.phases import PHASE_MAPS, PhaseMap
from steady.registry import Registry
from steady.schema import Context, Key, KindRegistry
from transient.output import read_run
from transient.preconditioners import PRECONDITIONERS
from transient.stepping import SCHEMES

#: The face: a 4 mm x 8 mm rectangle, stripes across x.
WIDTH, LENGTH = 4e-3, 8e-3
#: Stripes of phase 1, 1 mm wide, every 4 mm: an area fraction of 1/4.
PERIOD, STRIPE = 4e-3, 1e-3
K0, K1 = 1e-13, 1e-12     # 1/Pa
FORCE = 1.0               # N: an rms slope of 0.04, within the small slopes


@dataclasses.dataclass(frozen=True)
class Stripes(PhaseMap):
    """Stripes of phase 1 of width ``stripe`` (m) every ``period`` (m) along x; phase 0 between.

    A stripe starts at the left edge of the face's bounding box, ``x = -L_x``, and every
    ``period`` after it.  Two pixels across a stripe resolve it.
    """

    period: float
    stripe: float

    def __post_init__(self):
        if not 0 < self.stripe < self.period:
            raise ValueError(f"stripe must lie in (0, period = {self.period!r} m), got "
                             f"{self.stripe!r} m")

    @classmethod
    def from_values(cls, values, context):
        return cls(values["period"], values["stripe"])

    @property
    def n_phases(self):
        return 2

    def min_grid(self, outline=None):
        # Pixels of side 2 L / n, at most half a stripe: n >= 4 L / stripe.
        scale = 1.0 if outline is None else outline.scale
        return max(8, math.ceil(4.0 * scale / self.stripe - 1e-9))

    def check_grid(self, grid):
        if grid.h > 0.5 * self.stripe * (1 + 1e-9):
            raise ValueError(f"grid too coarse for stripes {self.stripe!r} m wide: n = "
                             f"{grid.n}, the minimum is n = {self.min_grid(grid.outline)}")
        return grid.n

    def labels(self, grid):
        self.check_grid(grid)
        lx, _ = grid.outline.half_extent
        inside = np.mod(grid.x + lx, self.period) < self.stripe
        return np.where(grid.mask, np.broadcast_to(inside[:, None], grid.shape), -1)

    def file_record(self):
        return {"stripes": {"period": self.period, "period_units": "m",
                            "stripe": self.stripe, "stripe_units": "m"}}


KEYS = (Key("period", "number", unit="m", low=0.0, required=True, doc="stripe spacing"),
        Key("stripe", "number", unit="m", low=0.0, required=True, doc="stripe width"))


@pytest.fixture
def stripes():
    """The kind ``stripes`` registered for one test, withdrawn after it."""
    PHASE_MAPS.register("stripes", KEYS, doc="parallel stripes of phase 1")(Stripes)
    yield Stripes
    PHASE_MAPS.unregister("stripes")


def stripes_scene(path, n=32):
    """A scene file of the striped rectangle, with a run-in section."""
    path.write_text(f"""[punch]
shape = "rectangle"
width = {WIDTH!r}
length = {LENGTH!r}
[load]
normal_force = {FORCE!r}
[counterbody]
E_star = 1.3e6
[grid]
n = {n}
[wear]
coefficients = [{K0!r}, {K1!r}]
[phases]
map = {{ kind = "stripes", period = {PERIOD!r}, stripe = {STRIPE!r} }}
[transient]
tol = 1e-3
""")
    return path


def test_a_phase_map_kind_from_a_test_module_runs_through_runin_steady(stripes, tmp_path,
                                                                       capsys):
    scene, out = stripes_scene(tmp_path / "s.toml"), tmp_path / "steady.h5"
    status, _, err = run_cli(steady_cli, [scene, "-o", out, "--no-slope-error"], capsys)
    assert status == 0, f"exit {status}: {err}"
    result = read_result(out).result
    # The face (32 x 16 pixels of 0.25 mm) holds two periods whose edges are pixel edges:
    # the realised fill factors are the stripes' area fractions exactly.
    fraction = STRIPE / PERIOD
    assert result.shape == (16, 32), f"grid {result.shape}"
    assert np.allclose(result.fill_factors, (1 - fraction, fraction), rtol=0, atol=1e-15), \
        f"fill factors {result.fill_factors}, stripes {fraction}"
    p0, p1 = result.phase_pressures
    assert K0 * p0 == pytest.approx(K1 * p1, rel=1e-12), f"eq. 7: k_0 p_0 {K0 * p0} != " \
                                                          f"k_1 p_1 {K1 * p1}"
    area = WIDTH * LENGTH
    load = area * ((1 - fraction) * p0 + fraction * p1)
    assert load == pytest.approx(FORCE, rel=1e-12), f"the phases carry {load} N"
    with h5py.File(out, "r") as f:
        record = dict(f["stripes"].attrs)
    assert record == {"period": PERIOD, "period_units": "m", "stripe": STRIPE,
                      "stripe_units": "m"}, f"the map's own record: {record}"


def test_a_phase_map_kind_from_a_test_module_runs_in_to_its_steady_face(stripes, tmp_path,
                                                                        capsys):
    scene, out = stripes_scene(tmp_path / "s.toml"), tmp_path / "run.h5"
    status, _, err = run_cli(transient_cli, [scene, "-o", out], capsys)
    assert status == 0, f"exit {status}: {err}"
    result, _, arrays = read_run(out)
    assert result.status == "steady", f"the run ended {result.status!r}: {result.message}"
    labels = Stripes(PERIOD, STRIPE).labels(Rectangle(WIDTH, LENGTH).grid(32))
    assert np.array_equal(arrays["phase"], labels), "the run's phase map is the stripes"
    with h5py.File(out, "r") as f:
        comparison = {name: ds[()] for name, ds in f["comparison"].items()}
    # The run stops within tol = 1e-3 (f*) of the steady state (docs/model.md, "Stop test").
    assert comparison["face_error"] < 1e-3, f"face error {comparison['face_error']}"
    assert comparison["phase_pressure_error"] < 1e-3, \
        f"phase pressure error {comparison['phase_pressure_error']}"


def test_a_kind_must_subclass_the_contract_and_is_withdrawn_after_its_test(stripes):
    assert "stripes" in PHASE_MAPS and PHASE_MAPS["stripes"] is Stripes, "registered"

    class Loose:
        pass

    with pytest.raises(TypeError, match=r"phase map kind 'loose'.*must subclass "
                                        r"steady\.phases\.PhaseMap"):
        PHASE_MAPS.register("loose")(Loose)
    assert "loose" not in PHASE_MAPS, "a refused kind is not registered"
    with pytest.raises(ValueError, match="phase map kind 'stripes' is already registered"):
        PHASE_MAPS.register("stripes", KEYS)(Stripes)


def test_the_built_in_map_kinds_register_from_their_own_modules():
    # inclusions, micrograph and the 3-d kinds live in modules the scene reader does not
    # import: the registry loads them on its first lookup.
    assert {"homogeneous", "voronoi", "rods", "file", "inclusions", "micrograph", "voxels",
            "spheres"} <= set(PHASE_MAPS), sorted(PHASE_MAPS)
    assert all(issubclass(PHASE_MAPS[kind], PhaseMap) for kind in PHASE_MAPS), \
        "every kind subclasses PhaseMap"


# -- the registry class ----------------------------------------------------------------
def test_a_registry_looks_up_iterates_and_unregisters():
    colours = Registry("colour")
    colours.register("red", (1.0, 0.0, 0.0))
    colours.register("none", None)

    @colours.register("green")
    def green():
        return (0.0, 1.0, 0.0)

    assert list(colours) == ["red", "none", "green"], "the order of registration"
    assert colours["none"] is None and colours["green"] is green, "entries as registered"
    assert len(colours) == 3 and "red" in colours and ["x"] not in colours, "membership"
    with pytest.raises(ValueError, match=r"^unknown colour 'blue'; expected one of "
                                         r"\['green', 'none', 'red'\]$"):
        colours["blue"]
    with pytest.raises(ValueError, match="colour 'red' is already registered"):
        colours.register("red", 0)
    colours.unregister("red")
    assert list(colours) == ["none", "green"], "unregistered"
    with pytest.raises(ValueError, match="unknown colour 'red'"):
        colours.unregister("red")


def test_schemes_and_preconditioners_share_the_registry():
    assert isinstance(SCHEMES, Registry) and isinstance(PRECONDITIONERS, Registry), \
        "one registry class"
    with pytest.raises(ValueError, match=r"unknown preconditioner 'ilu'; expected one of \["):
        PRECONDITIONERS["ilu"]
    assert PRECONDITIONERS["none"] is None, "'none' is no preconditioner"


def test_modules_named_by_a_registry_register_on_first_lookup(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    shapes = KindRegistry("demo shape", "kind", modules=("demo_shapes_module",))
    sys.modules.pop("demo_shapes_module", None)
    monkeypatch.setattr(steady.registry, "_demo", shapes, raising=False)
    (tmp_path / "demo_shapes_module.py").write_text(
        "import steady.registry\n"
        "@steady.registry._demo.register('dot')\n"
        "class Dot:\n"
        "    @classmethod\n"
        "    def from_values(cls, values, context):\n"
        "        return cls()\n")
    assert "demo_shapes_module" not in sys.modules, "not imported before the lookup"
    assert shapes.build({"kind": "dot"}, Context(where="[demo]")).kind == "dot", "built"
    monkeypatch.delitem(sys.modules, "demo_shapes_module")


def test_entry_points_register_kinds_of_other_packages(tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(str(tmp_path))
    registry = Registry("demo law", entry_point_group="demo.laws")
    monkeypatch.setattr(steady.registry, "_demo", registry, raising=False)
    (tmp_path / "demo_law_plugin.py").write_text(
        "import steady.registry\nsteady.registry._demo.register('exponential', 'a law')\n")
    points = importlib.metadata.EntryPoints([
        importlib.metadata.EntryPoint("exponential", "demo_law_plugin", "demo.laws"),
        importlib.metadata.EntryPoint("broken", "demo_missing_module", "demo.laws"),
        importlib.metadata.EntryPoint("other", "demo_missing_module", "another.group")])
    monkeypatch.setattr(steady.registry, "_installed_entry_points", lambda: points)
    with pytest.warns(RuntimeWarning, match="demo law plug-in 'broken'.*cannot be loaded"):
        names = list(registry)
    assert names == ["exponential"] and registry["exponential"] == "a law", names
    monkeypatch.delitem(sys.modules, "demo_law_plugin")
