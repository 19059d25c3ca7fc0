"""The Mitsuba 3 adapter plugin. Importing this module does not import mitsuba."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from .adapter import MitsubaAdapter

    register("mitsuba", MitsubaAdapter)


def register_bsdfs() -> None:
    """Register the ward, phong and ashikhmin_shirley Python BSDFs with Mitsuba (after set_variant)."""
    from .bsdfs import register_bsdfs as _register

    _register()


@hookimpl
def brdfremap_register_formats(register_reader, register_writer):
    from .reader import MitsubaXmlReader
    from .writer import MitsubaLibraryWriter

    register_reader(MitsubaXmlReader())
    register_writer(MitsubaLibraryWriter())


@hookimpl
def brdfremap_register_scene_writers(register):
    from .probe_scene import MitsubaSceneWriter

    register(MitsubaSceneWriter())
