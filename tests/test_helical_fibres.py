"""Helical fibre families for a pipe wall (issue 19 item 5): nodes on the cylinder and tangents at the
winding angle to round-off, the Hermite centreline close to the helix between the nodes."""
import re

import numpy as np
import pytest

from mortar1d3d.generate import helical_fibres
from mortar1d3d.io.vtu import sample_beams

R, LENGTH = 0.15, 0.4


@pytest.mark.parametrize("angle", [15.0, 54.7356, -54.7356, 85.0])
def test_nodes_on_the_cylinder_and_tangents_at_the_winding_angle(angle):
    beams = helical_fibres(R, LENGTH, angle, count=5, elements=6, phase=0.3, z0=-0.1)
    x, t = beams.positions, beams.tangents
    assert beams.n_elements == 30 and beams.n_nodes == 35
    assert np.abs(np.hypot(x[:, 0], x[:, 1]) - R).max() < 1e-16 * 4
    assert np.abs(np.degrees(np.arccos(t[:, 2])) - abs(angle)).max() < 1e-12
    # the tangent is tangential to the cylinder and winds with the sign of the angle
    radial = x[:, :2] / R
    assert np.abs(np.einsum("ij,ij->i", t[:, :2], radial)).max() < 1e-15
    circumferential = t[:, 1] * radial[:, 0] - t[:, 0] * radial[:, 1]
    assert (np.sign(circumferential) == np.sign(angle)).all()
    # fibre 0 starts at phase 0.3 at z0, fibres evenly spaced, z from z0 to z0 + length
    first = x[::7]
    assert np.allclose(np.arctan2(first[:, 1], first[:, 0]) % (2 * np.pi), (0.3 + 2 * np.pi * np.arange(5) / 5) % (2 * np.pi))
    assert np.allclose(x[6::7, 2], 0.3) and np.allclose(first[:, 2], -0.1)


def test_hermite_centreline_follows_the_helix():
    """Between nodes the cubic Hermite curve leaves the cylinder by O(h⁴): at 60° over 0.74 turns,
    measured 2.9e-4 R with 8 elements (33° of arc each) and 1.8e-5 R with 16 (ratio 16.1)."""
    deviation = []
    for m in (8, 16):
        beams = helical_fibres(R, LENGTH, 60.0, count=1, elements=m)
        x = sample_beams(beams, 21).points
        deviation.append(np.abs(np.hypot(x[:, 0], x[:, 1]) - R).max() / R)
    assert deviation[0] < 4e-4 and deviation[1] < deviation[0] / 14, deviation


def test_bad_arguments():
    with pytest.raises(ValueError, match=re.escape("0 < |angle| < 90 degrees")):
        helical_fibres(R, LENGTH, 90.0, 3, 4)
