"""Mitsuba 3's models, each one object (`model.MitsubaModel`) defined with its family: its
parameters, its BSDF dictionary, its reading as an `Appearance` and its converted start. No
mitsuba import here."""

from __future__ import annotations

from .blend import BLEND
from .conductors import AS_CONDUCTOR, CONDUCTOR, ROUGHCONDUCTOR
from .glasses import DIELECTRIC, ROUGHDIELECTRIC, THINDIELECTRIC
from .legacy import PHONG, WARD
from .model import MitsubaModel
from .params import CONDUCTOR_PRESETS  # noqa: F401  (the names `material=` accepts)
from .plastics import AS_PLASTIC, DIFFUSE, PLASTIC, ROUGHPLASTIC
from .principled import PRINCIPLED

MODELS: dict[str, MitsubaModel] = {m.name: m for m in (
    ROUGHCONDUCTOR, CONDUCTOR, ROUGHPLASTIC, PLASTIC, DIFFUSE, DIELECTRIC, ROUGHDIELECTRIC, THINDIELECTRIC, PRINCIPLED,
    WARD, PHONG, AS_CONDUCTOR, AS_PLASTIC, BLEND)}
