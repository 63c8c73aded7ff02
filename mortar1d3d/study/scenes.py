"""The study's scenes: Hermite fibres, straight or helical, in a unit cube of hex8, hex27 or tet10.

The scene kinds (:data:`SCENE_KINDS`), the beam-to-solid element size ratios (:data:`RATIOS`) and the
embeddings (:data:`EMBEDDINGS`) span the grid of scenes every integration variant is measured on.
"""
import numpy as np

from .. import generate
from ..mesh import BeamMesh

#: scene kinds: (solid element, curved fibres, distortion amplitude of the solid mesh)
SCENE_KINDS = {
    "straight fibres, hex8": ("hexahedron", False, 0.0),
    "curved fibres, hex27": ("hexahedron27", True, 0.1),
    "curved fibres, tet10": ("tetra10", True, 0.1),
}
#: the scene kinds the solution monitor runs on. Its fibres are torsion-free beams, which hold for
#: initially straight centrelines only (issue 16). A truss is no substitute for the curved kinds: it
#: needs operators of a line centreline, not the Hermite ones this study measures, and half of the
#: scenes have fibres partly outside the cube, where a truss has no stiffness against sideways
#: motion. Curved fibres wait for a beam with a material frame (Simo–Reissner).
MONITOR_KINDS = tuple(k for k, (_, curved, _) in SCENE_KINDS.items() if not curved)
#: beam element length over solid element size
RATIOS = (0.25, 1.0, 4.0)
EMBEDDINGS = ("embedded", "partly outside")


def build_scene(kind, ratio, embedding, cells=8, fibres=12, fibre_length=0.5, seed=2024):
    """Fibres in the unit cube for one cell of the study.

    Parameters
    ----------
    kind : str
        Key of :data:`SCENE_KINDS`: solid element type, straight or helical fibres, distortion
        of the solid mesh (quadratic elements get curved faces).
    ratio : float
        Beam element length over solid element size h_S = 1 / cells (the fibre's elements:
        ``max(1, round(fibre_length / (ratio h_S)))``).
    embedding : {"embedded", "partly outside"}
        Fibres fully inside (2% margin), or centred on a random face of the cube so that about
        half of every fibre is outside.

    Returns
    -------
    beams : BeamMesh (Hermite), solid : SolidMesh
    """
    element, curved, amplitude = SCENE_KINDS[kind]
    if embedding not in EMBEDDINGS:
        raise ValueError(f"embedding must be one of {EMBEDDINGS}, got {embedding!r}")
    solid = generate.box((0, 0, 0), (1, 1, 1), (cells,) * 3, element)
    if amplitude:
        solid = generate.distort(solid, amplitude, seed=seed)
    m = max(1, int(round(fibre_length * cells / ratio)))
    rng = np.random.default_rng(seed)
    axes = rng.normal(size=(fibres, 3))
    axes /= np.linalg.norm(axes, axis=1)[:, None]
    radius = 0.1 * fibre_length if curved else 0.0
    reach = 0.5 * fibre_length + radius + 0.02
    centres = reach + (1.0 - 2.0 * reach) * rng.uniform(size=(fibres, 3))
    if embedding == "partly outside":
        face_axis = rng.integers(0, 3, size=fibres)
        centres[np.arange(fibres), face_axis] = rng.integers(0, 2, size=fibres).astype(float)
    phase = rng.uniform(0.0, 2.0 * np.pi, size=fibres)
    positions, tangents = generate._helices(centres, axes, fibre_length, radius, 0.5, phase, m)
    return BeamMesh.hermite(positions, tangents, generate._chain_elements(fibres, m)), solid

