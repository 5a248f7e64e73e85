"""Which appearance space and prior fit an image: chosen from known spectra held out of the solve.

The appearance space decides which pixels the prior of Eq. 6.3 links. RGBXY (Eq. 6.5, the
thesis's choice) links pixels of like colour nearby: right where neighbours share a material and
the RGB noise is what separates them (mosaics). The learned space
(:mod:`recon.spectralize.learned_appearance`) links pixels whose spectra, predicted from the
patch around them, are alike: right where colour changes smoothly and pixels of one RGB need
not share a spectrum (blends of materials). :func:`choose_appearance` decides from the data at
hand: for every space it runs the cross-validation of :func:`recon.spectralize.choose_prior`
over the same folds of spots (the learned space refitted in each fold without the held-out
spots) and keeps the space and prior whose held-out spots are predicted best.

References
----------
- The thesis, Eq. 6.3-6.5, 6.8; section 11.2 (richer appearance descriptors).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

import numpy as np

from recon.errors import InputError
from recon.progress import progress_steps
from recon.spectralize.appearance import APPEARANCE_SPACES, NeighbourGraph
from recon.spectralize.hierarchy import choose_prior_on_samples, on_lattice
from recon.spectralize.learned_appearance import (
    LEARNED_SPACES,
    fitted_on,
    standardized_features,
)
from recon.spectralize.prior_choice import FOLDS, PriorChoice, choose_prior
from recon.spectralize.solve import graph_for

__all__ = ["SPACES", "AppearanceChoice", "choose_appearance"]

SPACES = ("rgbxy", "learned")
"""The appearance spaces tried by default."""


@dataclass(frozen=True)
class AppearanceChoice:
    """The chosen ``appearance`` space, its :class:`~recon.spectralize.PriorChoice`
    (``prior_choice``: the prior chosen with it, its folds and held-out predictions), the
    ``energy`` options that select the space for the solve from all spots (``appearance`` and
    ``appearance_options``, a learned space fitted on all spots) and its appearance ``graph``
    where the folds used it (None for a learned space, whose folds find their own graphs, and
    where the folds were solved on a lattice of samples,
    :func:`recon.spectralize.hierarchy.choose_prior_on_samples`), and per space tried the
    held-out error (Eq. 6.8, %) of its better prior."""

    appearance: str
    prior_choice: PriorChoice
    energy: dict[str, Any]
    graph: NeighbourGraph | None
    held_out_errors: dict[str, float]


def choose_appearance(
    rgb: np.ndarray,
    response: np.ndarray,
    known_pixels: np.ndarray,
    known_spectra: np.ndarray,
    *,
    spaces: Sequence[str] = SPACES,
    folds: int = FOLDS,
    sample_stride: int = 1,
    progress: bool = False,
    **options: Any,
) -> AppearanceChoice:
    """Pick the appearance space and the prior by held-out spots (module description).

    Parameters
    ----------
    rgb, response, known_pixels, known_spectra, folds
        As in :func:`recon.spectralize.choose_prior`.
    spaces
        Appearance spaces to try (names of
        :data:`~recon.spectralize.appearance.APPEARANCE_SPACES`); a tie goes to the first.
    sample_stride
        Above 1, the spaces of :data:`recon.spectralize.hierarchy.SPACES` are cross-validated
        on the lattice of every ``sample_stride``-th pixel of every ``sample_stride``-th row
        of an ``(H, W, C)`` image (:func:`recon.spectralize.hierarchy.choose_prior_on_samples`),
        so that their held-out errors are those of the hierarchical reconstruction; 1: every
        space on every pixel.
    progress
        Show a progress bar over the spaces.
    **options
        The other energy and solver options, for every space (``neighbours``, ``weights``,
        ``tol``, ``appearance_options`` such as ``xy_scale``, ...); not ``appearance``,
        ``prior`` or ``graph``, which it sets itself.

    Returns
    -------
    AppearanceChoice

    Examples
    --------
    >>> import numpy as np
    >>> rng = np.random.default_rng(0)
    >>> response, basis = rng.random((8, 3)), rng.random((3, 8))
    >>> truth = rng.random((12, 12, 3)) @ basis
    >>> pixels = np.arange(0, 144, 7)
    >>> spectra = truth.reshape(-1, 8)[pixels]
    >>> choice = choose_appearance(truth @ response, response, pixels, spectra)
    >>> sorted(choice.held_out_errors), choice.prior_choice.spots
    (['learned', 'rgbxy'], 21)
    """
    unknown = [space for space in spaces if space not in APPEARANCE_SPACES]
    if unknown or not spaces:
        raise InputError(
            f"spaces: expected some of {sorted(APPEARANCE_SPACES)}, got {list(spaces)}"
        )
    taken = sorted({"appearance", "prior", "graph"} & set(options))
    if taken:
        raise InputError(f"{', '.join(taken)}: choose_appearance sets them; do not pass them")
    images = np.asarray(rgb, dtype=np.float64)
    choices: dict[str, tuple[PriorChoice, dict[str, Any], NeighbourGraph | None]] = {}
    with progress_steps("choosing the appearance space", len(spaces), enabled=progress) as step:
        for space in spaces:
            energy = {"appearance": space} | {
                key: options[key] for key in ("appearance_options",) if key in options
            }
            if space in LEARNED_SPACES:
                energy = fitted_on(energy, np.asarray(known_pixels), np.asarray(known_spectra))
                if not options.get("p_dyn"):  # the features of every fold's fit, found once
                    energy["appearance_options"]["features"] = standardized_features(
                        images if images.ndim == 4 else images[None]
                    )
            graph = None
            if on_lattice(space, sample_stride) and images.ndim == 3:
                choice = choose_prior_on_samples(
                    images,
                    response,
                    known_pixels,
                    known_spectra,
                    folds=folds,
                    stride=sample_stride,
                    **(options | energy),
                )
            else:
                if space not in LEARNED_SPACES:  # a learned space's folds find their own
                    graph = graph_for(images, options | energy)
                choice = choose_prior(
                    images,
                    response,
                    known_pixels,
                    known_spectra,
                    folds=folds,
                    graph=graph,
                    **(options | energy),
                )
            choices[space] = (choice, energy, graph)
            step()
    errors = {space: choices[space][0].held_out_errors[choices[space][0].prior] for space in spaces}
    chosen = min(spaces, key=errors.__getitem__)
    choice, energy, graph = choices[chosen]
    return AppearanceChoice(chosen, choice, energy, graph, errors)
