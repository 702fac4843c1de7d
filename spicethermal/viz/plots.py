"""Figures, organised by the paper's figure they reproduce (and extend): one import place.

The figures live in the modules of :mod:`spicethermal.viz`: ``base`` (shared helpers), ``fit``,
``identify``, ``bootstrap``, ``diagnosis`` and ``pwm``; this module gathers their public names.

matplotlib is imported only when a function here is called, and only its object-oriented API
is used (``Figure`` with the Agg canvas, no pyplot state), so nothing here changes a user's
backend. Functions that draw take ``ax=`` (an Axes to draw into; a new figure when omitted)
and return the Axes; ``figN(..., path)`` functions write a whole PNG figure atomically.

Contents
--------
* Fig. 7 — the ladder fit: :func:`plot_fit` (a), :func:`plot_residuals` (b),
  :func:`plot_ladder` (c), all three in :func:`fig7`.
* NID (T3Ster-style analysis): :func:`plot_spectrum_fit`, :func:`plot_spectrum`,
  :func:`fig_spectrum`; structure functions :func:`plot_cumulative_structure`,
  :func:`plot_differential_structure`, :func:`fig_structure` (separation marked).
* Bootstrap bands — :func:`shade`, on the fit :func:`fig_fit_band`, the spectrum
  :func:`fig_spectrum_band` and the structure functions :func:`fig_structure_band`.
* Diagnosis — residuals per data set :func:`plot_dataset_residuals`, before/after an effect
  :func:`fig_before_after`, candidates :func:`plot_candidates`, :func:`fig_candidates`,
  the RMS staircase of the iterative diagnosis :func:`plot_staircase`, :func:`fig_staircase`,
  the paper's Table 2 :func:`fig_table2_diagnosis`; all in :func:`diagnosis_figures`.
* Fig. 8 and Table 2 — duty-cycle impedance curves :func:`plot_r_duty`, :func:`fig8`; PWM
  residuals as grouped bars :func:`plot_table2` and heat map :func:`plot_table2_heatmap`, both in
  :func:`fig_table2`.
* The heater as an electrothermal part — the diode law's fit :func:`fig_diode_fit`; Vf, I and
  Tj in the bench circuit (Fig. 3) :func:`fig_circuit`.
"""

from __future__ import annotations

from .base import (
    axes,
    eng,
    new_figure,
    save_figure,
)
from .bootstrap import fig_fit_band, fig_spectrum_band, fig_structure_band, shade
from .diagnosis import (
    diagnosis_figures,
    fig_before_after,
    fig_candidates,
    fig_stages,
    fig_staircase,
    fig_table2_diagnosis,
    plot_candidates,
    plot_dataset_residuals,
    plot_staircase,
)
from .electrothermal import fig_circuit, fig_diode_fit
from .fit import (
    fig7,
    fig_calibration,
    fig_table1,
    plot_calibration,
    plot_fit,
    plot_ladder,
    plot_residuals,
)
from .identify import (
    fig_spectrum,
    fig_structure,
    plot_cumulative_structure,
    plot_differential_structure,
    plot_spectrum,
    plot_spectrum_fit,
)
from .pwm import (
    FIG8_DUTIES,
    fig8,
    fig_drive,
    fig_table2,
    plot_drive,
    plot_drive_duty,
    plot_r_duty,
    plot_table2,
    plot_table2_heatmap,
)

__all__ = ["FIG8_DUTIES", "axes", "diagnosis_figures", "eng", "fig7", "fig8",
           "fig_before_after", "fig_calibration", "fig_candidates", "fig_circuit",
           "fig_diode_fit", "fig_drive", "fig_fit_band", "fig_spectrum", "fig_spectrum_band",
           "fig_stages", "fig_staircase", "fig_structure", "fig_structure_band", "fig_table1",
           "fig_table2",
           "fig_table2_diagnosis", "new_figure", "plot_calibration", "plot_candidates",
           "plot_cumulative_structure", "plot_dataset_residuals",
           "plot_differential_structure", "plot_drive", "plot_drive_duty", "plot_fit",
           "plot_ladder", "plot_r_duty", "plot_residuals", "plot_spectrum",
           "plot_spectrum_fit", "plot_staircase", "plot_table2", "plot_table2_heatmap",
           "save_figure", "shade"]
