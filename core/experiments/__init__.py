"""Experiments from the paper as runnable files: parameter sweeps and round trips (Figs. 5-10).

Rooms: `spec` (the file format and its grid of points), `run` (jobs through the store and the
runner), `analysis` (rows, cliffs, the round-trip line), `table` (CSV and summary), `plots`.
No renderer knowledge here: derived quantities (a conductor's reflectivity) come from the
reports, which have them from the adapters."""

from .analysis import Leg, Row, detect_cliffs, find_cliffs, roundtrip_fit
from .run import run_experiment, validate
from .spec import Experiment, Point, label, load_experiment, points_of
from .table import ExperimentResult

__all__ = ["Experiment", "ExperimentResult", "Leg", "Point", "Row", "detect_cliffs", "find_cliffs", "label",
           "load_experiment", "points_of", "roundtrip_fit", "run_experiment", "validate"]
