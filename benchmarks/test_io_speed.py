"""Speed of the VTU output for 20000 beam elements (vectorised sampling, no per-element loop)."""
import pytest

from mortar1d3d import generate
from mortar1d3d.io.vtu import sample_beams, write_beams


@pytest.fixture(scope="module")
def beams():
    beams, _ = generate.fibre_cube(2, 1000, 20, curved=True)
    return beams


def test_sample_beams_20000_elements(benchmark, beams):
    samples = benchmark.pedantic(sample_beams, args=(beams,), rounds=5, iterations=1)
    assert len(samples.points) == 8 * beams.n_elements


def test_write_beams_20000_elements_uncompressed(benchmark, beams, tmp_path):
    path = benchmark.pedantic(write_beams, args=(tmp_path / "raw.vtu", beams), kwargs={"compression": None},
                              rounds=3, iterations=1)
    assert path.exists()
