"""Figures a benchmark script hands on to ``benchmarks/targets.py``.

A script calls :func:`record` where it has a figure; when the environment variable
``MORTAR1D3D_BENCH_RECORD`` names a file, the figure is appended to it as one JSON line
(``{"kind": ..., ...}``); otherwise nothing happens, so the scripts print exactly what they
printed before when run by hand. ``targets.py`` sets the variable for each child it runs and
reads the lines back.
"""
import json
import os

ENV = "MORTAR1D3D_BENCH_RECORD"


def record(kind, **figures):
    """Append ``{"kind": kind, **figures}`` to the file named by ``$MORTAR1D3D_BENCH_RECORD``, if set."""
    path = os.environ.get(ENV)
    if not path:
        return
    with open(path, "a", encoding="utf-8") as f:
        f.write(json.dumps({"kind": kind, **figures}) + "\n")


def read(path):
    """The records of a file written by :func:`record` (an empty list if it does not exist)."""
    try:
        with open(path, encoding="utf-8") as f:
            return [json.loads(line) for line in f if line.strip()]
    except FileNotFoundError:
        return []
