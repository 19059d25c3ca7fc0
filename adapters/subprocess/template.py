"""The placeholder language of a renderer definition's scene template and `template_vars`.

`{name}` is replaced by its value; `{{` and `}}` are a literal brace, so scene languages that use
braces (and comments that mention them) can be written as they are. A model's `template_vars`
may use the scene's placeholders and the model's own `{p_<parameter>}` (an RGB value written
through `rgb_format`); the template may use all of those and the `template_vars`' names. Every
placeholder is checked when the definition is loaded, naming the file and line."""

from __future__ import annotations

import math
import re
from pathlib import Path

from brdfremap.core.data.errors import ConfigError
from brdfremap.core.data.scene import ProbeScene

_PIECE = re.compile(r"\{\{|\}\}|\{([a-z_][a-z0-9_]*)\}")
"""A literal brace pair or a placeholder. Anything else, lone braces included, is text."""


def sample_vars(spp: int) -> dict[str, str]:
    """The samples per pixel, and as a renderer may take them: the side of a square grid
    (``spp_sqrt``, rounded up) or a power of two's exponent (``spp_log2``, rounded up)."""
    return {"spp": str(spp), "spp_sqrt": str(math.isqrt(spp - 1) + 1), "spp_log2": str((spp - 1).bit_length())}


def scene_vars(scene: ProbeScene) -> dict[str, str]:
    """The probe scene's placeholders: sizes, samples, the camera, the sphere and its one point light."""
    cam, light, sph = scene.camera, scene.point_lights[0], scene.sphere
    out = {"width": scene.resolution, "height": scene.resolution, "seed": scene.seed, **sample_vars(scene.spp),
           "fov": cam.fov, "sphere_radius": sph.radius, "light_intensity": light.intensity}
    for prefix, vec in (("camera", cam.position), ("target", cam.target), ("up", cam.up),
                        ("light", light.position), ("sphere", sph.center)):
        for axis, v in zip("xyz", vec):
            out[f"{prefix}_{axis}"] = v
    return {k: (f"{v:.9g}" if isinstance(v, float) else str(v)) for k, v in out.items()}


SCENE_VARS = tuple(scene_vars(ProbeScene())) + ("model",)


def placeholders(text: str) -> list[tuple[str, int]]:
    """Each placeholder's name and line (1-based), escapes left out."""
    return [(m.group(1), text.count("\n", 0, m.start()) + 1) for m in _PIECE.finditer(text) if m.group(1)]


def substitute(text: str, values: dict[str, str], where: str) -> str:
    """Fill ``text``; an unknown placeholder is an error naming ``where`` and its line (the
    definition's check at load time makes that a bug, not a user's error)."""

    def one(m: re.Match) -> str:
        if m.group(0) in ("{{", "}}"):
            return m.group(0)[0]
        name = m.group(1)
        if name not in values:
            line = text.count("\n", 0, m.start()) + 1
            raise ConfigError(f"line {line}: unknown placeholder {{{name}}}", field=where)
        return values[name]

    return _PIECE.sub(one, text)


_NEAR = re.compile(r"(?<!\{)\{([A-Za-z_][A-Za-z0-9_]*)\}(?!\})")


def check(text: str, known: set[str], file: str, what: str, lines: bool = True) -> None:
    """Every placeholder of ``text`` is in ``known``, else one line naming the file and, for a file
    of its own (``lines``), the line; a near miss in capitals (``{P_albedo}``) is named too."""
    for name, line in placeholders(text):
        if name not in known:
            shown = ", ".join(sorted(known))
            where = f"line {line}: " if lines else ""
            raise ConfigError(f"{where}unknown placeholder {{{name}}} in {what} (known here: {shown}; "
                              "a literal brace is written {{ or }})", file=file)
    for m in _NEAR.finditer(text):
        if m.group(1) != m.group(1).lower() and m.group(1).lower() in known:
            where = f"line {text.count(chr(10), 0, m.start()) + 1}: " if lines else ""
            raise ConfigError(f"{where}{{{m.group(1)}}} in {what} is not a placeholder (they are lower case): "
                              f"write {{{m.group(1).lower()}}}", file=file)


def check_definition(path: Path, definition) -> None:
    """The scene template and each model's `template_vars`, against what each model fills."""
    template = None
    if definition.scene_template:
        tpath = path.parent / definition.scene_template
        try:
            template = tpath.read_text(encoding="utf-8")
        except (OSError, UnicodeDecodeError) as exc:
            raise ConfigError(f"cannot read the scene template {tpath}: {getattr(exc, 'strerror', None) or exc}",
                              file=str(path), field="scene_template") from None
    for name, m in definition.models.items():
        params = {f"p_{p.name}" for p in m.parameters}
        for key in m.template_vars:
            if not re.fullmatch(r"[a-z_][a-z0-9_]*", key) or key in SCENE_VARS or key in params:
                raise ConfigError(f"{key!r} cannot be a template_vars name: use lower case, digits and underscores, "
                                  "and no name the scene or a parameter already fills",
                                  file=str(path), field=f"models.{name}.template_vars")
        if m.native is not None:
            check(m.native.text, params | {"model"}, str(path), f"models.{name}.native.text", lines=False)
        inner = set(SCENE_VARS) | params
        for key, text in m.template_vars.items():
            check(text, inner, str(path), f"models.{name}.template_vars.{key}", lines=False)
        if template is not None:
            check(template, inner | set(m.template_vars), str(path.parent / definition.scene_template),
                  f"the scene template (model {name!r})")
