"""Parallel VTU output: every rank writes its owned elements, rank 0 the ``.pvtu`` and ``.pvd`` that join them.

Per state k (k = 0 the reference state, then each load step) every rank that owns elements writes
``solid_<k>_<rank>.vtu`` (its owned solid elements with their nodes: point data ``displacement``
and ``solid_node``, the serial node ids; cell data ``green_lagrange_strain``, ``cauchy_stress`` and
``solid_element``, the serial element ids) and ``beams_[<group>_]<k>_<rank>.vtu`` (its owned beam
elements sampled as in the serial output, with ``displacement``, the beam type's fields, ``beam``
and the serial ``beam_element`` and ``arc_length`` as point data). Rank 0 writes one
``solid_<k>.pvtu`` / ``beams_..._<k>.pvtu`` per state (VTK's parallel unstructured grid: the
arrays of the pieces declared once, one ``Piece Source`` per written piece; a rank without
elements writes no piece) and ``result.pvd``, the series of the ``.pvtu`` files over the load
factors, which ParaView opens like the serial ``result.pvd``.

Every rank holds the converged states in the serial numbering (the Newton loop's iterate is
replicated), so no field is gathered; the ``.pvtu`` headers are made from the arrays each rank
reads back from its own piece (exchanged with one gather). The output directory must be one that
all ranks see (as on a cluster's shared file system).
"""
import xml.etree.ElementTree as ET
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..io.vtu import _write_text, beam_fibres, sample_beams, write_beams, write_pvd, write_solid


def _declared(path):
    """The arrays of a ``.vtu`` piece: ``{"PointData": [(type, name, components)], "CellData": [...],
    "Points": (type, components), "byte_order": ...}``."""
    out = {"PointData": [], "CellData": []}
    section = None
    for event, element in ET.iterparse(path, events=("start", "end")):
        tag = element.tag
        if event == "start":
            if tag == "VTKFile":
                out["byte_order"] = element.get("byte_order", "LittleEndian")
            elif tag in ("PointData", "CellData", "Points"):
                section = tag
            elif tag == "DataArray" and section is not None:
                entry = (element.get("type"), element.get("Name"), element.get("NumberOfComponents", "1"))
                if section == "Points":
                    out["Points"] = (entry[0], entry[2])
                else:
                    out[section].append(entry)
        else:
            if tag in ("PointData", "CellData", "Points"):
                section = None
            element.clear()
    return out


def write_pvtu(path, pieces, declared):
    """Write a ``.pvtu`` joining ``pieces`` (file names relative to its directory) whose arrays are
    ``declared`` (:func:`_declared` of one of them)."""
    lines = ['<?xml version="1.0"?>',
             f'<VTKFile type="PUnstructuredGrid" version="0.1" byte_order={quoteattr(declared["byte_order"])}>',
             '  <PUnstructuredGrid GhostLevel="0">']
    for section in ("PointData", "CellData"):
        lines.append(f"    <P{section}>")
        for kind, name, components in declared[section]:
            lines.append(f"      <PDataArray type={quoteattr(kind)} Name={quoteattr(name)} "
                         f"NumberOfComponents={quoteattr(components)}/>")
        lines.append(f"    </P{section}>")
    kind, components = declared["Points"]
    lines += ["    <PPoints>",
              f"      <PDataArray type={quoteattr(kind)} NumberOfComponents={quoteattr(components)}/>",
              "    </PPoints>"]
    lines += [f"    <Piece Source={quoteattr(Path(p).as_posix())}/>" for p in pieces]
    lines += ["  </PUnstructuredGrid>", "</VTKFile>", ""]
    return _write_text(path, "\n".join(lines))


def _beam_fields(model, k, physics, d, s):
    """The beam type's output fields of one rank's elements of group ``k`` (as the serial output samples them)."""
    from ..result import beam_output_fields
    return beam_output_fields(model.groups[k].type, physics.sample(d, np.linspace(-1.0, 1.0, s)), s)


def write_pieces(directory, model, owned, states, comm, samples_per_element=8, *, compression="zlib"):
    """Write this rank's pieces of every state; rank 0 also the ``.pvtu`` files and ``result.pvd``.

    Collective (every rank calls it).

    Parameters
    ----------
    directory : path
        Seen by every rank.
    model : Model
        The (replicated) model of the run.
    owned : OwnedPhysics
        This rank's elements and their physics.
    states : list of (load factor, (n_unknowns,) array)
        The converged states in the serial numbering, the reference state first.
    comm : PETSc.Comm
    samples_per_element : int
        Samples of each beam element (as :meth:`Result.write`).

    Returns
    -------
    list of pathlib.Path
        On rank 0 the ``.pvtu`` files and ``result.pvd``; on every rank its own pieces after them.
    """
    rank = comm.getRank()
    directory = Path(directory)
    directory.mkdir(parents=True, exist_ok=True)
    s = samples_per_element
    # the serial fibre number and arc length of every sample (the pieces keep the serial ones)
    serial_samples = {}
    for k, *_ in owned.beams:
        mesh = model.groups[k].mesh
        fibre, start = beam_fibres(mesh)
        arc = np.repeat(start, s) + sample_beams(mesh, s).arc_length
        serial_samples[k] = (fibre, arc.reshape(-1, s))
    nS = 3 * model.n_solid_nodes
    mine = []                   # (state, kind, file name, declared arrays)
    for step, (_, z) in enumerate(states):
        if owned.solid is not None:
            u = z[:nS].reshape(-1, 3)[owned.solid_nodes]
            fields = owned.solid.cell_fields(u.ravel())
            cells = {name: np.asarray(v).reshape(len(v), -1) for name, v in fields.items()}
            cells["solid_element"] = owned.solid_elements
            name = f"solid_{step:04d}_{rank}.vtu"
            write_solid(directory / name, owned.solid.mesh, point_data={"displacement": u, "solid_node": owned.solid_nodes},
                        cell_data=cells, compression=compression)
            mine.append((step, "solid", name))
        for k, elements, entries, mesh, (physics, serial, _) in owned.beams:
            suffix = f"{k}_" if len(model.groups) > 1 else ""
            d = z[serial]
            data = _beam_fields(model, k, physics, d, s)
            data["beam"] = entries
            data["beam_element"] = np.repeat(elements, s)
            fibre, arc = serial_samples[k]
            data["fibre"], data["arc_length"] = np.repeat(fibre[elements], s), arc[elements].ravel()
            name = f"beams_{suffix}{step:04d}_{rank}.vtu"
            write_beams(directory / name, mesh, s, point_data=data, compression=compression)
            mine.append((step, f"beams_{suffix}".rstrip("_"), name))
    declared = [(step, kind, name, _declared(directory / name)) for step, kind, name in mine]
    everything = comm.tompi4py().gather(declared, root=0)
    if rank != 0:
        return [directory / name for _, _, name in mine]
    by_state = {}
    for step, kind, name, arrays in (item for part in everything for item in part):
        by_state.setdefault((step, kind), []).append((name, arrays))
    written = []
    for (step, kind), pieces in sorted(by_state.items()):
        name = f"{kind}_{step:04d}.pvtu"
        written.append(write_pvtu(directory / name, [p for p, _ in pieces], pieces[0][1]))
    # parts of the collection: one per kind, the same in every state
    kinds = sorted({k for (_, k) in by_state})
    entries = [(states[step][0], kinds.index(kind), f"{kind}_{step:04d}.pvtu") for (step, kind) in sorted(by_state)]
    written.append(write_pvd(directory / "result.pvd", entries))
    return written + [directory / name for _, _, name in mine]

