"""Parallel VTU output: every rank writes its owned elements, rank 0 the ``.pvtu`` and ``.pvd`` that join them.

Per state k (k = 0 the reference state, then each load step) every rank that owns elements writes
``solid_<k>_<rank>.vtu`` (its owned solid elements with their nodes: point data ``displacement``
and ``solid_node``, the serial node ids; cell data ``green_lagrange_strain``, ``cauchy_stress`` and
``solid_element``, the serial element ids) and ``beams_[<group>_]<k>_<rank>.vtu`` (its owned beam
elements sampled as in the serial output, with ``displacement``, the beam type's fields, the
coupling's ``line_load``, ``beam`` and the serial ``beam_element`` and ``arc_length`` as point
data). Rank 0 writes one
``solid_<k>.pvtu`` / ``beams_..._<k>.pvtu`` per state (VTK's parallel unstructured grid: the
arrays of the pieces declared once, one ``Piece Source`` per written piece; a rank without
elements writes no piece) and ``result.pvd``, the series of the ``.pvtu`` files over the load
factors, which ParaView opens like the serial ``result.pvd``.

Every rank gets the converged states at the unknowns its elements read (its own and the ghosts,
one ghost update per state, :meth:`~.system.DistributedSystem.ghosted`), so no field is gathered;
the ``.pvtu`` headers are made from the arrays each rank
reads back from its own piece (exchanged with one gather). The output directory must be one that
all ranks see (as on a cluster's shared file system).
"""
import xml.etree.ElementTree as ET
from pathlib import Path
from xml.sax.saxutils import quoteattr

import numpy as np

from ..elements.multiplier import multiplier as multiplier_type
from ..io.vtu import _write_text, beam_fibres, sample_beams, write_beams, write_pvd, write_solid
from ..mortar.assemble import lm_numbering
from .petsc import Entries, petsc


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


class LineLoads:
    """The coupling's line load λ at the LM nodes of this rank's owned beam elements, per state.

    Each rank samples λ on its own elements as the serial output does (the multiplier functions
    between the element's LM nodes); the LM nodes at its elements' ends that a neighbour owns come
    with one ``VecScatter`` per state, like the displacements' ghosts.

    Parameters
    ----------
    model : Model
    owned : OwnedPhysics
    rows : list of (3 n_lm,) int64
        Per beam group, where each serial LM row's λ is in the distributed vector that holds it:
        a row of ``weighted`` (penalty), or an unknown of the system (Lagrange multipliers); −1
        where no multiplier acts (λ = 0, as in the serial output).
    weighted : PETSc.Mat or None
        Penalty: ε diag(κ)⁻¹ B, so that λ = ``weighted`` x for the physical state x. None: λ is
        read from the state.
    template : PETSc.Vec
        A vector of the system's layout.
    """

    def __init__(self, model, owned, rows, weighted, template):
        lm = multiplier_type(model.scene.coupling["lm"])
        self.weighted, self.meshes, places = weighted, {}, {}
        for k, elements, _, mesh, _ in owned.beams:
            # the rank's elements as a mesh of their own: its LM nodes -> the group's serial LM nodes
            local, n_local = lm_numbering(mesh, lm)
            serial, _ = lm_numbering(model.groups[k].mesh, lm)
            serial_of_local = np.empty(n_local, dtype=np.int64)
            serial_of_local[local[:, :lm.n_functions]] = serial[elements, :lm.n_functions]
            places[k] = rows[k][(3 * serial_of_local[:, None] + np.arange(3)[None, :]).ravel()]
            self.meshes[k] = mesh
        wanted = np.unique(np.concatenate(list(places.values()) + [np.zeros(0, np.int64)]))
        wanted = wanted[wanted >= 0]
        # λ = 0 where no multiplier acts: the entry after the received ones
        self.places = {k: np.where(p >= 0, np.searchsorted(wanted, p), len(wanted)) for k, p in places.items()}
        layout = template if weighted is None else weighted.createVecLeft()
        self._received = Entries(layout, wanted)
        if layout is not template:
            layout.destroy()
        self.lm_name = model.scene.coupling["lm"]

    def at(self, x):
        """λ, (n_lm of the rank's mesh, 3) per group, of the physical state ``x`` (PETSc vector; collective)."""
        source = x if self.weighted is None else self.weighted * x
        values = np.append(self._received(source), 0.0)
        if source is not x:
            source.destroy()
        return {k: values[p].reshape(-1, 3) for k, p in self.places.items()}

    def zero(self):
        """λ of the reference state."""
        return {k: np.zeros((len(p) // 3, 3)) for k, p in self.places.items()}

    def samples(self, k, lam, s):
        """λ at the output samples of the rank's elements of group ``k`` (as :meth:`Result.write`)."""
        from ..result import Result
        return Result._lm_samples(self.meshes[k], self.lm_name, lam[k], s)


def _beam_fields(model, k, physics, d, s):
    """The beam type's output fields of one rank's elements of group ``k`` (as the serial output samples them)."""
    from ..result import beam_output_fields
    return beam_output_fields(model.groups[k].type, physics.sample(d, np.linspace(-1.0, 1.0, s)), s)


def write_pieces(directory, model, owned, states, comm, samples_per_element=8, *, lines=None, compression="zlib"):
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
    states : list of (load factor, array, line load)
        The converged states (physical components) at the unknowns ``owned.needed``, the reference
        state first, each with :meth:`LineLoads.at` of it (None without coupling).
    comm : PETSc.Comm
    samples_per_element : int
        Samples of each beam element (as :meth:`Result.write`).
    lines : LineLoads, optional
        Samples the states' line loads (with coupling).

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
    mine = []                   # (state, kind, file name, declared arrays)
    for step, (_, z, lam) in enumerate(states):
        if owned.solid is not None:
            u = owned.solid_displacement(z)
            fields = owned.solid.cell_fields(u.ravel())
            cells = {name: np.asarray(v).reshape(len(v), -1) for name, v in fields.items()}
            cells["solid_element"] = owned.solid_elements
            name = f"solid_{step:04d}_{rank}.vtu"
            write_solid(directory / name, owned.solid.mesh, point_data={"displacement": u, "solid_node": owned.solid_nodes},
                        cell_data=cells, compression=compression)
            mine.append((step, "solid", name))
        for k, elements, entries, mesh, (physics, _, _, local) in owned.beams:
            suffix = f"{k}_" if len(model.groups) > 1 else ""
            d = z[local]
            data = _beam_fields(model, k, physics, d, s)
            if lam is not None:
                data["line_load"] = lines.samples(k, lam, s)
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

