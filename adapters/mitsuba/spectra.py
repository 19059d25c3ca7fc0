"""A Mitsuba scene's spectral values as Mitsuba's RGB variants read them.

A `<spectrum>` of wavelength:value pairs (inline or an `.spd` file) is integrated against the
CIE 1931 observer under D65 into linear sRGB by Mitsuba's own `spectrum_list_to_srgb`, as its
XML parser does when it loads the file in an RGB variant: clamped to [0, 1] for a reflectance,
unclamped for a conductor's eta and k (Mitsuba reads those as unbounded). A single value is a
uniform spectrum: that value in every channel. Mitsuba is imported here (its `scalar_rgb`
module, without choosing a variant for the process), only when a file holds a spectrum."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

from brdfremap.core.data.errors import ConfigError

UNBOUNDED = frozenset({"eta", "k"})
"""Properties Mitsuba reads as unbounded spectra (a conductor's complex IOR); every other BSDF
property's spectrum is a reflectance, clamped to [0, 1]."""
SPECTRAL_ONLY = {"regular": "wavelength_min, wavelength_max, values", "irregular": "wavelengths, values"}
"""Spectrum plugins that Mitsuba's RGB variants load but cannot render: their values, as a spectral
variant renders them, are read through the same integration (with a note)."""
_TOKENS = re.compile(r"[,\s]+")


@dataclass(frozen=True)
class Reading:
    rgb: tuple[float, float, float]
    note: str = ""
    """Empty for a value Mitsuba takes as it is (a uniform spectrum)."""


def read_spectrum(prop: ET.Element, name: str, find: Callable[[str], Path]) -> Reading:
    """The RGB Mitsuba's RGB variants use for the `<spectrum>` element ``prop`` of BSDF property
    ``name``; ``find`` resolves a file name as the scene's file resolver does."""
    kind = prop.get("type")
    if kind is not None:
        return _plugin(prop, name, kind)
    if prop.get("filename") is not None:
        path = find(prop.get("filename", ""))
        wl, vals = _from_file(path)
        return _integrated(wl, vals, name, f"the spectrum of {path.name}")
    text = prop.get("value", "").strip()
    tokens = [t for t in _TOKENS.split(text) if t]
    if len(tokens) == 1 and ":" not in tokens[0]:
        v = _number(tokens[0], name)
        return Reading((v, v, v))
    wl, vals = [], []
    for t in tokens:
        parts = t.split(":")
        if len(parts) != 2:
            raise ConfigError(f"{name}: spectrum value {t!r} is not a wavelength:value pair (write value=\"400:0.5, "
                              "500:0.6, ...\" or one number)")
        wl.append(_number(parts[0], name))
        vals.append(_number(parts[1], name))
    return _integrated(wl, vals, name, f"a spectrum of {len(wl)} wavelengths")


def _plugin(prop: ET.Element, name: str, kind: str) -> Reading:
    fields = {c.get("name"): c.get("value", "") for c in prop}
    if kind == "srgb" and "color" in fields:
        rgb = [_number(t, name) for t in _TOKENS.split(fields["color"].strip()) if t]
        return Reading(tuple(rgb * 3 if len(rgb) == 1 else rgb[:3]))  # type: ignore[arg-type]
    if kind == "uniform" and "value" in fields:
        v = _number(fields["value"], name)
        return Reading((v, v, v))
    if kind not in SPECTRAL_ONLY:
        raise ConfigError(f"{name}: a {kind!r} spectrum is not read here (Mitsuba's RGB variants cannot render it on "
                          "a BSDF; give wavelength:value pairs, an .spd file or an RGB value)")
    try:
        vals = [float(t) for t in _TOKENS.split(fields["values"].strip()) if t]
        if kind == "irregular":
            wl = [float(t) for t in _TOKENS.split(fields["wavelengths"].strip()) if t]
        else:
            lo, hi = float(fields["wavelength_min"]), float(fields["wavelength_max"])
            wl = [lo + (hi - lo) * i / (len(vals) - 1) for i in range(len(vals))]
    except (KeyError, ValueError, ZeroDivisionError):
        raise ConfigError(f"{name}: a {kind!r} spectrum needs {SPECTRAL_ONLY[kind]}") from None
    got = _integrated(wl, vals, name, f"a {kind!r} spectrum plugin")
    return Reading(got.rgb, got.note + " (Mitsuba's RGB variants cannot render this plugin; read as a spectral "
                                      "variant shows it)")


def _integrated(wl: list[float], vals: list[float], name: str, what: str) -> Reading:
    if len(wl) < 2 or len(wl) != len(vals) or any(b <= a for a, b in zip(wl, wl[1:])):
        raise ConfigError(f"{name}: {what} needs at least two wavelengths, in increasing order")
    mi = _mitsuba(name)
    bounded = name not in UNBOUNDED
    logger = mi.logger()
    level = logger.log_level()
    logger.set_log_level(mi.LogLevel.Error)  # its clamping warning goes to stderr; the note says it
    try:
        rgb = tuple(float(x) for x in mi.scalar_rgb.spectrum_list_to_srgb(wl, vals, bounded, True))
    finally:
        logger.set_log_level(level)
    clamped = bounded and any(c == 1.0 for c in rgb)  # (a channel below 0 is clamped too: 0 cannot tell)
    shown = ", ".join(f"{c:.4g}" for c in rgb)
    return Reading(rgb, f"{name}: {what} turned into RGB ({shown}) as Mitsuba's RGB variants do (CIE 1931, "  # type: ignore[arg-type]
                        f"D65, linear sRGB{'' if bounded else ', unbounded'})"
                        f"{', clamped to the gamut as Mitsuba does' if clamped else ''}")


def _from_file(path: Path) -> tuple[list[float], list[float]]:
    wl, vals = [], []
    try:
        lines = path.read_text(errors="replace").splitlines()
    except OSError as exc:
        raise ConfigError(f"cannot read the spectrum file: {exc.strerror or exc}", file=str(path)) from None
    for i, line in enumerate(lines, 1):
        t = line.split("#", 1)[0].split()
        if not t:
            continue
        try:
            wl.append(float(t[0]))
            vals.append(float(t[1]))
        except (IndexError, ValueError):
            raise ConfigError(f"line {i} is not 'wavelength value'", file=str(path)) from None
    return wl, vals


def _number(text: str, name: str) -> float:
    try:
        return float(text)
    except ValueError:
        raise ConfigError(f"{name}: {text!r} is not a number") from None


def _mitsuba(name: str):
    try:
        import mitsuba as mi
    except ImportError:
        raise ConfigError(f"{name} is a spectrum: turning it into RGB as Mitsuba does needs the mitsuba package "
                          "(pip install 'brdf-remap[mitsuba]')") from None
    return mi
