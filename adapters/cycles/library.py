"""`.blend` files as libraries: read (every material whose surface is one of the adapter's BSDF
nodes) and written (one .blend holding every converted material under its source's name), each
through a Blender worker process of its own, never bpy in this process."""

from __future__ import annotations

import hashlib
import sys
from pathlib import Path

from brdfremap.core.data.atomic import temp_beside, write_text_atomic
from brdfremap.core.data.errors import ConfigError, RenderError
from brdfremap.core.library.formats import Converted, Entry, clip_into
from brdfremap.core.data.schemas import Material, Native
from brdfremap.core.data.textures import mean_value, read_values, texture
from brdfremap.core.run.workerproc import JsonLinesWorker

from .adapter import texture_request
from .material import python_snippet
from .models import MODELS

BLEND_MAGIC = (b"BLENDER", b"\x28\xb5\x2f\xfd")  # a .blend, or a zstd-compressed one


def _worker(what: str) -> JsonLinesWorker:
    from .adapter import CyclesAdapter

    reason = CyclesAdapter.unavailable_reason()
    if reason:
        raise ConfigError(f"{what} needs Blender's bpy module: {reason}; {CyclesAdapter.install_hint}")
    return JsonLinesWorker([sys.executable, "-m", "brdfremap.adapters.cycles.worker"], name=f"cycles ({what})")


class BlendReader:
    name = "Blender (.blend)"
    suffixes = (".blend",)

    def accepts(self, path: Path) -> bool:
        try:
            with open(path, "rb") as f:
                head = f.read(max(len(m) for m in BLEND_MAGIC))
            return any(head[:len(m)] == m for m in BLEND_MAGIC)
        except OSError:
            return True  # read() names the file and the reason

    def read(self, path: Path) -> list[Entry]:
        if not self.accepts(path):
            raise ConfigError("is not a .blend file (no BLENDER header)", file=str(path))
        worker = _worker("reading a .blend")
        try:
            found = worker.request({"op": "read_blend", "path": str(Path(path).resolve())}, timeout=300)["materials"]
        except RenderError as exc:
            raise ConfigError(f"Blender cannot read it: {str(exc).splitlines()[0]}", file=str(path)) from None
        finally:
            worker.close()
        digest = hashlib.sha256(Path(path).read_bytes()).hexdigest()
        return [_entry(m, str(path), digest) for m in found]


def _entry(m: dict, file: str, digest: str) -> Entry:
    """A material the worker read: its reading (a model's parameters, an image's input as the image's
    mean), and the file itself where Cycles renders it as the file holds it (`Native`)."""
    missing = [f for f in m.get("files", []) if not Path(f).is_file()]
    if m.get("native") and missing:
        why = f"its files {', '.join(missing)} are not found: Cycles cannot render it as the file holds it"
        if m["model"] is None:
            return Entry(name=m["name"], file=file, problem=why, notes=m["notes"])
        m = {**m, "native": False, "notes": [*m["notes"], why + "; converted from its reading"]}
    native = Native(file=str(Path(file).resolve()), name=m["name"], sha256=_digest(digest, m.get("files", [])),
                    driven=tuple([*m["textured"], *(d for d in m.get("driven", []) if not any(
                        t.endswith(d) for t in m["textured"]))]),
                    transmits=m.get("transmits", False)) if m.get("native") else None
    if m["model"] is None:
        if native is None:
            return Entry(name=m["name"], file=file, problem=m["problem"], notes=m["notes"])
        return Entry(name=m["name"], file=file, notes=m["notes"], textured=list(native.driven),
                     material=Material(adapter="cycles", model="", name=m["name"], native=native,
                                       params={"transmission": 1.0} if native.transmits else {}))
    params = {k: tuple(v) if isinstance(v, list) else v for k, v in m["params"].items()}
    try:
        notes = clip_into(MODELS[m["model"]], params) + m["notes"]
    except ConfigError as exc:
        return Entry(name=m["name"], file=file, problem=str(exc), notes=m["notes"])
    textures = {}
    for pname, t in m.get("textures", {}).items():
        try:
            textures[pname] = texture(t["file"], t["colorspace"], t["filter"], where=f"{m['name']}: {pname}")
            params[pname] = MODELS[m["model"]].param(pname).clip(mean_value(read_values(
                textures[pname], MODELS[m["model"]].param(pname).kind, where=f"{m['name']}: {pname}")))
        except ConfigError as exc:
            textures.pop(pname, None)
            notes.append(f"{pname}: {exc}: read as its constant")
    return Entry(name=m["name"], file=file, notes=notes, textured=m["textured"],
                 material=Material(adapter="cycles", model=m["model"], params=params, name=m["name"],
                                   textures=textures, native=native))


def _digest(blend: str, files: list[str]) -> str:
    """A material's content: its .blend's and every file it reads (an edited image is fitted again)."""
    h = hashlib.sha256(blend.encode())
    for f in files:
        try:
            h.update(hashlib.sha256(Path(f).read_bytes()).digest())
        except OSError as exc:
            raise ConfigError(f"cannot read {f}: {exc.strerror or exc}", file=f) from None
    return h.hexdigest()


class BlendLibraryWriter:
    name = "Blender library (.blend)"
    adapter = "cycles"
    models: tuple[str, ...] = ()

    def write(self, folder: Path, items: list[Converted]) -> list[Path]:
        blend = Path(folder) / "library.blend"
        tmp = temp_beside(blend)
        payload = [{"name": i.name, "model": i.model, "textures": texture_request(folder, i.textures),
                    "params": {k: list(v) if isinstance(v, tuple) else v for k, v in
                               MODELS[i.model].complete(i.params).items()}} for i in items]
        worker = _worker("writing library.blend")
        try:
            worker.request({"op": "save_library", "items": payload, "path": str(tmp.resolve())}, timeout=600)
            tmp.replace(blend)
        finally:
            worker.close()
            tmp.unlink(missing_ok=True)
        script = "\n\n".join(python_snippet(i.model, MODELS[i.model].complete(i.params), i.name, i.textures)
                               for i in items)
        return [blend, write_text_atomic(Path(folder) / "library.py", script)]
