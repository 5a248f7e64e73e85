"""Device protocols, capture plans, the session runner and the capture store of spectwin.

Never imports ``twin``, ``mitsuba`` or ``drjit``: the same code drives simulated and real rigs.
"""
