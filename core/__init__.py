"""brdf-remap core: the remap engine, metrics, schemas, plugin host and CLI. Knows no renderer."""

from .appearance import Appearance
from .errors import (
    AdapterUnavailableError,
    ConfigError,
    OptimisationError,
    RemapError,
    RenderError,
)
from .hookspecs import hookimpl
from .protocol import Adapter
from .scene import ProbeScene
from .schemas import LobeSpec, Material, ModelSpec, ParamSpec

__version__ = "0.1.0"
__all__ = [
    "hookimpl", "Adapter", "Appearance", "ProbeScene", "ModelSpec", "ParamSpec", "LobeSpec", "Material",
    "RemapError", "ConfigError", "AdapterUnavailableError", "RenderError", "OptimisationError",
]
