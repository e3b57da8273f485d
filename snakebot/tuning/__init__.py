"""Tuning on the twin and the robot: gait search, servo gain tuning, fitting the twin to logs.

``tuner.tune_gait`` (grid, CMA-ES, GA over a ``space.SearchSpace``), ``gain_search.search_gains``
and ``sysid.fit_servo`` are the entry points; ``engine.TwinBatch`` runs candidates in parallel.
See docs/tuning.md.
"""
