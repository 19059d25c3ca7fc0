"""The library report, `index.html`: one self-contained page (its images beside it, nothing
fetched), worst first, rendered from a jinja2 template with autoescaping."""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

from ..data.atomic import write_text_atomic
from ..data.schemas import format_value
from .records import ItemStatus
from ..data.scene import Lighting
from ..data.findings import Underdetermined
from ..job.report import PARTING

if TYPE_CHECKING:
    from .convert import Conversion, Item

RANK = {s: i for i, s in enumerate(ItemStatus)}
"""Worst first: the order `ItemStatus` declares."""


def _order(item: "Item") -> tuple:
    rep = item.done.report if item.done is not None else None
    return (RANK[item.status], -(rep.metrics.relative_rmse if rep else 0.0), item.entry.name.lower())


def _source(src) -> str:
    """The source as the card names it: its adapter and reading, and whether it is rendered as written."""
    if src is None:
        return ""
    if src.native is None:
        return f"{src.adapter}:{src.model}"
    return f"{src.adapter}, as written" + (f" (read as {src.model})" if src.model else " (no reading)")


def _card(item: "Item") -> dict:
    rep = item.done.report if item.done is not None else None
    src = item.entry.material
    remapped = rep is not None and rep.textures is not None
    card = {"name": item.entry.name, "file": item.entry.file, "status": item.status, "reason": item.reason,
            "model": item.model, "why": item.why, "notes": item.entry.notes, "textured": item.entry.textured,
            "texel": remapped,
            "source": _source(src), "report": None}
    if rep is not None:
        folder = f"materials/{item.slot}"
        m = rep.metrics
        card["report"] = {
            "folder": folder, "images": [f"{folder}/{n}.png" for n in ("source", "target", "error")],
            "parting": next(({"image": f"{folder}/{PARTING}", "label": f.label, "difference": f.difference}
                             for f in rep.findings if isinstance(f, Underdetermined)), None),
            # A source with no reading has no values to show (its held `transmission` is not one of its file's).
            "before": {} if src is not None and src.native is not None and not src.model else
            {k: format_value(_tuple(v)) for k, v in rep.source.params.items()},
            "after": {k: format_value(_tuple(v)) for k, v in rep.params.items()},
            "fitted": rep.fitted, "error": m.relative_rmse, "perceptual": m.perceptual, "noise": m.noise_floor,
            "threshold": m.threshold, "renders": rep.renders, "seconds": rep.seconds, "resumed": item.done.resumed,
            "findings": [{"severity": f.severity, "message": f.message} for f in rep.findings],
            "held_out": [{"label": c.label, "error": c.error, "noise": c.noise_floor, "beyond": c.beyond_noise,
                          "judged": c.noise_floor <= rep.job.settings.resolve_limit} for c in rep.validation],
            "fit_scene": rep.fit_scene.why if rep.fit_scene else "",
            "rule": {"name": rep.start.rule, "error": m.start_error} if rep.start.rule and m.start_error is not None
            else None,
            "target": f"{rep.target.adapter}:{rep.target.model}", "textures": _textures(rep, folder)}
    return card


def _textures(rep, folder: str) -> dict | None:
    """A textured source remapped texel by texel: its maps, the check's images and errors."""
    t = rep.textures
    if t is None:
        return None
    return {"table": t.table, "size": f"{t.width} x {t.height}",
            "maps": [{"param": m.param, "href": f"{folder}/{m.file}", "space": m.colorspace,
                      "range": f"{m.low:.3g} to {m.high:.3g}"} for m in t.maps],
            "images": [f"{folder}/textured-{n}.png" for n in ("source", "target", "error")] if t.checks else [],
            "lit": "studio" if t.checks[-1:] and t.checks[-1].condition == Lighting.ENVIRONMENT else "scene lights",
            "checks": [{"condition": c.condition, "error": c.error, "noise": c.noise_floor, "de": c.perceptual,
                        "resolution": c.resolution, "spp": c.spp} for c in t.checks],
            "skipped": t.check_skipped, "held": list(t.held.values()), "outside": t.outside, "notes": t.notes}


def _tuple(v):
    return tuple(v) if isinstance(v, list) else v


def write_index(path: Path, result: "Conversion") -> Path:
    import jinja2

    env = jinja2.Environment(loader=jinja2.FileSystemLoader(Path(__file__).with_name("templates")),
                             autoescape=True, undefined=jinja2.StrictUndefined)
    items = sorted(result.items, key=_order)
    counts = {s: sum(i.status is s for i in items) for s in ItemStatus if s is not ItemStatus.PENDING}
    html = env.get_template("index.html.j2").render(
        cards=[_card(i) for i in items], counts=counts, total=len(items), destination=result.destination,
        libraries=[p.name for p in result.libraries], library_notes=result.library_notes,
        seconds=result.seconds, where=result.where)
    return write_text_atomic(path, html)
