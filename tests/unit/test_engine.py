"""The optimiser against the analytic toy adapter (exact, fast)."""

import numpy as np
import pytest

from brdfremap.core.errors import OptimisationError
from brdfremap.core.remap import ParamSpace, RemapOptions, plan_stages, remap
from brdfremap.core.scene import ProbeScene
from brdfremap_example.adapter import TOY, ToyAdapter

SCENE = ProbeScene(resolution=48)
TRUTH = TOY.complete({"diffuse": (0.6, 0.3, 0.1), "specular": 0.8, "alpha": 0.15})


def _setup():
    adapter = ToyAdapter()
    render = lambda p, lobe=None: adapter.render("toy", p, SCENE, lobe)  # noqa: E731
    src = render(TRUTH)
    lobes = {lobe: render(TRUTH, lobe) for lobe in ("diffuse", "specular")}
    return adapter, render, src, lobes


def test_param_space_roundtrip_linear_and_log():
    base = TOY.complete({})
    space = ParamSpace(TOY, base, ["diffuse", "alpha"])
    assert space.dim == 4
    u = space.encode(TRUTH)
    assert np.allclose(u[3], np.log(0.15 / 0.01) / np.log(100))
    back = space.decode(u)
    assert np.allclose(back["diffuse"], TRUTH["diffuse"]) and np.isclose(back["alpha"], 0.15)
    assert back["specular"] == base["specular"]  # not free: from base


@pytest.mark.parametrize("scheme", ["one", "two", "three"])
def test_identity_remap_recovers_parameters(scheme):
    adapter, render, src, lobes = _setup()
    base = TOY.complete({})
    res = remap(TOY, render, src, lobes, base=base, free=TOY.fittable(base), options=RemapOptions(scheme=scheme))
    assert res.scheme_used == scheme
    assert res.relative_rmse < 1e-3
    assert abs(res.params["alpha"] / 0.15 - 1) < 0.01
    assert abs(res.params["specular"] / 0.8 - 1) < 0.01
    assert np.allclose(res.params["diffuse"], (0.6, 0.3, 0.1), atol=2e-3)
    assert res.reliable, res.reason
    assert res.renders == adapter.calls - 3  # the three source renders are not target renders


def test_two_stage_fits_specular_then_diffuse_on_lobe_images():
    _, render, src, lobes = _setup()
    base = TOY.complete({})
    res = remap(TOY, render, src, lobes, base=base, free=TOY.fittable(base))
    assert [s.name for s in res.stages] == ["specular", "diffuse"]
    assert res.stages[0].free == ["specular", "alpha"] and res.stages[1].free == ["diffuse"]


def test_two_stage_falls_back_when_source_has_no_lobes():
    _, render, src, _ = _setup()
    base = TOY.complete({})
    res = remap(TOY, render, src, {"diffuse": None, "specular": None}, base=base, free=TOY.fittable(base))
    assert res.scheme == "auto" and res.scheme_used == "one"
    assert "fell back to one-stage" in res.notes[0]


def test_float32_images_get_a_nonzero_jacobian():
    # scipy's default step (~1e-8) is below float32 resolution; ours must move the image.
    _, render, src, lobes = _setup()
    base = dict(TRUTH, alpha=0.3)
    res = remap(TOY, render, src, lobes, base=base, free=["alpha"], options=RemapOptions(scheme="one", starts=1))
    assert abs(res.params["alpha"] / 0.15 - 1) < 0.01


def test_verdict_flags_a_pinned_bound_and_high_error():
    _, render, src, lobes = _setup()
    # Specular capped far below the truth: the fit must sit on the bound and say so.
    capped = TOY.model_copy(update={"parameters": tuple(
        p.model_copy(update={"upper": 0.2}) if p.name == "specular" else p for p in TOY.parameters)})
    base = capped.complete({})
    base["specular"] = 0.1
    res = remap(capped, render, src, lobes, base=base, free=["specular", "alpha"],
                options=RemapOptions(scheme="one"))
    assert not res.reliable
    assert "specular pinned at its upper bound" in res.reason
    assert res.params["specular"] == pytest.approx(0.2, abs=1e-3)


