"""A glTF's images as files a texture can name: an image file beside the `.gltf` as it is; an image
embedded in the file (a data URI, or a buffer view of a `.glb`'s binary chunk) written once, by its
content, to `$XDG_CACHE_HOME/brdfremap/gltf-images/` (so a run that is interrupted and started again
names the same file, and its jobs resume). Only PNG and JPEG images are taken, by their first bytes;
nothing in a glTF is run."""

from __future__ import annotations

import base64
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
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "brdfremap" / "gltf-images"


def image_file(doc: dict[str, Any], blob: bytes | None, folder: Path, index: int) -> Path:
    """The file of image ``index`` of this document (``folder``: the `.gltf`'s; ``blob``: a `.glb`'s
    binary chunk); a ConfigError saying why when it has none."""
    images = doc.get("images") or []
    if not 0 <= index < len(images):
        raise ConfigError(f"image {index} is not in the file")
    image = images[index]
    uri = image.get("uri")
    scheme = urllib.parse.urlparse(uri).scheme if isinstance(uri, str) else "data"
    if scheme != "data":
        if scheme:
            raise ConfigError(f"image {index} is at {uri!r}: only files beside the glTF and embedded images are read")
        path = (folder / urllib.parse.unquote(uri)).resolve()
        if not path.is_file():
            raise ConfigError(f"image {index}'s file {path} is not there")
        return path
    data = _data_uri(uri, index) if isinstance(uri, str) else _buffer_view(doc, blob, folder, image, index)
    suffix = next((s for magic, s in MAGIC.items() if data[:len(magic)] == magic), None)
    if suffix is None:
        raise ConfigError(f"image {index} is neither a PNG nor a JPEG")
    path = cache_folder() / f"{hashlib.sha256(data).hexdigest()}{suffix}"
    if not path.is_file():
        try:
            path.parent.mkdir(parents=True, exist_ok=True)
            write_bytes_atomic(path, data)
        except OSError as exc:
            raise ConfigError(f"cannot write image {index} to {path.parent}: {exc.strerror or exc} "
                              "(set XDG_CACHE_HOME to a writable folder)") from None
    return path


def _data_uri(uri: str, index: int) -> bytes:
    head, _, body = uri.partition(",")
    if not head.endswith(";base64"):
        raise ConfigError(f"image {index}'s data URI is not base64")
    try:
        return base64.b64decode(body, validate=True)
    except ValueError:
        raise ConfigError(f"image {index}'s data URI is not valid base64") from None


def _buffer_view(doc: dict[str, Any], blob: bytes | None, folder: Path, image: dict[str, Any], index: int) -> bytes:
    views = doc.get("bufferViews") or []
    i = image.get("bufferView")
    if not isinstance(i, int) or not 0 <= i < len(views):
        raise ConfigError(f"image {index} has neither a URI nor a buffer view")
    view = views[i]
    buffers = doc.get("buffers") or []
    b = view.get("buffer", 0)
    if not isinstance(b, int) or not 0 <= b < len(buffers):
        raise ConfigError(f"image {index}'s buffer view {i} names no buffer")
    data = _buffer(buffers[b].get("uri"), blob, folder, index)
    start = int(view.get("byteOffset", 0))  # a buffer view's offset and length are the glTF's own
    out = data[start:start + int(view.get("byteLength", 0))]
    if len(out) != int(view.get("byteLength", 0)):
        raise ConfigError(f"image {index}'s buffer view {i} runs past its buffer")
    return out


def _buffer(uri: Any, blob: bytes | None, folder: Path, index: int) -> bytes:
    """A buffer's bytes: a data URI's, a file's beside the glTF, or (no URI) a `.glb`'s binary chunk."""
    if not isinstance(uri, str):
        if blob is None:
            raise ConfigError(f"image {index} is in a buffer of no URI, and the file has no binary chunk")
        return blob
    scheme = urllib.parse.urlparse(uri).scheme
    if scheme == "data":
        return _data_uri(uri, index)
    if scheme:
        raise ConfigError(f"image {index} is in a buffer at {uri!r}: only files beside the glTF are read")
    try:
        return (folder / urllib.parse.unquote(uri)).read_bytes()
    except OSError as exc:
        raise ConfigError(f"image {index}'s buffer {uri!r} cannot be read: {exc.strerror or exc}") from None
