"""An example third-party adapter package for brdf-remap.

Installing it (``pip install ./examples/brdfremap-example``) makes ``toy`` appear in
``remap adapters``: its pyproject declares this module in the ``brdfremap`` entry-point
group, and the host calls the hook below with a ``register`` callback."""

from brdfremap.core import hookimpl


@hookimpl
def brdfremap_register_adapters(register):
    # Register the class, not an instance: the host constructs it only when chosen.
    from .adapter import ToyAdapter

    register("toy", ToyAdapter)
