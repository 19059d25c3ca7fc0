"""Opening a USD stage for reading: usd-core's diagnostics become one line each (a layer it could not
load, a cycle of sublayers) instead of noise on the terminal; the `.mtlx` documents a stage references
(usd-core has no UsdMtlx: they are read from the file beside the stage); and the variant selections
that change what the stage's materials are."""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.imageio import captured_stderr

from .author import pxr


def open_stage(path: Path):
    """The stage (its composition errors in ``problems``); a file that is not USD at all is a
    ConfigError naming it."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    from pxr import Tf

    with captured_stderr():
        try:
            stage = Usd.Stage.Open(str(path), Usd.Stage.LoadAll)
        except Tf.ErrorException as exc:
            raise ConfigError(f"cannot read it as USD: {_first(str(exc))}", file=str(path)) from None
    if stage is None:
        raise ConfigError("cannot read it as USD", file=str(path))
    return stage


def problems(stage) -> list[str]:
    """The stage's composition errors, one line each, but a `.mtlx` it references (read beside it)."""
    out = []
    for err in stage.GetCompositionErrors():
        text = _first(str(err))
        if re.search(r"@[^@]*\.mtlx@", text):
            continue
        out.append(f"{text} (check the path: the materials it holds are not read, the others are)")
    return out


def _first(text: str) -> str:
    """usd-core's message without its C++ location: the quoted part of "Error in '...' at line N in
    file ... : 'message'", else the first non-empty line."""
    quoted = re.findall(r" : '(.*)'", text)
    lines = [line.strip() for line in (quoted or text.splitlines()) if line.strip()]
    return lines[0] if lines else "unknown error"


@dataclass(frozen=True)
class MtlxReference:
    """A `.mtlx` document a prim references (``target``: the prim path in it, e.g. /MaterialX/Materials)."""

    prim: str
    file: Path
    target: str


def mtlx_references(stage) -> list[MtlxReference]:
    """Every reference or payload to a `.mtlx` document in the prims' composed specs, its path
    resolved against the layer that wrote it."""
    found: list[MtlxReference] = []
    for prim in stage.TraverseAll():
        for spec in prim.GetPrimStack():
            for ref in [*spec.referenceList.GetAddedOrExplicitItems(), *spec.payloadList.GetAddedOrExplicitItems()]:
                asset = ref.assetPath
                if asset.lower().endswith(".mtlx"):
                    file = Path(spec.layer.ComputeAbsolutePath(asset)) if not spec.layer.anonymous else Path(asset)
                    found.append(MtlxReference(str(prim.GetPath()), file, str(ref.primPath)))
    return list(dict.fromkeys(found))


@dataclass(frozen=True)
class Variant:
    """One variant of a variant set on a prim, away from the stage's own selection."""

    prim: str
    set: str
    name: str

    @property
    def label(self) -> str:
        return f"{self.set}={self.name}"


def variants(stage) -> list[Variant]:
    """Every variant the stage does not select, of the variant sets on its prims as it opens."""
    out = []
    for prim in stage.Traverse():
        sets = prim.GetVariantSets()
        for name in sets.GetNames():
            chosen = sets.GetVariantSet(name).GetVariantSelection()
            out += [Variant(str(prim.GetPath()), name, v) for v in sets.GetVariantSet(name).GetVariantNames()
                    if v != chosen]
    return out


def select(stage, variant: Variant | None, previous: Variant | None = None) -> None:
    """Select ``variant`` in the stage's session layer (the file is not touched), clearing the
    ``previous`` selection first."""
    Gf, Sdf, Usd, UsdGeom, UsdShade = pxr()
    stage.SetEditTarget(stage.GetSessionLayer())
    with captured_stderr():
        if previous is not None:
            stage.GetPrimAtPath(previous.prim).GetVariantSets().GetVariantSet(previous.set).ClearVariantSelection()
        if variant is not None:
            stage.GetPrimAtPath(variant.prim).GetVariantSets().GetVariantSet(variant.set).SetVariantSelection(
                variant.name)
