"""Sensing: what a vehicle or a rig measures of a run, computed from its sample blocks.

The structure between the shoe pivots and the sensors (:mod:`.structure`, sampled linear
systems in :mod:`.lti`), the sensor channels and their signal paths (:mod:`.sensors`,
compiled in :mod:`.paths`) and sensor faults (:mod:`.faults`). It reads the physics'
sample blocks (:class:`~brake_sim_ros.model.run_setup.SampleBlock`) and never changes them.
"""
