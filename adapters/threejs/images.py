"""A glTF's images as files a texture can name: an image file beside the `.gltf` or below it (a
relative URI) as it is; an image embedded in the file (a data URI, or a buffer view of a data-URI buffer, a buffer
file beside it, or a `.glb`'s binary chunk) written once, by its content, to
`$XDG_CACHE_HOME/brdfremap/gltf-images/` (so a run that is interrupted and started again names the
same file, and its jobs resume). Only regular files are read, only the bytes a buffer view names,
and only PNG and JPEG images are taken, by their first bytes; nothing is fetched from a network and
nothing in a glTF is run. A malformed entry is a ConfigError naming its field."""

from __future__ import annotations

import base64
import binascii
import hashlib
import os
import urllib.parse
from pathlib import Path
from typing import Any

from brdfremap.core.data.atomic import write_bytes_atomic
from brdfremap.core.data.errors import ConfigError

MAGIC = {b"\x89PNG\r\n\x1a\n": ".png", b"\xff\xd8\xff": ".jpg"}
"""The image kinds glTF 2.0 allows, by their first bytes."""


def cache_folder() -> Path:
    """$XDG_CACHE_HOME/brdfremap/gltf-images (a relative XDG_CACHE_HOME is ignored, as the XDG spec says)."""
    base = os.environ.get("XDG_CACHE_HOME", "")
    if not os.path.isabs(base):
        base = os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "brdfremap" / "gltf-images"


def image_file(doc: dict[str, Any], blob: bytes | None, folder: Path, index: int) -> Path:
    """The file of image ``index`` of this document (``folder``: the `.gltf`'s; ``blob``: a `.glb`'s
    binary chunk); a ConfigError saying why when it has none."""
    image = item(doc, "images", index)
    field = f"images[{index}]"
    uri = image.get("uri")
    if uri is not None and not isinstance(uri, str):
        raise ConfigError(f"{field}.uri is not a string")
    if isinstance(uri, str) and _scheme(uri, field) != "data":
        path = _local(folder, uri, f"{field}.uri")
        kind(_read(path, 0, len(max(MAGIC, key=len)), f"{field}.uri"), f"{field} ({path})")
        return path
    data = _data_uri(uri, f"{field}.uri") if isinstance(uri, str) else _buffer_view(doc, blob, folder, image, index)
    suffix = kind(data, field)
    path = cache_folder() / f"{hashlib.sha256(data).hexdigest()}{suffix}"
    if not path.is_file():
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_bytes_atomic(path, data)
        except OSError as exc:
            raise ConfigError(f"cannot write {field} to {path.parent}: {exc.strerror or exc} "
                              "(set XDG_CACHE_HOME to a writable folder)") from None
    return path


def item(doc: dict[str, Any], key: str, index: Any) -> dict[str, Any]:
    """Entry ``index`` of the document's array ``key`` (an object), or a ConfigError naming it."""
    items = doc.get(key)
    if not isinstance(index, int) or not isinstance(items, list) or not 0 <= index < len(items) \
            or not isinstance(items[index], dict):
        raise ConfigError(f"{key}[{index}] is not in the file")
    return items[index]


def _scheme(uri: str, field: str) -> str:
    parsed = urllib.parse.urlparse(uri)
    if parsed.scheme == "data":
        return "data"
    if parsed.scheme or parsed.netloc:
        raise ConfigError(f"{field} is {uri[:80]!r}: only files beside the glTF and embedded data are read "
                          "(nothing is fetched)")
    return ""


def _local(folder: Path, uri: str, field: str) -> Path:
    """A relative URI's file: in the glTF's folder or below it, and a regular file (not a device, a
    pipe or a folder)."""
    home = folder.resolve()
    path = (home / urllib.parse.unquote(uri)).resolve()
    if not path.is_relative_to(home):
        raise ConfigError(f"{field}: {path} is outside the glTF's folder {home}: only files beside it (or below) "
                          "are read; copy the file there")
    if not path.is_file():
        raise ConfigError(f"{field}: {path} is not a file")
    return path


def _read(path: Path, start: int, length: int, field: str) -> bytes:
    try:
        with open(path, "rb") as f:
            f.seek(start)
            return f.read(length)
    except OSError as exc:
        raise ConfigError(f"{field}: cannot read {path}: {exc.strerror or exc}") from None


def kind(data: bytes, field: str) -> str:
    suffix = next((s for magic, s in MAGIC.items() if data[:len(magic)] == magic), None)
    if suffix is None:
        raise ConfigError(f"{field} is neither a PNG nor a JPEG image")
    return suffix


def _data_uri(uri: str, field: str) -> bytes:
    head, _, body = uri.partition(",")
    if not head.lower().endswith(";base64"):
        raise ConfigError(f"{field} is a data URI that is not base64")
    try:
        return base64.b64decode(body, validate=True)
    except (ValueError, binascii.Error):
        raise ConfigError(f"{field} is not valid base64") from None


def _buffer_view(doc: dict[str, Any], blob: bytes | None, folder: Path, image: dict[str, Any], index: int) -> bytes:
    """The bytes a buffer view names, and no more."""
    i = image.get("bufferView")
    if i is None:
        raise ConfigError(f"images[{index}] has neither a uri nor a bufferView")
    view = item(doc, "bufferViews", i)
    field = f"bufferViews[{i}]"
    b, start, length = view.get("buffer"), view.get("byteOffset", 0), view.get("byteLength")
    if not all(isinstance(x, int) and not isinstance(x, bool) and x >= 0 for x in (b, start, length)):
        raise ConfigError(f"{field}: buffer, byteOffset and byteLength must be whole numbers of at least 0")
    buffer = item(doc, "buffers", b)
    uri = buffer.get("uri")
    if uri is None:
        if b != 0 or blob is None:
            raise ConfigError(f"buffers[{b}] has no uri, and only a .glb's first buffer may (its binary chunk)")
        data = blob[start:start + length]
    elif not isinstance(uri, str):
        raise ConfigError(f"buffers[{b}].uri is not a string")
    elif _scheme(uri, f"buffers[{b}].uri") == "data":
        data = _data_uri(uri, f"buffers[{b}].uri")[start:start + length]
    else:
        data = _read(_local(folder, uri, f"buffers[{b}].uri"), start, length, f"buffers[{b}].uri")
    if len(data) != length:
        raise ConfigError(f"{field} runs past the end of buffers[{b}]")
    return data
