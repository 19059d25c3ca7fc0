"""The plugin host: one function builds it; adapters arrive through a register callback."""

from __future__ import annotations

import importlib.metadata
import os
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pluggy

from ..data.errors import AdapterUnavailableError, ConfigError
from . import hookspecs
from .model import Model

GROUP = "brdfremap"


@dataclass
class AdapterEntry:
    name: str
    factory: Any
    plugin: str
    source_file: Path | None = None
    """The definition file it was loaded from on the command line, if any."""

    @property
    def models(self) -> dict:
        return getattr(self.factory, "models", {})

    @property
    def version(self) -> str:
        """What determines the adapter's renders (`Adapter.identity`): part of a job's key."""
        identity = getattr(self.factory, "identity", None)
        if identity is None:
            return str(getattr(self.factory, "version", "1"))
        try:
            return str(identity())
        except Exception as exc:  # a broken plugin is reported when it renders, not here
            return f"{getattr(self.factory, 'version', '1')} (identity unknown: {type(exc).__name__})"

    @property
    def light_types(self) -> frozenset[str]:
        return frozenset(getattr(self.factory, "light_types", frozenset({"point"})))

    @property
    def natives(self) -> bool:
        """Whether it renders a material from its own file (`Adapter.natives`)."""
        return bool(getattr(self.factory, "natives", False))

    def scene_problem(self, scene) -> str | None:
        """Why this adapter cannot render ``scene`` (`Adapter.scene_problem`), or None."""
        check = getattr(self.factory, "scene_problem", None)
        return None if check is None else check(scene)

    def unavailable_reason(self) -> str | None:
        try:
            old = sorted(n for n, m in self.models.items() if not isinstance(m, Model))
            if old:
                return (f"its model {old[0]!r} is a plain ModelSpec: declare each model as a brdfremap.core.Model "
                        "(the same fields; the protocol passes the model object, and a Model subclass carries its "
                        "reading and converted start)")
            return self.factory.unavailable_reason()
        except Exception as exc:  # a broken plugin is listed with its error, not fatal
            return f"availability check failed: {exc}"


@dataclass
class AdapterRegistry:
    entries: dict[str, AdapterEntry] = field(default_factory=dict)
    broken: dict[str, str] = field(default_factory=dict)
    pm: Any = None
    conflicts: dict[str, str] = field(default_factory=dict)
    """Names registered twice: neither registration is used, and choosing the name says why."""

    def resolve(self, name: str, *, field_name: str = "--adapter") -> str:
        """An adapter name, or a definition file (``renderer.yaml``) loaded now through the
        ``brdfremap_adapter_from_file`` hook. Returns the adapter's name. Only for what the user
        types on the command line: a data file names adapters, it never points at a program."""
        if name in self.entries:
            return name
        path = Path(name)
        if path.suffix not in (".yaml", ".yml") and os.sep not in name:
            return self.get(name, field_name=field_name).name
        if not path.is_file():
            raise ConfigError("adapter file not found (check the path)", file=str(path), field=field_name)
        got = self.pm.hook.brdfremap_adapter_from_file(path=str(path)) if self.pm else None
        if got is None:
            raise ConfigError("no installed plugin understands this adapter file", file=str(path))
        adapter_name, factory = got
        existing = self.entries.get(adapter_name)
        if existing is not None:
            same = getattr(existing.factory, "source_file", None)
            if same is not None and Path(same).resolve() == path.resolve():
                return adapter_name
            raise ConfigError(f"adapter name {adapter_name!r} is already taken by {existing.plugin}",
                              file=str(path), field="name")
        self.entries[adapter_name] = AdapterEntry(adapter_name, factory, f"file {path}", path.resolve())
        return adapter_name

    def names(self) -> list[str]:
        return sorted(self.entries)

    def loaded_files(self) -> list[str]:
        """Definition files loaded through `resolve` (a worker process loads them again)."""
        return [str(e.source_file) for e in self.entries.values() if e.source_file is not None]

    def get(self, name: str, *, file: str | None = None, field_name: str = "--adapter") -> AdapterEntry:
        if name in self.conflicts:
            raise ConfigError(self.conflicts[name], file=file, field=field_name)
        if name not in self.entries:
            if file and (name.endswith((".yaml", ".yml")) or os.sep in name):
                raise ConfigError(f"{name!r} is a file: a data file names an installed adapter (see `remap "
                                  "adapters`); a renderer definition is given on the command line (--adapter "
                                  "FILE) or put in a renderer folder", file=file, field=field_name)
            known = ", ".join(self.names()) or "none"
            raise ConfigError(f"unknown adapter {name!r} (installed: {known}; see `remap adapters`)",
                              file=file, field=field_name)
        return self.entries[name]

    def create(self, name: str):
        entry = self.get(name)
        reason = entry.unavailable_reason()
        if reason:
            hint = getattr(entry.factory, "install_hint", "")
            raise AdapterUnavailableError(f"adapter {name!r} is unavailable: {reason}" + (f"; {hint}" if hint else ""))
        return entry.factory()


