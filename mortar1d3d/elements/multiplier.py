"""Lagrange-multiplier interpolations Φ_j on a beam element's parameter η ∈ [-1, 1].

==========  =====================  ================================================
type        nodes on η             LM nodes
==========  =====================  ================================================
``line2``   -1, +1                 the beam element's end nodes
``line3``   -1, +1, 0              end nodes + 1 interior LM node per beam element
``line4``   -1, +1, -1/3, +1/3     end nodes + 2 interior LM nodes per beam element
==========  =====================  ================================================

Numbering (docs/conventions.md §2): LM nodes of beam nodes carry the beam node's index; interior LM
nodes follow, element by element.
"""
from dataclasses import dataclass

import numpy as np

from .._config import njit

# padded node table: row n_phi - 2 holds the nodes of the n_phi-point multiplier
_NODES = np.array([
    [-1.0, 1.0, 0.0, 0.0],
    [-1.0, 1.0, 0.0, 0.0],
    [-1.0, 1.0, -1.0 / 3.0, 1.0 / 3.0],
])


@dataclass(frozen=True)
class MultiplierType:
    name: str
    n_functions: int

    @property
    def n_interior(self):
        return self.n_functions - 2

    @property
    def nodes(self):
        return _NODES[self.n_functions - 2, : self.n_functions].copy()


MULTIPLIERS = {name: MultiplierType(name, n) for name, n in (("line2", 2), ("line3", 3), ("line4", 4))}
MAX_FUNCTIONS = 4


def multiplier(name):
    try:
        return MULTIPLIERS[name]
    except KeyError:
        raise ValueError(f"unknown Lagrange multiplier type {name!r}; known types: "
                         f"{', '.join(MULTIPLIERS)}") from None


@njit
def shape(n_phi, eta, Phi):
    """Values of the ``n_phi``-node Lagrange multiplier functions at ``eta`` into ``Phi``."""
    nodes = _NODES[n_phi - 2]
    for j in range(n_phi):
        v = 1.0
        for m in range(n_phi):
            if m != j:
                v *= (eta - nodes[m]) / (nodes[j] - nodes[m])
        Phi[j] = v
