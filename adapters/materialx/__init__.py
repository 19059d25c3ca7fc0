"""The MaterialX format plugin: `.mtlx` documents read as Cycles Principled materials, and
libraries converted to Principled written as OpenPBR. Importing this module does not import
MaterialX."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_formats(register_reader, register_writer):
    from .reader import MaterialXReader
    from .writer import MaterialXWriter

    register_reader(MaterialXReader())
    register_writer(MaterialXWriter())
