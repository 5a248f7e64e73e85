"""The noise-free truth of a material: spectral BTF and camera RGB, rectified to texels.

For each light direction :math:`l` and view direction :math:`v` (sample frame), the material is
lit by a distant light of spectrally flat unit irradiance on a plane facing it and seen by an
orthographic camera whose rays run along :math:`-v` and whose pixels are the texels of the
sample's square, so every image is rectified like a measured BTF. The reflectance BTF (1/sr) is
:math:`L_o / (E \\cos\\theta_l)` averaged over each band's normalized passband; shadowing,
masking and interreflection within the material are included, as in a measurement.

Texture truth. The thesis's chapter 10 simulation starts from spectral reference images
:math:`S_{ref}` of a material under one light and view direction (Eq. 10.10, 10.11). The twin's
are rendered by :func:`truth_btf` (Mitsuba, reflectance averaged over 10 nm passbands) and
multiplied by :math:`\\pi`, so that a white Lambertian surface reads 1 (reflectance factors, as
Eq. 6.8's :math:`\\epsilon = 10^{-3}` assumes).

The renders evaluate the light transport at the materials' wavelength nodes
(:mod:`twin.render.node_transport`, the same transport as the gonioreflectometer's frames), so
the spectra carry no sampling noise; the samples per texel average the image over the texel. A
texture is stored as each texel's non-negative least-squares fit with the material's part
reflectances plus a flat spectrum (the surface reflection of a dielectric, i.e. highlights):
shading, shadowing, highlights and the mixing of parts within a texel are its weights, which
also give the texel's spectrum on the fine grid, where the cameras integrate it
(:mod:`twin.dome.capture`).
"""

from __future__ import annotations

import numpy as np
import trimesh
from scipy import optimize

from recon.errors import InputError
from recon.spectra import DEFAULT_GRID, SampledSpectra, WavelengthGrid, resample
from twin.components.lamps import FINE_GRID
from twin.materials import Material, load_material
from twin.materials.surfaces import MATERIAL_GRID
from twin.materials.textures import TextureTruth
from twin.render.node_transport import DistantLight, NodeScene, ParallelCamera, node_weights
from twin.render.ray_cast import first_hits

__all__ = ["band_passbands", "surface_share", "texture_truth", "truth_btf", "truth_camera_signal"]

TEXTURE_BASIS = 8
"""Basis spectra that stand for a part with a spectral texture in :func:`texture_truth`."""

_BOUNCES = 2  # light may meet three surfaces (Mitsuba's path tracer at max_depth 4)


def band_passbands(centres: WavelengthGrid = DEFAULT_GRID, fwhm_nm: float = 10.0) -> SampledSpectra:
    """Gaussian passbands of unit area on ``FINE_GRID``: channel value = band-mean spectrum."""
    sigma = fwhm_nm / (2 * np.sqrt(2 * np.log(2)))
    wavelengths = FINE_GRID.wavelengths_nm
    shapes = np.exp(-0.5 * ((wavelengths[None, :] - centres.wavelengths_nm[:, None]) / sigma) ** 2)
    shapes /= np.trapezoid(shapes, wavelengths, axis=1)[:, None]
    return SampledSpectra(FINE_GRID, shapes, tuple(f"band_{c:g}nm" for c in centres.wavelengths_nm))


def _renders(
    material: Material,
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    channels: SampledSpectra,
    irradiance: SampledSpectra,
    texels: int,
    spp: int,
    seed: int,
) -> np.ndarray:
    """Channel values ``(n_pairs, texels, texels, n_channels)`` of ``material`` lit by a distant
    light of spectral irradiance ``irradiance`` from each light direction, seen along the view
    direction in texel space."""
    scene = NodeScene(material.parts)
    weights = node_weights(channels * irradiance)
    images = []
    for light, view in zip(light_dirs, view_dirs, strict=True):
        radiance = scene.transport(
            ParallelCamera(view, material.size_m / 2, texels),
            DistantLight(light),
            spp=spp,
            seed=seed,
            bounces=_BOUNCES,
        )
        images.append(
            (radiance.reshape(-1, radiance.shape[-1]) @ weights).reshape(texels, texels, -1)
        )
    return np.stack(images)


