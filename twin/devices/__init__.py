"""Simulated devices behind the ``hwbridge`` protocols, and capture over a Dask cluster."""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "cluster": [
            "RendererSetup",
            "cluster_description",
            "dask_client",
            "run_capture",
            "run_process",
            "view_tasks",
        ],
        "sim_devices": [
            "Signal",
            "SimCamera",
            "SimGonioDevices",
            "SimLamp",
            "SimLedArray",
            "SimPositioner",
            "SimSpectrometer",
            "SimTunableFilter",
            "VirtualRig",
        ],
    },
)
