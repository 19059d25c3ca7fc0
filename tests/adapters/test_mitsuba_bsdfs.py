"""Mitsuba 0.5's Ward, Phong and Ashikhmin-Shirley as Mitsuba 3 plugins, validated as Mitsuba
validates its own BSDFs: chi-square tests of sampling against pdf, reciprocity, and white-furnace
albedo. Also the energy-conservation safeguard the paper's instabilities come from."""

import numpy as np
import pytest

from brdfremap.core.metrics import relative_rmse
from brdfremap.core.scene import ProbeScene

WI = ([0.0, 0.0, 1.0], [0.6, 0.2, 0.7745966692414834], [0.9, 0.0, 0.4358898943540673])

# (label, plugin dict, chi2 histogram resolution); sharp lobes need the finer grid.
CASES = [
    ("ward balanced", {"type": "ward", "alpha": 0.2, "specular_reflectance": 0.3, "diffuse_reflectance": 0.4}, 101),
    ("ward original, anisotropic", {"type": "ward", "variant": "ward", "alpha_u": 0.1, "alpha_v": 0.3,
                                    "specular_reflectance": 0.5, "diffuse_reflectance": 0.0}, 101),
    ("ward-duer rough", {"type": "ward", "variant": "ward-duer", "alpha": 0.5}, 101),
    ("ward balanced sharp", {"type": "ward", "alpha": 0.05, "specular_reflectance": 0.8,
                             "diffuse_reflectance": 0.1}, 201),
    ("phong", {"type": "phong", "exponent": 20.0}, 101),
    ("phong sharp", {"type": "phong", "exponent": 200.0, "diffuse_reflectance": 0.0}, 201),
    ("as conductor Au", {"type": "ashikhmin_shirley", "alpha": 0.3, "material": "Au"}, 101),
    ("as conductor anisotropic", {"type": "ashikhmin_shirley", "alpha_u": 0.1, "alpha_v": 0.4,
                                  "material": "Cu"}, 101),
    ("as conductor sharp", {"type": "ashikhmin_shirley", "alpha": 0.05, "reflectivity": 0.9,
                            "edge_tint": 0.5}, 201),
    ("as plastic", {"type": "ashikhmin_shirley", "form": "plastic", "alpha": 0.2, "int_ior": 1.5,
                    "diffuse_reflectance": 0.5}, 101),
    ("as plastic sharp", {"type": "ashikhmin_shirley", "form": "plastic", "alpha": 0.05, "int_ior": 1.7,
                          "diffuse_reflectance": [0.8, 0.2, 0.1]}, 201),
]


@pytest.fixture(scope="module")
def mi(mitsuba_adapter):
    """Mitsuba in the adapter's variant with the plugins registered (the adapter does both)."""
    return mitsuba_adapter.mi


def _uniform_dirs(mi, n, seed):
    rng = np.random.default_rng(seed)
    u = mi.Point2f(mi.Float(rng.random(n)), mi.Float(rng.random(n)))
    return mi.warp.square_to_uniform_hemisphere(u)


def albedo(mi, d, mu, n=384):
    """Directional albedo at cos(theta_i) = mu: stratified uniform-hemisphere quadrature of eval."""
    import drjit as dr

    bsdf = mi.load_dict(d)
    u = (np.arange(n) + 0.5) / n
    u1, u2 = np.meshgrid(u, u)
    wo = mi.warp.square_to_uniform_hemisphere(mi.Point2f(mi.Float(u1.ravel()), mi.Float(u2.ravel())))
    si = dr.zeros(mi.SurfaceInteraction3f, n * n)
    si.wi = mi.Vector3f(float(np.sqrt(1 - mu * mu)), 0.0, float(mu))
    v = np.array(bsdf.eval(mi.BSDFContext(), si, wo))
    v = v.reshape(-1, 3) if v.shape[-1] == 3 else v.T
    return v.mean(axis=0) * 2 * np.pi


