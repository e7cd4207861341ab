"""A wear law defined here only, registered through the public registry, runs end to end.

The exponential law ``dw/ds = k_i (exp(p / p0) - 1)`` is written against the contract
:class:`steady.wear.WearLaw` alone: no module of ``steady`` or ``transient`` knows it.  Its
steady state comes from its own inversion, ``p_i = p0 log(1 + C / k_i)`` with ``C`` from the
load, and the run-in reaches it; both commands write it to their files and read it back.  It is
the worked example of docs/model.md, "The code".
"""

import dataclasses
import math

import h5py
import numpy as np
import pytest
from scipy.optimize import brentq

from steady import WEAR_LAWS, WearLaw
from steady.cli import solve as steady_cli
from steady.output import read_result
from steady.schema import Key
from transient.cli import runin as transient_cli
from transient.output import read_run

#: The pressure scale of the test scene, Pa: twice its mean pressure, so that the law is
#: clearly not linear at the pressures of the run.
P0 = 4e5

SCENE = f"""
[punch]
radius = 0.004
[load]
normal_force = 10.0
[counterbody]
E_star = 1.3e6
[grid]
n = 32
[wear]
law = "exponential"
coefficients = [1.0e-4, 1.0e-3]
pressure_scale = {P0!r}
[phases]
map = {{ kind = "voronoi", n_seeds = 64, fill_factors = [0.7, 0.3], seed = 2031 }}
[transient]
tol = 1e-4
[initial_face]
kind = "flat"
"""


class ExponentialLaw(WearLaw):
    """``dw/ds = k_i (exp(p / p0) - 1)``: the rate grows exponentially with the pressure."""

    def __init__(self, coefficients, pressure_scale):
        self.coefficients = tuple(float(k) for k in coefficients)
        self.pressure_scale = float(pressure_scale)

    def __eq__(self, other):
        return (type(other) is type(self) and other.coefficients == self.coefficients
                and other.pressure_scale == self.pressure_scale)

    __hash__ = None

    @classmethod
    def from_values(cls, values, context):
        k = values["coefficients"]
        if context.n_phases is not None and len(k) != context.n_phases:
            raise ValueError(f"[wear] coefficients has {len(k)} values, the phase map "
                             f"{context.n_phases} phases")
        return cls(k, values["pressure_scale"])

    @property
    def n_phases(self):
        return len(self.coefficients)

    def describe(self):
        return (f"exponential law dw/ds = k (exp(p/p0) - 1), k = {list(self.coefficients)}, "
                f"p0 = {self.pressure_scale:g} Pa")

    def scene_values(self):
        return {"coefficients": list(self.coefficients), "pressure_scale": self.pressure_scale}

    def pressures_at(self, rate):
        """``g_i^-1(C) = p0 log(1 + C / k_i)`` of every phase, Pa."""
        return self.pressure_scale * np.log1p(rate / np.asarray(self.coefficients))

    def phase_pressures(self, counts, normal_force, pixel_area):
        areas = np.asarray(counts, dtype=float) * pixel_area

        def excess(log_rate):
            return float(np.dot(areas, self.pressures_at(math.exp(log_rate)))) - normal_force

        hi = 0.0
        while excess(hi) < 0:
            hi += 1.0
        log_rate = brentq(excess, hi - 60.0, hi, xtol=1e-14, rtol=4 * np.finfo(float).eps)
        return self.pressures_at(math.exp(log_rate))

    def wear_field(self, labels):
        k = np.asarray(self.coefficients)
        return np.where(labels >= 0, k[np.maximum(labels, 0)], 0.0)

    def rate(self, pressure, wear_field):
        return wear_field * np.expm1(np.maximum(pressure, 0.0) / self.pressure_scale)

    def _slope(self, pressure, field):
        return field / self.pressure_scale * np.exp(np.maximum(pressure, 0.0)
                                                    / self.pressure_scale)

    def linearisation(self, height, c, pressure, wear_field, face_mask, floor):
        p0 = np.where(face_mask, np.maximum(pressure, 0.0), 0.0)
        slope = self._slope(p0, wear_field)
        return c * slope, height + c * (self.rate(p0, wear_field) - slope * p0)

    def largest_rate_slope(self, pressure, coefficients, floor):
        return float(np.max(self._slope(pressure, coefficients)))

    def rate_constant(self, field, mean_pressure):
        return self._slope(mean_pressure, np.asarray(field, dtype=float))


@pytest.fixture()
def exponential_law():
    WEAR_LAWS.register("exponential", (
        Key("coefficients", "numbers", unit="1", low=0.0, required=True, per_phase=True,
            doc="k_i, m of depth per m of sliding at p = p0 log 2"),
        Key("pressure_scale", "number", unit="Pa", low=0.0, required=True, doc="p0")),
        doc="dw/ds = k_i (exp(p/p0) - 1)")(ExponentialLaw)
    yield ExponentialLaw
    WEAR_LAWS.unregister("exponential")


@pytest.fixture()
def scene_file(tmp_path):
    path = tmp_path / "exponential.toml"
    path.write_text(SCENE)
    return path


