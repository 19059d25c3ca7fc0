"""The Blender Cycles adapter plugin. Importing this module does not import bpy."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from .adapter import CyclesAdapter

    register("cycles", CyclesAdapter)


@hookimpl
def brdfremap_register_formats(register_reader, register_writer):
    from .library import BlendLibraryWriter, BlendReader

    register_reader(BlendReader())
    register_writer(BlendLibraryWriter())


@hookimpl
def brdfremap_register_scene_writers(register):
    from .probe_scene import BlendSceneWriter

    register(BlendSceneWriter())
