"""Experiment plots in the style of the paper's figures (matplotlib, PNG and SVG)."""

from __future__ import annotations

import math
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..data.atomic import temp_beside, why
from ..data.errors import ConfigError
from .analysis import channels, quantity
from .spec import PlotChannels, Side, SideParam, label

if TYPE_CHECKING:
    from .analysis import Row
    from .spec import Experiment


def _plt():
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    plt.rcParams.update({"font.size": 9, "axes.grid": True, "grid.alpha": 0.3, "svg.hashsalt": "brdf-remap",
                         "svg.fonttype": "none"})
    return plt


def _save(fig, base: Path, svg: bool = True) -> Path:
    """PNG (and SVG) written beside and renamed into place: a plot on disk is always whole."""
    base.parent.mkdir(parents=True, exist_ok=True)
    png = base.with_suffix(".png")
    for path, kw in [(png, {"dpi": 110})] + ([(base.with_suffix(".svg"), {"metadata": {"Date": None}})] if svg else []):
        tmp = temp_beside(path)
        try:
            fig.savefig(tmp, format=path.suffix[1:], bbox_inches="tight", **kw)
            tmp.replace(path)
        except OSError as exc:
            raise ConfigError(f"cannot write: {why(exc)} (the previous file, if any, is kept)", file=str(path)) \
                from None
        finally:
            tmp.unlink(missing_ok=True)
    return png


def _name(q: SideParam) -> str:
    return q.name.replace("_", " ")


def _points(exp: "Experiment", rows: list["Row"], xq: SideParam, yq: SideParam):
    out = []  # (group label, x, y, flagged, cliff, channel, mismatch)
    for r in rows:
        xs = channels(quantity(r, xq), exp.plot.channels)
        ys = channels(quantity(r, yq), exp.plot.channels)
        n = min(len(xs), len(ys))
        for c in range(n):
            out.append((r.point.group, xs[c] if len(xs) > 1 else xs[0], ys[c] if len(ys) > 1 else ys[0],
                        r.flagged, bool(r.cliff), c if n > 1 else None, r.mismatch))
    return out


def _grouplabel(exp: "Experiment", g: Any) -> str:
    return f"{exp.groups.param} = {label(g)}" if exp.groups else exp.source.model


def sweep_plot(base: Path, exp: "Experiment", rows: list["Row"]) -> Path:
    """y against x, one curve per group; unreliable points crossed, points after a cliff ringed."""
    plt = _plt()
    fig, ax = plt.subplots(figsize=(6.0, 4.2))
    pts = _points(exp, rows, exp.plot.x, exp.plot.y)
    groups = list(dict.fromkeys(p[0] for p in pts))
    cmap = plt.get_cmap("viridis")
    markers = {None: "o", 0: "o", 1: "s", 2: "^"}
    for gi, g in enumerate(groups):
        color = cmap(gi / max(len(groups) - 1, 1) * 0.9)
        mine = [p for p in pts if p[0] == g]
        for ch in sorted({p[5] for p in mine}, key=lambda c: -1 if c is None else c):
            series = sorted((p for p in mine if p[5] == ch), key=lambda p: p[1])
            x = [p[1] for p in series]
            y = [p[2] for p in series]
            label = _grouplabel(exp, g) if ch in (None, 0) else None
            ax.plot(x, y, "-", color=color, lw=0.8, alpha=0.6)
            ax.plot(x, y, markers[ch], color=color, ms=3.5, label=label, ls="none")
    mm = [p for p in pts if p[6]]
    if mm:
        ax.plot([p[1] for p in mm], [p[2] for p in mm], "s", mfc="none", mec="0.55", ms=6, mew=0.8, ls="none",
                label="error above threshold (model mismatch)")
    bad = [p for p in pts if p[3]]
    if bad:
        ax.plot([p[1] for p in bad], [p[2] for p in bad], "x", color="crimson", ms=6, mew=1.2, ls="none",
                label="unreliable (trimmed, pinned, ...) or cliff")
    cl = [p for p in pts if p[4]]
    if cl:
        ax.plot([p[1] for p in cl], [p[2] for p in cl], "o", mfc="none", mec="black", ms=9, mew=1.0, ls="none",
                label="after a cliff")
    ax.set_xlabel(exp.plot.xlabel or f"{exp.source.model}: {_name(exp.plot.x)}")
    ax.set_ylabel(exp.plot.ylabel or f"{exp.target.model}: {_name(exp.plot.y)}")
    n_cliffs = sum(bool(r.cliff) for r in rows)
    title = exp.plot.title or exp.name
    ax.set_title(f"{title}\n{len(rows)} points, {sum(r.flagged for r in rows)} flagged, {n_cliffs} after a cliff"
                 + (f"  (channels: {'R ○ G □ B △'})" if exp.plot.channels == PlotChannels.EACH else ""), fontsize=9)
    ax.legend(fontsize=7, loc="best")
    path = _save(fig, base)
    plt.close(fig)
    return path


