"""The subprocess adapter plugin: external renderers described by YAML files.

Definitions are found in $BRDFREMAP_RENDERERS (a path list) and ~/.config/brdfremap/renderers
(never the current folder: a data bundle must not choose a program); `--adapter
path/to/renderer.yaml` loads one directly."""

from pathlib import Path

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from brdfremap.core.data.configio import WrongKindError
    from brdfremap.core.data.errors import ConfigError

    from .adapter import adapter_class, broken_definition, search_dirs

    found: dict[str, list[tuple[Path, type]]] = {}
    for folder in search_dirs():
        for path in sorted(folder.glob("*.y*ml")):
            try:
                cls = adapter_class(path)
            except WrongKindError:
                continue  # a material or scene kept beside the definitions: not a renderer
            except ConfigError as exc:
                # Listed as unavailable with the reason, so a typo in a definition is seen.
                cls = broken_definition(path, str(exc))
            found.setdefault(cls.name, []).append((path, cls))
    for name, defs in found.items():
        if len(defs) == 1:
            register(name, defs[0][1])
        else:  # which one was meant cannot be known: neither, and say where both are
            files = " and ".join(str(p) for p, _ in defs)
            register(name, broken_definition(defs[0][0], f"the name {name!r} is defined twice, in {files}: "
                                                         "rename one (its `name:`) or remove it"))


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