def test_a_parameter_that_does_not_change_the_image_is_noted():
    _, render, src, lobes = _setup()
    base = dict(TRUTH, alpha=0.3, specular=0.3)
    res = remap(TOY, render, src, lobes, base=base, free=["alpha", "specular", "unused"],
                options=RemapOptions(scheme="one"))
    assert res.reliable, res.reason  # the appearance matches; the value of `unused` is arbitrary
    assert any("unused did not change the image" in n for n in res.notes)


def test_no_parameter_changing_the_image_is_unreliable():
    _, render, src, lobes = _setup()
    res = remap(TOY, render, src, lobes, base=dict(TRUTH), free=["unused"], options=RemapOptions(scheme="one"))
    assert not res.reliable and "no fitted parameter changes the image" in res.reason


def test_model_mismatch_is_named_as_such():
    _, render, src, lobes = _setup()
    base = TOY.complete({"diffuse": 0.0})
    # Fit only the specular lobe to an image that also has a strong diffuse term.
    res = remap(TOY, render, src, lobes, base=base, free=["specular", "alpha"], options=RemapOptions(scheme="one"))
    assert not res.reliable
    assert "above the 5% threshold" in res.reason


def test_render_budget_stops_the_fit_at_the_best_point():
    _, render, src, lobes = _setup()
    base = TOY.complete({})
    res = remap(TOY, render, src, lobes, base=base, free=TOY.fittable(base),
                options=RemapOptions(scheme="one", max_renders_per_stage=6))
    assert res.stages[0].renders == 6
    assert "render budget" in res.stages[0].status
    assert res.stages[0].error <= res.stages[0].start_error


def test_bad_source_images_are_rejected_before_any_render():
    _, render, src, lobes = _setup()
    base = TOY.complete({})
    with pytest.raises(OptimisationError, match="black"):
        remap(TOY, render, np.zeros_like(src), base=base, free=["alpha"])
    bad = src.copy()
    bad[0, 0, 0] = np.nan
    with pytest.raises(OptimisationError, match="NaN"):
        remap(TOY, render, bad, base=base, free=["alpha"])
    with pytest.raises(OptimisationError, match="`free`"):
        remap(TOY, render, src, base=base, free=["nope"])


def test_plan_stages_folds_a_missing_target_lobe_into_the_full_image():
    from brdfremap.core.schemas import LobeSpec

    conductor = TOY.model_copy(update={"lobes": {"diffuse": LobeSpec(empty=True),
                                                 "specular": LobeSpec(params=("specular", "alpha"))}})
    used, stages, _ = plan_stages("two", conductor, ["specular", "alpha"], {"diffuse": 1, "specular": 1})
    assert used == "two"
    assert stages == [("specular", None, ["specular", "alpha"], None)]


def test_auto_scheme_splits_only_lobes_that_divide_the_parameters():
    from brdfremap.core.schemas import LobeSpec

    lobes = {"diffuse": 1, "specular": 1}
    used, stages, _ = plan_stages("auto", TOY, TOY.fittable(TOY.complete({})), lobes)
    assert used == "two" and [s[0] for s in stages] == ["specular", "diffuse"]
    # Principled-like: every diffuse parameter also shapes the specular lobe.
    coupled = TOY.model_copy(update={"lobes": {"diffuse": LobeSpec(params=("diffuse",)),
                                               "specular": LobeSpec(params=("diffuse", "specular", "alpha"))}})
    used, stages, _ = plan_stages("auto", coupled, ["diffuse", "specular", "alpha"], lobes)
    assert used == "one" and stages == [("all", None, ["diffuse", "specular", "alpha"], None)]
    assert plan_stages("two", coupled, ["diffuse", "specular", "alpha"], lobes)[0] == "two"  # asked for: kept
    # A lobe whose parameters are all held (Ward with its diffuse fixed at 0) divides nothing: the
    # specular lobe is still fitted against the source's specular image, with its scaled starts.
    used, stages, _ = plan_stages("auto", TOY, ["specular", "alpha"], lobes)
    assert used == "two" and stages[0] == ("specular", "specular", ["specular", "alpha"], "specular")
    assert all(not free for _, _, free, _ in stages[1:])  # nothing left to fit: skipped


