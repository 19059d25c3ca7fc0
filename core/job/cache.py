"""Render cache: identical requests are rendered once and counted once."""

from __future__ import annotations

import hashlib
import json
from collections import OrderedDict
from typing import Any, Callable

import numpy as np


def render_key(adapter: str, model: str, params: dict[str, Any], scene_key: str, lobe: str | None) -> str:
    canon = {k: (list(v) if isinstance(v, tuple) else v) for k, v in sorted(params.items())}
    blob = json.dumps([adapter, model, canon, scene_key, lobe], sort_keys=True, default=float)
    return hashlib.sha1(blob.encode()).hexdigest()


class RenderCache:
    """LRU of images by key. ``misses`` counts real renders."""

    def __init__(self, max_items: int = 512):
        self._items: OrderedDict[str, np.ndarray] = OrderedDict()
        self.max_items = max_items
        self.hits = 0
        self.misses = 0

    def __contains__(self, key: str) -> bool:
        return key in self._items

    def get_or_render(self, key: str, render: Callable[[], np.ndarray]) -> np.ndarray:
        if key in self._items:
            self.hits += 1
            self._items.move_to_end(key)
            return self._items[key]
        img = render()
        self.misses += 1
        img.setflags(write=False)
        self._items[key] = img
        if len(self._items) > self.max_items:
            self._items.popitem(last=False)
        return img
