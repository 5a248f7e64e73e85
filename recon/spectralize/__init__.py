"""Spectralization: dense spectral images from dense RGB plus sparse or noisy spectral data
(thesis chapters 6 and 10): the energies, the appearance graph and the solvers.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "appearance": [
            "APPEARANCE_SPACES",
            "NeighbourGraph",
            "appearance_neighbours",
            "appearance_points",
            "connect_components",
        ],
        "energy": [
            "AppearancePriorTerm",
            "CameraTerm",
            "DeviceIntegralTerm",
            "FilteredBandTerm",
            "PointSpectraTerm",
            "SpectralSmoothnessTerm",
            "gaussian_plane",
        ],
        "kronecker": ["KroneckerSolveInfo", "solve_kronecker_sum"],
        "solve": [
            "BandImage",
            "DeviceIntegrals",
            "EnergyWeights",
            "PointSpectra",
            "SpectralizationProblem",
            "SpectralizationResult",
            "build_problem",
            "dynamic_scale",
            "reconstruct",
            "spectralize",
        ],
    },
)
