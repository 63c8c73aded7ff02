"""The one-way pipeline (scene → build → Model → solvers.newton → Result) and the beam-type
registry: DOF map blocks, mesh readers, beam types as descriptors, the vectorised beam functions
and the linear step of the Newton module."""
import numpy as np
import pytest

from mortar1d3d.elements.beam import BEAM_ELEMENTS, MAX_FUNCTIONS, deriv, evaluate, shape


# --------------------------------------------------------------------------------------------
# vectorised beam functions (VTU output, arc lengths)
# --------------------------------------------------------------------------------------------
@pytest.mark.parametrize("name", list(BEAM_ELEMENTS))
def test_vectorised_beam_functions_have_the_kernels_bits(name):
    element = BEAM_ELEMENTS[name]
    eta = np.array([[-1.0, -0.7310, -0.2], [0.0, 0.3331, 1.0]])
    length = 0.8173
    for derivative, kernel in ((False, shape), (True, deriv)):
        values = evaluate(element, eta, length, derivative=derivative)
        assert values.shape == eta.shape + (MAX_FUNCTIONS,) and values.flags.c_contiguous
        for index in np.ndindex(eta.shape):
            H = np.zeros(MAX_FUNCTIONS)
            kernel(element.code, eta[index], length, H)
            assert values[index].tobytes() == H.tobytes()
