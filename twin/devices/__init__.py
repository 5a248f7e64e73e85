"""Simulated devices behind the ``hwbridge`` protocols, a lab's real devices in their place, and
capture over a Dask cluster."""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "cluster": ["dask_client", "run_capture", "run_process"],
        "lab_devices": ["LabDevices"],
        "sim_devices": ["SimDomeDevices", "SimGonioDevices", "VirtualRig"],
    },
)
