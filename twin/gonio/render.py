"""Renders and raw frames of the gonioreflectometer for one direction pair.

The material on its holder is rotated by the robot pose, the K4 + VariSpec camera stands on the
rail, the lamp at its position. One render of the light transport at the wavelength nodes
(:mod:`twin.render.node_transport`) gives the photo-electron rates of all 33 bands under every
lamp part (HMI: continuum and flickering lines); any exposure window is their weighted sum
(``LightSource.part_exposure_s``), run through the sensor model.
"""

from __future__ import annotations

import numpy as np

from twin.components.lamps import FINE_GRID, LightSource, lamp_model
from twin.components.lctf import LiquidCrystalTunableFilter
from twin.materials import Material
from twin.materials.sample_holder import holder_parts
from twin.materials.surfaces import SurfacePart
from twin.render.node_transport import NodeScene, PinholeRays, PointLight, node_weights
from twin.render.scene import PinholeCamera, lamp_position
from twin.rigs.gonio_kinematics import GonioPose
from twin.rigs.rig_config import GonioConfig
from twin.sensor.model import Sensor

__all__ = [
    "GONIO_SPP",
    "GonioScene",
    "gonio_camera",
    "gonio_lamp",
    "gonio_part_rates",
    "pose_matrix",
    "simulate_band_frames",
]

GONIO_SPP = 16
"""Samples per pixel of the gonioreflectometer's renders, stratified 4 x 4 over the pixel. The
spectra carry no sampling noise (:mod:`twin.render.node_transport`); the samples average the
image over each pixel's area where edges cross it, which registration measures: on the demo's
20 pairs the registered corners are off by at most 0.32 px at 4 samples, 0.12 px at 16 and
0.10 px at 64, and the BTF's error against the truth is the same at all three (BENCHMARKS.md)."""


def gonio_lamp(config: GonioConfig, lamp_id: str) -> tuple[LightSource, np.ndarray]:
    """The lamp model and position of ``lamp_id``."""
    placement = next(lamp for lamp in config.lamps if lamp.id == lamp_id)
    lamp = lamp_model(placement.spectrum)
    return lamp, lamp_position(placement.azimuth_deg, placement.elevation_deg, placement.distance_m)


def gonio_camera(
    config: GonioConfig, rail_deg: float, pixels: int, window: int | None = None
) -> PinholeCamera:
    """The spectral camera on the rail at ``rail_deg``: ``pixels`` across its field, the centred
    ``window`` of them read out (default all)."""
    position = config.rail.radius_m * np.array(
        [np.cos(np.radians(rail_deg)), np.sin(np.radians(rail_deg)), 0.0]
    )
    return PinholeCamera(position, config.camera.field_of_view_m, pixels, window=window)


def pose_matrix(pose: GonioPose) -> np.ndarray:
    """4x4 sample-to-world transform of the robot pose (rotation, then the centre's offset)."""
    matrix = np.eye(4)
    matrix[:3, :3] = pose.rotation().as_matrix()
    matrix[:3, 3] = pose.offset_m
    return matrix


