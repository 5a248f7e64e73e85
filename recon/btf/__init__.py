"""Spectral BTFs: the BTF store, its processing from a measurement run, and its PCA compression
(thesis 4.1.2).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "compression": [
            "CompressedBTF",
            "CompressionReport",
            "LAYOUTS",
            "Layout",
            "SvdMethod",
            "compress_btf",
            "compressed_floats",
            "compression_report",
            "load_compressed",
            "predicted_ratio",
            "save_compressed",
        ],
        "processing": [
            "GonioRun",
            "PairOutcomes",
            "inset_corners",
            "open_btf_store",
            "prepare_gonio_run",
            "process_gonio",
            "process_pairs",
            "record_outcomes",
        ],
        "store": ["BTFStore", "BTF_FORMAT", "BTF_FORMAT_VERSION", "COMPRESSED_GROUP", "write_btf"],
    },
)
