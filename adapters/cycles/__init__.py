"""The Blender Cycles adapter plugin. Importing this module does not import bpy."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from .adapter import CyclesAdapter

    register("cycles", CyclesAdapter)