def _check_directions(
    light_dirs: np.ndarray, view_dirs: np.ndarray
) -> tuple[np.ndarray, np.ndarray]:
    light_dirs, view_dirs = np.atleast_2d(light_dirs), np.atleast_2d(view_dirs)
    if light_dirs.shape != view_dirs.shape or light_dirs.shape[1] != 3:
        raise InputError("light_dirs, view_dirs: expected matching (n, 3) unit vectors")
    if not np.allclose(np.linalg.norm(light_dirs, axis=1), 1) or not np.allclose(
        np.linalg.norm(view_dirs, axis=1), 1
    ):
        raise InputError("light_dirs, view_dirs: expected unit vectors")
    if np.any(light_dirs[:, 2] <= 0) or np.any(view_dirs[:, 2] <= 0):
        raise InputError("light_dirs, view_dirs: expected directions above the sample (z > 0)")
    return light_dirs, view_dirs


def truth_btf(
    material: Material,
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    *,
    texels: int = 64,
    bands: WavelengthGrid = DEFAULT_GRID,
    passbands: SampledSpectra | None = None,
    spp: int = 64,
    seed: int = 0,
) -> np.ndarray:
    """True reflectance BTF ``(n_pairs, texels, texels, n_bands)`` in 1/sr.

    Each band is the reflectance averaged over its passband: by default Gaussians of 10 nm FWHM
    at ``bands`` (:func:`band_passbands`); an instrument's own weighting (filter x sensor x
    lamp, each row of unit area on ``FINE_GRID``) gives the values that instrument measures.
    """
    light_dirs, view_dirs = _check_directions(light_dirs, view_dirs)
    flat = SampledSpectra(FINE_GRID, np.ones(FINE_GRID.size))
    if passbands is None:
        passbands = band_passbands(bands)
    elif passbands.grid != FINE_GRID or passbands.values.ndim != 2:
        raise InputError(
            f"passbands: expected (n_bands, K) rows on {FINE_GRID.describe()}, got "
            f"{passbands.values.shape} on {passbands.grid.describe()}"
        )
    images = _renders(material, light_dirs, view_dirs, passbands, flat, texels, spp, seed)
    return (images / light_dirs[:, 2, None, None, None]).astype(np.float32)


def truth_camera_signal(
    material: Material,
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    response: SampledSpectra,
    illuminant: SampledSpectra,
    *,
    texels: int = 64,
    spp: int = 64,
    seed: int = 0,
) -> np.ndarray:
    """True, noise-free camera values ``(n_pairs, texels, texels, n_channels)``:
    :math:`\\int L_o R_c d\\lambda` under ``illuminant`` (irradiance on a plane facing the light),
    both on ``FINE_GRID``."""
    light_dirs, view_dirs = _check_directions(light_dirs, view_dirs)
    return _renders(material, light_dirs, view_dirs, response, illuminant, texels, spp, seed)


