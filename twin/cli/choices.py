"""The closed sets of names the ``spectwin`` options accept, as enums (shown in ``--help``).

The names repeat those of the modules that define them (``twin.components``,
``twin.studies.camchar_scenes``, ``twin.studies.dome``) so that the command line starts
without importing
the spectral data; ``tests/e2e/test_cli_bad_input.py`` checks that they agree.
"""

from __future__ import annotations

from enum import StrEnum
from typing import Annotated

import typer

__all__ = ["Chart", "DomeMaterial", "Encoding", "EncodingOption", "Light", "RGBCamera"]


class RGBCamera(StrEnum):
    """Cameras of ``twin.components.RGB_CAMERA_RESPONSES``."""

    aptina_mt9m131 = "Aptina MT9M131"
    nikon_5100 = "Nikon 5100 (NPL)"
    nikon_d100 = "Nikon D100"
    nikon_d70 = "Nikon D70"
    sigma_sd_merrill = "Sigma SDMerill (NPL)"


class Chart(StrEnum):
    """Charts of ``twin.studies.camchar_scenes.CHARTS``."""

    esser = "esser"
    colorchecker = "colorchecker"


class Light(StrEnum):
    """Lights of ``twin.studies.camchar_scenes.LIGHTS``."""

    daylight = "daylight"
    halogen = "halogen"
    fluorescent = "fluorescent"
    hmi = "hmi"


class DomeMaterial(StrEnum):
    """Materials of ``twin.studies.dome.DOME_MATERIALS``."""

    lego = "lego"
    wallpaper = "wallpaper"
    colorchecker16 = "colorchecker16"
    red_fabric = "red_fabric"


class Encoding(StrEnum):
    """Encodings of 8-bit images, ``recon.image_files.ENCODINGS``."""

    linear = "linear"
    srgb = "srgb"


EncodingOption = Annotated[
    Encoding | None,
    typer.Option(
        help="Of 8-bit images, which are refused without it: srgb decodes the sRGB curve, "
        "linear takes the values as they are."
    ),
]
