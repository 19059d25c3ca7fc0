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
    """Every registered scene writer by its format's name; a name registered twice is an error naming both."""
    from ..host.plugins import get_plugin_manager

    pm = pm or get_plugin_manager()
    found: dict = {}
    for impl in pm.hook.brdfremap_register_scene_writers.get_hookimpls():
        def register(writer, _plugin=impl.plugin_name) -> None:
            if writer.name in found:
                raise ConfigError(f"plugins {found[writer.name][0]!r} and {_plugin!r} both write scenes as "
                                  f"{writer.name!r}: uninstall one")
            found[writer.name] = (_plugin, writer)
        impl.function(register=register)
    return {name: writer for name, (_, writer) in found.items()}


def _chosen(writers: dict, formats: list[str] | None) -> list[str]:
    """The formats asked for (each installed and able to write here), else every one that can."""
    if not formats:
        able = sorted(n for n, w in writers.items() if w.unavailable_reason() is None)
        if not able:
            raise ConfigError("no scene writer can write here: " + "; ".join(
                f"{n}: {w.unavailable_reason()}" for n, w in sorted(writers.items())), field="--format")
        return able
    for name in formats:
        if name not in writers:
            raise ConfigError(f"no scene writer for {name!r} (installed: {', '.join(sorted(writers))})",
                              field="--format")
        why = writers[name].unavailable_reason()
        if why:
            raise ConfigError(f"{name}: {why}", field="--format")
    return list(dict.fromkeys(formats))


def _renders_kept(folder: Path, manifest: Manifest) -> None:
    """A folder exported before with other shots, whose renders hold images: those images would be read as
    the new shots'. Refused: export elsewhere, or move the renders away."""
    path = folder / MANIFEST
    if not path.is_file():
        return
    try:
        old = Manifest.model_validate_json(path.read_text())
    except (OSError, ValueError):
        old = None
    if (old is None or old.shots != manifest.shots) and any((folder / RENDERS).rglob("*.exr")):
        raise ConfigError(f"was exported before with other scenes and {RENDERS}/ holds images rendered of them: "
                          "export to a new folder (or move the renders away)", file=str(folder))


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
    chosen = _chosen(writers, formats)
    manifest = Manifest(shots=shots(scene, spp))
    _renders_kept(folder, manifest)
    folder.mkdir(parents=True, exist_ok=True)
    maps = _maps(folder, manifest)
    written: list[Path] = list(maps.values())
    files: dict[str, dict[str, str]] = {}
    for name in chosen:
        writer = writers[name]
        (folder / name).mkdir(exist_ok=True)
        try:
            for shot in manifest.shots:
                path = folder / name / f"{shot.name}{writer.suffix}"
                made = writer.write(shot.scene, path, maps)  # none: the format cannot hold this shot's lights
                written += made
                if made:
                    files.setdefault(name, {})[shot.name] = str(path.relative_to(folder))
        finally:
            writer.close()  # a writer that runs its renderer (a .blend's) lets it go
    manifest = manifest.model_copy(update={"files": files})
    for sub in (CALIBRATION, "MATERIAL"):
        (folder / RENDERS / sub).mkdir(parents=True, exist_ok=True)
    written.append(write_text_atomic(folder / MANIFEST, manifest.model_dump_json(indent=1) + "\n"))
    written.append(write_text_atomic(folder / "SHEET.md", sheet(manifest, {n: writers[n] for n in chosen})))
    return Exported(folder, manifest, written)


def sheet(manifest: Manifest, writers: dict) -> str:
    """The one page a user renders from (templates/sheet.md.j2); each format's writer says how a user puts their
    material in its files (``swap``)."""
    import jinja2

    env = jinja2.Environment(loader=jinja2.FileSystemLoader(Path(__file__).with_name("templates")),
                             autoescape=False, keep_trailing_newline=True, undefined=jinja2.StrictUndefined)
    first = manifest.shots[0].scene
    return env.get_template("sheet.md.j2").render(m=manifest, formats=list(writers), writers=writers, first=first,
                                                  albedo=ALBEDO, calibration=CALIBRATION, renders=RENDERS)
