"""Mitsuba 0.5's Ward, Phong and Ashikhmin-Shirley as Mitsuba 3 plugins, validated as Mitsuba
validates its own BSDFs: chi-square tests of sampling against pdf, reciprocity, and white-furnace
albedo. Also the energy-conservation safeguard the paper's instabilities come from."""

import numpy as np
import pytest

from brdfremap.core.data.metrics import relative_rmse
from brdfremap.core.data.scene import ProbeScene

from brdfremap.adapters.mitsuba.validation import (CHI2_CASES as CASES, FURNACE_CASES as FURNACE, FURNACE_COS,
                                                   INCIDENT as WI, albedo, chi2, reciprocity)


@pytest.fixture(scope="module")
def mi(mitsuba_adapter):
    """Mitsuba in the adapter's variant with the plugins registered (the adapter does both)."""
    return mitsuba_adapter.mi


@pytest.mark.parametrize("label, d, res", CASES, ids=[c[0] for c in CASES])
@pytest.mark.parametrize("wi", range(len(WI)))
def test_chi2_sampling_matches_pdf(mi, label, d, res, wi):
    ok, p, log = chi2(mi, d, WI[wi], res)
    assert ok, f"{label}: {log}"


@pytest.mark.parametrize("label, d, res", CASES, ids=[c[0] for c in CASES])
def test_reciprocity(mi, label, d, res):
    assert reciprocity(mi, d) < 1e-3, label


@pytest.mark.parametrize("d", FURNACE, ids=[f"{d['type']}-{i}" for i, d in enumerate(FURNACE)])
def test_white_furnace_albedo_at_most_one(mi, d):
    for mu in FURNACE_COS:
        a = albedo(mi, d, mu).max()
        assert 0.0 < a <= 1.0 + 2e-3, f"albedo {a:.4f} at cos(theta_i) = {mu}"


def test_ward_duer_exceeds_one_at_grazing_angles_as_in_mitsuba_05(mi):
    """Dür's normalisation is not bounded at grazing angles; the safeguard bounds reflectances only."""
    d = {"type": "ward", "variant": "ward-duer", "alpha": 0.5, "specular_reflectance": 1.0,
         "diffuse_reflectance": 0.0}
    assert albedo(mi, d, 0.7).max() < 1.0
    assert albedo(mi, d, 0.05).max() > 1.0


def test_safeguard_trims_and_can_be_switched_off(mi):
    on = {"type": "ward", "alpha": 0.1, "specular_reflectance": [1.5, 1.2, 0.6], "diffuse_reflectance": 0.0}
    same = dict(on, specular_reflectance=[0.99, 0.792, 0.396], ensure_energy_conservation=False)
    off = dict(on, ensure_energy_conservation=False)
    a_on, a_same, a_off = (albedo(mi, d, 0.9, n=128) for d in (on, same, off))
    np.testing.assert_allclose(a_on, a_same, rtol=1e-5)  # scaled by 0.99 / max(ks + kd) = 0.66
    np.testing.assert_allclose(a_off / a_on, 1.5 / 0.99, rtol=1e-4)
    assert a_off.max() > 1.0


def test_trimmed_reflectance_above_one_renders_the_same(mitsuba_adapter):
    """Why the paper's Ward fits jump: above 1, only the ratio of the channels reaches the image."""
    spec, scene = mitsuba_adapter.models["ward"], ProbeScene(resolution=48)
    a = mitsuba_adapter.render("ward", spec.complete({"specular_reflectance": [1.2, 1.0, 0.8],
                                                      "diffuse_reflectance": 0.0}), scene)
    b = mitsuba_adapter.render("ward", spec.complete({"specular_reflectance": [1.8, 1.5, 1.2],
                                                      "diffuse_reflectance": 0.0}), scene)
    assert relative_rmse(a, b) < 1e-6
    notes = spec.notes(spec.complete({"specular_reflectance": 1.2, "diffuse_reflectance": 0.0}))
    assert notes and "0.825" in notes[0]
    assert spec.notes(spec.complete({})) == []


def test_as_conductor_preset_equals_its_reflectivity_and_edge_tint(mitsuba_adapter):
    spec, scene = mitsuba_adapter.models["ashikhmin_shirley"], ProbeScene(resolution=48)
    preset = spec.complete({"material": "Cu", "alpha": 0.15})
    d = spec.derive(preset)
    artist = spec.complete({"material": "reflectivity", "alpha": 0.15, "reflectivity": list(d["reflectivity"]),
                            "edge_tint": list(np.clip(d["edge_tint"], 0, 1))})
    assert relative_rmse(mitsuba_adapter.render("ashikhmin_shirley", preset, scene),
                         mitsuba_adapter.render("ashikhmin_shirley", artist, scene)) < 1e-4


@pytest.mark.parametrize("alpha", [0.05, 0.1, 0.2])
def test_as_distribution_is_close_to_beckmann_when_smooth(mitsuba_adapter, alpha):
    """n = 2/α² − 2 makes the Phong lobe match Beckmann's for small α: a check on the normalisation."""
    scene = ProbeScene(resolution=64)
    a = mitsuba_adapter.render("ashikhmin_shirley", mitsuba_adapter.models["ashikhmin_shirley"].complete(
        {"material": "Au", "alpha": alpha}), scene)
    b = mitsuba_adapter.render("roughconductor", mitsuba_adapter.models["roughconductor"].complete(
        {"material": "Au", "alpha": alpha}), scene)
    assert relative_rmse(a, b) < 0.1


def test_as_plastic_lobes_sum_to_the_full_image(mitsuba_adapter):
    spec, scene = mitsuba_adapter.models["ashikhmin_shirley_plastic"], ProbeScene(resolution=48)
    p = spec.complete({"diffuse_reflectance": [0.2, 0.4, 0.6], "alpha": 0.15, "int_ior": 1.6})
    full = mitsuba_adapter.render("ashikhmin_shirley_plastic", p, scene)
    parts = sum(mitsuba_adapter.render("ashikhmin_shirley_plastic", p, scene, lobe) for lobe in ("diffuse", "specular"))
    assert relative_rmse(full, parts) < 1e-5


def test_plugins_load_from_xml(mi):
    bsdf = mi.load_string('<bsdf version="3.0.0" type="ward"><string name="variant" value="ward-duer"/>'
                          '<float name="alpha" value="0.2"/><rgb name="specular_reflectance" value="0.3, 0.2, 0.1"/>'
                          '<boolean name="ensure_energy_conservation" value="false"/></bsdf>')
    assert "ward-duer" in str(bsdf)
    with pytest.raises(Exception, match="variant must be one of"):
        mi.load_string('<bsdf version="3.0.0" type="ward"><string name="variant" value="nope"/></bsdf>')