def test_coarse_to_fine_does_most_renders_at_low_resolution():
    from brdfremap.core.remap import Level

    adapter = ToyAdapter()
    small = SCENE.with_(resolution=16)
    render = lambda p, lobe=None: adapter.render("toy", p, SCENE, lobe)  # noqa: E731
    render_small = lambda p, lobe=None: adapter.render("toy", p, small, lobe)  # noqa: E731
    src, src_small = render(TRUTH), render_small(TRUTH)
    lobes = {lobe: render(TRUTH, lobe) for lobe in ("diffuse", "specular")}
    lobes_small = {lobe: render_small(TRUTH, lobe) for lobe in ("diffuse", "specular")}
    base = TOY.complete({})
    res = remap(TOY, render, src, lobes, base=base, free=TOY.fittable(base),
                coarse=Level(render_small, src_small, lobes_small))
    coarse = [s for s in res.stages if s.resolution == 16]
    fine = [s for s in res.stages if s.resolution == 48]
    assert coarse and sum(s.renders for s in coarse) > sum(s.renders for s in fine)
    for s in fine:
        assert s.renders <= len(s.free) * 3 + 1 + RemapOptions().fine_steps
    assert abs(res.params["alpha"] / 0.15 - 1) < 0.01 and res.relative_rmse < 1e-3
    assert res.reliable, res.reason



class _Cached:
    """A render function with a cache, as the session gives the engine; ``many`` renders a batch."""

    def __init__(self, render, batch: bool):
        self.render, self.images, self.batches, self.count = render, {}, [], 0
        if batch:
            self.many = self._many

    def _key(self, p, lobe):
        return repr((sorted(p.items()), lobe))

    def __call__(self, p, lobe=None):
        k = self._key(p, lobe)
        if k not in self.images:
            self.count += 1
            self.images[k] = self.render(p, lobe)
        return self.images[k]

    def _many(self, items):
        self.batches.append(len(items))
        for p, lobe in items:
            self(p, lobe)


def test_a_batched_jacobian_changes_nothing_but_the_grouping():
    _, render, src, lobes = _setup()
    base = TOY.complete({})
    out = {}
    for batch in (False, True):
        fn = _Cached(render, batch)
        out[batch] = (remap(TOY, fn, src, lobes, base=base, free=TOY.fittable(base), options=RemapOptions()), fn)
    (a, fa), (b, fb) = out[False], out[True]
    assert a.params == b.params and a.relative_rmse == b.relative_rmse
    assert fa.count == fb.count and a.renders == b.renders
    assert fb.batches and min(fb.batches) >= 2  # every Jacobian went out as one batch


def test_scaled_starts_fit_a_linear_reflectance_in_fewer_renders():
    params = tuple(p.model_copy(update={"linear_in": ("diffuse",)}) if p.name == "diffuse" else p
                   for p in TOY.parameters)
    spec = TOY.model_copy(update={"parameters": params})
    adapter, render, src, lobes = _setup()
    base = spec.complete({"diffuse": (0.05, 0.05, 0.05)})  # a start far too dark
    res = {}
    for scaled in (False, True):
        res[scaled] = remap(spec, render, src, lobes, base=base, free=spec.fittable(base),
                            options=RemapOptions(linear_starts=scaled))
    assert np.allclose(res[True].params["diffuse"], (0.6, 0.3, 0.1), atol=2e-3)
    assert res[True].relative_rmse <= res[False].relative_rmse + 1e-4
    diffuse = {s: next(st for st in res[s].stages if st.lobe == "diffuse") for s in (False, True)}
    assert diffuse[True].renders < diffuse[False].renders


