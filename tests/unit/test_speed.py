"""What makes a remap cheaper without changing how it is judged (issue: fast), without a renderer:
the account of every render, the frontal lights' resolution, and no tries of a distribution for
a mirror. A real remap's account is checked in tests/e2e/test_remap_cycles.py."""

from __future__ import annotations

import numpy as np
import pytest

from brdfremap.core.data.account import PURPOSES, Ledger, Metered, purpose
from brdfremap.core.data.scene import PointLight, ProbeScene
from brdfremap.core.job.validation import CONDITIONS, point_resolution, scenes


class _Renderer:
    """Renders a constant image per call; counts the calls."""

    name = "fake"

    def __init__(self, value=1.0):
        self.value, self.calls = value, []

    def render(self, model, params, scene, lobe=None):
        self.calls.append(scene)
        return np.full((scene.resolution, scene.resolution, 3), self.value, np.float32)

    def render_batch(self, requests):
        return [self.render(*r) for r in requests]


def test_the_account_counts_each_render_under_the_purpose_it_ran_in():
    ledger = Ledger()
    src, tgt = Metered(_Renderer(), "source", ledger), Metered(_Renderer(), "target", ledger)
    scene = ProbeScene(resolution=32, spp=16)
    with purpose("fit"):
        tgt.render("m", {}, scene)
        tgt.render_batch([("m", {}, scene, None), ("m", {}, scene.with_(spp=64), None)])
    with purpose("validation"):
        src.render("m", {}, scene)
    tgt.render("m", {}, scene)  # outside any step: "other"
    acc = ledger.account(total_seconds=10.0)
    rows = {(r.purpose, r.side): r for r in acc.renders}
    assert rows["fit", "target"].renders == 3
    assert rows["fit", "target"].pixel_samples == 32 * 32 * (16 + 16 + 64)
    assert rows["validation", "source"].renders == 1 and rows["other", "target"].renders == 1
    assert [r.purpose for r in acc.renders] == sorted((r.purpose for r in acc.renders), key=PURPOSES.index)
    assert acc.other_seconds == pytest.approx(10.0 - acc.render_seconds)
    assert acc.by_purpose()["fit"].renders == 3
    assert src.name == "fake" and src.unmetered is not tgt.unmetered  # everything else is the adapter's


def test_frontal_point_lights_take_half_the_resolution_where_the_highlight_shows_there():
    scene = ProbeScene(resolution=128, spp=16)
    assert point_resolution(scene, highlight_px=4 * 16) == 64
    assert point_resolution(scene, highlight_px=4 * 16 - 1) == 128
    res = {c.name: a.resolution for c, a, _ in scenes(scene, resolution=64)}
    # grazing and rim light the outline, whose share of the pixels doubles at half the size
    assert res == {"grazing": 128, "rim": 128, "headlight": 64, "environment": 64}
    assert all(isinstance(x, PointLight) for x in CONDITIONS[2].lights)


def test_no_tries_of_a_distribution_for_a_target_held_smooth():
    from brdfremap.core.job.execute import alternatives
    from brdfremap.core.job.job import Job, Target, resolve
    from brdfremap.core.host.plugins import collect_adapters
    from brdfremap.core.data.schemas import Material

    registry = collect_adapters()
    why = registry.get("cycles").unavailable_reason()
    if why:
        pytest.skip(why)
    src = Material(adapter="mitsuba", model="roughplastic", params={"distribution": "beckmann", "alpha": 0.2})
    job = resolve(Job(source=src, target=Target(adapter="cycles", model="principled"), label="m.yaml"), registry)
    assert alternatives(job, {}) and alternatives(job, {"roughness": 0.0})  # roughness 0 as a start: still fitted
    assert not alternatives(job, {"roughness": 0.0}, smooth={"roughness": 0.0})  # held there: a mirror
