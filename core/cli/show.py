"""How a result is printed: its parameters, its verdict, its held-out lights, its textures (the
`remap` and `remap --table` commands print one alike)."""

from __future__ import annotations

from typing import TYPE_CHECKING

from ..data.schemas import format_value

if TYPE_CHECKING:
    from ..job.report import Report


def format_params(params: dict, names: list[str] | None = None) -> str:
    return " ".join(f"{k}={format_value(tuple(v) if isinstance(v, list) else v)}" for k, v in params.items()
                    if names is None or k in names)


def _held_out(r: Report) -> str:
    """Each held-out condition's error, with its noise floor where that is not negligible."""
    if not r.validation:
        return "not checked (--validate none)" if not r.validation_skipped else \
            "none: " + "; ".join(f"{k} {v}" for k, v in r.validation_skipped.items())
    parts = [f"{c.label} {c.error:.1%}" + (f" (noise {c.noise_floor:.1%})" if c.noise_floor >= 0.01 else "")
             for c in r.validation]
    levels: dict[tuple[int, int], list[str]] = {}
    for c in r.validation:
        if not c.given:
            levels.setdefault((c.resolution, c.spp), []).append(c.label)
    where = "; ".join(f"{', '.join(v) if len(levels) > 1 else 'each'} at {res} px {spp} spp"
                      for (res, spp), v in levels.items())
    skipped = "".join(f"; {k} skipped: {v}" for k, v in r.validation_skipped.items())
    return ", ".join(parts) + f"   ({where}; seeds the fit never saw{skipped})"


def _textures(t) -> str:
    """A textured source's maps and its textured check, each condition's error beside its noise."""
    maps = ", ".join(m.param for m in t.maps) or "none"
    checks = ", ".join(f"{c.condition} {c.error:.1%} (noise {c.noise_floor:.1%})" for c in t.checks) or \
        f"not rendered: {t.check_skipped}"
    return (f"{t.width} x {t.height} texels remapped texel by texel in {t.seconds:.2f} s; maps {maps}; textured "
            f"check at {t.checks[0].resolution if t.checks else '-'} px: {checks}")


def _verdict(r: Report) -> str:
    """The status and why (an unchecked result names the lights that judged it and those that could not)."""
    word = {"ok": "ok", "mismatch": "MISMATCH", "unreliable": "UNRELIABLE", "unchecked": "UNCHECKED"}[r.verdict]
    told = r.as_verdict().told
    return f"{word}: {told}" if told else word


def _start(r: Report) -> tuple[str, str]:
    lk = r.job.lookup
    if lk is not None:
        expected = f"; direct fits here reach about {lk.expected_error:.1%}" if lk.expected_error is not None else ""
        return "table", f"{lk.table} ({lk.method} map): nothing fitted{expected}" + (
            f"; clamped: {'; '.join(lk.outside)}" if lk.outside else "")
    if r.job.start is not None:
        return "start", "the job's own: " + format_params(r.start.params)
    if r.start.rule:
        error = f" ({r.metrics.start_error:.2%} on the fit scene)" if r.metrics.start_error is not None else ""
        return "start", f"the fixed rule, {r.start.rule}{error}: " + format_params(r.start.params)
    return "start", ("the exporters' conversion: " + format_params(r.start.params) if r.start.informed
                     else "the target's defaults")


def print_report(r: Report, folder, resumed: bool) -> None:
    m = r.metrics
    rows = [
        ("params", format_params(r.params)),
        ("relative RMSE", f"{m.relative_rmse:.2%}   (noise floor {m.noise_floor:.2%})"),
        ("perceptual", f"{m.perceptual:.2f} mean ΔE_ITP"),
        *([("fit scene", r.fit_scene.why)] if r.fit_scene else []),
        ("held-out", _held_out(r)),
        *([("textures", _textures(r.textures))] if r.textures else []),
        _start(r),
        ("renders", f"{r.renders} target ({', '.join(f'{v} at {k}' for k, v in r.renders_by_resolution.items())})"
                    f" + {r.source_renders} source"),
        ("seconds", f"{r.seconds:.2f}" + ("   (the stored result of this same job: --force to fit again)"
                                          if resumed else "")),
        *([] if r.job.lookup else [("scheme", r.scheme if r.scheme == r.scheme_used
                                                 else f"{r.scheme} (used {r.scheme_used})")]),
        ("verdict", _verdict(r)),
        ("wrote", f"{folder}/ ({', '.join([f.name for f in r.files] + ['result.json'])})"),
    ]
    width = max(len(k) for k, _ in rows)
    for k, v in rows:
        print(f"{k:<{width}}  {v}")
