"""What accuracy costs in time: the integration trade-off study of issue 5.

Measures, on a set of scenes, every integration variant of :func:`assemble_mortar`
(element-based, segment-based and ``"auto"`` with a range of Gauss counts) for

- **cost**: median wall time of the whole ``assemble_mortar`` call (JIT excluded: one untimed
  call first), split into the stages of ``ops.timings``, and the peak of memory allocated
  through Python/NumPy during one call (``tracemalloc``; the kernels' few per-chunk scratch
  buffers are not seen by it);
- **accuracy**: errors of D and M against a converged reference (segment-based with a high
  Gauss count): relative Frobenius norm ``‖A - A_ref‖_F / ‖A_ref‖_F`` and worst entry
  ``max |A - A_ref| / max |A_ref|``. The reference itself is checked against an independent
  adaptive quadrature (:func:`pair_reference_check`: ``scipy.integrate.quad_vec`` over each
  segment, own centreline formulas, own Newton projection);
- **solution error**: the displacement at a monitor point after a linear solve with each
  variant's operators, against the solve with the reference operators
  (:class:`MonitorProblem`, :func:`solution_monitor`, :func:`monitor_error`): a clamped,
  self-weighted linear elastic cube with stiff fibres, penalty-coupled; the solid is factorised
  once per mesh (:class:`ClampedSolid`) and each variant costs one small dense solve. Straight
  fibres only (:data:`MONITOR_KINDS`): the fibres are torsion-free beams, whose theory needs
  initially straight centrelines.

Also: scaling of time and memory with the number of integration points (log-log fit), cold vs
warm start in fresh processes, and the ``"auto"`` target (segment-based accuracy at <= 1.3x the
element-based time) on the benchmark scene ``fibre_cube(20, 1000, 20)``.

Entry points: :func:`run_study` (returns a plain dict of numbers), :func:`write_report` (Markdown,
PNG plots, JSON), :func:`make_report` (both; used by ``mortar1d3d bench report``).

A tool beside the library, not part of it: ``import mortar1d3d`` does not import this package.
Its modules, in the order the study runs:

- :mod:`~mortar1d3d.study.scenes`: the scene kinds, size ratios and embeddings; :func:`build_scene`.
- :mod:`~mortar1d3d.study.config`: the integration variants, :class:`StudyConfig` and its presets.
- :mod:`~mortar1d3d.study.timing`: the clock: one assembly and its stages, scaling, start-up.
- :mod:`~mortar1d3d.study.accuracy`: the errors of D, M and κ against the reference.
- :mod:`~mortar1d3d.study.monitor`: the solution monitor (:class:`ClampedSolid`, :class:`MonitorProblem`).
- :mod:`~mortar1d3d.study.reference`: the independent adaptive quadrature and Newton projection.
- :mod:`~mortar1d3d.study.run`: every variant on every scene, the checks, the benchmark scene.
- :mod:`~mortar1d3d.study.report`: sentences, Markdown, JSON; :mod:`~mortar1d3d.study.plots`: the PNGs.
"""
from .accuracy import operator_errors
from .config import INTEGRATIONS, StudyConfig, preset
from .monitor import (MONITOR_BEAM, MONITOR_BODY_FORCE, MONITOR_SOLID, ClampedSolid, MonitorProblem, monitor_error,
                      monitor_scene, solution_monitor)
from .reference import adaptive_segment_integrals, newton_projection, pair_reference_check
from .report import monitor_sentences, sentences, write_report
from .run import auto_target, make_report, reference_checks, run_study, study_scene
from .scenes import EMBEDDINGS, MONITOR_KINDS, RATIOS, SCENE_KINDS, build_scene
from .timing import STAGES, STARTUP_CODE, scaling, startup, time_assembly

__all__ = [
    "EMBEDDINGS", "INTEGRATIONS", "MONITOR_BEAM", "MONITOR_BODY_FORCE", "MONITOR_KINDS", "MONITOR_SOLID", "RATIOS",
    "SCENE_KINDS", "STAGES", "STARTUP_CODE", "ClampedSolid", "MonitorProblem", "StudyConfig",
    "adaptive_segment_integrals", "auto_target", "build_scene", "make_report", "monitor_error", "monitor_scene",
    "monitor_sentences", "newton_projection", "operator_errors", "pair_reference_check", "preset",
    "reference_checks", "run_study", "scaling", "sentences", "solution_monitor", "startup", "study_scene",
    "time_assembly", "write_report",
]