@pytest.mark.parametrize("label, d, res", CASES, ids=[c[0] for c in CASES])
@pytest.mark.parametrize("wi", range(len(WI)))
def test_chi2_sampling_matches_pdf(mi, label, d, res, wi, tmp_path, monkeypatch):
    import drjit as dr
    from mitsuba.chi2 import BSDFAdapter, ChiSquareTest, SphericalDomain

    monkeypatch.chdir(tmp_path)  # a rejected test writes chi2_data.py into the working folder
    sample, pdf = BSDFAdapter(d["type"], d, wi=dr.normalize(mi.ScalarVector3f(WI[wi])))
    test = ChiSquareTest(domain=SphericalDomain(), sample_func=sample, pdf_func=pdf, sample_dim=3,
                         res=res, ires=8 if res > 101 else 4, sample_count=1_000_000)
    assert test.run(), f"{label}: {test.messages}"


@pytest.mark.parametrize("label, d, res", CASES, ids=[c[0] for c in CASES])
def test_reciprocity(mi, label, d, res):
    import drjit as dr

    bsdf = mi.load_dict(d)
    a, b = _uniform_dirs(mi, 4000, 1), _uniform_dirs(mi, 4000, 2)
    si = dr.zeros(mi.SurfaceInteraction3f, 4000)
    si.wi = a
    f_ab = np.array(bsdf.eval(mi.BSDFContext(), si, b)) / np.array(b.z)
    si.wi = b
    f_ba = np.array(bsdf.eval(mi.BSDFContext(), si, a)) / np.array(a.z)
    rel = np.abs(f_ab - f_ba) / np.maximum(np.abs(f_ab) + np.abs(f_ba), 1e-6)
    assert rel.max() < 1e-3, label


FURNACE = [
    # Reflectances at their maximum with the safeguard on: white base, perfect specular.
    {"type": "ward", "alpha": 0.1, "specular_reflectance": 1.5, "diffuse_reflectance": 0.0},  # trimmed to 0.99
    {"type": "ward", "alpha": 0.5, "specular_reflectance": 0.6, "diffuse_reflectance": 0.6},  # trimmed
    {"type": "ward", "variant": "ward", "alpha": 0.3, "specular_reflectance": 0.5, "diffuse_reflectance": 0.5},
    {"type": "phong", "exponent": 2.0, "specular_reflectance": 1.0, "diffuse_reflectance": 0.0},
    {"type": "phong", "exponent": 100.0, "specular_reflectance": 0.6, "diffuse_reflectance": 0.6},  # trimmed
    {"type": "ashikhmin_shirley", "alpha": 0.05, "material": "Ag"},
    {"type": "ashikhmin_shirley", "alpha": 0.3, "material": "Al"},
    {"type": "ashikhmin_shirley", "form": "plastic", "alpha": 0.3, "int_ior": 1.5, "diffuse_reflectance": 1.0},
    {"type": "ashikhmin_shirley", "form": "plastic", "alpha": 0.05, "int_ior": 1.9, "diffuse_reflectance": 1.0},
]


@pytest.mark.parametrize("d", FURNACE, ids=[f"{d['type']}-{i}" for i, d in enumerate(FURNACE)])
def test_white_furnace_albedo_at_most_one(mi, d):
    for mu in (1.0, 0.7, 0.4, 0.2, 0.1):
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
    notes = mitsuba_adapter.notes("ward", spec.complete({"specular_reflectance": 1.2, "diffuse_reflectance": 0.0}))
    assert notes and "0.825" in notes[0]
    assert mitsuba_adapter.notes("ward", spec.complete({})) == []


def test_as_conductor_preset_equals_its_reflectivity_and_edge_tint(mitsuba_adapter):
    spec, scene = mitsuba_adapter.models["ashikhmin_shirley"], ProbeScene(resolution=48)
    preset = spec.complete({"material": "Cu", "alpha": 0.15})
    d = mitsuba_adapter.derived("ashikhmin_shirley", preset)
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
