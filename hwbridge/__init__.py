"""Device protocols, capture plans, the session runner and the capture store of spectwin.

The capture store's layout: :mod:`hwbridge.store`; its metadata, typed and versioned:
:mod:`hwbridge.schema`; what a dome capture puts in it: :mod:`hwbridge.dome_layout`.

Never imports ``twin``, ``mitsuba`` or ``drjit``: the same code drives simulated and real rigs.
"""
