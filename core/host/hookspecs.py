"""Hook specifications of the brdfremap plugin host."""

from __future__ import annotations

import pluggy

hookspec = pluggy.HookspecMarker("brdfremap")
hookimpl = pluggy.HookimplMarker("brdfremap")


@hookspec
def brdfremap_register_adapters(register):
    """Register renderer adapters.

    Call ``register(name, factory)`` once per adapter. ``factory`` is an ``Adapter`` subclass
    (or any callable with the same class attributes: ``models``, ``summary``,
    ``install_hint``, ``unavailable_reason()``). Register the class, not an instance, and do
    not import the renderer at module level: the host constructs the adapter only when a
    user chooses it, so ``remap --help`` and ``remap adapters`` stay fast.
    """


@hookspec(firstresult=True)
def brdfremap_adapter_from_file(path):
    """Load an adapter described by a file (``--adapter path/to/renderer.yaml``).

    Return ``(name, factory)`` if this plugin understands the file, else None. Raise
    ``ConfigError`` naming the file and field when it is yours but invalid."""


@hookspec
def brdfremap_register_schemas(register):
    """Register the file formats this plugin reads, for `remap schema NAME`.

    Call ``register(name, model)`` with a pydantic model class per format (e.g. ``renderer``
    for a renderer definition file). The host rejects a name registered twice."""


@hookspec
def brdfremap_register_formats(register_reader, register_writer):
    """Register library file formats (`remap convert`).

    Call ``register_reader(reader)`` for each format this plugin reads (an object with ``name``,
    ``suffixes``, ``accepts(path)`` and ``read(path) -> list[Entry]``; see
    ``brdfremap.core.library.formats``) and ``register_writer(writer)`` for each native library
    it writes (``name``, ``adapter``, ``models``, ``write(folder, items) -> list[Path]``). A
    reader must not run any program a file names, and must name the file in its errors."""


@hookspec
def brdfremap_register_scene_writers(register):
    """Register writers of the probe scene in a renderer's own format (`remap scene export`), for users
    who render it themselves (a renderer the tool cannot drive: `core.images`).

    Call ``register(writer)`` once per format: an object with ``name`` (the format, e.g. ``usd``; its
    files go to a folder of that name), ``suffix`` (``.usda``) and
    ``write(scene, path, maps) -> list[Path]``: one single-view ``ProbeScene`` (camera, sphere, lights in
    the scene's physical units, black background) written to ``path`` with the white Lambertian of albedo
    0.8 on the sphere, which a user swaps for their material (the sheet says how: ``material`` names it
    in the file); ``maps`` gives each environment light's map (its ``map`` field) as the path of an
    equirectangular EXR in the project's convention (`core.data.environment`) with its scale and rotation
    applied, which the file names relative to itself. Returns every file written (none: the format cannot
    hold that scene's lights). Also ``swap`` (a line of the sheet: how a user puts their material in the
    format's file), ``unavailable_reason()`` (None, or why it cannot write here: a package missing) and
    ``close()`` (called after an export: a writer that runs its renderer lets it go)."""
