import os
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT / "examples" / "brdfremap-example"))  # the example adapter package
sys.path.insert(0, str(ROOT / "tests"))  # helpers shared by the tests (reports.py)


def pytest_addoption(parser):
    parser.addoption("--run-slow", action="store_true", help="also run tests marked slow")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--run-slow"):
        return
    skip = pytest.mark.skip(reason="slow: pass --run-slow")
    for item in items:
        if "slow" in item.keywords:
            item.add_marker(skip)


@pytest.fixture(scope="session")
def root() -> Path:
    return ROOT


def need_adapter(factory):
    """Skip clearly when an adapter is unavailable here; in CI that is a failure instead."""
    reason = factory.unavailable_reason()
    if reason:
        if os.environ.get("CI"):
            pytest.fail(f"adapter {factory.name} must be available in CI: {reason}")
        pytest.skip(f"adapter {factory.name} unavailable: {reason}")


def _open_adapter(module: str, name: str):
    """One adapter for the whole session (one Blender worker, one set of Mitsuba kernels)."""
    import importlib

    factory = getattr(importlib.import_module(module), name)
    need_adapter(factory)
    adapter = factory()
    yield adapter
    adapter.close()


@pytest.fixture(scope="session")
def mitsuba_adapter():
    yield from _open_adapter("brdfremap.adapters.mitsuba.adapter", "MitsubaAdapter")


@pytest.fixture(scope="session")
def cycles_adapter():
    yield from _open_adapter("brdfremap.adapters.cycles.adapter", "CyclesAdapter")


CORPUS = ROOT.parent / "shared" / "corpus"
"""Public material files the project did not write (their README says what): the acceptance test."""


@pytest.fixture(scope="session")
def corpus() -> Path:
    if not (CORPUS / "README.md").is_file():
        if os.environ.get("CI"):
            pytest.fail(f"the corpus of public files must be beside the checkout in CI: {CORPUS}")
        pytest.skip(f"the corpus of public files is not here: {CORPUS}")
    return CORPUS
