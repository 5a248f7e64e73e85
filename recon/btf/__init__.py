"""Spectral BTFs: the BTF store, its processing from a measurement run, and its PCA compression
(thesis 4.1.2).
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "compression": ["CompressedBTF", "compress_btf", "load_compressed", "save_compressed"],
        "processing": ["process_gonio"],
        "store": ["BTFStore", "write_btf"],
    },
)
