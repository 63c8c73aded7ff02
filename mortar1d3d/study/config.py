"""What one study run measures: the integration variants, the sizes, the presets."""
from dataclasses import dataclass, field

from .scenes import EMBEDDINGS, RATIOS, SCENE_KINDS

#: the integration variants of ``assemble_mortar`` the study compares
INTEGRATIONS = ("element", "segment", "auto")


@dataclass
class StudyConfig:
    """Sizes and variants of one study run (see :func:`preset`)."""

    name: str = "full"
    cells: int = 8                     # solid cells per cube edge (h_S = 1 / cells)
    fibres: int = 12
    fibre_length: float = 0.5
    lm: str = "line2"
    kinds: tuple = tuple(SCENE_KINDS)
    ratios: tuple = RATIOS
    embeddings: tuple = EMBEDDINGS
    gauss: dict = field(default_factory=lambda: {
        "element": (1, 2, 3, 4, 6, 8, 12, 16, 24, 32),
        "segment": (1, 2, 3, 4, 5, 6, 7, 8),
        "auto": (1, 2, 3, 4, 5, 6, 7, 8)})
    reference_gauss: int = 24
    repeats: int = 5
    threads: int = 1
    memory: bool = True
    thresholds: tuple = (1e-4, 1e-8)
    reference_pairs: int = 6           # beam elements per reference check (adaptive quadrature)
    benchmark_scene: tuple = (20, 1000, 20)
    benchmark_repeats: int = 7
    scaling_points: tuple = (1e3, 1e4, 1e5, 1e6, 1e7)
    startup_cold: bool = True
    seed: int = 2024
    monitor: bool = True               # solution monitor (MonitorProblem) on the study's scenes
    monitor_max_solid_dofs: int = None  # ... only where the solid has at most this many DOFs (None: all)


def preset(name):
    """``"full"`` (``make report``), ``"quick"`` (< 2 minutes here) or ``"tiny"`` (the test suite)."""
    if name == "full":
        return StudyConfig()
    if name == "quick":
        return StudyConfig(name="quick", cells=6, fibres=6, repeats=3, reference_gauss=16, reference_pairs=3,
                           gauss={"element": (1, 2, 4, 8, 16, 32), "segment": (1, 2, 3, 4, 6, 8),
                                  "auto": (1, 2, 4, 8)},
                           benchmark_repeats=3, scaling_points=(1e3, 1e4, 1e5), startup_cold=False,
                           # monitor on the hex8 scenes only (1029 solid DOFs, < 0.1 s set-up); the hex27 and
                           # tet10 solids (6591 DOFs) measured 6-8 s CPU set-up per scene, over the 2-minute budget
                           monitor_max_solid_dofs=2000)
    if name == "tiny":
        return StudyConfig(name="tiny", cells=3, fibres=2, kinds=("straight fibres, hex8", "curved fibres, tet10"),
                           ratios=(1.0,), repeats=1, memory=False, reference_gauss=12, reference_pairs=2,
                           gauss={"element": (1, 4), "segment": (2, 4), "auto": (2,)},
                           benchmark_scene=(4, 10, 5), benchmark_repeats=1, scaling_points=(1e3, 3e3),
                           startup_cold=False)
    raise ValueError(f"unknown study preset {name!r}; choose full, quick or tiny")

