"""Production characterization: many devices in one run, on Dask.

:func:`~spicethermal.batch.runner.run_batch` fits, diagnoses and exports every bundle or curve
under the given paths on a ``dask.distributed`` cluster (:mod:`.runner`, one device in
:mod:`.device`); :mod:`.spread` turns the population into outliers with their reasons, a
typical and a worst-case ladder and a PWM peak table; :mod:`.summary` writes the HTML report;
:mod:`.population` simulates a population with manufacturing spread and planted defects.
Dask is an optional extra (``pip install 'spicethermal[batch]'``), imported only when a batch
runs.
"""