def roundtrip_plot(base: Path, exp: "Experiment", rows: list["Row"], fit: dict[str, float] | None) -> Path:
    """Recovered against original with the unit line and the fitted line of the unflagged points."""
    plt = _plt()
    name = exp.compared()
    fig, ax = plt.subplots(figsize=(4.8, 4.5))
    pts = _points(exp, rows, SideParam(Side.SOURCE, name), SideParam(Side.BACK, name))
    good = [p for p in pts if not p[3]]
    bad = [p for p in pts if p[3]]
    if pts:
        lo = min(min(p[1] for p in pts), min(p[2] for p in pts))
        hi = max(max(p[1] for p in pts), max(p[2] for p in pts))
        ax.plot([lo, hi], [lo, hi], "-", color="0.6", lw=1, label="unit line")
        if fit and not math.isnan(fit.get("slope", float("nan"))):
            xs = np.array([lo, hi])
            ax.plot(xs, fit["slope"] * xs + fit["intercept"], "--", color="black", lw=1,
                    label=f"fit: slope {fit['slope']:.3f}, R² {fit['r2']:.4f}")
    ax.plot([p[1] for p in good], [p[2] for p in good], "o", color="tab:blue", ms=3.5, ls="none",
            label=f"kept ({len(good)})")
    if bad:
        ax.plot([p[1] for p in bad], [p[2] for p in bad], "x", color="crimson", ms=5, ls="none",
                label=f"flagged ({len(bad)})")
    ax.set_xlabel(f"original {name.replace('_', ' ')} ({exp.source.model})")
    ax.set_ylabel(f"recovered {name.replace('_', ' ')} ({exp.source.model} → {exp.target.model} → back)")
    ax.set_title(exp.plot.title or exp.name, fontsize=9)
    ax.set_aspect("equal", adjustable="datalim")
    ax.legend(fontsize=7, loc="upper left")
    path = _save(fig, base)
    plt.close(fig)
    return path


def cliff_figure(path: Path, exp: "Experiment", before: "Row", after: "Row", out: Path) -> Path:
    """The paper's Fig. 8: source, remapped target and error map on both sides of a cliff."""
    plt = _plt()
    fig, axes = plt.subplots(2, 3, figsize=(6.3, 4.5))
    for row_axes, r in zip(axes, (before, after)):
        d = out / "points" / r.point.id
        for ax, name, title in zip(row_axes, ("source", "target", "error"),
                                   ("source", f"remapped ({r.forward.relative_rmse:.1%})", "error (0–10 %)")):
            img = plt.imread(d / f"{name}.png") if (d / f"{name}.png").exists() else np.zeros((8, 8, 3))
            ax.imshow(img)
            ax.set_xticks([])
            ax.set_yticks([])
            ax.grid(False)
            ax.set_title(title, fontsize=8)
        row_axes[0].set_ylabel(f"{exp.sweep.param} = {label(r.point.value)}", fontsize=8)
    fig.suptitle(f"{exp.name}: both sides of a cliff", fontsize=9)
    saved = _save(fig, path.with_suffix(""), svg=False)
    plt.close(fig)
    return saved
