"""Calibration of the machine and its probe from measured data (M1, M4, M5).

M5 (planar grating, 21 geometric errors of a 3-axis machine): readings I/O in
``grating_io``, the linearised volumetric model and identifiability in
``identify_model``, the global and stepwise identifications in ``identify`` and
``identify_stepwise``, outputs (compensation tables, maps, plots) in ``grating_out``.

M4 (rotary axes of a five-axis B/C machine): the seed's B ±90° test (δ, ε, rigid and
compliant) and the pivot calibration (ISO 230-7 location errors of B and C with their
standard uncertainties) in ``rotary``.
"""
