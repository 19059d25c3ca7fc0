"""Helpers shared by the tests."""

from __future__ import annotations

import types

from brdfremap.core import hookimpl
from brdfremap.core.plugins import collect_adapters, get_plugin_manager


def registry_of(name: str, factory) -> object:
    """A fresh registry holding one adapter, registered through the plugin host as a plugin would."""
    mod = types.ModuleType(f"{name}plug")

    @hookimpl
    def brdfremap_register_adapters(register):
        register(name, factory)

    mod.brdfremap_register_adapters = brdfremap_register_adapters
    return collect_adapters(get_plugin_manager(load_entrypoints=False, plugins=(mod,)))