def test_jacobian_updates_reach_the_same_fit_in_fewer_renders():
    _, render, src, lobes = _setup()
    base = TOY.complete({})
    res = {n: remap(TOY, render, src, lobes, base=base, free=TOY.fittable(base),
                    options=RemapOptions(scheme="one", jacobian_updates=n)) for n in (0, 8)}
    assert res[8].relative_rmse < 1e-3 and abs(res[8].params["alpha"] / 0.15 - 1) < 0.01
    assert np.allclose(res[8].params["diffuse"], (0.6, 0.3, 0.1), atol=2e-3)
    assert res[8].renders < res[0].renders
    assert sum(s.updates for s in res[8].stages) > 0 and sum(s.updates for s in res[0].stages) == 0
    assert res[8].reliable, res[8].reason


def _stage_with_updates():
    """One full-image stage of the toy with Broyden updates on, and its start point."""
    from brdfremap.core.remap import _Stage

    _, render, src, _ = _setup()
    base = TOY.complete({})
    space = ParamSpace(TOY, base, TOY.fittable(base))
    stage = _Stage("t", None, space, render, src, float(np.linalg.norm(src)), RemapOptions(jacobian_updates=3),
                   None, [0])
    return stage, space, space.encode(base)


def test_an_updated_jacobian_keeps_the_separable_structure():
    stage, space, u0 = _stage_with_updates()
    J0 = stage.jacobian(u0)
    u1 = u0 + 0.05
    stage.residual(u1)  # a step taken at its first try
    renders = stage.renders
    J1 = stage.jacobian(u1)
    assert stage.renders == renders and stage.n_updates == 1  # updated, not rendered
    sl = space.slices["diffuse"]
    for c, j in enumerate(range(sl.start, sl.stop)):
        other = [k for k in range(3) if k != c]
        assert all(np.all(J0[k::3, j] == 0) and np.all(J1[k::3, j] == 0) for k in other)
    assert not np.allclose(J0, J1)


def test_a_retried_step_gets_a_fresh_jacobian():
    stage, _, u0 = _stage_with_updates()
    stage.jacobian(u0)
    stage.residual(u0 + 0.2)  # rejected
    stage.residual(u0 + 0.05)  # accepted on the second try
    stage.jacobian(u0 + 0.05)
    assert stage.n_jacobians == 2 and stage.n_updates == 0


def test_the_verdict_reuses_the_last_stage_jacobian_when_updates_are_on():
    _, render, src, lobes = _setup()
    base = TOY.complete({})
    out = {n: remap(TOY, render, src, lobes, base=base, free=TOY.fittable(base),
                    options=RemapOptions(scheme="one", jacobian_updates=n)) for n in (0, 8)}
    assert out[8].renders == sum(s.renders for s in out[8].stages) + 1  # the final render only
    assert out[0].renders == sum(s.renders for s in out[0].stages) + 1  # its renders are the stage's
    assert out[8].jacobian_condition is not None and out[8].reliable


def test_the_polish_leaves_out_parameters_the_coarse_fit_settled():
    """A parameter pinned at its bound by the coarse fit, and one that cannot change the image
    there (inert_when), are not polished: fewer full-resolution renders, same fit, same verdict."""
    from brdfremap.core.remap import Level
    from brdfremap.core.schemas import ModelSpec

    capped = ModelSpec(name="toy", lobes=TOY.lobes, parameters=(
        TOY.param("diffuse"), TOY.param("specular").model_copy(update={"upper": 0.6}), TOY.param("alpha"),
        TOY.param("unused").model_copy(update={"fit": True, "inert_when": {"specular": 0.6}})))
    adapter = ToyAdapter()
    small = SCENE.with_(resolution=16)
    render = lambda p, lobe=None: adapter.render("toy", p, SCENE, lobe)  # noqa: E731
    render_small = lambda p, lobe=None: adapter.render("toy", p, small, lobe)  # noqa: E731
    base = capped.complete({})
    free = capped.fittable(base)
    assert "unused" in free
    out = {}
    for hold in (True, False):
        out[hold] = remap(capped, render, render(TRUTH), base=base, free=free,
                          options=RemapOptions(scheme="one", hold_settled=hold),
                          coarse=Level(render_small, render_small(TRUTH), {}))
    polish = out[True].stages[-1]
    assert polish.held == {"specular": "pinned", "unused": "inert"}
    assert polish.free == ["diffuse", "alpha"]
    assert out[True].params["specular"] == 0.6
    full = lambda r: sum(s.renders for s in r.stages if s.resolution == SCENE.resolution)  # noqa: E731
    assert full(out[True]) < full(out[False])
    assert out[True].relative_rmse <= out[False].relative_rmse * 1.01
    # The verdict still sees the pinned bound (from the coarse gradient) and the inert parameter.
    assert "specular pinned at its upper bound" in out[True].reason
    assert "specular pinned at its upper bound" in out[False].reason
    assert any(n.startswith("unused did not change the image") for n in out[True].notes)


