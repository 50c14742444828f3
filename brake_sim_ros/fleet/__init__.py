"""Fleets: how one brake unit and one run's operating conditions differ from the nominal.

:mod:`.scatter` draws a unit's parameters and sensor calibration from its id (manufacturing
scatter, keyed and reproducible); :mod:`.conditions` draws a run's operating conditions
(load, temperature, force profile) from its seed.
"""
