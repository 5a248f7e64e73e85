"""Write the Flea3's relative RGB response of the llanos2019 bench as a CSV camera file, and as
the white balance per filter that ``spectwin camchar --truth`` compares with.

    python scripts/llanos2019_flea3_response.py   # writes recon/data/real/llanos2019/
                                                  # flea3_filter_band_response.csv and
                                                  # flea3_filter_white_balance.csv

Source: ``multispectral_images/sensor.mat`` of the llanos2019 data (B. Llanos, University of
Alberta, 2019, Boost Software License 1.0): ``sensor_map_relative``, the camera's Red and Blue
response to the light of each of the 7 band-pass filters relative to its Green response
(Green = 1), estimated by the data set's author from HDR images of a disk pattern and of the
ColorChecker under the same filters. The CSV holds those ratios as a step function: each filter's
ratios from midway to its neighbour's centroid (the centroids of the filters' main lobes as the
spectrometer measured them in ``spectral_data/spectra_averaged.csv``), the outer steps held to
380 and 780 nm. Green's own spectral shape is not in the data (it is flat here): only the light
inside the filters' passbands is meaningful, and the bench's lamp power per filter absorbs the
Green response there. The white balance is the same ratios as measured, one row per filter
(``light,R,G,B``, the filters named as the columns of ``spectra_averaged.csv``).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from scipy import io

from recon.measured_data import read_spectra_columns

FOLDER = Path(__file__).resolve().parents[1] / "recon" / "data" / "real" / "llanos2019"
FILTER_COLUMNS = ("400 nm", "442 nm", "500 nm", "550 nm", "600 nm", "650 nm", "700 nm")
MAIN_LOBE_NM = 20.0


def filter_centroids() -> np.ndarray:
    """Centroid of each filter's transmission within 20 nm of its peak (380-780 nm, the camera's
    visible range)."""
    filters = read_spectra_columns(
        FOLDER / "spectral_data" / "spectra_averaged.csv", FILTER_COLUMNS, low_nm=380, high_nm=780
    )
    wavelengths = filters.wavelengths_nm
    centroids = []
    for transmission in np.clip(filters.values, 0, None):
        lobe = np.abs(wavelengths - wavelengths[np.argmax(transmission)]) <= MAIN_LOBE_NM
        centroids.append(np.sum(wavelengths[lobe] * transmission[lobe]) / transmission[lobe].sum())
    return np.array(centroids)


def main() -> None:
    ratios = io.loadmat(FOLDER / "multispectral_images" / "sensor.mat")["sensor_map_relative"]
    centroids = filter_centroids()
    wavelengths = np.arange(380.0, 781.0)
    band = np.abs(wavelengths[:, None] - centroids[None, :]).argmin(axis=1)
    rows = ratios[:, band].T  # (K, 3): R/G, 1, B/G of the nearest filter
    header = (
        "# Flea3 FL3-GE-50S5C of the llanos2019 bench: R and B response relative to G per\n"
        "# band-pass filter (sensor.mat sensor_map_relative, B. Llanos 2019, Boost Software\n"
        "# License 1.0), a step function between the filters' centroids "
        + ", ".join(f"{value:.1f}" for value in centroids)
        + " nm;\n# written by scripts/llanos2019_flea3_response.py. Meaningful only inside the "
        "filters' passbands.\n"
    )
    table = "\n".join(
        f"{w:.0f},{r:.6g},{g:.6g},{b:.6g}" for w, (r, g, b) in zip(wavelengths, rows, strict=True)
    )
    path = FOLDER / "flea3_filter_band_response.csv"
    path.write_text(header + "wavelength_nm,R,G,B\n" + table + "\n")
    print(path)
    balance = (
        "# Flea3 FL3-GE-50S5C of the llanos2019 bench: its RGB of a white surface under each\n"
        "# band-pass filter, relative to G (sensor.mat sensor_map_relative, B. Llanos 2019, Boost\n"
        "# Software License 1.0), the filters named as in spectral_data/spectra_averaged.csv;\n"
        "# written by scripts/llanos2019_flea3_response.py.\nlight,R,G,B\n"
    ) + "\n".join(
        f"{name},{r:.6g},{g:.6g},{b:.6g}"
        for name, (r, g, b) in zip(FILTER_COLUMNS, ratios.T, strict=True)
    )
    path = FOLDER / "flea3_filter_white_balance.csv"
    path.write_text(balance + "\n")
    print(path)


if __name__ == "__main__":
    main()
