"""The LED dome's processing (thesis chapter 10): a dome run's capture store and the dome's
calibration to a spectral BTF store, without a renderer.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "processing": ["check_dome_run", "process_dome"],
        "run": ["DomeRun", "open_dome_run"],
    },
)
