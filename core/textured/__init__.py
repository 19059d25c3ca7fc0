"""Textured sources, texel by texel through a remap table: a room above one job (`core.job`) and
the tables (`core.tables`), which it joins."""

from .remap import texture_result

__all__ = ["texture_result"]
