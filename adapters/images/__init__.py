"""Images rendered elsewhere as a source (`core.images`): the adapter that answers a source's renders
from the files a user rendered of `remap scene export`'s scenes. It renders nothing itself."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    from .adapter import ImagesAdapter

    register("images", ImagesAdapter)
