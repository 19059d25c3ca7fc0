"""Many jobs: where results are stored, how jobs are run (in process, worker processes, Dask),
renderers' worker processes and the signals that stop a run. Imports the rooms below it."""
