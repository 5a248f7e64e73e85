"""Spectralization: dense spectral images from dense RGB plus sparse or noisy spectral data
(thesis chapters 6 and 10): the energies, the appearance graph and the solvers.
"""

import lazy_loader

__getattr__, __dir__, __all__ = lazy_loader.attach(
    __name__,
    submod_attrs={
        "appearance": ["appearance_neighbours"],
        "appearance_choice": ["AppearanceChoice", "choose_appearance"],
        "joint": ["reconstruct_priors"],
        "kronecker": ["solve_kronecker_sum"],
        "prior_choice": ["PriorChoice", "choose_prior"],
        "solve": [
            "EnergyWeights",
            "build_problem",
            "neighbour_graph",
            "reconstruct",
            "spectralize",
        ],
    },
)
