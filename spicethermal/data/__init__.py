"""Data sets shipped with spicethermal (read with :mod:`importlib.resources`).

* ``mur880e_table1.csv`` — the paper's Table 1: MUR880E normalized junction-to-case thermal
  impedance r(t) at 10 us ... 1 s, datasheet and measured (Rthjc = 1.51 K/W). Loaded by
  :func:`spicethermal.datasheet.mur880e`.
"""
