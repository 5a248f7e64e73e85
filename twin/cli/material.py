"""``spectwin material check`` and ``spectwin material examples``: a user's own sample from
files (:mod:`twin.materials.user`), checked and previewed, and two examples to start from."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated

import typer

from twin.cli.errors import SpectwinGroup, require_output_folder
from twin.cli.output import JsonFlag, console, print_summary

__all__ = ["register"]

material_app = typer.Typer(
    cls=SpectwinGroup,
    help="Bring your own sample: check a material YAML and preview it, or write examples.",
    no_args_is_help=True,
)


@material_app.command("check")
def check(
    material: Annotated[
        Path, typer.Argument(help="A material YAML (material: user, or built-in).")
    ],
    out: Annotated[Path, typer.Option(help="Folder for the preview PNG.")] = Path("out/material"),
    texels: Annotated[int, typer.Option(min=8, max=512, help="Preview texels per side.")] = 64,
    spp: Annotated[int, typer.Option(min=1, max=4096, help="Samples per texel.")] = 16,
    as_json: JsonFlag = False,
) -> None:
    """Read every file the material names, check it and render a preview: its true BTF at three
    direction pairs (sRGB) and its parts' spectra, as material_preview.png in --out.

    Example: spectwin material check my_tile/tile.yaml --out out/tile
    """
    from twin.materials import load_material
    from twin.render.material_preview import preview_material, write_preview_figure

    require_output_folder(out)
    with console.status("reading the material's files"):
        built = load_material(material)
    with console.status("rendering the preview"):
        preview = preview_material(built, texels=texels, spp=spp)
    out.mkdir(parents=True, exist_ok=True)
    figure = write_preview_figure(preview, out / "material_preview.png")
    parts = {
        part.name: {
            "faces": len(part.mesh.faces),
            "texels": "x".join(str(v) for v in part.texels),
            "bsdf": part.bsdf_kind,
        }
        for part in built.parts
    }
    summary = {
        "material": built.name,
        "size_mm": round(1e3 * built.size_m, 2),
        "parts": parts,
        **preview.summary(),
        "figure": str(figure),
    }
    print_summary(summary, "material checked", as_json)


@material_app.command("examples")
def examples(
    out: Annotated[Path, typer.Option(help="Folder to write the example materials into.")],
    as_json: JsonFlag = False,
) -> None:
    """Write two user materials made from files only: printed_tile (an OBJ mesh with a spectral
    OpenEXR texture) and painted_card (an sRGB photograph plus three measured spectra).

    Example: spectwin material examples --out my_materials
    """
    from twin.materials.user_examples import write_user_examples

    require_output_folder(out)
    written = write_user_examples(out)
    print_summary({"materials": [str(path) for path in written]}, "example materials", as_json)


def register(app: typer.Typer) -> None:
    """Add the ``material`` command group to ``app``."""
    app.add_typer(material_app, name="material")