def surface_share(
    material: Material, view_dirs: np.ndarray, *, texels: int, strata: int = 4
) -> np.ndarray:
    """``(n_views, texels, texels)`` the share of each texel's rays (through the centres of
    ``strata`` x ``strata`` cells of the texel, along :math:`-v` as the truth's renders look)
    whose first surface lies within the sample's square: 1 where a texel shows the material's
    surface alone; less where, seen from the side, it shows the sample's outer sides or past
    its outline (a sample raised by :math:`h` above the texels' plane, seen at
    :math:`\\theta_v`: a border :math:`h \\tan\\theta_v` deep on the camera's side). Such
    texels show the holder in a capture and nothing in the truth, so neither measures the
    material."""
    view_dirs = np.atleast_2d(view_dirs)
    half = material.size_m / 2
    cells = (np.arange(texels * strata) + 0.5) / (texels * strata) * 2 * half - half
    x, y = np.meshgrid(cells, -cells)
    on_plane = np.stack([x, y, np.zeros_like(x)], axis=-1).reshape(-1, 3)
    mesh = trimesh.util.concatenate([part.mesh for part in material.parts])
    assert isinstance(mesh, trimesh.Trimesh)  # the parts are triangle meshes
    # the outer sides lie on the square's edges: float32 positions there compare either way
    inside = half * (1 - 1e-6)
    # every view's rays in one trace (one scene for all of them)
    origins = on_plane[None] + 0.1 * view_dirs[:, None]
    directions = np.broadcast_to(-view_dirs[:, None], origins.shape)
    hit, points, _ = first_hits(mesh, origins.reshape(-1, 3), directions.reshape(-1, 3))
    shown = np.zeros(hit.size)
    shown[hit] = np.all(np.abs(points[:, :2]) < inside, axis=1)
    return shown.reshape(len(view_dirs), texels, strata, texels, strata).mean(axis=(2, 4))


def _part_basis(part) -> tuple[list[np.ndarray], list[str]]:
    """A part's basis spectra on ``FINE_GRID``: its reflectance, or for a spectral texture its
    distinct texel spectra (at most :data:`TEXTURE_BASIS`, else k-means centres of them)."""
    if part.texture is None:
        spectrum = resample(part.reflectance, FINE_GRID, method="linear", out_of_range="clamp")
        return [spectrum.values], [part.name]
    texels = part.texture.values.reshape(-1, part.texture.grid.size)
    distinct = np.unique(texels, axis=0)
    if len(distinct) > TEXTURE_BASIS:
        from sklearn.cluster import KMeans

        distinct = KMeans(TEXTURE_BASIS, n_init=4, random_state=0).fit(texels).cluster_centers_
    on_nodes = resample(
        SampledSpectra(part.texture.grid, distinct), MATERIAL_GRID, out_of_range="clamp"
    )  # as the node transport holds the texture
    spectra = resample(on_nodes, FINE_GRID, method="linear", out_of_range="clamp")
    return list(spectra.values), [f"{part.name}[{i}]" for i in range(len(distinct))]


def _basis(material: Material, surface: bool) -> tuple[np.ndarray, np.ndarray, tuple[str, ...]]:
    spectra: list[np.ndarray] = []
    names: list[str] = []
    for part in material.parts:
        part_spectra, part_names = _part_basis(part)
        spectra += part_spectra
        names += part_names
    if surface:
        spectra.append(np.ones(FINE_GRID.size))
        names.append("surface")
    fine = np.array(spectra)
    passbands = band_passbands(DEFAULT_GRID)
    return fine, fine @ (passbands.values * FINE_GRID.quadrature_weights()).T, tuple(names)


def texture_truth(
    material: str | Material,
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    *,
    texels: int = 48,
    spp: int = 64,
    surface: bool = True,
) -> TextureTruth:
    """Render ``material`` for each (light, view) pair and fit every texel with its basis.

    Parameters
    ----------
    material
        A twin material or its name (``scenes/materials``).
    light_dirs, view_dirs
        ``(n_images, 3)`` unit directions in the sample frame, z up.
    texels
        Texture side in texels.
    spp
        Samples per pixel of the renders.
    surface
        Include the flat spectrum (highlights) in the basis.
    """
    model = load_material(material) if isinstance(material, str) else material
    if texels < 2:
        raise InputError(f"texels: expected at least 2, got {texels}")
    btf = np.pi * truth_btf(model, light_dirs, view_dirs, texels=texels, spp=spp)
    fine, bands, names = _basis(model, surface)
    pixels = btf.reshape(-1, btf.shape[-1]).astype(np.float64)
    weights = np.array([optimize.nnls(bands.T, pixel)[0] for pixel in pixels])
    return TextureTruth(weights.reshape(*btf.shape[:-1], len(names)), fine, bands, names)