def test_inert_when_must_name_another_parameter():
    from brdfremap.core.schemas import ModelSpec

    bad = TOY.param("unused").model_copy(update={"inert_when": {"nope": 1.0}})
    with pytest.raises(ValueError, match="inert_when refers to 'nope'"):
        ModelSpec(name="t", parameters=(TOY.param("diffuse"), bad))
    assert not TOY.is_inert("specular", TOY.complete({}))



def test_a_parameter_nearly_inert_gets_a_zero_column_without_a_render():
    """inert_when met within 1 % of the range: the column is zero, not rendered, and stays zero
    through the updates; away from it the column is rendered again."""
    from brdfremap.core.remap import _Stage
    from brdfremap.core.schemas import ModelSpec

    spec = ModelSpec(name="toy", lobes=TOY.lobes, parameters=(
        TOY.param("diffuse"), TOY.param("specular"), TOY.param("alpha").model_copy(update={"inert_when": {"specular": 0.0}})))
    adapter, render, src, _ = _setup()
    base = spec.complete({"specular": 0.01})  # 0.5 % of specular's range from 0: alpha barely matters
    space = ParamSpace(spec, base, spec.fittable(base))
    stage = _Stage("t", None, space, render, src, float(np.linalg.norm(src)), RemapOptions(jacobian_updates=3), None, [0])
    u0 = space.encode(base)
    j = space.slices["alpha"].start
    J0 = stage.jacobian(u0)
    assert stage.renders == 1 + 2  # the point, diffuse (one render for RGB), specular: not alpha
    assert np.all(J0[:, j] == 0)
    u1 = u0.copy()
    u1[space.slices["diffuse"]] += 0.05
    stage.residual(u1)
    assert np.all(stage.jacobian(u1)[:, j] == 0) and stage.n_updates == 1
    u2 = u1.copy()
    u2[space.slices["specular"].start] = 0.4  # far from inert: a rendered Jacobian with alpha's column
    stage.residual(u2)
    J2 = stage.jacobian(u2)
    assert stage.n_jacobians == 2 and np.linalg.norm(J2[:, j]) > 0


def test_the_verdict_run_again_after_a_joint_round_does_not_repeat_its_notes():
    from brdfremap.core.remap import _verdict

    _, render, src, _ = _setup()
    params, notes = dict(TRUTH), []
    norm = float(np.sqrt(np.mean(np.asarray(src, dtype=np.float64) ** 2)))
    for _ in range(2):
        _verdict(TOY, params, ["alpha", "unused"], src, norm, render, 0.0, RemapOptions(), [0], notes)
    assert [n for n in notes if "unused did not change the image" in n] == [notes[0]] and len(notes) == 1


def test_a_start_on_a_bound_is_moved_inside_it():
    """TRF started on a bound hardly moves along it (scipy nudges the start 1e-10 inside and scales
    that coordinate's steps by the distance): from alpha at its lower bound the toy fit stalled at
    82 % error; moved 5 % of the range inside, the same start recovers the truth."""
    _, render, src, _ = _setup()
    base = TOY.complete({"alpha": TOY.param("alpha").lower})
    out = {m: remap(TOY, render, src, base=base, free=["diffuse", "specular", "alpha"],
                    options=RemapOptions(scheme="one", starts=1, linear_starts=False, start_margin=m))
           for m in (0.0, 0.05)}
    assert out[0.0].relative_rmse > 0.5
    assert out[0.05].relative_rmse < 1e-4
    assert abs(out[0.05].params["alpha"] / 0.15 - 1) < 1e-3
