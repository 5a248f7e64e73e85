"""Write the ASD-measured ColorChecker of the llanos2019 data as a chart CSV (``spectwin camchar``).

    python scripts/llanos2019_colorchecker_csv.py   # writes recon/data/real/llanos2019/
                                                    # colorchecker_asd.csv

Source: ``spectral_data/spectra_averaged.csv`` of the llanos2019 data (B. Llanos, University of
Alberta, 2019, Boost Software License 1.0; measured by J. Feng with an ASD spectrometer, relative
to a Spectralon tile): the 24 patches of the ColorChecker Classic photographed in
``captured_images``, in reading order (``recon.llanos_capture.LLANOS2019_PATCH_NAMES``), 380-780
nm in 1 nm steps, in the layout of ``recon.chart_photos.spectra_files`` (one column per patch).
The file holds the other measurements of the session too (filters, chequerboards, paper), which
a chart file must not.
"""

from __future__ import annotations

from recon.llanos_capture import read_llanos2019_chart_spectra
from recon.measured_data import data_path


def main() -> None:
    _, patches = read_llanos2019_chart_spectra(380.0, 780.0)
    header = (
        "# ColorChecker Classic of the llanos2019 capture (B. Llanos 2019, Boost Software License\n"
        "# 1.0): reflectance factors relative to a Spectralon tile measured with an ASD\n"
        "# spectrometer (spectral_data/spectra_averaged.csv), patches in reading order;\n"
        "# written by scripts/llanos2019_colorchecker_csv.py.\n"
    )
    names = patches.names or ()
    rows = [
        ",".join([f"{wavelength:g}", *(f"{value:.6g}" for value in column)])
        for wavelength, column in zip(patches.wavelengths_nm, patches.values.T, strict=True)
    ]
    path = data_path("real/llanos2019") / "colorchecker_asd.csv"
    path.write_text(header + ",".join(["wavelength_nm", *names]) + "\n" + "\n".join(rows) + "\n")
    print(path)


if __name__ == "__main__":
    main()
