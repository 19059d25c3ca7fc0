"""The plugin host: fresh manager per test, no global registry."""

import types

import pytest

from brdfremap.core import hookimpl
from brdfremap.core.data.errors import AdapterUnavailableError, ConfigError
from brdfremap.core.host.plugins import collect_adapters, get_plugin_manager
from brdfremap_example.adapter import ToyAdapter


def _plugin(name, *adapters):
    mod = types.ModuleType(name)

    @hookimpl
    def brdfremap_register_adapters(register):
        for a in adapters:
            register(a.name, a)

    mod.brdfremap_register_adapters = brdfremap_register_adapters
    return mod


def test_registered_adapter_is_found_and_constructed_only_on_demand():
    pm = get_plugin_manager(load_entrypoints=False, plugins=(_plugin("toyplug", ToyAdapter),))
    reg = collect_adapters(pm)
    assert reg.names() == ["toy"]
    assert "toy" in reg.get("toy").models
    assert isinstance(reg.create("toy"), ToyAdapter)


def test_duplicate_names_are_rejected_naming_both_plugins_and_the_others_keep_working():
    class Other(ToyAdapter):
        name = "other"

    pm = get_plugin_manager(load_entrypoints=False, plugins=(
        _plugin("first_pkg", ToyAdapter), _plugin("second_pkg", ToyAdapter, Other)))
    reg = collect_adapters(pm)
    assert reg.names() == ["other"] and isinstance(reg.create("other"), Other)
    with pytest.raises(ConfigError) as e:
        reg.get("toy")
    assert "first_pkg" in str(e.value) and "second_pkg" in str(e.value) and "registered twice" in str(e.value)
    assert any("registered twice" in v for v in reg.broken.values())


def test_misspelt_hook_fails_at_start_up_with_its_name():
    mod = types.ModuleType("typo_pkg")

    @hookimpl
    def brdfremap_register_adaptors(register):  # misspelt
        pass

    mod.brdfremap_register_adaptors = brdfremap_register_adaptors
    with pytest.raises(ConfigError, match="brdfremap_register_adaptors"):
        get_plugin_manager(load_entrypoints=False, plugins=(mod,))


def test_a_plugin_that_raises_is_listed_not_fatal():
    mod = types.ModuleType("broken_pkg")

    @hookimpl
    def brdfremap_register_adapters(register):
        raise RuntimeError("boom")

    mod.brdfremap_register_adapters = brdfremap_register_adapters
    reg = collect_adapters(get_plugin_manager(load_entrypoints=False, plugins=(mod, _plugin("ok", ToyAdapter))))
    assert reg.names() == ["toy"]
    assert any("boom" in v for v in reg.broken.values())


def test_unavailable_adapter_says_why_and_how_to_install():
    class Missing(ToyAdapter):
        name = "missing"
        install_hint = "pip install missing-renderer"

        @classmethod
        def unavailable_reason(cls):
            return "the missing package is not installed"

    reg = collect_adapters(get_plugin_manager(load_entrypoints=False, plugins=(_plugin("m", Missing),)))
    with pytest.raises(AdapterUnavailableError, match="not installed; pip install missing-renderer"):
        reg.create("missing")


def test_unknown_adapter_lists_the_installed_ones():
    reg = collect_adapters(get_plugin_manager(load_entrypoints=False, plugins=(_plugin("t", ToyAdapter),)))
    with pytest.raises(ConfigError, match="unknown adapter 'cyclez' \\(installed: toy"):
        reg.get("cyclez")


def test_builtin_adapters_come_through_the_entry_point_group():
    reg = collect_adapters(get_plugin_manager())
    assert "mitsuba" in reg.names()
    assert reg.get("mitsuba").plugin.startswith("brdf-remap")


def test_example_package_installs_with_pip_and_appears_in_remap_adapters(tmp_path, root):
    import subprocess
    import sys

    target = tmp_path / "site"
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps", "--no-build-isolation",
                    "--target", str(target), str(root / "examples" / "brdfremap-example")], check=True)
    env = {**__import__("os").environ, "PYTHONPATH": str(target)}
    out = subprocess.run([sys.executable, "-m", "brdfremap.core.cli", "adapters"], env=env, capture_output=True,
                         text=True, check=True).stdout
    assert "toy  [brdfremap-example (toy)]" in out
    assert "model toy (each lobe renders alone):" in out and "alpha (scalar [0.01, 1], log; default 0.2)" in out
