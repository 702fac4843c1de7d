"""What a bundle's TSP readings mean: the converter of its calibration, whatever its kind (points
fitted here, a polynomial given, a K-factor declared; :mod:`spicethermal.io.datasets` holds
them as read), and the junction temperatures of its cooling curves.
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..core.errors import DataFormatError
from ..io.columns import frozen
from ..io.datasets import CalibrationTable, KFactorLaw
from .calibration import Calibration, Converter, KFactor

if TYPE_CHECKING:  # pragma: no cover
    from numpy.typing import NDArray

    from ..io.bundle import Bundle


def converter(calibration: CalibrationTable | KFactorLaw, degree: int | str = "auto"
              ) -> Converter:
    """The converter of a calibration as a bundle holds it, any kind: the polynomial fitted
    to a table's points (``degree``: 1, 2 or ``"auto"``, see :meth:`Calibration.fit`), the
    polynomial given with them (``degree`` ignored), or the K-factor declared.

    Parameters
    ----------
    calibration : CalibrationTable or KFactorLaw
        What was read (:mod:`spicethermal.io.datasets`).
    degree : int or str
        Of the polynomial fitted to a table.

    Returns
    -------
    Calibration or KFactor

    Examples
    --------
    >>> round(converter(CalibrationTable([25, 75], [0.60, 0.50])).k_factor_mv_per_k, 9)
    -2.0
    >>> round(float(converter(KFactorLaw(-2e-3, 0.6, 25.0)).temperature(0.55)), 9)
    50.0
    """
    if isinstance(calibration, KFactor):
        return calibration
    if isinstance(calibration, KFactorLaw):
        return KFactor(calibration.k_v_per_k, calibration.v_ref_v, calibration.t_ref_c,
                       calibration.label)
    if calibration.coefficients is not None:
        return Calibration.from_coefficients(calibration.coefficients, calibration.temp_c,
                                             calibration.v_tsp_v)
    return Calibration.fit(calibration.temp_c, calibration.v_tsp_v, degree=degree)


def calibration_fit(bundle: Bundle, degree: int | str = "auto") -> Converter:
    """The TSP converter of a bundle's calibration, any kind (:func:`converter`).

    Parameters
    ----------
    bundle : Bundle
        A bundle with a calibration (else :class:`DataFormatError`).
    degree : int or str
        As for :func:`converter`.

    Returns
    -------
    Calibration or KFactor
        What converts the bundle's TSP voltages to temperatures.

    Examples
    --------
    >>> from spicethermal.io.bundle import Bundle
    >>> b = Bundle(calibration=CalibrationTable([25, 75], [0.60, 0.50]))
    >>> round(calibration_fit(b).k_factor_mv_per_k, 6)
    -2.0
    """
    if bundle.calibration is None:
        where = f"{bundle.source}: " if bundle.source else ""
        raise DataFormatError(f"{where}the bundle has no calibration")
    return converter(bundle.calibration, degree)


def cooling_tj_c(bundle: Bundle, index: int = 0) -> NDArray:
    """Junction temperature of a bundle's cooling curve ``index``, degC: its ``tj_c``, or its
    ``v_tsp_v`` converted through the calibration (:func:`calibration_fit`).

    Parameters
    ----------
    bundle : Bundle
        The bundle.
    index : int
        Which cooling curve.

    Returns
    -------
    NDArray
        Read-only.

    Examples
    --------
    >>> from spicethermal.io.bundle import Bundle, CoolingTable
    >>> b = Bundle(calibration=KFactorLaw(-2e-3, 0.6, 25.0),
    ...            cooling=(CoolingTable([1e-3, 1.0], 1.0, v_tsp_v=[0.55, 0.59]),))
    >>> cooling_tj_c(b).round(9).tolist()
    [50.0, 30.0]
    """
    c = bundle.cooling[index]
    if c.tj_c is not None:
        return c.tj_c
    return frozen(calibration_fit(bundle).temperature(c.v_tsp_v))
