"""Registration of spectwin's Python plugins with Mitsuba, and the data they are handed.

Plugin properties cannot carry arrays, so a scene dict names its data by a key
(:func:`PluginData.keep`) that the plugin's constructor looks up. Plugin classes derive from
Mitsuba's base classes, which exist only once the variant is set: they are built and registered
on first use (:func:`register_once`).
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

from twin.render.variant import activate

__all__ = ["PluginData", "register_once"]

_REGISTERED: set[str] = set()


class PluginData:
    """Data handed to plugin instances by key."""

    def __init__(self, prefix: str):
        self._prefix, self._items, self._keys = prefix, {}, itertools.count()

    def keep(self, item: Any) -> str:
        """Keep ``item`` and return the key to put in the scene dict."""
        key = f"{self._prefix}{next(self._keys)}"
        self._items[key] = item
        return key

    def __getitem__(self, key: str) -> Any:
        return self._items[key]


def register_once(kind: str, name: str, build_class: Callable[[], type]) -> None:
    """Register the plugin ``name`` of ``kind`` (``"bsdf"``, ``"emitter"``) on first call."""
    if name in _REGISTERED:
        return
    activate()
    import mitsuba as mi

    plugin = build_class()
    getattr(mi, f"register_{kind}")(name, lambda props: plugin(props))
    _REGISTERED.add(name)
