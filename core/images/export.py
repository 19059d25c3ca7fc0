"""`remap scene export DIR`: the probe and its held-out conditions written for a renderer the tool
cannot drive, in each format a plugin writes (`brdfremap_register_scene_writers`), with the environment
maps as EXR, the manifest an images source reads back (`exported.Manifest`) and a sheet that says what to
render and how to name it. Every file is written atomically; a folder written before is updated."""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from ..data.atomic import write_text_atomic
from ..data.environment import is_builtin, realise
from ..data.errors import ConfigError
from ..data.imageio import read_image, write_exr
from ..data.scene import EnvironmentLight, ProbeScene
from .exported import ALBEDO, CALIBRATION, MANIFEST, Manifest, shots

RENDERS = "renders"


def scene_writers(pm=None) -> dict:
    """Every registered scene writer by its format's name."""
    from ..host.plugins import get_plugin_manager

    pm = pm or get_plugin_manager()
    found: dict = {}
    for impl in pm.hook.brdfremap_register_scene_writers.get_hookimpls():
        impl.function(register=lambda writer: found.setdefault(writer.name, writer))
    return found


def _maps(folder: Path, manifest: Manifest) -> dict[str, Path]:
    """Each environment's map as rendered (scale and rotation applied) in maps/, by its name."""
    out: dict[str, Path] = {}
    for shot in manifest.shots:
        for light in shot.scene.lights:
            if isinstance(light, EnvironmentLight) and light.map not in out:
                stem = light.map if is_builtin(light.map) else Path(light.map).stem
                path = folder / "maps" / f"{stem}.exr"
                path.parent.mkdir(parents=True, exist_ok=True)
                write_exr(path, read_image(realise(light.map, light.scale, light.rotation)))
                out[light.map] = path
    return out


@dataclass(frozen=True)
class Exported:
    folder: Path
    manifest: Manifest
    files: list[Path]


def export(folder: Path, scene: ProbeScene, spp: int, formats: list[str] | None = None) -> Exported:
    """Write the shots of ``scene`` (`exported.shots`) at ``spp`` in ``formats`` (default every one) to
    ``folder``: FORMAT/SHOT.* per format, maps/, scenes.json, SHEET.md and the empty renders/ folders."""
    writers = scene_writers()
    chosen = formats or sorted(writers)
    unknown = [f for f in chosen if f not in writers]
    if unknown:
        raise ConfigError(f"no scene writer for {', '.join(unknown)} (installed: {', '.join(sorted(writers))})",
                          field="--format")
    manifest = Manifest(shots=shots(scene, spp))
    folder.mkdir(parents=True, exist_ok=True)
    maps = _maps(folder, manifest)
    written: list[Path] = list(maps.values())
    files: dict[str, dict[str, str]] = {}
    for name in chosen:
        writer = writers[name]
        (folder / name).mkdir(exist_ok=True)
        for shot in manifest.shots:
            path = folder / name / f"{shot.name}{writer.suffix}"
            written += writer.write(shot.scene, path, maps)
            files.setdefault(name, {})[shot.name] = str(path.relative_to(folder))
    manifest = manifest.model_copy(update={"files": files})
    for sub in (CALIBRATION, "MATERIAL"):
        (folder / RENDERS / sub).mkdir(parents=True, exist_ok=True)
    written.append(write_text_atomic(folder / MANIFEST, manifest.model_dump_json(indent=1) + "\n"))
    written.append(write_text_atomic(folder / "SHEET.md", sheet(manifest, chosen)))
    return Exported(folder, manifest, written)


def sheet(manifest: Manifest, formats: list[str]) -> str:
    """The one page a user renders from (templates/sheet.md.j2)."""
    import jinja2

    env = jinja2.Environment(loader=jinja2.FileSystemLoader(Path(__file__).with_name("templates")),
                             autoescape=False, keep_trailing_newline=True, undefined=jinja2.StrictUndefined)
    first = manifest.shots[0].scene
    return env.get_template("sheet.md.j2").render(m=manifest, formats=formats, first=first, albedo=ALBEDO,
                                                  calibration=CALIBRATION, renders=RENDERS)
