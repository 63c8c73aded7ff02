"""Output for ParaView: VTU files of the solid, beams, mortar segments and integration points,
and PVD collections (see :mod:`mortar1d3d.io.vtu`)."""
from .vtu import (BeamSamples, sample_beams, write_beams, write_integration_points, write_mortar,
                  write_pvd, write_segments, write_solid)

__all__ = ["write_solid", "write_beams", "write_segments", "write_integration_points",
           "write_mortar", "write_pvd", "sample_beams", "BeamSamples"]