class PluginManager(pluggy.PluginManager):
    """pluggy's manager plus the plugins that failed to load (listed, never fatal)."""

    def __init__(self) -> None:
        super().__init__(GROUP)
        self.broken: dict[str, str] = {}
        self.labels: dict[int, str] = {}


def get_plugin_manager(*, load_entrypoints: bool = True, plugins: tuple = ()) -> PluginManager:
    """Build the plugin manager: add specs, register ``plugins``, load the entry-point group
    ``brdfremap`` (built-ins arrive this way too), then ``check_pending()`` so a misspelt
    hook fails at start-up naming the plugin."""
    pm = PluginManager()
    pm.add_hookspecs(hookspecs)
    for plugin in plugins:
        pm.register(plugin)
        pm.labels[id(plugin)] = getattr(plugin, "__name__", repr(plugin))
    if load_entrypoints:
        for ep in importlib.metadata.entry_points(group=GROUP):
            label = f"{ep.dist.name if ep.dist else '?'} ({ep.name})"
            if pm.get_plugin(ep.name) is not None:
                continue
            try:
                plugin = ep.load()
            except Exception as exc:
                pm.broken[label] = f"cannot import {ep.value}: {type(exc).__name__}: {exc}"
                continue
            pm.register(plugin, name=ep.name)
            pm.labels[id(plugin)] = label
    try:
        pm.check_pending()
    except pluggy.PluginValidationError as exc:
        raise ConfigError(f"plugin {exc.plugin!r} implements an unknown hook: {exc}") from None
    return pm


def collect_adapters(pm: PluginManager | None = None) -> AdapterRegistry:
    """Call every plugin's register hook; duplicate names are rejected naming both plugins."""
    pm = pm or get_plugin_manager()
    registry = AdapterRegistry(broken=dict(getattr(pm, "broken", {})), pm=pm)
    labels = getattr(pm, "labels", {})
    for impl in pm.hook.brdfremap_register_adapters.get_hookimpls():
        label = labels.get(id(impl.plugin), impl.plugin_name)

        def register(name: str, factory: Any, _label=label) -> None:
            if not isinstance(name, str) or not name:
                raise ConfigError(f"plugin {_label} registered an adapter with an invalid name {name!r}")
            if name in registry.entries or name in registry.conflicts:
                _conflict(registry, AdapterEntry(name, factory, _label))
                return
            registry.entries[name] = AdapterEntry(name, factory, _label)

        try:
            impl.function(register=register)
        except ConfigError:
            raise
        except Exception as exc:
            registry.broken[label] = f"{type(exc).__name__}: {exc}"
    return registry


def _definition(entry: AdapterEntry | None) -> Any:
    """The definition file of a renderer defined by one (a YAML file in a renderer folder)."""
    return getattr(entry.factory, "source_file", None) if entry is not None else None


def _conflict(registry: AdapterRegistry, new: AdapterEntry) -> None:
    """A name registered twice. An installed adapter keeps its name over a renderer definition
    that takes it (the definition is listed as broken, naming its file); two of a kind are both
    unused, since which one was meant cannot be known, and choosing the name says who."""
    name, label = new.name, new.plugin
    old = registry.entries.get(name)
    if old is not None and (_definition(old) is None) != (_definition(new) is None):
        kept, dropped = (new, old) if _definition(old) else (old, new)
        registry.entries[name] = kept
        registry.broken[f"renderer definition {_definition(dropped)}"] = (
            f"its name {name!r} is an installed adapter's ({kept.plugin}): rename it (its `name:`)")
        return
    first = registry.entries.pop(name, None)
    who = f"{first.plugin} and by {label}" if first is not None else f"{label} as well"
    if first is None and name in registry.conflicts:
        registry.conflicts[name] = registry.conflicts[name].replace("; uninstall", f", and by {label}; uninstall", 1)
    else:
        registry.conflicts[name] = (f"adapter {name!r} is registered twice: by {who}; uninstall or rename one of "
                                    "them (a renderer definition's `name:`)")
    registry.broken[f"adapter {name!r}"] = registry.conflicts[name]
