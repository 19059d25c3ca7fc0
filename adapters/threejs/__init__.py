"""The three.js adapter plugin (three.js in headless Chromium) and glTF files. Importing this module
starts no browser."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from .adapter import ThreeJsAdapter

    register("threejs", ThreeJsAdapter)


@hookimpl
def brdfremap_register_formats(register_reader, register_writer):
    from .library import GltfLibraryWriter, GltfReader

    register_reader(GltfReader())
    register_writer(GltfLibraryWriter())


@hookimpl
def brdfremap_register_scene_writers(register):
    from .probe_scene import GltfSceneWriter

    register(GltfSceneWriter())