def _balanced(law, counts, pixel_area, pressures, force):
    """The common rate of the phases and the relative load error of ``pressures``."""
    rates = law.rate(np.asarray(pressures), np.asarray(law.coefficients))
    load = float(np.dot(counts, pressures)) * pixel_area
    return rates, load / force - 1.0


def test_the_law_inverts_its_own_steady_state(exponential_law):
    law = exponential_law((1e-4, 1e-3), P0)
    p = law.phase_pressures([700, 300], 10.0, 1e-8)
    rates, load = _balanced(law, [700, 300], 1e-8, p, 10.0)
    assert abs(rates[1] / rates[0] - 1) < 1e-13, f"rates {rates} differ"
    assert abs(load) < 1e-13, f"load off by {load:.3g}"
    assert law.restrict([1]) == exponential_law((1e-3,), P0), "restriction by per-phase keys"
    assert law.scene_words() == ("[wear] law = 'exponential', coefficients = [0.0001, 0.001], "
                                 f"pressure_scale = {P0!r}"), law.scene_words()


def test_steady_command_solves_the_law_and_records_it(exponential_law, scene_file, tmp_path,
                                                     capsys):
    out = tmp_path / "steady.h5"
    status = steady_cli.main([str(scene_file), "-o", str(out)])
    assert status == 0, capsys.readouterr().err
    stored = read_result(out).result
    law = exponential_law((1e-4, 1e-3), P0)
    assert stored.wear == law, f"the file reads back as {stored.wear}"
    counts = np.bincount(stored.labels[stored.labels >= 0])
    rates, load = _balanced(law, counts, stored.pixel_size ** 2, stored.phase_pressures, 10.0)
    assert abs(rates[1] / rates[0] - 1) < 1e-12, f"phase wear rates {rates} differ"
    assert abs(load) < 1e-12, f"load off by {load:.3g}"
    # Not eq. 7 of Archard's law, whose p_0 / p_1 is k_1 / k_0 = 10: at p ~ p0 the
    # exponential rate's curvature narrows the pressure ratio.
    ratio = stored.phase_pressures[0] / stored.phase_pressures[1]
    assert ratio < 9, f"p_0 / p_1 = {ratio}"
    with h5py.File(out) as f:
        assert f.attrs["wear_law_kind"] == "exponential", dict(f.attrs)
        scale = f["wear_pressure_scale"]
        assert scale[()] == P0 and scale.attrs["units"] == "Pa", "the law's own quantities"


def test_run_in_reaches_the_law_s_steady_face(exponential_law, scene_file, tmp_path, capsys):
    out = tmp_path / "run.h5"
    status = transient_cli.main([str(scene_file), "-o", str(out)])
    report, err = capsys.readouterr()
    assert status == 0, err
    result, attrs, _ = read_run(out)
    assert result.status == "steady", result.message
    with h5py.File(out) as f:
        face_error = float(f["comparison/face_error"][()])
        pressures = f["comparison"]["phase_pressures"][()]
        steady_pressures = f["comparison"]["steady_phase_pressures"][()]
    # The jump's own tolerance, as for the power law (tests/test_runin.py).
    assert face_error < 1e-6, f"final face {face_error:.3g} of the relief from the steady one"
    assert np.allclose(pressures, steady_pressures, rtol=1e-8), (pressures, steady_pressures)
    assert attrs["wear_law_kind"] == "exponential", "the run file records the law"
    status = transient_cli.main([str(scene_file), "-o", str(out), "--resume"])
    assert status == 0, capsys.readouterr().err


def test_a_resume_under_another_law_is_refused(exponential_law, scene_file, tmp_path, capsys):
    out = tmp_path / "run.h5"
    assert transient_cli.main([str(scene_file), "-o", str(out), "--max-steps", "3"]) == 1
    other = tmp_path / "power.toml"
    other.write_text(SCENE.replace('law = "exponential"', 'law = "power"')
                     .replace(f"pressure_scale = {P0!r}", "exponent = 1.0"))
    capsys.readouterr()
    status = transient_cli.main([str(other), "-o", str(out), "--resume"])
    err = capsys.readouterr().err
    assert status == 2 and "another wear law ([wear] law = 'exponential'" in err, err


def test_an_unregistered_law_is_not_read_back(exponential_law, scene_file, tmp_path, capsys):
    out = tmp_path / "steady.h5"
    assert steady_cli.main([str(scene_file), "-o", str(out)]) == 0, capsys.readouterr().err
    WEAR_LAWS.unregister("exponential")
    try:
        assert read_result(out).result.wear is None, "a law this program does not know"
    finally:
        WEAR_LAWS.register("exponential", exponential_law.keys)(exponential_law)


def test_the_contract_is_complete():
    abstract = sorted(WearLaw.__abstractmethods__)
    assert abstract == ["describe", "from_values", "largest_rate_slope", "linearisation",
                        "n_phases", "phase_pressures", "rate", "rate_constant",
                        "scene_values", "wear_field"], abstract
    assert dataclasses.is_dataclass(WEAR_LAWS["power"]), "the shipped laws are frozen values"
