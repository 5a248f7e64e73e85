"""Regenerate ``recon/data/spectra/jakob2019_srgb_16.coeff``, the Jakob and Hanika (2019) table
of ``recon.rgb_upsampling`` (about 45 minutes on 2 cores).

Run: .venv/bin/python scripts/make_jakob2019_table.py
"""

import colour
from colour.recovery import LUT3D_Jakob2019

from recon.measured_data import data_path


def main() -> None:
    table = LUT3D_Jakob2019()
    table.generate(colour.RGB_COLOURSPACES["sRGB"], size=16)
    table.write(str(data_path("spectra/jakob2019_srgb_16.coeff")))


if __name__ == "__main__":
    main()