class GonioScene:
    """A material on the gonioreflectometer, ready to render from any robot pose: one scene in
    the sample frame (:class:`twin.render.node_transport.NodeScene`, built once) and the K4 +
    VariSpec channels under each lamp part as node weights.

    The robot moves the sample; rendering moves the camera and the lamp into the sample's frame
    instead (the inverse pose), which gives the same image and keeps the scene unchanged.

    Parameters
    ----------
    config
        The rig.
    material
        The material on the holder (``None``: the holder alone).
    holder
        Put the material on the sample holder.
    extra_parts
        Further surfaces in the sample frame (e.g. a white target).
    """

    def __init__(
        self,
        config: GonioConfig,
        material: Material | None,
        *,
        holder: bool = True,
        extra_parts: list[SurfacePart] | None = None,
    ):
        parts = (holder_parts() if holder else []) + list(material.parts if material else [])
        self._config = config
        self._scene = NodeScene(parts + list(extra_parts or []))
        sensor = Sensor(config.camera.definition)
        bands = LiquidCrystalTunableFilter.varispec(config.camera.filter).transmission(FINE_GRID)
        channels = sensor.electron_responses(FINE_GRID, bands)
        self._bands = channels.values.shape[0]
        self._weights: dict[str, np.ndarray] = {}
        for placement in config.lamps:
            lamp, _ = gonio_lamp(config, placement.id)
            spectral_parts = lamp.spectral_parts(FINE_GRID)
            self._weights[placement.id] = np.concatenate(
                [
                    node_weights(channels * spectral_parts.row(name))
                    for name in spectral_parts.names or ()
                ],
                axis=1,
            ).astype(np.float32)  # (n_nodes, n_parts * n_bands)

    def part_rates(
        self,
        pose: GonioPose,
        *,
        pixels: int = 256,
        spp: int = GONIO_SPP,
        seed: int = 0,
        window: int | None = None,
    ) -> np.ndarray:
        """Photo-electron rates ``(n_parts, H, W, n_bands)`` in e-/s per pixel, one per lamp
        part, at robot pose ``pose``; ``window`` reads out only the centred window of the
        ``pixels`` across the field."""
        camera = gonio_camera(self._config, pose.rail_deg, pixels, window)
        _, lamp_m = gonio_lamp(self._config, pose.lamp_id)
        world_to_sample = np.linalg.inv(pose_matrix(pose))
        rotation, shift = world_to_sample[:3, :3], world_to_sample[:3, 3]
        left, up, forward = camera.frame()
        rays = PinholeRays(
            rotation @ camera.position_m + shift,
            rotation @ left,
            rotation @ up,
            rotation @ forward,
            float(np.tan(np.radians(camera.fov_deg) / 2)),
            pixels,
            window,
        )
        radiance = self._scene.transport(
            rays, PointLight(rotation @ lamp_m + shift), spp=spp, seed=seed
        )
        height, width, count = radiance.shape
        # (n_parts * n_bands, H * W): each band's image contiguous, for the sensor
        rates = self._weights[pose.lamp_id].T @ radiance.reshape(-1, count).T
        return rates.reshape(-1, self._bands, height, width).transpose(0, 2, 3, 1)


def gonio_part_rates(
    config: GonioConfig,
    pose: GonioPose,
    material: Material | None,
    *,
    pixels: int = 256,
    spp: int = GONIO_SPP,
    seed: int = 0,
    holder: bool = True,
    extra_parts: list[SurfacePart] | None = None,
    window: int | None = None,
) -> np.ndarray:
    """Photo-electron rates ``(n_parts, H, W, n_bands)`` in e-/s per pixel, one per lamp part
    (:meth:`GonioScene.part_rates` of a scene built for this one render).

    ``holder`` puts the material on the sample holder; ``extra_parts`` adds surfaces in the
    sample frame (e.g. a white target); ``window`` reads out only the centred window of the
    ``pixels`` across the field.
    """
    scene = GonioScene(config, material, holder=holder, extra_parts=extra_parts)
    return scene.part_rates(pose, pixels=pixels, spp=spp, seed=seed, window=window)


def simulate_band_frames(
    config: GonioConfig,
    pose: GonioPose,
    rates: np.ndarray,
    exposures_s: np.ndarray,
    rng: np.random.Generator,
    *,
    start_s: float = 0.0,
) -> np.ndarray:
    """Raw K4 frames ``(n_bands, H, W)`` of one pair: band by band, each band's exposure window
    following the previous one after the filter switch and download (thesis 4.1.1)."""
    lamp, _ = gonio_lamp(config, pose.lamp_id)
    pixels = rates.shape[1]
    sensor = Sensor(config.camera.definition, roi=(pixels, pixels))
    frames, clock = [], start_s
    for band, exposure_s in enumerate(exposures_s):
        weights = lamp.part_exposure_s(clock, float(exposure_s))
        electrons = np.tensordot(weights, rates[..., band], axes=1)
        frames.append(sensor.capture(electrons.astype(np.float32), float(exposure_s), rng))
        clock += float(exposure_s) + config.timing.switch_and_download_s
    return np.stack(frames)
