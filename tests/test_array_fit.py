"""Fitting the array's N-port network to its self and mutual curves."""

from __future__ import annotations

import numpy as np
import pytest

from spicethermal.array.data import CouplingData, Element
from spicethermal.array.fit import fit_array
from spicethermal.bench.array_devices import ArrayGeometry
from spicethermal.core.errors import DataFormatError

T = np.geomspace(1e-4, 100, 61)


@pytest.fixture(scope="module")
def square():
    """A 2 x 2 array and its curves with 0.1 K/W of noise (0.1 % of Z_ii)."""
    truth = ArrayGeometry(rows=2, cols=2).model()
    return truth, CouplingData.of_model(truth, T, noise_k_per_w=0.1, seed=1)


def test_the_order_is_chosen_and_every_element_is_reproduced(square) -> None:
    truth, data = square
    fit = fit_array(data)
    assert fit.order == 4  # the cells' four layers (BIC)
    assert [t.order for t in fit.trials][:4] == [1, 2, 3, 4]
    assert fit.max_error < 0.01  # every element within 1 % of Z_ii (noise included)
    dc = np.diag(truth.modes.dc())
    vs_truth = np.max(np.abs(fit.model.zth(T) - truth.zth(T)), axis=0) / dc[:, None]
    assert vs_truth.max() < 0.005
    # the properties of the matrix hold by construction: symmetric, PSD, shared time constants
    z = fit.model.zth(T)
    np.testing.assert_allclose(z, np.swapaxes(z, 1, 2), atol=1e-10)
    assert min(np.linalg.eigvalsh(zk).min() for zk in z) > -1e-9
    assert "R1C1" in fit.table() and "worst element" in str(fit)
    report = fit.model.provenance["fit"]
    assert report["order"] == 4 and len(report["error_per_element"]) == 4


def test_mutual_curves_may_be_missing_but_self_curves_may_not(square) -> None:
    truth, data = square
    some = CouplingData(data.ports, tuple(e for e in data.elements if e.i == e.j or e.j == 0))
    fit = fit_array(some, order=4)
    assert np.isnan(fit.error[0, 1]) and fit.max_error < 0.01
    with pytest.raises(DataFormatError, match="no self curve of port R2C2"):
        CouplingData(data.ports, tuple(e for e in data.elements if (e.i, e.j) != (3, 3)))
    with pytest.raises(DataFormatError, match="positive and increasing"):
        Element(0, 0, np.array([1.0, 0.5]), np.array([1.0, 2.0]))
    with pytest.raises(DataFormatError, match="order 0"):
        fit_array(data, order=0)
