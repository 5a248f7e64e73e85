"""The ``spectwin`` command line: one typer app (:mod:`twin.cli.app`), its gonioreflectometer and
dome commands, and the kit they share (choices, one-line errors, rounded tables and JSON).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "app": ["app"],
    },
)
