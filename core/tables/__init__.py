"""Remap tables (Sztrajman et al., JCGT 2019): a grid of fits over a source model's parameters, a
smooth map learnt from them, and lookups through it for instant remaps and textured materials.

Rooms: `spec` (the spec file and the grid), `maps` (candidate regressions), `table` (the table
file and lookups through its map), `plan` (a spec checked, its points as jobs), `refits` (points
fitted again: remedies, continuation, cliffs), `build` (the fits through the runner, the choice of
map), `outputs` (what is regressed), `dense` (the map baked for texels), `texels`, and `lookup` (a
material through a table)."""

from .spec import Axis, Layout, TableSpec, load_table_spec
from .table import Table, TableMap, read_table

__all__ = ["Axis", "Layout", "TableSpec", "load_table_spec", "Table", "TableMap", "read_table"]
