"""Simulated devices behind the ``hwbridge`` protocols, the dome's devices simulated or real, and
capture over a Dask cluster."""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "cluster": ["dask_client", "run_capture", "run_process"],
        "dome_devices": ["DomeDevices"],
        "sim_devices": ["SimDomeDevices", "SimGonioDevices", "VirtualRig"],
    },
)
