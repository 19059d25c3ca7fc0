"""The Mitsuba 3 adapter plugin. Importing this module does not import mitsuba."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from .adapter import MitsubaAdapter

    register("mitsuba", MitsubaAdapter)
