"""Registration of spectwin's Python plugins with Mitsuba, and the data they are handed.

Plugin properties cannot carry arrays, so a scene dict names its data by a key
(:func:`PluginData.keep`) that the plugin's constructor looks up.

Plugin classes derive from Mitsuba's base classes (``mi.BSDF``, ``mi.Emitter``), which resolve to
the classes of the active variant. Each plugin module therefore activates the variant
(:func:`twin.render.variant.activate`, the one place that chooses it) when it is imported, then
defines its class at module level and registers it like Mitsuba's own Python plugins
(``mi.register_bsdf(name, lambda props: Cls(props))``) through :func:`register_once`.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any

__all__ = ["PluginData", "register_once"]

_REGISTERED: set[str] = set()


class PluginData:
    """Data handed to plugin instances by key.

    Parameters
    ----------
    prefix : str
        Start of every key, naming the kind of data (``"btf"``, ``"map"``).
    """

    def __init__(self, prefix: str):
        self._prefix, self._keys = prefix, itertools.count()
        self._items: dict[str, Any] = {}

    def keep(self, item: Any) -> str:
        """Keep ``item`` and return the key to put in the scene dict.

        Parameters
        ----------
        item : Any
            The data a plugin instance reads in its constructor.

        Returns
        -------
        str
            A key unique within this store.
        """
        key = f"{self._prefix}{next(self._keys)}"
        self._items[key] = item
        return key

    def __getitem__(self, key: str) -> Any:
        return self._items[key]


def register_once(
    name: str, register: Callable[[str, Callable[[Any], Any]], None], plugin: Callable[[Any], Any]
) -> bool:
    """Register the plugin ``name`` with Mitsuba unless it is registered already.

    Parameters
    ----------
    name : str
        The plugin name a scene dict's ``"type"`` gives.
    register : callable
        Mitsuba's registration function for the plugin's kind (``mi.register_bsdf``,
        ``mi.register_emitter``).
    plugin : callable
        The factory Mitsuba calls with the plugin's ``mi.Properties``, e.g.
        ``lambda props: SpectralBTF(props)``.

    Returns
    -------
    bool
        Whether this call registered the plugin (``False``: it was registered before, e.g. when
        the plugin's module is imported a second time).
    """
    if name in _REGISTERED:
        return False
    register(name, plugin)
    _REGISTERED.add(name)
    return True
