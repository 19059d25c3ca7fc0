"""The MaterialX plugin: a renderer adapter (MaterialX's own GLSL, `adapter.py`) whose models are
MaterialX's surface shaders, and the `.mtlx` format: documents read as materials of those models,
libraries written as documents. Importing this module imports no MaterialX."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from .adapter import MaterialXAdapter

    register("materialx", MaterialXAdapter)


@hookimpl
def brdfremap_register_formats(register_reader, register_writer):
    from .reader import MaterialXReader
    from .writer import MaterialXWriter, PrincipledAsOpenPbr

    register_reader(MaterialXReader())
    register_writer(MaterialXWriter())
    register_writer(PrincipledAsOpenPbr())
