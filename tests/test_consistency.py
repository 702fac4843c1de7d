"""The consistency of a device effect with the cooling dynamics: a power that sags with
temperature is not a temperature coefficient, a real R(T) keeps its name."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.analysis.diagnose import diagnose
from spicethermal.analysis.scenarios import ACTUATOR_R, ACTUATOR_TAU, scenario_bundle
from spicethermal.analysis.verdict import at_noise
from spicethermal.core.ladder import Foster
from spicethermal.io.bundle import Bundle, CoolingTable

#: full diagnoses: the slow tier (`make test` runs it, `make check` does not)
pytestmark = pytest.mark.slow

T = 10.0 ** (np.arange(-50, 21) / 10)  # 10 µs ... 100 s


def _sagging_heater(gamma_per_k: float, seed: int = 0, noise_k: float = 0.02) -> Bundle:
    """Two cooling curves of a linear ladder whose heater dissipates ``P (1 − γ θj)`` in the
    steady state (the nominal ``P`` recorded): each curve is the linear Zth shape scaled by
    the power actually dissipated, ``θj = P Rth / (1 + γ P Rth)``."""
    lad = Foster.from_tau(ACTUATOR_R, ACTUATOR_TAU)
    rng = np.random.default_rng(seed)
    curves = []
    for p in (0.12, 0.30):
        actual = p / (1 + gamma_per_k * p * lad.rth)
        tj = 25.0 + actual * lad.cooling(T) + rng.normal(0.0, noise_k, T.size)
        curves.append(CoolingTable(T, p, tj_c=tj, tref_steady_c=25.0,
                                   tj_steady_c=25.0 + actual * lad.rth))
    return Bundle(ambient_c=25.0, cooling=curves, source="sagging heater")


def test_amplitude_only_physics_is_not_named_temperature_coefficient():
    d = diagnose(_sagging_heater(4e-3))
    assert d.effects == [] and d.verdict_effect is None
    assert "scaled per curve" in d.verdict_reason and "not in the catalogue" in d.verdict_reason
    # it is the temperature coefficient that the rule refused, on the cooling dynamics
    assert d.candidates[0].effect.name == "temperature-coefficient"
    assert d.candidates[0].improvement > 3


@pytest.mark.parametrize("seed", [0, 1])
def test_a_real_temperature_coefficient_keeps_its_name(seed):
    d = diagnose(scenario_bundle("temperature-coefficient", seed=seed))
    assert d.effects[:1] == ["temperature-coefficient"]


def _remounted(contact_k_per_w: float, seed: int = 0, noise_k: float = 0.02) -> Bundle:
    """Two cooling curves of a linear Cauer network (the independent validation network's
    own eigen-solution) whose second curve was measured after a remount: its outermost layer
    (the contact to the reference) gained ``contact_k_per_w``."""
    from spicethermal.validation.network import Network

    rng = np.random.default_rng(seed)
    r0, c0 = (4.0, 15.0, 45.0, 80.0), (2e-5, 2e-4, 8e-3, 0.35)
    curves = []
    for p, extra in ((0.12, 0.0), (0.30, contact_k_per_w)):
        r_f, tau = Network((*r0[:-1], r0[-1] + extra), c0).foster()
        rise = p * np.sum(r_f[None, :] * np.exp(-T[:, None] / tau[None, :]), axis=1)
        tj = 25.0 + rise + rng.normal(0.0, noise_k, T.size)
        curves.append(CoolingTable(T, p, tj_c=tj, tref_steady_c=25.0,
                                   tj_steady_c=25.0 + p * float(np.sum(r_f))))
    return Bundle(ambient_c=25.0, cooling=curves, source="remounted device")


@pytest.mark.parametrize("contact", [1.5, 3.0])
def test_a_remounted_contact_is_not_named_temperature_coefficient(contact):
    """A contact 2-4 % of Rth worse on the second curve: an outer layer's coefficient fits it
    to the noise (it was named so), but the linear ladder with that layer's resistance changed
    between the curves fits decisively better."""
    d = diagnose(_remounted(contact))
    assert d.effects == [] and d.verdict_effect is None, d.verdict_reason
    assert "outermost layer's resistance changed between curves" in d.verdict_reason
    # the change is read off the curves
    change = float(d.verdict_reason.split("cooling_2 ")[1].split(" K/W")[0])
    assert change == pytest.approx(contact, rel=0.05)
    # without the remount the same device is linear: nothing to name
    assert diagnose(_remounted(0.0)).verdict_effect is None


def test_an_outer_coefficient_that_a_change_of_setup_fits_as_well_is_not_named():
    """Draw 016 of ``bench/bench_validation_random.py 30 --seed 101 --only uncatalogued``
    (independent generator): an actuator whose outer layer's resistance drops 10-40 % when
    it passes 33 °C (convection changing regime). A coefficient of the outer layers fits the
    cooling curves at the noise, and so does the linear ladder with that layer's resistance
    changed between the curves: the data cannot tell the layer's temperature dependence from
    a change of setup, and nothing is named."""
    from conftest import bench_script

    c = bench_script("bench_validation_random").draw(30, 101, "uncatalogued")[16]
    assert c.name.startswith("016 uncatalogued/convection-switch")
    d = diagnose(c.record().bundle)
    assert d.effects == [] and d.verdict_effect is None, d.verdict_reason
    assert "cannot tell that layer's temperature dependence from a change of setup" in \
        d.verdict_reason


def test_a_junction_coefficient_that_a_power_error_fits_as_well_is_not_named():
    """Draws 019 and 027 of ``bench/bench_validation_random.py 30 --seed 202 --only
    uncatalogued`` (independent generator): heaters whose power falls 0.38 and 0.15 %/K of
    their own temperature. A coefficient of the junction form scales every layer's resistance
    by one law of the junction temperature: before the cut it scales the whole steady rise, as
    a power other than the recorded one does. On both it fits the cooling curves no more
    closely than the linear ladder with a power per curve (its dynamics while the device cools
    are within the noise): the data cannot tell the two apart, and nothing is named. On 027
    the coefficient's model fits every data set at its noise: it was named before, on the
    amplitudes alone, which the power explains as well."""
    from conftest import bench_script

    cases = bench_script("bench_validation_random").draw(30, 202, "uncatalogued")
    for k in (19, 27):
        c = cases[k]
        assert c.name.startswith(f"0{k} uncatalogued/heater-sag")
        d = diagnose(c.record().bundle)
        assert d.effects == [] and d.verdict_effect is None, d.verdict_reason
        assert "no catalogued effect explains the misfit: temperature-coefficient (junction) " \
            "fits the cooling curves no more closely than the linear ladder's shape scaled " \
            "per curve" in d.verdict_reason
        assert "cannot tell a resistance that follows the junction temperature from a " \
            "heating power other than the recorded one" in d.verdict_reason


def test_a_power_law_coefficient_is_weighed_on_its_converged_fit_before_it_is_refused():
    """Seed 303's draw 032 of ``bench/bench_validation_random.py 40 --seed 303 --only effect``
    (independent generator): a MOSFET whose layers' conductivity follows T^-2.1 (a heat
    capacity rising with T). Within the candidate's budget the power-law form stopped at
    n = 2.19 with its ladder unmoved, and a power per curve, fitting the cooling curves better
    than every form as fitted, refused the coefficient; refitted until it converges, the power
    law fits every data set and keeps its name, at the truth's exponent."""
    from conftest import bench_script

    c = bench_script("bench_validation_random").draw(33, 303, "effect")[32]
    assert c.name == "032 temperature-coefficient/power/n=2.1"
    d = diagnose(c.record().bundle)
    assert d.effects == ["temperature-coefficient"], d.verdict_reason
    first = d.steps[0].chosen.effect
    assert first.form == "power-law"
    assert first.params["exponent"] == pytest.approx(2.1, abs=0.1)
    assert at_noise(d.steps[-1].chosen.comparison, d.noise_k)
