"""Fleets of runs: campaign specification, the resumable store, execution on processes or Dask, and the method study."""
