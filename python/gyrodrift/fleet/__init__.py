"""Fleets of runs: campaign spec, one run's science, the resumable store, one executor, the method study."""
