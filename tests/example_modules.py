"""Load a script of ``examples/`` as a module (the examples are scripts, not a package)."""
import importlib.util
from pathlib import Path

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


def load_example(name, module_name=None):
    """The module ``examples/<name>.py``, executed under ``module_name`` (default ``<name>_example``),
    without running its ``__main__`` block."""
    spec = importlib.util.spec_from_file_location(module_name or f"{name}_example", EXAMPLES / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module
