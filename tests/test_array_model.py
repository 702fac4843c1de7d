"""The N-port array model: its network, Z(t) matrix, file format and the simulated array."""

from __future__ import annotations

import json

import numpy as np
import pytest

from spicethermal.array.ansatz import Layout, neighbours, response
from spicethermal.array.braille import cell_ports, text_patterns
from spicethermal.array.modal import ArraySchedule
from spicethermal.array.model import ArrayModel, Port, is_array_document
from spicethermal.bench.array_devices import ArrayGeometry
from spicethermal.bench.devices import preset
from spicethermal.core.errors import DataFormatError
from spicethermal.core.ladder import Foster
from spicethermal.model import ThermalModel

T = np.geomspace(1e-5, 200, 80)


@pytest.fixture(scope="module")
def cell() -> ArrayModel:
    return ArrayGeometry().model()


def test_an_array_of_one_is_the_single_port_model() -> None:
    single = ThermalModel(Foster.from_tau([6.0, 20.0, 50.0, 70.0], [2e-4, 5e-3, 0.4, 12.0]))
    one = ArrayModel.from_thermal_model(single)
    assert one.n_ports == 1
    np.testing.assert_allclose(one.zth(T)[:, 0, 0], single.ladder.zth(T), atol=1e-9)
    back = one.self_model(0).ladder
    np.testing.assert_allclose(back.r, single.ladder.r, rtol=1e-9)
    np.testing.assert_allclose(back.tau, single.ladder.tau, rtol=1e-9)


def test_the_simulated_array_of_one_on_an_ideal_heat_sink_is_the_actuator() -> None:
    one = ArrayGeometry(rows=1, cols=1, base_share=1.0, substrate_r_k_per_w=1e-3,
                        substrate_c_j_per_k=1e-3).model()
    actuator = preset("actuator").foster
    np.testing.assert_allclose(one.zth(T)[:, 0, 0], actuator.zth(T), atol=2e-3)  # R_sub


def test_z_is_symmetric_passive_and_shares_its_time_constants(cell: ArrayModel) -> None:
    z = cell.zth(T)
    np.testing.assert_allclose(z, np.swapaxes(z, 1, 2), atol=1e-12)
    for zk in z:  # positive semidefinite at every time
        assert np.linalg.eigvalsh(zk).min() > -1e-9 * zk.max()
    # every element is a sum over the same modes: Z(t) = Σ w wᵀ (1 - exp(-λ t)) / λ
    m = cell.modes
    f = -np.expm1(-np.outer(T, m.lam)) / m.lam
    np.testing.assert_allclose(np.einsum("ik,jk,tk->tij", m.w, m.w, f), z, atol=1e-12)


def test_the_default_braille_cell_couples_within_the_issues_range(cell: ArrayModel) -> None:
    dc = cell.modes.dc()
    ratio = dc / np.diag(dc)[:, None]
    off = ratio[~np.eye(cell.n_ports, dtype=bool)]
    assert 0.05 <= off.min() and off.max() <= 0.30
    assert [p.name for p in cell.ports] == [f"D{k}" for k in range(1, 9)]


def test_the_exact_response_is_the_step_matrix_and_superposes(cell: ArrayModel) -> None:
    m = cell.modes
    p = np.zeros(8)
    p[2] = 0.25
    z = m.response(ArraySchedule.of([0.0], [p]), T)
    np.testing.assert_allclose(z @ m.w.T, 0.25 * cell.zth(T)[:, :, 2], atol=1e-9)
    # on for 1 s, then off: the step minus the step delayed
    on_off = m.response(ArraySchedule.of([0.0, 1.0], [p, np.zeros(8)]), T) @ m.w.T
    late = T > 1.0
    expected = 0.25 * (cell.zth(T)[:, :, 2] - np.where(late[:, None],
                                                        cell.zth(np.maximum(T - 1, 1e-12))[:, :, 2],
                                                        0.0))
    np.testing.assert_allclose(on_off, expected, atol=1e-9)


def test_the_model_file_round_trips_and_bad_files_name_the_key(cell: ArrayModel, tmp_path
                                                             ) -> None:
    path = cell.save(tmp_path / "array.json")
    assert is_array_document(path)
    back = ArrayModel.load(path)
    np.testing.assert_allclose(back.zth(T), cell.zth(T), rtol=1e-12)
    assert back.ports == cell.ports
    doc = json.loads(path.read_text())
    doc["resistors"][0]["b"] = "nowhere"
    with pytest.raises(DataFormatError, match=r"resistors\[0\]\.b: 'nowhere' is no node"):
        ArrayModel.from_dict(doc, "m.json")
    doc = json.loads(path.read_text())
    doc["nodes"][3]["c_j_per_k"] = -1
    with pytest.raises(DataFormatError, match=r"nodes\[3\]\.c_j_per_k: -1 must be positive"):
        ArrayModel.from_dict(doc, "m.json")
    with pytest.raises(DataFormatError, match="spicethermal-array-model/1"):
        ArrayModel.from_dict({"format": "spicethermal-model/3"}, "m.json")


def test_a_network_without_a_steady_state_is_refused() -> None:
    with pytest.raises(DataFormatError, match="no steady state"):
        ArrayModel((Port("A"),), ("A", "B"), ((0, 1, 1.0),), ((0, 1.0), (1, 1.0)))


def test_schedules_are_checked() -> None:
    with pytest.raises(DataFormatError, match="start at 0"):
        ArraySchedule.of([1.0], [[0.1]])
    with pytest.raises(DataFormatError, match="negative"):
        ArraySchedule.of([0.0], [[-0.1]])


def test_the_jacobian_of_z_is_exact() -> None:
    ports = cell_ports(2, 2)
    lay = Layout.of(ports, 3)
    rng = np.random.default_rng(1)
    p = np.log(np.concatenate([rng.uniform(0.01, 0.2, len(lay.conductances)),
                               rng.uniform(1e-3, 0.3, len(lay.capacitor_nodes))]))
    groups = [(T[::4], [(0, 0), (0, 1), (2, 3)]), (T[::4] * 1.01, [(1, 3), (3, 3)])]
    z, dz = response(lay, p, groups)
    for k in (0, 5, len(lay.conductances) - 1, len(p) - 1):
        h = np.zeros_like(p)
        h[k] = 1e-5
        zp, _ = response(lay, p + h, groups, False)
        zm, _ = response(lay, p - h, groups, False)
        for a, b, d in zip(zp, zm, dz, strict=True):
            np.testing.assert_allclose((a - b) / 2e-5, d[k], atol=1e-4 * np.abs(d[k]).max())


def test_neighbours_and_braille_patterns() -> None:
    six = cell_ports(3, 2)
    assert [p.name for p in six] == [f"D{k}" for k in range(1, 7)]
    assert len(neighbours(six)) == 11
    assert len(neighbours([Port("A"), Port("B"), Port("C")])) == 3  # no positions: every pair
    assert text_patterns("Hi 1") == [(1, 2, 5), (2, 4), (), (1,)]
    with pytest.raises(DataFormatError, match="position 2"):
        text_patterns("a€")


def test_the_documented_example_is_a_valid_model() -> None:
    import re
    from pathlib import Path

    text = (Path(__file__).resolve().parents[1] / "docs" / "array-model-format.md").read_text()
    doc = json.loads(re.search(r"```json\n(.*?)```", text, re.S).group(1))
    model = ArrayModel.from_dict(doc, "docs/array-model-format.md")
    assert model.n_ports == 2 and model.to_dict()["resistors"] == doc["resistors"]
