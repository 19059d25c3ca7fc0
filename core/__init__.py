"""brdf-remap core: the remap engine, metrics, schemas, plugin host and CLI. Knows no renderer."""

from .data.appearance import Appearance
from .data.errors import AdapterUnavailableError, ConfigError, OptimisationError, RemapError, RenderError
from .data.scene import ProbeScene
from .data.schemas import LobeSpec, Material, ModelSpec, ParamSpec
from .host.hookspecs import hookimpl
from .host.model import Model
from .host.protocol import Adapter

__version__ = "0.1.0"
__all__ = [
    "hookimpl", "Adapter", "Model", "Appearance", "ProbeScene", "ModelSpec", "ParamSpec", "LobeSpec", "Material",
    "RemapError", "ConfigError", "AdapterUnavailableError", "RenderError", "OptimisationError",
]
