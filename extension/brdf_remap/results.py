"""A conversion's summary (`convert.json`) as the panel shows it: one row per material, its verdict,
error, model and the images of its remap. No bpy here."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

USABLE = ("ok", "mismatch", "unreliable", "unchecked")
"""Verdicts of a material that was converted (a mismatch or an unreliable one is kept, and says so)."""
IMAGES = ("source.png", "target.png", "error.png")
"""The source, the remap and their error, side by side, as the report shows them."""


@dataclass(frozen=True)
class Row:
    name: str
    status: str
    error: float | None
    model: str
    reason: str
    folder: Path | None
    """None for a material that was not converted (failed, unsupported)."""
    verdict: str = ""
    """What its verdict tells beside its status (a uniform target for a textured source, why unreliable)."""

    @property
    def converted(self) -> bool:
        return self.status in USABLE

    def images(self) -> list[Path]:
        return [] if self.folder is None else [self.folder / f for f in IMAGES if (self.folder / f).is_file()]

    def line(self) -> str:
        err = f"{self.error:.2%}" if self.error is not None else "–"
        told = self.verdict if self.converted else self.reason
        return f"{self.status}, {err}" + (f" ({self.model})" if self.model else "") + (f": {told}" if told else "")


def rows(summary: dict, out: Path) -> list[Row]:
    """The summary's materials, worst first as the report orders them: failed, unsupported, then by error."""
    found = [Row(m["name"], m["status"], m.get("relative_rmse"), m.get("model") or "", m.get("reason") or "",
                 Path(out) / "materials" / m["slot"] if m.get("slot") else None, m.get("verdict") or "")
             for m in summary.get("materials", [])]
    return sorted(found, key=lambda r: (r.converted, -(r.error or 0.0)))


def libraries(summary: dict, out: Path) -> dict[str, Path]:
    """The libraries written, by suffix (".blend", ".gltf", ".xml", ".mtlx", ".usda")."""
    return {Path(f).suffix: Path(out) / f for f in summary.get("libraries", [])}
