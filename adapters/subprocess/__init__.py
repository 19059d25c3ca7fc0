"""The subprocess adapter plugin: external renderers described by YAML files.

Definitions are found in $BRDFREMAP_RENDERERS (a path list), ./configs/renderers and
~/.config/brdfremap/renderers; `--adapter path/to/renderer.yaml` loads one directly."""

from pathlib import Path

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from brdfremap.core.errors import ConfigError

    from .adapter import adapter_class, broken_definition, search_dirs

    for folder in search_dirs():
        for path in sorted(folder.glob("*.y*ml")):
            try:
                cls = adapter_class(path)
            except ConfigError as exc:
                # Listed as unavailable with the reason, so a typo in a definition is seen.
                cls = broken_definition(path, str(exc))
            register(cls.name, cls)


@hookimpl
def brdfremap_adapter_from_file(path):
    if Path(path).suffix not in (".yaml", ".yml"):
        return None
    from .adapter import adapter_class

    cls = adapter_class(path)
    return cls.name, cls


@hookimpl
def brdfremap_register_schemas(register):
    from .definition import RendererDef

    register("renderer", RendererDef)
